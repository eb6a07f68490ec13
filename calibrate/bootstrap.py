r"""Bootstrap over seeds: parameter intervals and held-out (out-of-bag) prediction scores.

A replicate draws, within each ensemble (group), as many seeds as it has, with
replacement; both routes are refitted on the drawn seeds (route 1 from scratch,
route 2 warm-started from its full-data fit under a smaller budget). The seeds
*not* drawn are held out: each route's replicate parameters predict their runs
(``curves_fit.score``). Intervals are the 2.5 and 97.5 percentiles of the replicate
values; the held-out score of a route is the mean over replicates that held a
seed out.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from model import params_from_dict

from . import backsolve_fit, curves_fit, integration_batcher

BLOCKS = ("friction_eq2", "friction_quadratic", "model1", "model2")


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


def run(cases, samples, steady_fn, replays, full, base_doc, settings, n_boot=20, seed=0, boot_evals=60,
        log=print, edges=None):
    """Bootstrap both routes.

    Parameters
    ----------
    cases : list of io.Case
    samples : DataFrame (``smoothing.smooth_cases``)
    steady_fn : callable(list of case names) -> steady dict
    replays : list of calibrate.dem_replays.Replay
    full : dict
        Full-data results: ``route1`` (dict of FitResult) and ``route2`` (dict model -> FitResult).
    base_doc : dict
        Parameter document with route-1 friction laws.
    settings : dict with ``backsolve``, ``route2``, ``steady_weight``, ``xc_margin``
    n_boot, seed, boot_evals : int
    edges : array, optional
        Bin edges of the full-data back-solve: the bins are re-solved per
        replicate (route "bins", block = the bin's lower edge).

    Returns
    -------
    values : DataFrame, one row per (replicate, route, block, parameter)
    heldout : DataFrame, one row per (replicate, route, model) with the held-out scores
    """
    rng = np.random.default_rng(seed)
    rows, held_rows = [], []
    s2 = replace(settings["route2"], max_evals=boot_evals)
    prepared = []
    for k in range(n_boot):
        drawn, held = draw(cases, rng)
        smp = resample(samples, drawn)
        steady = steady_fn(drawn)
        try:
            r1 = backsolve_fit.fit_blocks(smp, steady, settings["backsolve"], settings["steady_weight"],
                                          settings["xc_margin"], model1_start=full["route1"]["model1"].values)
        except ValueError as exc:
            log(f"bootstrap replicate {k}: route 1 failed ({exc}); replicate skipped")
            continue
        prepared.append((k, smp, r1, drawn, held, steady))

    def replicate(batcher, k, smp, r1, drawn, held, steady):
        doc1, doc2, fitted = _refit(k, smp, r1, drawn, replays, full, base_doc, steady, settings, s2, edges, batcher)
        return fitted, _heldout_scores(k, doc1, doc2, [r for r in replays if r.case in held], r1["sigma_mu"],
                                       settings["route2"], batcher)

    jobs = [lambda batcher, p=p: replicate(batcher, *p) for p in prepared]
    # batched: the replicates' curves fits and scores advance together, their integrations in one batch per round
    done = integration_batcher.run_jobs(jobs, settings["route2"])
    for (k, _, _, drawn, held, _), (fitted, scores) in zip(prepared, done):
        rows += fitted
        held_rows += scores
        log(f"bootstrap replicate {k + 1}/{n_boot}: drawn {len(drawn)} seeds, held out {len(held)}")
    values = pd.DataFrame(rows, columns=["replicate", "route", "block", "parameter", "value"])
    heldout = pd.DataFrame(held_rows)
    return values, heldout


def _refit(k, smp, r1, drawn, replays, full, base_doc, steady, settings, s2, edges, batcher):
    """One replicate's refits: route-1 rows, re-solved bins, route 2 warm-started from the full fit.

    Returns the replicate's route-1 and route-2 parameter documents and its
    ``values`` rows (replicate, route, block, parameter, value).
    """
    rows = [(k, "backsolve", block, name, v) for block in BLOCKS for name, v in r1[block].values.items()]
    if edges is not None:
        from .backsolve import binned
        bb = binned(smp, settings["backsolve"], edges=edges)
        for _, row in bb.iterrows():
            key = f"{row.X_lo:.6g}"
            rows += [(k, "bins", key, "alpha1", row.alpha1), (k, "bins", key, "alpha2", row.alpha2)]
    doc1 = params_doc(base_doc, {b: r1[b].values for b in BLOCKS})
    reps = [r for name in drawn for r in replays if r.case == name]
    doc2 = dict(doc1)
    for model in ("model1", "model2"):
        f = curves_fit.fit(reps, doc1, model, full["route2"][model].values, steady, r1["sigma_mu"], s2,
                           batcher=batcher)
        doc2[model] = f.values
        rows += [(k, "curves", model, name, v) for name, v in f.values.items()]
    return doc1, doc2, rows


#: The first columns of ``heldout_scores.csv`` (the scores follow; the header alone when no replicate held a seed out).
HELDOUT_COLUMNS = ["replicate", "route", "model", "n_heldout_runs"]


def _heldout_scores(k, doc1, doc2, held_reps, sigma_mu, settings_route2, batcher) -> list:
    """Scores of one replicate's routes on its held-out runs (none if every seed was drawn)."""
    out = []
    if not held_reps:
        return out
    keys = [(route, doc, model) for route, doc in (("backsolve", doc1), ("curves", doc2))
            for model in ("model1", "model2")]
    prms = {route: params_from_dict(doc, source=f"bootstrap {k} {route}") for route, doc, _ in keys}
    scores = curves_fit.score_many([(prms[route], model) for route, _, model in keys], held_reps, settings_route2,
                                   sigma_mu, batcher)   # the four (route, model) pairs in one batch
    for (route, _, model), sc in zip(keys, scores):
        out.append({**dict(zip(HELDOUT_COLUMNS, (k, route, model, len(held_reps)))), **sc})
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
