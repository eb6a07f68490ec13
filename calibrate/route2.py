r"""Route 2: fit Model 1 / Model 2 to the DEM curves by integrating ``model.simulate``.

Method
------
Eq. 4 is rate independent (docs/model.md, Eq. 4), so a run is replayed in *path strain*:
each piece of one sign of the shear rate becomes ``model.steady_shear(length,
sign)`` at unit rate, where time equals path strain, and the model is read at
the samples' path strains (``t_eval``). The fabric starts from the run's own
DEM state before the reversal (``dem_contract.pre_reversal_state``, the start
``compare`` uses too): a parameter set that cannot carry every seed through
its reversal (a start past the pole, a fabric that runs away) scores as
failed. The plateau the run recovers to, and the steady residuals, test the
model's own steady state.

Residuals, over every sample of every seed and chosen protocol (raw DEM values,
not smoothed):

.. math::
    \frac{a_m - a}{\sigma_a},\ \frac{b_m - b}{\sigma_b},\
    w_\mu\frac{g\sigma_{xy}/p|_m - g\sigma_{xy}/p}{\sigma_\mu}

with each run's sample noise, plus the steady-state residuals of ``fits``. A
parameter set that runs into the pole, or cannot shear steadily (no stable
steady state of simple shear, or forward shear from isotropy leaving the
physical fabrics within a few strains: ``calibrate.shear_stability``), gets a
large constant residual. The friction law is held at its route-1 fit (Eq. 2 for
Model 1, the quadratic law for Model 2). ``scipy.optimize.least_squares`` (trf,
2-point Jacobian with relative step ``diff_step``) runs under a budget of
``max_evals`` model evaluations (each = one integration per run); the best
point seen is returned if the budget runs out.

Integrator
----------
``Route2Settings.integrator`` chooses how the runs are integrated:

- ``"batched"`` (default): every integration of one residual evaluation (all
  runs), and of one finite-difference Jacobian (the n + 1 parameter sets of the
  2-point scheme times all runs), is one ``model.batched.simulate_batch`` call:
  Dormand-Prince 5(4) in path strain with per-trajectory error control at
  ``rtol``/``atol``, falling back to ``simulate`` (``method``, ``rtol``,
  ``atol``, ``max_steps``) for a trajectory it cannot finish (model/README.md,
  "Batched integration"). The Jacobian's parameter sets reach it through
  ``least_squares``' ``workers`` (its map over the finite-difference points),
  so the steps, the bounds handling and the evaluation order are scipy's own.
- ``"loop"``: ``model.simulate`` one run at a time (the path before the batch).

A failure is per trajectory in both: a parameter set one of whose runs meets
the pole, diverges or fails scores as failed; the other sets of the same batch
are unaffected.
"""
from __future__ import annotations

import threading
from dataclasses import asdict, dataclass, field

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from dem_contract import angle_difference, fabric_angle_deg, fabric_norm, pre_reversal_state
from model import PoleError, params_from_dict, simulate, steady_shear
from model.batched import simulate_batch

from . import fits, shear_stability
from .fits import FitResult

PENALTY = 1e3
INTEGRATORS = ("batched", "loop")
#: What a failed integration or residual raises (a pole, a diverging fabric, no steady state, a step budget).
FAILURES = (PoleError, ValueError, FloatingPointError, RuntimeError)


@dataclass(frozen=True)
class Route2Settings:
    method: str = "LSODA"   # switches to an implicit method where a trial set makes Eq. 4 stiff
    rtol: float = 1e-6
    atol: float = 1e-9
    max_steps: int = 20000  # per history segment: a trial set past it scores as failed
    diff_step: float = 1e-3
    max_evals: int = 300   # Model 1 on the quick campaign used 150 up before converging
    mu_weight: float = 1.0
    steady_weight: float = 1.0
    xc_margin: float = 2e-3
    integrator: str = "batched"  # or "loop": model.simulate one run at a time (module Notes)

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"route 2: integrator = {self.integrator!r} is not one of {INTEGRATORS}")

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass
class Replay:
    """One DEM run prepared for replay: pieces (sign, path-strain length), samples and their noise."""

    label: str
    case: str
    A0: tuple
    pieces: list
    s: np.ndarray
    g: np.ndarray
    a: np.ndarray
    b: np.ndarray
    mu: np.ndarray
    sd_a: float
    sd_b: float
    _cached: dict = field(default_factory=dict, repr=False, compare=False)   # key and report grid, made once


