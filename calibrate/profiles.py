r"""Profiles of the curves fit's objective: each of X_c and the c_i held on a grid, the other parameters re-fitted.

Method
------
For a parameter :math:`\theta_j` of a model block and a grid value :math:`g`,
the profile is

.. math:: C_p(g) = \min_{\theta_{-j}} C(\theta_j = g, \theta_{-j}),
          \qquad C = \tfrac12 \lVert r \rVert^2,

with :math:`r` the curves fit's normalised residuals (``curves_fit``, module Notes).
Each grid point is one ``curves_fit.fit`` with ``fixed={name: g}`` under a budget
of ``ProfileSettings.evals`` model evaluations, warm-started by continuation:
the grid is walked outwards from the estimate in two chains (below, above),
each point started from its neighbour's re-fit (the full fit for the first).
A point whose every trial meets the pole or diverges is kept as failed
(objective NaN). The chains of every profiled parameter of a model run
together under ``integration_batcher.IntegrationBatcher``: their integrations go into one
``model.batched.simulate_batch`` call per round.

The 95 % profile interval is the set of :math:`g` with

.. math:: C_p(g) - C_{min} \le \Delta = \tfrac12\,\chi^2_{1,\,0.95}\,
          \hat s^2\,\frac{1 + \rho}{1 - \rho},
          \qquad \hat s^2 = \frac{2 C_{min}}{n - p},

the likelihood-ratio threshold with the residual variance estimated from the
fit (the DEM's misfit is larger than its sample noise) and inflated for the
serial correlation of the residuals (lag-1 autocorrelation :math:`\rho`,
AR(1), ``io.ar1_variance_inflation``). Its ends are interpolated linearly
between grid points. An end that no grid point crosses is open: the interval
reaches the edge of the grid (``-inf``/``inf``) or the parameter's bound (the
bound's value; also for a grid that stops short of a finite bound, as Model 1's
log grids of c1 and c2 stop short of 0). A parameter is *identified* when both ends are
finite crossings strictly inside its bounds.

Grids: X_c from its lower bound (``fits.xc_lower_bound``) to ``fits.XC_MAX``;
Model 1's c1 (<= 0) and c2 (>= 0) geometrically from 1/100 to 100 times the
estimate; Model 2's c_i linearly over the estimate +- ``span`` times
max(|estimate|, 1, the width of its bootstrap interval).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np
import pandas as pd
from scipy import stats

from model import params_from_dict

from . import curves_fit, fits, integration_batcher, io

#: The parameters profiled per model block.
PROFILED = {"model1": ("c1", "c2", "X_c"), "model2": ("c1", "c2", "c3")}
FRICTION = {"model1": "eq2", "model2": "quadratic"}
COLUMNS = ["model", "parameter", "value", "objective", "delta", "threshold", "evaluations", "message"]


@dataclass(frozen=True)
class ProfileSettings:
    n_points: int = 20      # grid points per profiled parameter (0: no profiles)
    evals: int = 60         # model evaluations per grid point's re-fit
    level: float = 0.95
    span: float = 1.5       # Model 2 grids: estimate +- span * max(|estimate|, 1)
    decades: float = 2.0    # Model 1 c1, c2 grids: estimate * 10**[-decades, decades]
    models: tuple = ("model1", "model2")   # the blocks profiled

    def as_dict(self) -> dict:
        return {**asdict(self), "models": list(self.models)}


def grid(model: str, name: str, estimate: float, x_lower: float, settings: ProfileSettings,
         width: float = 0.0) -> np.ndarray:
    """The grid of one profiled parameter (module Notes); ``width``: its bootstrap interval's width, if known."""
    n = settings.n_points
    if model == "model1" and name == "X_c":
        return np.linspace(x_lower, fits.XC_MAX, n)
    if model == "model1":
        sign = -1.0 if name == "c1" else 1.0
        mag = max(abs(estimate), 1e-6)
        return sign * mag * np.logspace(-settings.decades, settings.decades, n)
    half = settings.span * max(abs(estimate), 1.0, width if np.isfinite(width) else 0.0)
    return np.linspace(estimate - half, estimate + half, n)


