r"""The curve fit of Model 1 with its pole a fitted offset above each run's start (``model.pole_start``).

Not one X_c for every run, but :math:`X_c = \max(X_{rev}, 0) + \delta` per run,
with :math:`X_{rev}` the model's mirrored X at the run's reversal
(``model.pole_start``: the start fabric's for a step, the state at the zero of
the rate for a half cosine) and one fitted :math:`\delta \ge \delta_{min}`
shared by every run, with a_i, b_i, c_i of Eq. 6.

Method
------
The residuals, their weights, the steady-state terms and the optimiser are
the curves route's (``calibrate.curves_integration``): the same replays in path strain from each
run's own start (``dem_contract.pre_reversal_state``), the friction law held at
its Eq. 2 fit. Per residual evaluation two batched integrations
(``model.batched.simulate_batch``): the forward part of the runs that shear
forward before reversing (their X_rev; X < 0 there, so it does not depend on
the pole), then every run with its own X_c. A parameter set whose forward part
or run fails (divergence, no steady state) scores as failed, as in the curve fit.

Profile of delta: delta held on a grid from ``DELTA_MIN`` (the pole at the
start) up, every other parameter refitted (warm start from the optimum); the
95 % interval is the curve fit's likelihood-ratio threshold
(``calibrate.profiles.threshold``). A profile whose lowest point is inside the
threshold has its lower end at 0: the data cannot tell the pole from the start.

Command line::

    python -m calibrate.pole_start_fit --dem results/dem/<case> ... --params results/calibration/<set>/params.yaml \
        --protocols heaviside sinusoidal --out results/calibration/<set>/pole_start.yaml
        # -> pole_start.yaml (fitted block, delta and its profile interval), pole_start_profile.csv

The workflow gives the fit the budget of its set's calibration (``budget``): calibrate's own options
(``calibration.options``), read by calibrate's parser, set ``--max-evals`` and ``--profile-points``.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from scipy.optimize import least_squares

from model import load_params
from model.batched import simulate_batch
from model.pole_start import (DELTA_MIN, FORMAT_TAG, KEYS, block_params, far_pole, forward_history, load,  # noqa: F401
                              mirrored_x, with_pole)

from . import curves_fit, curves_integration, fits, profiles
from .curves_integration import FAILURES, CurvesOptions, CurvesSettings
from .settings import Settings

SCALE = np.array([1.0, 10.0, 1e3, 1.0, 10.0, 1e3, 0.01])
DELTA_MAX = 0.4
DELTA_STARTS = (0.003, 0.01, 0.03, 0.1)
#: Pole strengths (c1, c2) to start from besides the set's own (those of ``fits.fit_model1``'s starts).
C_STARTS = ((-1e3, 1e3), (-1e2, 1e2), (-1e4, 1e3))
N_FITS = 3
PROFILE_POINTS = 10
#: Relative steps of the profile's grid next to the optimum (the rest is geometric out to DELTA_MIN and beyond).
NEAR = (0.05, 0.15, 0.4)


def bounds():
    """Lower and upper bounds in ``KEYS`` order: Eq. 6's (``fits.M1_BOUNDS``), ``DELTA_MIN <= delta <= DELTA_MAX``."""
    lo, hi = zip(*fits.M1_BOUNDS)
    return np.array([*lo, DELTA_MIN]), np.array([*hi, DELTA_MAX])


def _block_params(base_doc: dict, vals: dict):
    """``model.pole_start.block_params``: a ``ModelParams`` with ``vals``' a_i, b_i, c_i (range-checked)."""
    return block_params(base_doc, vals)