def _noise(y):
    d = np.diff(y) / np.sqrt(2.0)
    return max(float(1.4826 * np.median(np.abs(d - np.median(d)))), 1e-6)


def prepare(cases, samples: pd.DataFrame, settings_backsolve) -> list:
    """Build a ``Replay`` for every chosen reversal run of every case.

    The history comes from the raw run (turning points of the signed strain);
    the samples are those the back-solve keeps (rate and reversal rules),
    except that no skip after a reversal is applied here.
    """
    from .smoothing import pieces as sign_pieces

    out = []
    for c in cases:
        pre = pre_reversal_state(c.preshear.data)
        for proto, run in c.runs.items():
            d = run.data
            strain = d["strain"].to_numpy()
            s_all = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(strain)))])
            idx = sign_pieces(d["gammadot"].to_numpy())
            # a turning point lies between the last sample of one sign and the first of the next
            bounds = [0.0] + [0.5 * (s_all[ix[0] - 1] + s_all[ix[0]]) for ix in idx[1:]] + [float(s_all[-1])]
            segs = [(float(np.sign(d["gammadot"].iloc[ix[0]])), bounds[k], bounds[k + 1]) for k, ix in enumerate(idx)]
            sm = samples[(samples["case"] == c.name) & (samples["protocol"] == proto)]
            keep = sm["rate_frac"].to_numpy() >= settings_backsolve.rate_min
            sm = sm[keep]
            start = run.initial_state or pre   # a schedule's later reversal starts from the state before it
            out.append(Replay(
                label=f"{c.name}/{proto}", case=c.name, A0=(start["A_xx"], start["A_xy"]),
                pieces=[(sg, e - b0) for sg, b0, e in segs if e - b0 > 0],
                s=sm["s"].to_numpy(), g=sm["g"].to_numpy(), a=sm["a_raw"].to_numpy(), b=sm["b_raw"].to_numpy(),
                mu=(sm["sigma_xy_over_p"] * sm["g"]).to_numpy(),
                sd_a=_noise(run.data["A_xx"].to_numpy()), sd_b=_noise(run.data["A_xy"].to_numpy()),
            ))
    return out


def history_of(replay: Replay):
    """The unit-rate history in path strain (time = path strain)."""
    h = None
    for sg, length in replay.pieces:
        part = steady_shear(length, sg)
        h = part if h is None else h + part
    return h


def _replay_key(replay: Replay):
    """Runs with the same start, history and samples share one integration."""
    if "key" not in replay._cached:
        replay._cached["key"] = _key_of(replay)
    return replay._cached["key"]


def _key_of(replay: Replay):
    return (replay.A0, tuple(np.round([x for pc in replay.pieces for x in pc], 9)), replay.s.tobytes())


def _report_grid(replay: Replay):
    """The history, the sorted report times (samples clipped to the history) and the sort order."""
    if "grid" not in replay._cached:
        h = history_of(replay)
        t = np.clip(replay.s, 0.0, h.t_end)
        order = np.argsort(t, kind="stable")
        replay._cached["grid"] = (h, t[order], order)
    return replay._cached["grid"]


def _signed(m, replay: Replay):
    out = m.copy()
    out[:, 2] *= replay.g
    return out


def replay_run(params, replay: Replay, model: str, friction: str, settings: Route2Settings, cache=None):
    """Model a, b and signed friction at the replay's samples, by ``model.simulate``. Raises PoleError / ValueError.

    ``cache`` (a dict) shares one integration between runs with the same
    start, history and samples.
    """
    key = _replay_key(replay)
    if cache is not None and key in cache:
        m = cache[key]
    else:
        a0, b0 = replay.A0
        h, t, order = _report_grid(replay)
        sim = simulate(params, h, model=model, A0=(a0, b0), method=settings.method, rtol=settings.rtol,
                       atol=settings.atol, friction=friction, t_eval=t, max_steps=settings.max_steps)
        m = np.empty((len(t), 3))
        m[order] = sim[["A_xx", "A_xy", "sigma_xy_over_p"]].to_numpy()
        if cache is not None:
            cache[key] = m
    return _signed(m, replay)


