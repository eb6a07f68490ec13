r"""The curves route fitted (the tables' ``curves``): its residuals, its objective under a budget, the fit, its scores.

Residuals, over every sample of every seed and chosen protocol (raw DEM values,
not smoothed), of the model's curves along the runs' replays (``calibrate.curves_integration.curves``):

.. math::
    \frac{a_m - a}{\sigma_a},\ \frac{b_m - b}{\sigma_b},\
    w_\mu\frac{g\sigma_{xy}/p|_m - g\sigma_{xy}/p}{\sigma_\mu}

with each run's sample noise, plus the steady-state residuals of ``fits``. A
parameter set that cannot carry every seed through its reversal (a start past
the pole, a fabric that runs away), or cannot shear steadily (no stable
steady state of simple shear, or forward shear from isotropy leaving the
physical fabrics within a few strains: ``calibrate.shear_stability``), gets a
large constant residual. The friction law is held at its back-solve fit (Eq. 2 for
Model 1, the quadratic law for Model 2). ``scipy.optimize.least_squares`` (trf,
2-point Jacobian with relative step ``diff_step``) runs under a budget of
``max_evals`` model evaluations (each = one integration per run); the best
point seen is returned if the budget runs out.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from dem_contract import angle_difference, fabric_angle_deg, fabric_norm
from model import params_from_dict

from . import fits, shear_stability
from .fits import FitResult
from .curves_integration import FAILURES, CurvesSettings, curves

PENALTY = 1e3


def residual_vector(ms, replays, sigma_mu, settings: CurvesSettings):
    """The curves route's normalised data residuals of the model curves ``ms``, replay after replay (module Notes)."""
    parts = []
    for m, r in zip(ms, replays):
        parts += [(m[:, 0] - r.a) / r.sd_a, (m[:, 1] - r.b) / r.sd_b,
                  settings.mu_weight * (m[:, 2] - r.mu) / sigma_mu]
    return np.concatenate(parts)


def residuals(params, replays, model, friction, sigma_mu, settings: CurvesSettings):
    """Normalised residuals of every replay (see module Notes); raises on pole / no steady state."""
    (c,) = curves([(params, model, friction)], replays, settings)
    if isinstance(c, Exception):
        raise c
    return residual_vector(c, replays, sigma_mu, settings)


def fit_residuals(ms, replays, sigma_mu, settings: CurvesSettings, alphas, steady):
    """The residuals the curves fit minimises: the data residuals (``residual_vector``), then the steady fabric's rows.

    ``alphas`` = (alpha1, alpha2) the fitted law gives at the steady X (``steady["X"]``): Model 1's or
    Model 2's law (``fits.alpha_model1``/``alpha_model2``) in ``fit``, a free-form spline in
    ``calibrate.freeform``; the rows are ``fits.steady_fabric_residuals`` (weight ``settings.steady_weight``).
    """
    return np.concatenate([residual_vector(ms, replays, sigma_mu, settings),
                           fits.steady_fabric_residuals(*alphas, steady, settings.steady_weight)])


class BudgetExhausted(Exception):
    """``counted_objective``'s residual function was called past its budget of model evaluations."""


def _with_block(base: dict, block: str, values: dict):
    d = dict(base)
    d[block] = dict(values)
    return params_from_dict(d, source=f"curves trial ({block})")


def _scaled_bounds(model, steady, settings: CurvesSettings, x_lower):
    """Keys, scale and scaled bounds of the fitted block (Model 1: X_c above ``fits.xc_lower_bound``)."""
    if model == "model1":
        scale = np.array([1.0, 10.0, 1e3, 1.0, 10.0, 1e3, 0.01])
        xl = fits.xc_lower_bound(steady, settings.xc_margin) if x_lower is None else x_lower
        lo, hi = (b / scale for b in fits.model1_bounds(xl))
        return fits.M1_KEYS, scale, lo, hi
    return fits.M2_KEYS, np.array([1.0, 1.0, 10.0]), np.full(3, -np.inf), np.full(3, np.inf)