def reversal_x(params_list, replays, settings: CurvesSettings) -> np.ndarray:
    """The model's mirrored X at each replay's reversal, per parameter set: array (n_sets, n_replays), NaN if failed.

    A replay of one piece starts reversed: the mirrored X of its start fabric.
    One that shears forward first (pieces of two signs) is integrated over that
    first piece (``model.pole_start.forward_history``, pole out of reach), all
    sets and replays in one ``simulate_batch`` call.
    """
    out = np.full((len(params_list), len(replays)), np.nan)
    jobs = []
    for j, r in enumerate(replays):
        if len(r.pieces) == 1:
            out[:, j] = mirrored_x(r.A0[1], r.pieces[0][0])
        else:
            jobs.append(j)
    if not jobs or not params_list:
        return out
    P, H, A0, T, where = [], [], [], [], []
    for i, p in enumerate(params_list):
        for j in jobs:
            sign, length = replays[j].pieces[0]
            P.append(far_pole(p))
            H.append(forward_history(length, sign))
            A0.append(tuple(replays[j].A0))
            T.append(np.array([length]))
            where.append((i, j))
    res = simulate_batch(P, H, model="model1", friction="eq2", A0=A0, t_eval=T, rtol=settings.rtol,
                         atol=settings.atol, fallback_method=settings.method, fallback_rtol=settings.rtol,
                         fallback_atol=settings.atol, fallback_max_steps=settings.max_steps)
    last = res.table.groupby("trajectory")["A_xy"].last()
    for k, (i, j) in enumerate(where):
        if res.errors[k] is None and k in last.index:
            out[i, j] = mirrored_x(float(last.loc[k]), replays[j].pieces[1][0])
    return out


def curves(points, replays, settings: CurvesSettings) -> list:
    """Per point ``(params, delta)``, the list (per replay) of the curve fit's model arrays, or the exception that failed it.

    Each run is integrated with its own pole, ``with_pole(params, X_rev, delta)``; every
    (point, run) is one trajectory of a single batch (``curves_integration.integrate_requests``).
    """
    if not points:
        return []
    xr = reversal_x([p for p, _ in points], replays, settings)
    requests = []
    for j, r in enumerate(replays):
        items = [(with_pole(p, xr[i, j] if np.isfinite(xr[i, j]) else 0.0, d), "model1", "eq2")
                 for i, (p, d) in enumerate(points)]
        requests.append((items, [r], settings))
    got = curves_integration.integrate_requests(requests)
    out = []
    for i in range(len(points)):
        bad = next((j for j in range(len(replays)) if not np.isfinite(xr[i, j])), None)
        if bad is not None:
            out.append(ValueError(f"{replays[bad].label}: the forward part before the reversal failed"))
            continue
        err = next((got[j][i] for j in range(len(replays)) if isinstance(got[j][i], Exception)), None)
        out.append(err if err is not None else [got[j][i][0] for j in range(len(replays))])
    return out


def _objective(replays, base_doc, steady, sigma_mu, settings: CurvesSettings, n_res, keys, scale, fixed):
    """``curves_fit.counted_objective`` over the variant's residuals (the curve fit's, with the steady-state terms)."""
    def evaluate(points):
        out, trials = [None] * len(points), []
        for k, p in enumerate(points):
            vals = {**fixed, **dict(zip(keys, (np.asarray(p) * scale).tolist()))}
            try:
                trials.append((k, vals, _block_params(base_doc, vals)))
            except FAILURES:
                pass
        got = curves([(prm, vals["delta"]) for _, vals, prm in trials], replays, settings)
        for (k, vals, _), c in zip(trials, got):
            if isinstance(c, Exception):
                continue
            r = curves_fit.residual_vector(c, replays, sigma_mu, settings)
            s1, s2 = fits.alpha_model1(steady["X"], *[vals[q] for q in fits.M1_KEYS[:-1]], 1.0)
            r = np.concatenate([r, fits.steady_fabric_residuals(s1, s2, steady, settings.steady_weight)])
            if np.all(np.isfinite(r)):
                out[k] = r
        return out

    return curves_fit.counted_objective(evaluate, n_res, settings.max_evals)