def curves(items, replays, settings: Route2Settings) -> list:
    """Model curves of every replay for many parameter sets, by ``settings.integrator``.

    Parameters
    ----------
    items : list of (params, model, friction) or (params, model, friction, alpha_spline)
        One parameter set each (``ModelParams``), with its model and friction law; an
        ``model.laws.AlphaSpline`` replaces the model's alphas (free-form fit,
        ``calibrate.freeform``; batched integrator only).
    replays : list of Replay
        The runs every set is integrated on.
    settings : Route2Settings

    Returns
    -------
    list
        Per item, either a list (per replay) of arrays ``(n_samples, 3)``: a, b
        and the signed friction at the samples (``replay_run``'s), or the
        exception that failed the item: the first of its runs, in replay order,
        that met the pole, diverged or failed. Items fail alone.
    """
    if settings.integrator == "loop":
        if any(len(it) > 3 and it[3] is not None for it in items):
            raise ValueError("route 2: free-form alphas (alpha_spline) need integrator = 'batched'")
        out = []
        for prm, model, friction, *_ in items:
            cache = {}
            try:
                out.append([replay_run(prm, r, model, friction, settings, cache) for r in replays])
            except FAILURES as exc:
                out.append(exc)
        return out
    return _curves_batched(items, replays, settings)


def _curves_batched(items, replays, settings: Route2Settings) -> list:
    """``curves`` by one ``simulate_batch`` call over every (item, distinct run); in lockstep when one runs."""
    if not items:
        return []
    if getattr(_LOCKSTEP, "current", None) is not None:
        return _LOCKSTEP.current.submit((items, replays, settings))
    return integrate_requests([(items, replays, settings)])[0]


def integrate_requests(requests) -> list:
    """``curves`` of several requests (items, replays, settings; same tolerances) in one ``simulate_batch`` call.

    A trajectory's numbers do not depend on the rest of its batch
    (model/README.md), so each request gets what it would get alone.
    """
    settings = requests[0][2]
    P, H, M, F, A0, T, S, plan, n = [], [], [], [], [], [], [], [], 0
    for items, replays, _ in requests:
        unique = {}
        for r in replays:
            unique.setdefault(_replay_key(r), r)
        keys, runs = list(unique), list(unique.values())
        grids = [_report_grid(r) for r in runs]
        for prm, model, friction, *spline in items:
            S += [spline[0] if spline else None] * len(runs)
            P += [prm] * len(runs)
            M += [model] * len(runs)
            F += [friction] * len(runs)
            H += [g[0] for g in grids]
            T += [g[1] for g in grids]
            A0 += [tuple(r.A0) for r in runs]
        plan.append((n, keys, grids, len(items), replays))
        n += len(items) * len(runs)
    res = simulate_batch(P, H, model=M, friction=F, A0=A0, t_eval=T, rtol=settings.rtol, atol=settings.atol,
                         fallback_method=settings.method, fallback_rtol=settings.rtol, fallback_atol=settings.atol,
                         fallback_max_steps=settings.max_steps, alpha_spline=S)
    traj = res.table["trajectory"].to_numpy()
    vals = res.table[["A_xx", "A_xy", "sigma_xy_over_p"]].to_numpy()
    lo = np.searchsorted(traj, np.arange(n), side="left")
    hi = np.searchsorted(traj, np.arange(n), side="right")
    outs = []
    for first, keys, grids, n_items, replays in plan:
        out, n_runs = [], len(keys)
        for j in range(n_items):
            idx = range(first + j * n_runs, first + (j + 1) * n_runs)
            err = next((res.errors[i] for i in idx if res.errors[i] is not None), None)
            if err is not None:
                out.append(err)
                continue
            by_key = {}
            for k, i in enumerate(idx):
                m = np.empty((hi[i] - lo[i], 3))
                m[grids[k][2]] = vals[lo[i]:hi[i]]
                by_key[keys[k]] = m
            out.append([_signed(by_key[_replay_key(r)], r) for r in replays])
        outs.append(out)
    return outs


