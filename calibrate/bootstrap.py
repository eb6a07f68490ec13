r"""Bootstrap over seeds: parameter intervals and held-out (out-of-bag) prediction scores.

A replicate draws, within each ensemble (group), as many seeds as it has, with
replacement; both routes are refitted on the drawn seeds (the back-solve from scratch,
the curve fit warm-started from its full-data fit under a smaller budget). The seeds
*not* drawn are held out: each route's replicate parameters predict their runs
(``curves_fit.score``). Intervals are the 2.5 and 97.5 percentiles of the replicate
values; the held-out score of a route is the mean over replicates that held a
seed out.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from model import params_from_dict

from . import backsolve_fit, curves_fit, integration_batcher, io
from .backsolve import binned
from .results import BLOCKS, MODELS, Bootstrap


def draw(cases, rng):
    """Drawn case names (with repeats) and held-out case names of one replicate."""
    groups = {}
    for c in cases:
        groups.setdefault(c.group, []).append(c.name)
    drawn = []
    for names in groups.values():
        drawn += list(rng.choice(names, size=len(names), replace=True))
    held = [c.name for c in cases if c.name not in set(drawn)]
    return drawn, held


def resample(samples: pd.DataFrame, drawn) -> pd.DataFrame:
    """Samples of the drawn cases; a case drawn twice enters twice (as distinct pseudo-seeds)."""
    parts = []
    for k, name in enumerate(drawn):
        d = samples[samples["case"] == name].copy()
        d["seed"] = d["seed"].astype(str) + f"#{k}"
        parts.append(d)
    return pd.concat(parts, ignore_index=True)


def params_doc(base: dict, blocks: dict) -> dict:
    doc = dict(base)
    for k, v in blocks.items():
        doc[k] = dict(v)
    return doc


@dataclass(frozen=True, eq=False)
class Replicate:
    """One replicate: its number ``k``, the case names drawn (with repeats) and held out, the drawn cases'
    samples (``resample``) and steady state, and its back-solve (``backsolve_fit.fit_blocks``)."""

    k: int
    drawn: list
    held: list
    samples: pd.DataFrame
    steady: dict
    backsolve: dict


def run(problem, backsolve, curves, log=print) -> Bootstrap:
    """Step 6, the bootstrap over seeds: both routes refitted per replicate, their held-out scores (module Notes).

    Parameters
    ----------
    problem : calibrate.problem.Problem
        Its cases are drawn from: ``settings.n_boot`` replicates from ``settings.seed``, each curve fit under
        ``settings.boot_evals`` model evaluations.
    backsolve : results.BacksolveFit
        The full-data back-solve: each replicate's Model 1 start, and the bins every replicate re-solves
        (route "bins", block = the bin's lower edge).
    curves : results.CurvesFit
        The full-data curve fit: each replicate's start.

    Returns
    -------
    results.Bootstrap
        ``values``, one row per (replicate, route, block, parameter); ``heldout``, one row per (replicate,
        route, model) with the held-out scores; their percentile ``intervals``.
    """
    settings = problem.settings
    rng = np.random.default_rng(settings.seed)
    by_name = {c.name: c for c in problem.cases}
    bins = backsolve.bins
    edges = np.append(bins["X_lo"].to_numpy(), bins["X_hi"].iloc[-1]) if len(bins) else None
    rows, held_rows, prepared = [], [], []
    for k in range(settings.n_boot):
        drawn, held = draw(problem.cases, rng)
        smp = resample(problem.samples, drawn)
        steady = io.steady_values([by_name[n] for n in drawn])
        try:
            solved = backsolve_fit.fit_blocks(smp, steady, settings.backsolve, settings.steady_weight,
                                              settings.xc_margin, model1_start=backsolve.fits["model1"].values)
        except ValueError as exc:
            log(f"bootstrap replicate {k}: back-solve failed ({exc}); replicate skipped")
            continue
        prepared.append(Replicate(k, drawn, held, smp, steady, solved))

    def replicate(batcher, rep):
        docs, fitted = refit(problem, rep, curves, edges, batcher)
        return fitted, heldout_scores(problem, rep, docs, batcher)

    jobs = [lambda batcher, rep=rep: replicate(batcher, rep) for rep in prepared]
    # batched: the replicates' curve fits and scores advance together, their integrations in one batch per round
    done = integration_batcher.run_jobs(jobs, settings.curves)
    for rep, (fitted, scores) in zip(prepared, done):
        rows += fitted
        held_rows += scores
        log(f"bootstrap replicate {rep.k + 1}/{settings.n_boot}: drawn {len(rep.drawn)} seeds, "
            f"held out {len(rep.held)}")
    values = pd.DataFrame(rows, columns=["replicate", "route", "block", "parameter", "value"])
    iv = intervals(values) if len(values) else pd.DataFrame(columns=["route", "block", "parameter", "low", "high"])
    return Bootstrap(values, pd.DataFrame(held_rows), iv)


def refit(problem, rep: Replicate, curves, edges, batcher) -> tuple:
    """One replicate's refits: back-solve rows, re-solved bins, the curve fit warm-started from the full fit.

    Returns the replicate's parameter documents (route -> document: ``backsolve``, ``curves``)
    and its ``values`` rows (replicate, route, block, parameter, value).
    """
    settings, k, solved = problem.settings, rep.k, rep.backsolve
    rows = [(k, "backsolve", block, name, v) for block in BLOCKS for name, v in solved[block].values.items()]
    if edges is not None:
        bb = binned(rep.samples, settings.backsolve, edges=edges)
        for _, row in bb.iterrows():
            key = f"{row.X_lo:.6g}"
            rows += [(k, "bins", key, "alpha1", row.alpha1), (k, "bins", key, "alpha2", row.alpha2)]
    backsolve_doc = params_doc(problem.base_doc, {b: solved[b].values for b in BLOCKS})
    reps = [r for name in rep.drawn for r in problem.replays if r.case == name]
    budget = replace(settings.curves, max_evals=settings.boot_evals)
    curves_doc = dict(backsolve_doc)
    for model in MODELS:
        f = curves_fit.fit(reps, backsolve_doc, model, curves.fits[model].values, rep.steady, solved["sigma_mu"],
                           budget, batcher=batcher)
        curves_doc[model] = f.values
        rows += [(k, "curves", model, name, v) for name, v in f.values.items()]
    return {"backsolve": backsolve_doc, "curves": curves_doc}, rows


#: The first columns of ``heldout_scores.csv`` (the scores follow; the header alone when no replicate held a seed out).
HELDOUT_COLUMNS = ["replicate", "route", "model", "n_heldout_runs"]


def heldout_scores(problem, rep: Replicate, docs: dict, batcher) -> list:
    """Scores of one replicate's routes (``docs``: route -> document) on its held-out runs (none if every seed
    was drawn)."""
    held_reps = [r for r in problem.replays if r.case in rep.held]
    out = []
    if not held_reps:
        return out
    keys = [(route, model) for route in docs for model in MODELS]
    prms = {route: params_from_dict(doc, source=f"bootstrap {rep.k} {route}") for route, doc in docs.items()}
    scores = curves_fit.score_many([(prms[route], model) for route, model in keys], held_reps,
                                   problem.settings.curves, rep.backsolve["sigma_mu"], batcher)   # one batch
    for (route, model), sc in zip(keys, scores):
        out.append({**dict(zip(HELDOUT_COLUMNS, (rep.k, route, model, len(held_reps)))), **sc})
    return out


def intervals(values: pd.DataFrame, level=0.95) -> pd.DataFrame:
    """Percentile intervals per (route, block, parameter)."""
    q = (1 - level) / 2
    g = values.groupby(["route", "block", "parameter"])["value"]
    out = g.quantile(q).rename("low").to_frame().join(g.quantile(1 - q).rename("high"))
    out["n_replicates"] = g.count()
    return out.reset_index()


def t_widened(iv: pd.DataFrame, values: pd.DataFrame, estimates: dict, n_seeds: int, level=0.95) -> pd.DataFrame:
    r"""The percentile interval widened to at least the t interval over seeds.

    The percentile interval of a bootstrap over :math:`n` seeds is too narrow
    for small :math:`n` (with 3 seeds, resamples take 10 distinct values and
    the spread of the replicates is :math:`\sqrt{(n-1)/n}` times the standard
    error). As the claims stage does for its means (``shared_stats.mean_interval``),
    the reported interval is the union of the percentile interval and

    .. math:: \hat\theta \pm t_{(1+\text{level})/2,\,n-1}\; s^*\sqrt{n/(n-1)},

    with :math:`s^*` the standard deviation of the replicate values and
    :math:`n` the seeds of the smallest ensemble.

    Parameters
    ----------
    iv : DataFrame
        ``intervals(values)``.
    values : DataFrame
        The replicate values (``run``).
    estimates : dict
        (route, block, parameter) -> the full-data estimate.
    n_seeds : int
        Seeds of the smallest ensemble (no widening below 2).

    Returns
    -------
    DataFrame
        ``iv`` with ``boot_low``, ``boot_high`` (the percentile interval) and
        ``low``, ``high`` replaced by the widened interval.
    """
    from scipy import stats

    out = iv.copy()
    out["boot_low"], out["boot_high"] = out["low"], out["high"]
    if n_seeds < 2 or not len(out):
        return out
    sd = values.groupby(["route", "block", "parameter"])["value"].std(ddof=1)
    t = float(stats.t.ppf(0.5 + level / 2, n_seeds - 1)) * np.sqrt(n_seeds / (n_seeds - 1))
    for i, row in out.iterrows():
        key = (row["route"], row["block"], row["parameter"])
        est, s = estimates.get(key, np.nan), sd.get(key, np.nan)
        if np.isfinite(est) and np.isfinite(s):
            out.loc[i, "low"] = min(row["low"], est - t * s)
            out.loc[i, "high"] = max(row["high"], est + t * s)
    return out