def fit(replays, base_doc: dict, start: dict, steady: dict, sigma_mu: float,
        settings: CurvesSettings, fixed=None) -> fits.FitResult:
    """Least-squares fit of a_i, b_i, c_i and delta (``KEYS``) from ``start``; ``fixed`` holds some at given values.

    ``extra`` holds ``evaluations``, ``failed_evaluations`` and ``residuals`` (the
    normalised data residuals at the best point, for ``profiles.threshold``).
    """
    fixed = dict(fixed or {})
    lo, hi = bounds()
    free = np.array([k not in fixed for k in KEYS])
    keys, scale = tuple(k for k in KEYS if k not in fixed), SCALE[free]
    lo, hi = lo[free] / scale, hi[free] / scale
    n_res = sum(3 * len(r.s) for r in replays) + fits.N_STEADY
    res, workers, state = _objective(replays, base_doc, steady, sigma_mu, settings, n_res, keys, scale, fixed)
    x0 = np.clip(np.array([start[k] for k in keys]) / scale, lo + 1e-9 * np.abs(lo) + 1e-12,
                 hi - 1e-9 * np.abs(hi) - 1e-12)
    try:
        sol = least_squares(res, x0, bounds=(lo, hi), x_scale="jac", diff_step=settings.diff_step,
                            max_nfev=settings.max_evals, workers=workers)
        message = sol.message
    except curves_fit.BudgetExhausted:
        message = f"budget of {settings.max_evals} model evaluations used up; best point kept"
    p = state["best"] if state["best"] is not None else x0
    vals = {**fixed, **dict(zip(keys, (p * scale).tolist()))}
    vals = {k: float(vals[k]) for k in KEYS}
    ok = state["best_cost"] < 0.5 * n_res * curves_fit.PENALTY**2
    c = curves([(_block_params(base_doc, vals), vals["delta"])], replays, settings)[0] if ok else None
    resid = (curves_fit.residual_vector(c, replays, sigma_mu, settings)
             if c is not None and not isinstance(c, Exception) else np.array([]))
    return fits.FitResult("model1_start", vals, float(state["best_cost"]), n_res - fits.N_STEADY,
                          float(np.sqrt(2 * state["best_cost"] / max(n_res, 1))), bool(ok), str(message),
                          {"evaluations": state["n"], "failed_evaluations": state["fails"], "residuals": resid})


def starts(base_doc: dict) -> list:
    """Candidate starting points: every combination of a linear part, a pair (c1, c2) and a delta.

    The linear parts are the set's Model 1 (a_i, b_i) and its Model 2 (Eq. 5 is Eq. 6 with
    a1 = c1, b1 = 0, a2 = c2, b2 = c3); the pole strengths the set's own and ``C_STARTS``
    (with c1 + c2 X_c < 0 the pole repels, so the runs can be integrated up to it); the
    deltas ``DELTA_STARTS`` (the objective has several minima in delta: a near pole with
    small c_i and a far one with large c_i fit alike).
    """
    m1, m2 = base_doc["model1"], base_doc["model2"]
    linear = [(m1["a1"], m1["b1"], m1["a2"], m1["b2"]), (m2["c1"], 0.0, m2["c2"], m2["c3"])]
    strengths = [(m1["c1"], m1["c2"]), *C_STARTS]
    return [dict(a1=a1, b1=b1, c1=c1, a2=a2, b2=b2, c2=c2, delta=d)
            for a1, b1, a2, b2 in linear for c1, c2 in strengths for d in DELTA_STARTS]


def fit_multistart(replays, base_doc, steady, sigma_mu, settings: CurvesSettings,
                   n_fits: int = N_FITS) -> fits.FitResult:
    """``fit`` from the ``n_fits`` best of ``starts`` (all scored in one batch first); the lowest cost.

    The evaluations of all (screen and fits) are summed in ``extra``.
    """
    cands = starts(base_doc)
    ok = [c for c in cands if np.all(np.isfinite(list(c.values())))]
    clipped = []
    lo, hi = bounds()
    for c in ok:
        v = np.clip([c[k] for k in KEYS], lo, hi)
        clipped.append(dict(zip(KEYS, v.tolist())))
    got = curves([(_block_params(base_doc, c), c["delta"]) for c in clipped], replays, settings)
    costs = [float(np.sum(curves_fit.residual_vector(g, replays, sigma_mu, settings) ** 2))
             if not isinstance(g, Exception) else np.inf for g in got]
    order = [i for i in np.argsort(costs) if np.isfinite(costs[i])][:n_fits] or [0]
    results = [fit(replays, base_doc, clipped[i], steady, sigma_mu, settings) for i in order]
    best = min(results, key=lambda r: r.cost)
    best.extra["evaluations"] = len(clipped) + sum(r.extra["evaluations"] for r in results)
    best.extra["starts"] = [(r.values["delta"], r.cost) for r in results]
    return best