class Lockstep:
    """Run jobs in threads whose batched ``curves`` requests are integrated together, one batch per round.

    Each job (e.g. one bootstrap replicate's fits) runs in its own thread; when
    every job still running is waiting on a ``curves`` request, the last to
    arrive integrates all requests in one ``simulate_batch`` call and hands
    each its part. A job's results are those it gets alone (the batch's
    trajectories are independent), so ``run`` returns what running the jobs one
    after the other would; only the number of numpy passes changes.
    """

    def __init__(self):
        self._cv = threading.Condition()
        self._pending, self._active = [], 0

    def run(self, jobs) -> list:
        """Call every job (a callable without arguments) in its own thread; their results, or raise the first error."""
        results, errors = [None] * len(jobs), [None] * len(jobs)
        self._active = len(jobs)

        def work(k):
            _LOCKSTEP.current = self
            try:
                results[k] = jobs[k]()
            except BaseException as exc:   # re-raised below, in the caller's thread
                errors[k] = exc
            finally:
                _LOCKSTEP.current = None
                with self._cv:
                    self._active -= 1
                    self._flush_if_ready()

        threads = [threading.Thread(target=work, args=(k,), daemon=True) for k in range(len(jobs))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        for e in errors:
            if e is not None:
                raise e
        return results

    def submit(self, request):
        slot = {"request": request}
        with self._cv:
            self._pending.append(slot)
            self._flush_if_ready()
            self._cv.wait_for(lambda: "out" in slot)
        if isinstance(slot["out"], BaseException):
            raise slot["out"]
        return slot["out"]

    def _flush_if_ready(self):
        if not self._pending or len(self._pending) < self._active:
            return
        slots, self._pending = self._pending, []
        groups = {}   # requests with the same tolerances share a batch
        for s in slots:
            st = s["request"][2]
            groups.setdefault((st.rtol, st.atol, st.method, st.max_steps), []).append(s)
        for group in groups.values():
            try:
                outs = integrate_requests([s["request"] for s in group])
            except Exception as exc:   # a bad request: every job waiting on this batch gets the error
                outs = [exc] * len(group)
            for s, o in zip(group, outs):
                s["out"] = o
        self._cv.notify_all()


_LOCKSTEP = threading.local()   # .current: the Lockstep the thread's job runs under, if any


def residual_vector(ms, replays, sigma_mu, settings: Route2Settings):
    """Route 2's normalised data residuals of the model curves ``ms``, replay after replay (module Notes)."""
    parts = []
    for m, r in zip(ms, replays):
        parts += [(m[:, 0] - r.a) / r.sd_a, (m[:, 1] - r.b) / r.sd_b,
                  settings.mu_weight * (m[:, 2] - r.mu) / sigma_mu]
    return np.concatenate(parts)


def residuals(params, replays, model, friction, sigma_mu, settings: Route2Settings):
    """Normalised residuals of every replay (see module Notes); raises on pole / no steady state."""
    (c,) = curves([(params, model, friction)], replays, settings)
    if isinstance(c, Exception):
        raise c
    return residual_vector(c, replays, sigma_mu, settings)


def fit_residuals(ms, replays, sigma_mu, settings: Route2Settings, alphas, steady):
    """The residuals route 2 minimises: the data residuals (``residual_vector``), then the steady fabric's rows.

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
    return params_from_dict(d, source=f"route2 trial ({block})")


def _scaled_bounds(model, steady, settings: Route2Settings, x_lower):
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
    best point are those of one call per point. Shared by route 2 and ``calibrate.freeform``.

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


def _objective(replays, base_params, model, keys, scale, steady, sigma_mu, settings: Route2Settings, n_res,
               fixed=None):
    """The residual function of ``fit``, its ``workers`` map, and the state they keep (``counted_objective``).

    A trial set that cannot be integrated (pole, divergence) or cannot shear steadily
    (``shear_stability.check``) is a failed point; with the batched integrator the Jacobian's points are integrated in one batch.
    ``fixed`` (name -> value) holds parameters of the block out of ``keys`` at those values.
    """
    friction = "eq2" if model == "model1" else "quadratic"
    alpha = fits.alpha_model1 if model == "model1" else fits.alpha_model2
    order = fits.M1_KEYS if model == "model1" else fits.M2_KEYS
    fixed = dict(fixed or {})

    def evaluate(points):
        """Residuals of each scaled point, or None where it cannot be integrated (one batch for all)."""
        out, trials = [None] * len(points), []
        for k, p in enumerate(points):
            vals = {**fixed, **dict(zip(keys, (np.asarray(p) * scale).tolist()))}
            try:
                trials.append((k, vals, _with_block(base_params, model, vals)))
            except FAILURES:
                pass
        got = curves([(prm, model, friction) for _, _, prm in trials], replays, settings)
        for (k, vals, prm), c in zip(trials, got):
            try:
                if isinstance(c, Exception):
                    raise c
                r = fit_residuals(c, replays, sigma_mu, settings, alpha(steady["X"], *[vals[key] for key in order]),
                                  steady)
                if not np.all(np.isfinite(r)):
                    raise ValueError("non-finite residuals")
                if not shear_stability.check_block(prm, model)["stable"]:
                    raise ValueError("cannot shear steadily")     # penalised to exclusion
                out[k] = r
            except FAILURES:
                pass
        return out

    return counted_objective(evaluate, n_res, settings.max_evals, batched=settings.integrator == "batched")


def fit(replays, base_params: dict, model: str, start: dict, steady: dict, sigma_mu: float,
        settings: Route2Settings = Route2Settings(), x_lower=None, fixed=None) -> FitResult:
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
    """
    keys, scale, lo, hi = _scaled_bounds(model, steady, settings, x_lower)
    fixed = dict(fixed or {})
    free = np.array([k not in fixed for k in keys])
    keys, scale, lo, hi = tuple(k for k in keys if k not in fixed), scale[free], lo[free], hi[free]
    n_res = sum(3 * len(r.s) for r in replays) + fits.N_STEADY
    res, workers, state = _objective(replays, base_params, model, keys, scale, steady, sigma_mu, settings, n_res,
                                     fixed)
    x0 = np.array([start[k] for k in keys]) / scale
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
    vals = {**fixed, **dict(zip(keys, (p * scale).tolist()))}
    vals = {k: vals[k] for k in (fits.M1_KEYS if model == "model1" else fits.M2_KEYS)}
    n_data = n_res - fits.N_STEADY
    rms = float(np.sqrt(2 * state["best_cost"] / max(n_res, 1)))
    ok = state["best_cost"] < 0.5 * n_res * PENALTY**2
    return FitResult(model, vals, state["best_cost"], n_data, rms, ok, message, {"evaluations": state["n"], "failed_evaluations": state["fails"]})


def score(params, replays, model: str, settings: Route2Settings, sigma_mu: float) -> dict:
    """Prediction error of ``params`` on ``replays`` (e.g. held-out seeds).

    Returns RMS of |A|, theta_A (degrees, wrapped), mu, ``score`` = RMS of
    the normalised residuals (the route-2 objective without the steady terms),
    and ``failure``: empty, or, if the model cannot be integrated (pole,
    diverging fabric, no steady state), the reason, with ``inf`` in every
    number (the worst score, for comparisons; tables write NaN and the reason).
    """
    return score_many([(params, model)], replays, settings, sigma_mu)[0]


def score_many(items, replays, settings: Route2Settings, sigma_mu: float) -> list:
    """``score`` of each (params, model) of ``items`` on ``replays``, integrated together (``curves``)."""
    friction = {"model1": "eq2", "model2": "quadratic"}
    got = curves([(prm, model, friction[model]) for prm, model in items], replays, settings)
    return [_score_of(c, replays, settings, sigma_mu) for c in got]


def _score_of(c, replays, settings: Route2Settings, sigma_mu: float) -> dict:
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
