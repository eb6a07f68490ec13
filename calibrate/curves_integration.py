r"""The curves route's integrations: the model along every DEM replay, for many parameter sets at once.

The curves route (the tables' ``curves``, once "route 2") fits Model 1 / Model 2 to the DEM
curves (the fit: ``calibrate.curves_fit``) along the runs' replays (``calibrate.dem_replays``).
This module integrates the model along every replay for each parameter set it is given
(``curves``); jobs that run side by side batch their integrations through
``calibrate.integration_batcher``.

Integrator
----------
``CurvesOptions.integrator`` chooses how the runs are integrated:

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

from dataclasses import asdict, dataclass

import numpy as np

from model import PoleError, simulate
from model.batched import simulate_batch

from .dem_replays import Replay, report_grid, replay_key, signed

INTEGRATORS = ("batched", "loop")
#: What a failed integration or residual raises (a pole, a diverging fabric, no steady state, a step budget).
FAILURES = (PoleError, ValueError, FloatingPointError, RuntimeError)


@dataclass(frozen=True)
class CurvesOptions:
    """The curves route's own settings, the home of their defaults: its integration (``method`` to
    ``max_steps``, ``integrator``; this module) and its fit's (``diff_step`` to ``mu_weight``;
    ``calibrate.curves_fit``).

    The fit also weighs the steady state and bounds X_c as the back-solve does: ``CurvesSettings``
    adds those two settings of the whole calibration (``calibrate.settings.Settings.curves`` builds it).
    """

    method: str = "LSODA"   # switches to an implicit method where a trial set makes Eq. 4 stiff
    rtol: float = 1e-6
    atol: float = 1e-9
    max_steps: int = 20000  # per history segment: a trial set past it scores as failed
    diff_step: float = 1e-3
    max_evals: int = 300   # Model 1 on the quick campaign used 150 up before converging
    mu_weight: float = 1.0
    integrator: str = "batched"  # or "loop": model.simulate one run at a time (module Notes)

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"curves route: integrator = {self.integrator!r} is not one of {INTEGRATORS}")


@dataclass(frozen=True, kw_only=True)
class CurvesSettings(CurvesOptions):
    """The curves route's settings (``CurvesOptions``) with the calibration's ``steady_weight`` and ``xc_margin``
    (no default here: ``calibrate.settings.Settings`` is their one home, ``Settings.curves`` builds this record),
    one record written to params.yaml."""

    steady_weight: float
    xc_margin: float

    def as_dict(self) -> dict:
        """The record, in the order released params.yaml files carry (``integrator`` last)."""
        d = asdict(self)
        return {**{k: v for k, v in d.items() if k != "integrator"}, "integrator": d["integrator"]}


def replay_run(params, replay: Replay, model: str, friction: str, settings: CurvesSettings, cache=None):
    """Model a, b and signed friction at the replay's samples, by ``model.simulate``. Raises PoleError / ValueError.

    ``cache`` (a dict) shares one integration between runs with the same
    start, history and samples.
    """
    key = replay_key(replay)
    if cache is not None and key in cache:
        m = cache[key]
    else:
        a0, b0 = replay.A0
        h, t, order = report_grid(replay)
        sim = simulate(params, h, model=model, A0=(a0, b0), method=settings.method, rtol=settings.rtol,
                       atol=settings.atol, friction=friction, t_eval=t, max_steps=settings.max_steps)
        m = np.empty((len(t), 3))
        m[order] = sim[["A_xx", "A_xy", "sigma_xy_over_p"]].to_numpy()
        if cache is not None:
            cache[key] = m
    return signed(m, replay)


def curves(items, replays, settings: CurvesSettings, batcher=None) -> list:
    """Model curves of every replay for many parameter sets, by ``settings.integrator``.

    Parameters
    ----------
    items : list of (params, model, friction) or (params, model, friction, alpha_spline)
        One parameter set each (``ModelParams``), with its model and friction law; an
        ``model.laws.AlphaSpline`` replaces the model's alphas (free-form fit,
        ``calibrate.freeform``; batched integrator only).
    replays : list of Replay
        The runs every set is integrated on.
    settings : CurvesSettings
    batcher : calibrate.integration_batcher.IntegrationBatcher, optional
        The batcher the calling job runs under (batched integrator): the request
        waits there and is integrated in one batch with every other job's
        (``IntegrationBatcher.run``); without one it is integrated at once.

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
            raise ValueError("curves route: free-form alphas (alpha_spline) need integrator = 'batched'")
        out = []
        for prm, model, friction, *_ in items:
            cache = {}
            try:
                out.append([replay_run(prm, r, model, friction, settings, cache) for r in replays])
            except FAILURES as exc:
                out.append(exc)
        return out
    if not items:
        return []
    if batcher is not None:
        return batcher.submit((items, replays, settings))
    return integrate_requests([(items, replays, settings)])[0]


def integrate_requests(requests) -> list:
    """``curves`` of several requests (items, replays, settings; same tolerances) in one ``simulate_batch`` call.

    A trajectory's numbers do not depend on the rest of its batch
    (model/README.md), so each request gets what it would get alone.
    """
    settings = requests[0][2]
    params_list, histories, models, frictions, starts, report_times, splines = [], [], [], [], [], [], []
    plan, n = [], 0   # per request: its first trajectory, run keys, report grids, items, replays; trajectories so far
    for items, replays, _ in requests:
        unique = {}
        for r in replays:
            unique.setdefault(replay_key(r), r)
        keys, runs = list(unique), list(unique.values())
        grids = [report_grid(r) for r in runs]
        for prm, model, friction, *spline in items:
            splines += [spline[0] if spline else None] * len(runs)
            params_list += [prm] * len(runs)
            models += [model] * len(runs)
            frictions += [friction] * len(runs)
            histories += [g[0] for g in grids]
            report_times += [g[1] for g in grids]
            starts += [tuple(r.A0) for r in runs]
        plan.append((n, keys, grids, len(items), replays))
        n += len(items) * len(runs)
    res = simulate_batch(params_list, histories, model=models, friction=frictions, A0=starts, t_eval=report_times,
                         rtol=settings.rtol, atol=settings.atol,
                         fallback_method=settings.method, fallback_rtol=settings.rtol, fallback_atol=settings.atol,
                         fallback_max_steps=settings.max_steps, alpha_spline=splines)
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
            out.append([signed(by_key[replay_key(r)], r) for r in replays])
        outs.append(out)
    return outs

