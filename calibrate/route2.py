r"""Route 2's curves: the DEM runs' replays (``calibrate.dem_replays``) integrated for many parameter sets.

Route 2 fits Model 1 / Model 2 to the DEM curves (the tables' "curves" route; the fit:
``calibrate.curves_fit``). This module integrates the model along every replay for each
parameter set it is given, and schedules those integrations into batches.

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

Scheduler
---------
``Lockstep`` runs jobs (bootstrap replicates, profile points, free-form folds) in
threads and integrates the ``curves`` requests of every waiting job in one batch.
A job joins the lockstep it runs under through the thread it runs in (``curves``
finds it there), so the fits it calls take no argument for it.
"""
from __future__ import annotations

import threading
from dataclasses import asdict, dataclass

import numpy as np

from model import PoleError, simulate
from model.batched import simulate_batch

from .dem_replays import Replay, report_grid, replay_key, signed

INTEGRATORS = ("batched", "loop")
#: What a failed integration or residual raises (a pole, a diverging fabric, no steady state, a step budget).
FAILURES = (PoleError, ValueError, FloatingPointError, RuntimeError)


@dataclass(frozen=True)
class Route2Settings:
    """Route 2's settings: its integration (``method`` to ``max_steps``, ``integrator``; this module) and its fit
    (``diff_step`` to ``xc_margin``; ``calibrate.curves_fit``), one record written to params.yaml."""

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


def replay_run(params, replay: Replay, model: str, friction: str, settings: Route2Settings, cache=None):
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