def bounds_of(model: str, name: str, x_lower: float) -> tuple:
    """The search bounds of one parameter of ``curves_fit.fit`` (Model 2: none)."""
    if model == "model1":
        lo, hi = fits.model1_bounds(x_lower)
        k = fits.M1_KEYS.index(name)
        return float(lo[k]), float(hi[k])
    return -math.inf, math.inf


def threshold(data_residuals, cost_min: float, n_free: int, level: float = 0.95) -> float:
    r"""The profile threshold :math:`\Delta` of the module Notes.

    Parameters
    ----------
    data_residuals : array
        The curves fit's normalised data residuals at the optimum, run after run.
    cost_min : float
        :math:`C_{min}`.
    n_free : int
        Fitted parameters :math:`p`.
    """
    r = np.asarray(data_residuals, float)
    s2 = 2.0 * cost_min / max(r.size - n_free, 1)
    return 0.5 * float(stats.chi2.ppf(level, 1)) * s2 * io.ar1_variance_inflation(r)


def profile(problem, base_doc: dict, model: str, fitted: dict, x_lower=None, names=None, widths=None) -> pd.DataFrame:
    """Profiles of ``names`` (default ``PROFILED[model]``) about the curve fit ``fitted``.

    Parameters
    ----------
    problem : calibrate.problem.Problem
        The replays, steady state and friction noise the curve fit ran on; its settings' ``curves`` (the fit's)
        and ``profile`` (the grids and each re-fit's budget, ``ProfileSettings``).
    base_doc : dict
        The parameter document holding the friction laws (the back-solve's).
    model : {"model1", "model2"}
    fitted : dict
        The block's curve-fit values (the optimum, and every re-fit's start).
    x_lower : float, optional
        X_c's lower bound (default ``fits.xc_lower_bound(steady, xc_margin)`` of the curves settings).
    widths : dict, optional
        name -> the width of its bootstrap interval (widens Model 2's grids, ``grid``).

    Returns
    -------
    DataFrame
        ``COLUMNS`` plus the other parameters of the block (their re-fitted
        values); the optimum itself is one row per parameter (message "optimum").
    """
    replays, steady, sigma_mu = problem.replays, problem.steady, problem.sigma_mu
    curves_settings, settings = problem.settings.curves, problem.settings.profile
    names = tuple(names or PROFILED[model])
    xl = fits.xc_lower_bound(steady, curves_settings.xc_margin) if x_lower is None else x_lower
    s = replace(curves_settings, max_evals=settings.evals)
    prm = params_from_dict({**base_doc, model: dict(fitted)})
    resid = curves_fit.residuals(prm, replays, model, FRICTION[model], sigma_mu, curves_settings)
    steady_r = fits.steady_fabric_residuals(*(fits.alpha_model1 if model == "model1" else fits.alpha_model2)(
        steady["X"], *[fitted[k] for k in (fits.M1_KEYS if model == "model1" else fits.M2_KEYS)]),
        steady, curves_settings.steady_weight)
    cost0 = 0.5 * float(np.sum(resid**2) + np.sum(np.asarray(steady_r) ** 2))
    chains = []   # per parameter, the grid below the estimate (downwards) and above it (upwards)
    for name in names:
        g = np.sort(grid(model, name, fitted[name], xl, settings, (widths or {}).get(name, 0.0)))
        chains += [(name, [float(x) for x in g[g < fitted[name]][::-1]]), (name, [float(x) for x in g[g >= fitted[name]]])]

    def walk(batcher, name, values):
        """One chain of re-fits outwards from the optimum, each started from the last that could be integrated."""
        start, out = dict(fitted), []
        for g in values:
            f = curves_fit.fit(replays, base_doc, model, {**start, name: g}, steady, sigma_mu, s, x_lower=xl,
                               fixed={name: g}, batcher=batcher)
            out.append((g, f))
            if f.success:
                start = dict(f.values)
        return out

    jobs = [lambda batcher, c=c: walk(batcher, *c) for c in chains if c[1]]
    done = integration_batcher.run_jobs(jobs, s)
    rows = [{"model": model, "parameter": name, "value": fitted[name], "objective": cost0, "evaluations": 0,
             "message": "optimum", **{f"at_{k}": v for k, v in fitted.items()}} for name in names]
    for (name, _), chain in zip([c for c in chains if c[1]], done):
        for g, f in chain:
            rows.append({"model": model, "parameter": name, "value": g,
                         "objective": f.cost if f.success else math.nan, "evaluations": f.extra["evaluations"],
                         "message": str(f.message) if f.success else
                         "failed: no re-fit could be integrated (a pole or a runaway fabric on every trial)",
                         **{f"at_{k}": v for k, v in f.values.items()}})
    out = pd.DataFrame(rows)
    n_free = len(fitted)
    # the profile's minimum may lie below the fit's (a grid point found a better optimum): use the lowest
    out["threshold"] = threshold(resid, cost0, n_free, settings.level)
    out["delta"] = out["objective"] - out.groupby("parameter")["objective"].transform("min")
    out = out.sort_values(["parameter", "value"], kind="stable").reset_index(drop=True)
    return out[COLUMNS + [c for c in out.columns if c not in COLUMNS]]