def profile_delta(replays, base_doc, fitted: dict, steady, sigma_mu, settings: CurvesSettings, cost_min: float,
                  residuals, n_points: int = PROFILE_POINTS) -> tuple:
    """Profile of delta down to ``DELTA_MIN`` (module Notes): the table and its interval (``profiles.interval``).

    Returns
    -------
    DataFrame
        ``value`` (delta), ``objective``, ``delta`` (objective minus the profile's minimum), ``threshold``,
        ``integrable``, ``evaluations``, ``message``.
    dict
        ``low``, ``high``, ``identified``, ``note`` (``profile_interval``).
    dict, float
        The values and cost at the profile's lowest point: the estimate, when a refit on the
        grid went lower than the fit it started from (a fit that ran out of budget).
    """
    d_hat = fitted["delta"]
    near = [d_hat * (1.0 - f) for f in NEAR[: n_points // 4]] + [d_hat * (1.0 + f) for f in NEAR[: n_points // 4]]
    n_far = max(n_points - len(near), 2)
    down = np.geomspace(DELTA_MIN, max(d_hat * (1.0 - NEAR[-1]), DELTA_MIN), n_far - n_far // 2)[::-1]
    up = np.geomspace(d_hat * (1.0 + NEAR[-1]) * 1.5, DELTA_MAX, n_far // 2)
    grid = np.unique(np.clip(np.concatenate([near, down, up]), DELTA_MIN, DELTA_MAX))
    thr = profiles.threshold(residuals, cost_min, len(KEYS)) if len(residuals) else math.nan
    rows = [dict(value=d_hat, objective=cost_min, integrable=True, evaluations=0, message="optimum", fit=fitted)]
    for side in (grid[grid < d_hat][::-1], grid[grid > d_hat]):   # away from the optimum, warm-started
        start = dict(fitted)
        for d in side:
            r = fit(replays, base_doc, start, steady, sigma_mu, settings, fixed={"delta": float(d)})
            rows.append(dict(value=float(d), objective=r.cost, integrable=bool(r.success),
                             evaluations=r.extra["evaluations"], message=r.message, fit=r.values))
            if r.success:
                start = r.values
    prof = pd.DataFrame(rows)
    prof["delta"] = prof["objective"] - float(prof.loc[prof["integrable"], "objective"].min())
    prof["threshold"] = thr
    prof = prof.sort_values("value").reset_index(drop=True)
    iv = profile_interval(prof)
    best = prof.loc[prof.loc[prof["integrable"], "objective"].idxmin()]
    return (prof[["value", "objective", "delta", "threshold", "integrable", "evaluations", "message"]], iv,
            dict(best["fit"]), float(best["objective"]))


def profile_interval(prof: pd.DataFrame) -> dict:
    r"""The 95 % profile interval of delta from ``profile_delta``'s rows.

    Each end lies between the last grid point inside the threshold and the first
    outside, interpolated linearly in :math:`\sqrt{\Delta C}` (exact for a quadratic
    profile; ``profiles.interval`` interpolates :math:`\Delta C` itself, which on a
    steep profile puts the end next to the inner point). An end with no point outside
    is open: 0 at the low side (the profile reaches ``DELTA_MIN``, the pole at the
    start), ``DELTA_MAX`` or the grid's end at the high side; a neighbour that cannot
    be integrated ends it there.
    """
    v, d = prof["value"].to_numpy(float), prof["delta"].to_numpy(float)
    ok = prof["integrable"].to_numpy(bool)
    thr = float(prof["threshold"].iloc[0])
    inside = ok & (d <= thr)
    if not np.isfinite(thr) or not inside.any():
        return {"low": math.nan, "high": math.nan, "identified": False, "note": "no profile threshold"}
    i0, i1 = int(np.argmax(inside)), int(len(v) - 1 - np.argmax(inside[::-1]))
    notes = []

    def end(i, j, side):
        if j < 0:
            notes.append("profiled down to the start (DELTA_MIN): the lower end is 0")
            return 0.0, False
        if j >= len(v):
            notes.append(f"upper end open at {v[i]:.4g}, the end of the grid")
            return float(v[i]), False
        if not ok[j]:
            notes.append(f"{side} end at {v[j]:.4g}, where no re-fit can be integrated")
            return float(v[j]), False
        si, sj = np.sqrt(max(d[i], 0.0)), np.sqrt(d[j])
        return float(v[i] + (np.sqrt(thr) - si) * (v[j] - v[i]) / (sj - si)), True

    lo, ok_lo = end(i0, i0 - 1, "lower")
    hi, ok_hi = end(i1, i1 + 1, "upper")
    return {"low": lo, "high": hi, "identified": bool(ok_lo and ok_hi), "note": "; ".join(notes)}


def run(case_dirs, params_path, protocols, out_yaml, max_evals: int = CurvesOptions.max_evals,
        profile_points: int = PROFILE_POINTS, log=print) -> dict:
    """Fit the variant on ``case_dirs`` (their ``protocols``) from the set's ``params.yaml``; write it and its profile.

    The friction law is the set's Eq. 2; the start is the set's Model 1 block. Writes
    ``out_yaml`` (format tag ``FORMAT_TAG``: the Model 1 block of Eq. 6 with ``delta`` in
    place of X_c, delta's profile interval, the fit's summary, the X_rev of every run)
    and ``<stem>_profile.csv`` beside it. Returns the document.
    """
    from .problem import pose
    from .settings import Settings

    settings = Settings(protocols=tuple(protocols))
    s2 = dataclasses.replace(settings.curves, max_evals=int(max_evals))
    problem = pose(case_dirs, settings)
    replays, steady, sigma_mu = problem.replays, problem.steady, problem.sigma_mu
    base = load_params(params_path)
    doc = base.to_dict()
    doc.pop("provenance", None)
    doc.pop("intervals", None)
    res = fit_multistart(replays, doc, steady, sigma_mu, s2)
    log(f"pole at start: delta = {res.values['delta']:.4g}, {res.extra['evaluations']} evaluations, {res.message}")
    prof, iv, values, cost = profile_delta(replays, doc, res.values, steady, sigma_mu, s2, res.cost,
                                           res.extra["residuals"], profile_points)
    if cost < res.cost:   # a refit on the profile's grid went lower: it is the estimate
        log(f"pole at start: the profile went lower at delta = {values['delta']:.4g} ({cost:.6g} < {res.cost:.6g})")
        rms = float(np.sqrt(2 * cost / (res.n_data + fits.N_STEADY)))
        res = dataclasses.replace(res, values=values, cost=cost, rms=rms)
    xr = reversal_x([_block_params(doc, res.values)], replays, s2)[0]
    out = {"format": FORMAT_TAG, "version": 1, "params": str(params_path),
           "model1": {k: res.values[k] for k in KEYS},
           "delta_interval": [float(iv["low"]), float(iv["high"])], "delta_identified": bool(iv["identified"]),
           "delta_note": iv["note"], "delta_min": DELTA_MIN,
           "fit": {"cost": res.cost, "rms": res.rms, "success": bool(res.success), "message": res.message,
                   "evaluations": int(res.extra["evaluations"]), "n_data": int(res.n_data)},
           "x_rev": {r.label: float(x) for r, x in zip(replays, xr)}}
    out_yaml = Path(out_yaml)
    out_yaml.parent.mkdir(parents=True, exist_ok=True)
    out_yaml.write_text(yaml.safe_dump(out, sort_keys=False))
    prof.to_csv(out_yaml.with_name(out_yaml.stem + "_profile.csv"), index=False)
    return out


def budget(calibrate_options: list[str]) -> tuple[int, int]:
    """``--max-evals`` and ``--profile-points`` of this fit from ``python -m calibrate``'s options, read by its parser.

    ``--route2-evals`` (calibrate's default when not given) and ``--profile-points`` (this fit's
    ``PROFILE_POINTS`` when not given: the variant's one profile is cheaper than calibrate's).
    """
    from .__main__ import parser as calibrate_parser

    ap = calibrate_parser()
    ap.set_defaults(profile_points=PROFILE_POINTS)
    a = ap.parse_args(["--dem", "-", "--out", "-", *calibrate_options])
    return a.route2_evals, a.profile_points


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m calibrate.pole_start_fit", description=__doc__.split("\n\n")[0])
    ap.add_argument("--dem", nargs="+", required=True, help="DEM case directories the set is calibrated on")
    ap.add_argument("--params", required=True, help="the set's params.yaml (its Eq. 2 and Model 1 start)")
    ap.add_argument("--protocols", nargs="+", default=list(Settings.protocols))
    ap.add_argument("--max-evals", type=int, default=CurvesOptions.max_evals, help="model evaluations per fit")
    ap.add_argument("--profile-points", type=int, default=PROFILE_POINTS)
    ap.add_argument("--out", required=True, help="pole_start.yaml to write (its profile CSV beside it)")
    args = ap.parse_args(argv)
    try:
        run(args.dem, args.params, args.protocols, args.out, args.max_evals, args.profile_points)
    except ValueError as exc:
        print(f"calibrate.pole_start_fit: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