def counted_objective(evaluate, n_res: int, max_evals: int, batched: bool = True):
    """``least_squares``' residual function over ``evaluate``, its ``workers`` map, and the state they keep.

    ``evaluate(points)`` returns the residual vector of each (scaled) point, or None
    where it cannot be integrated; such a point gets ``PENALTY`` in every one of its
    ``n_res`` residuals. Past ``max_evals`` evaluations ``res`` raises ``BudgetExhausted``.
    With ``batched``, ``workers(fun, xs)`` (the map ``least_squares`` evaluates the
    Jacobian's finite-difference points with) evaluates all points in one call first,
    then calls ``fun`` on each in scipy's order, so the counting, the budget and the
    best point are those of one call per point. Shared by ``fit`` and ``calibrate.freeform``.

    Returns
    -------
    res, workers : callable
    state : dict
        ``n`` (evaluations), ``fails``, ``best`` (scaled point) and ``best_cost`` (half the sum of squares).
    """
    state = {"n": 0, "best": None, "best_cost": np.inf, "fails": 0}
    ready = {}   # point (bytes) -> residuals computed by the last batch (None: failed)

    def res(p):
        if state["n"] >= max_evals:
            raise BudgetExhausted
        state["n"] += 1
        key = np.asarray(p, dtype=float).tobytes()
        r = ready.pop(key) if key in ready else evaluate([p])[0]
        if r is None:
            state["fails"] += 1
            r = np.full(n_res, PENALTY)
        cost = 0.5 * float(np.sum(r**2))
        if cost < state["best_cost"]:
            state["best_cost"], state["best"] = cost, np.array(p, dtype=float)
        return r

    def workers(fun, points):
        points = [np.array(x, dtype=float) for x in points]
        ready.clear()
        if batched:
            ready.update(zip((x.tobytes() for x in points), evaluate(points)))
        return [fun(x) for x in points]

    return res, workers, state


@dataclass(frozen=True, eq=False)
class FitInputs:
    """What a curves fit holds fixed while its block moves: the runs, the parameter document holding the
    friction laws, the model, the steady state and friction noise, the route's settings and the batcher."""

    replays: list
    base_params: dict
    model: str
    steady: dict
    sigma_mu: float
    settings: CurvesSettings
    batcher: object = None   # calibrate.integration_batcher.IntegrationBatcher, or None: integrate at once

    @property
    def n_res(self) -> int:
        """The residuals of one evaluation: three per sample of every run, and the steady state's."""
        return sum(3 * len(r.s) for r in self.replays) + fits.N_STEADY


@dataclass(frozen=True, eq=False)
class FreeBlock:
    """The block's parameters ``least_squares`` moves (``keys``, each in units of its ``scale``) and those
    held at given values (``fixed``, name -> value)."""

    keys: tuple
    scale: np.ndarray
    fixed: dict

    def values(self, p) -> dict:
        """The block's values at the scaled point ``p``: the held ones, then the moved ones."""
        return {**self.fixed, **dict(zip(self.keys, (np.asarray(p) * self.scale).tolist()))}


def _objective(inputs: FitInputs, block: FreeBlock):
    """The residual function of ``fit``, its ``workers`` map, and the state they keep (``counted_objective``).

    A trial set that cannot be integrated (pole, divergence) or cannot shear steadily
    (``shear_stability.check``) is a failed point; with the batched integrator the Jacobian's points are integrated in one batch.
    """
    model, settings, steady = inputs.model, inputs.settings, inputs.steady
    friction = "eq2" if model == "model1" else "quadratic"
    alpha = fits.alpha_model1 if model == "model1" else fits.alpha_model2
    order = fits.M1_KEYS if model == "model1" else fits.M2_KEYS

    def evaluate(points):
        """Residuals of each scaled point, or None where it cannot be integrated (one batch for all)."""
        out, trials = [None] * len(points), []
        for k, p in enumerate(points):
            vals = block.values(p)
            try:
                trials.append((k, vals, _with_block(inputs.base_params, model, vals)))
            except FAILURES:
                pass
        got = curves([(prm, model, friction) for _, _, prm in trials], inputs.replays, settings, inputs.batcher)
        for (k, vals, prm), c in zip(trials, got):
            try:
                if isinstance(c, Exception):
                    raise c
                r = fit_residuals(c, inputs.replays, inputs.sigma_mu, settings,
                                  alpha(steady["X"], *[vals[key] for key in order]), steady)
                if not np.all(np.isfinite(r)):
                    raise ValueError("non-finite residuals")
                if not shear_stability.check_block(prm, model)["stable"]:
                    raise ValueError("cannot shear steadily")     # penalised to exclusion
                out[k] = r
            except FAILURES:
                pass
        return out

    return counted_objective(evaluate, inputs.n_res, settings.max_evals, batched=settings.integrator == "batched")