#: Why a profile's neighbour cannot be re-fitted, per model: only Model 1 has a pole (Eq. 6).
UNFITTABLE = {"model1": "the pole, not the data",
              "model2": "a set that diverges or cannot shear steadily: the model, not the data"}


def interval(prof: pd.DataFrame, lower: float = -math.inf, upper: float = math.inf, model: str = "model1") -> dict:
    """The profile interval of one parameter's profile rows (module Notes).

    ``model`` names the cause of an end where no re-fit can be integrated (``UNFITTABLE``):
    Model 1's pole, or, for Model 2 (no pole), a set that diverges or cannot shear steadily.

    Returns
    -------
    dict
        ``low``, ``high`` (``-inf``/``inf`` when open at the grid's edge, the
        bound when open at a bound), ``identified`` (bool) and ``note``.
    """
    p = prof.sort_values("value")
    v, d = p["value"].to_numpy(float), p["delta"].to_numpy(float)
    thr = float(p["threshold"].iloc[0])
    inside = np.isfinite(d) & (d <= thr)
    if not inside.any():
        return {"low": math.nan, "high": math.nan, "identified": False, "note": "no grid point below the threshold"}
    i0, i1 = int(np.argmax(inside)), int(len(inside) - 1 - np.argmax(inside[::-1]))
    notes = []

    def end(i, j, bound, side):
        if j < 0 or j >= len(v):   # no crossing on this side of the grid
            at_bound = np.isfinite(bound) and abs(v[i] - bound) <= 1e-6 * max(abs(bound), 1.0)
            if at_bound:
                notes.append(f"{side} end open: reaches the bound {bound:.4g}")
            elif np.isfinite(bound):   # a grid short of a finite bound (Model 1's c1, c2 on a log grid)
                notes.append(f"{side} end open: beyond the grid, towards the bound {bound:.4g}")
            else:
                notes.append(f"{side} end open: beyond the grid")
            return (bound if np.isfinite(bound) else (-math.inf if side == "lower" else math.inf)), False
        if not np.isfinite(d[j]):   # the neighbour cannot be integrated: the model, not the data, ends it
            notes.append(f"{side} end at {v[j]:.4g}, where no re-fit can be integrated "
                         f"({UNFITTABLE.get(model, UNFITTABLE['model2'])})")
            return float(v[j]), False
        dj = d[j]
        return float(v[i] + (thr - d[i]) * (v[j] - v[i]) / (dj - d[i])), True

    lo, ok_lo = end(i0, i0 - 1, lower, "lower")
    hi, ok_hi = end(i1, i1 + 1, upper, "upper")
    if not inside[i0:i1 + 1].all():
        notes.append("profile has several minima below the threshold (interval spans them)")
    return {"low": lo, "high": hi, "identified": bool(ok_lo and ok_hi), "note": "; ".join(notes)}


def intervals(prof: pd.DataFrame, x_lower: float) -> pd.DataFrame:
    """``interval`` of every profiled (model, parameter) of ``prof``."""
    rows = []
    for (model, name), p in prof.groupby(["model", "parameter"], sort=False):
        lo, hi = bounds_of(model, name, x_lower)
        rows.append({"model": model, "parameter": name, **interval(p, lo, hi, model)})
    return pd.DataFrame(rows, columns=["model", "parameter", "low", "high", "identified", "note"])