def fit(replays, base_params: dict, model: str, start: dict, steady: dict, sigma_mu: float,
        settings: CurvesSettings, x_lower=None, fixed=None, batcher=None) -> FitResult:
    """Least-squares fit of the ``model`` block to the replays, from ``start``.

    Parameters
    ----------
    replays : list of Replay
    base_params : dict
        A full parameter document (``ModelParams.to_dict()``) holding the friction laws to use.
    model : {"model1", "model2"}
    start : dict
        Starting values of the block.
    steady : dict
        ``io.steady_values``.
    sigma_mu : float
    x_lower : float, optional
        Lower bound of X_c (Model 1); default ``fits.xc_lower_bound(steady, xc_margin)``.
    fixed : dict, optional
        Parameters of the block held at these values (not fitted; a profile's point,
        ``calibrate.profiles``); they are part of the returned values.
    batcher : calibrate.integration_batcher.IntegrationBatcher, optional
        The batcher the calling job runs under (``curves_integration.curves``).
    """
    inputs = FitInputs(replays, base_params, model, steady, sigma_mu, settings, batcher)
    keys, scale, lo, hi = _scaled_bounds(model, steady, settings, x_lower)
    fixed = dict(fixed or {})
    free = np.array([k not in fixed for k in keys])
    block = FreeBlock(tuple(k for k in keys if k not in fixed), scale[free], fixed)
    lo, hi = lo[free], hi[free]
    n_res = inputs.n_res
    res, workers, state = _objective(inputs, block)
    x0 = np.array([start[k] for k in block.keys]) / block.scale
    with np.errstate(invalid="ignore"):
        x0 = np.clip(x0, np.where(np.isfinite(lo), lo + 1e-9 * np.abs(lo) + 1e-12, lo),
                     np.where(np.isfinite(hi), hi - 1e-9 * np.abs(hi) - 1e-12, hi))
    message = ""
    try:
        sol = least_squares(res, x0, bounds=(lo, hi), x_scale="jac", diff_step=settings.diff_step,
                            max_nfev=settings.max_evals, workers=workers)
        message = sol.message
    except BudgetExhausted:
        message = f"budget of {settings.max_evals} model evaluations used up; best point kept"
    p = state["best"] if state["best"] is not None else x0
    vals = block.values(p)
    vals = {k: vals[k] for k in (fits.M1_KEYS if model == "model1" else fits.M2_KEYS)}
    n_data = n_res - fits.N_STEADY
    rms = float(np.sqrt(2 * state["best_cost"] / max(n_res, 1)))
    ok = state["best_cost"] < 0.5 * n_res * PENALTY**2
    return FitResult(model, vals, state["best_cost"], n_data, rms, ok, message, {"evaluations": state["n"], "failed_evaluations": state["fails"]})


def score(params, replays, model: str, settings: CurvesSettings, sigma_mu: float) -> dict:
    """Prediction error of ``params`` on ``replays`` (e.g. held-out seeds).

    Returns RMS of |A|, theta_A (degrees, wrapped), mu, ``score`` = RMS of
    the normalised residuals (the curves fit's objective without the steady terms),
    and ``failure``: empty, or, if the model cannot be integrated (pole,
    diverging fabric, no steady state), the reason, with ``inf`` in every
    number (the worst score, for comparisons; tables write NaN and the reason).
    """
    return score_many([(params, model)], replays, settings, sigma_mu)[0]


def score_many(items, replays, settings: CurvesSettings, sigma_mu: float, batcher=None) -> list:
    """``score`` of each (params, model) of ``items`` on ``replays``, integrated together (``curves``, under
    ``batcher`` if given)."""
    friction = {"model1": "eq2", "model2": "quadratic"}
    got = curves([(prm, model, friction[model]) for prm, model in items], replays, settings, batcher)
    return [_score_of(c, replays, settings, sigma_mu) for c in got]


def _score_of(c, replays, settings: CurvesSettings, sigma_mu: float) -> dict:
    try:
        if isinstance(c, Exception):
            raise c
        z = residual_vector(c, replays, sigma_mu, settings)
        dA, dth, dmu = [], [], []
        for m, r in zip(c, replays):
            dth.append(angle_difference(fabric_angle_deg(m[:, 0], m[:, 1]), fabric_angle_deg(r.a, r.b)))
            dA.append(fabric_norm(m[:, 0], m[:, 1]) - fabric_norm(r.a, r.b))
            dmu.append(m[:, 2] - r.mu)
        rms = lambda v: float(np.sqrt(np.mean(np.concatenate(v) ** 2)))  # noqa: E731
        return {"score": float(np.sqrt(np.mean(z**2))), "rms_A_norm": rms(dA), "rms_theta_A": rms(dth),
                "rms_mu": rms(dmu), "failure": ""}
    except FAILURES as exc:
        reason = f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
        return {"score": np.inf, "rms_A_norm": np.inf, "rms_theta_A": np.inf, "rms_mu": np.inf, "failure": reason}
