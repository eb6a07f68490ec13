"""The calibration from DEM case directories to ``results/calibration/`` (what the command line runs)."""
from __future__ import annotations

import datetime
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import fabric_angle_deg, fabric_norm
from model import default_params, params_from_dict, steady_state

from . import (backsolve_fit, bootstrap, curves_fit, dem_replays, fits, freeform, identifiability, io, profiles,
               curves_integration, shear_stability, smoothing, tables)
from .settings import Settings

BLOCKS = ("friction_eq2", "friction_quadratic", "model1", "model2")
#: Fewest seeds per ensemble for bootstrap intervals worth the name; below it the calibration warns.
MIN_SEEDS = 3
SCORES = ("score", "rms_A_norm", "rms_theta_A", "rms_mu")


def _route2_start(replays, doc, model, r1_values, steady, sigma_mu, s2, xc_margin):
    """First start with a finite score that can shear steadily: the route-1 values, their linear part, the defaults
    (as they are, with their pole above every run's start, and their linear part: the defaults' pole can sit
    where a run starts, and a set that cannot be integrated is no start)."""
    cands = [r1_values]
    if model == "model1":
        x_free = fits.xc_lower_bound(steady, xc_margin) + 0.01    # a pole no run's start reaches
        lin = dict(r1_values, c1=-1.0, c2=1.0, X_c=max(r1_values["X_c"], x_free))
        paper = default_params().model1.__dict__
        cands += [lin, paper, dict(paper, X_c=max(paper["X_c"], x_free)),
                  dict(paper, c1=-1.0, c2=1.0, X_c=max(paper["X_c"], x_free))]
    else:
        cands += [default_params().model2.__dict__]
    valid = []
    for c in cands:
        d = dict(doc)
        d[model] = dict(c)
        try:
            valid.append((c, params_from_dict(d)))
        except ValueError:
            continue
    scores = curves_fit.score_many([(prm, model) for _, prm in valid], replays, s2, sigma_mu)   # one batch
    for (c, prm), sc in zip(valid, scores):   # a start that cannot shear steadily would be a flat, failed objective
        if math.isfinite(sc["score"]) and shear_stability.check_block(prm, model)["stable"]:
            return dict(c)
    return dict(r1_values)


def choose_route(heldout: pd.DataFrame, insample: dict) -> str:
    """The default route of a model: route 2 ("curves") unless route 1 predicts held-out seeds *clearly* better.

    The route whose replicates fail to predict fewer held-out runs (a pole, a
    diverging fabric) wins. Otherwise route 2 minimises the prediction error
    itself, so it is the default; the back-solve route wins only if its
    held-out score is lower by more than two standard errors of the paired
    difference over the replicates. Without held-out replicates, the lower
    in-sample score wins.
    """
    if len(heldout):
        wide = heldout.pivot(index="replicate", columns="route", values="score")
        if {"backsolve", "curves"} <= set(wide.columns):
            fails = (~np.isfinite(wide[["backsolve", "curves"]])).sum()
            if fails["backsolve"] != fails["curves"]:
                return "backsolve" if fails["backsolve"] < fails["curves"] else "curves"
            d = (wide["backsolve"] - wide["curves"]).to_numpy()
            d = d[np.isfinite(d)]
            if len(d) > 1:
                return "backsolve" if d.mean() < -2.0 * d.std(ddof=1) / np.sqrt(len(d)) else "curves"
    return "backsolve" if insample["backsolve"] < insample["curves"] else "curves"


def steady_check(doc) -> dict:
    """Steady state implied by each model block of ``doc`` (``model.steady_state``): |A|, theta_A, X or an error."""
    out = {}
    prm = params_from_dict(doc)
    for model in ("model1", "model2"):
        try:
            a, b, X = steady_state(prm, model)
            out[model] = {"A_norm": float(fabric_norm(a, b)), "theta_A": float(fabric_angle_deg(a, b)), "X": float(X)}
        except ValueError as exc:
            out[model] = {"error": str(exc)}
    return out


# --------------------------------------------------------------------------- the steps of ``run``


def read_inputs(case_dirs, settings: Settings) -> list:
    """Step 1, read: the case directories, checked (``io.read_cases``)."""
    return io.read_cases(case_dirs, settings.protocols, settings.min_samples)


def smooth(cases, settings: Settings):
    """Step 2, smooth: the smoothed samples of every run and the ensemble steady state of the pre-shears."""
    return smoothing.smooth_cases(cases, settings.smoothing), io.steady_values(cases)


def fit_friction(samples, steady, settings: Settings) -> dict:
    """Step 3, fit friction: Eq. 2 and the quadratic law to mu(X) (``backsolve_fit.fit_friction``)."""
    return backsolve_fit.fit_friction(samples, steady, settings.backsolve, settings.steady_weight)


def fit_route1(samples, steady, friction: dict, settings: Settings):
    """Step 4, route 1: back-solve and fit both models to alpha(X); the route-1 parameter document.

    Returns
    -------
    r1 : dict
        ``friction`` merged with ``backsolve_fit.fit_coefficients`` (the layout of ``backsolve_fit.fit_blocks``).
    doc1 : dict
        A full parameter document holding every route-1 block (range-checked).
    """
    r1 = dict(friction)
    r1.update(backsolve_fit.fit_coefficients(samples, steady, settings.backsolve, settings.steady_weight,
                                      settings.xc_margin))
    doc1 = default_params().to_dict()
    doc1.pop("provenance", None)
    for b in BLOCKS:
        doc1[b] = r1[b].values
    params_from_dict(doc1, source="route-1 fit")  # range check
    return r1, doc1


def fit_route2(cases, samples, steady, r1, doc1, settings: Settings, log):
    """Step 5, route 2: each model fitted to the DEM curves from its best start.

    Returns
    -------
    replays : list of dem_replays.Replay
    r2 : dict
        model -> ``fits.FitResult``.
    doc2 : dict
        ``doc1`` with the route-2 model blocks.
    """
    t0 = time.time()
    replays = dem_replays.prepare(cases, samples, settings.backsolve)
    r2, doc2 = {}, dict(doc1)
    for model in ("model1", "model2"):
        start = _route2_start(replays, doc1, model, r1[model].values, steady, r1["sigma_mu"], settings.curves,
                              settings.xc_margin)
        r2[model] = curves_fit.fit(replays, doc1, model, start, steady, r1["sigma_mu"], settings.curves)
        doc2[model] = r2[model].values
        log(f"route 2 {model}: {r2[model].extra['evaluations']} evaluations, {r2[model].message} "
            f"({time.time() - t0:.1f} s in route 2)")
    return replays, r2, doc2


def fit_freeform(replays, doc2, steady, r1, out: Path, settings: Settings, log):
    """Step 5b (only with ``settings.freeform``): free-form alphas against Models 1 and 2, ``freeform.csv``.

    Returns the curves for Figs. 3a, 3b (``freeform.curves_for_figure``) and the ``fit_quality.csv`` row of
    the free-form set's shear stability (``shear_stability.check``), or (None, None) when the step is off
    (``freeform.csv`` then says so in one note row).
    """
    if settings.freeform is None:
        tables.write_csv(freeform.not_requested_table(), out / "freeform.csv")
        return None, None
    seeds = sorted({r.case for r in replays})
    if len(seeds) < 2:
        note = f"free-form fit skipped: its cross-validation leaves one seed out and needs 2 or more, got {seeds}"
        log(f"warning: {note}")
        tables.write_csv(freeform.note_table(note), out / "freeform.csv")
        return None, None
    t0 = time.process_time()
    res = freeform.run(replays, doc2, steady, r1["sigma_mu"], settings.curves, settings.freeform, log)
    tables.write_csv(res["table"], out / "freeform.csv")
    log(f"free-form fit done ({time.process_time() - t0:.1f} s CPU)")
    v = shear_stability.check(res["spline"])
    if not v["stable"]:
        log(f"shear stability: freeform curves (free-form alphas) refused: {v['note']}")
    row = {"model": "freeform", "route": "curves", "default": False, "shear_stable": v["stable"],
           "shear_note": v["note"], "fit_message": res["fit"]["message"]}
    br = res["spline"].breaks
    return freeform.curves_for_figure(res, np.linspace(br[0], br[-1], 200)), row


def run_bootstrap(cases, samples, replays, r1, r2, doc1, settings: Settings, log):
    """Step 6, bootstrap over seeds: replicate values, held-out scores and percentile intervals.

    Returns
    -------
    values, heldout, intervals : DataFrame
        ``bootstrap.run``'s two tables and ``bootstrap.intervals`` of the first
        (empty, with its columns, when no replicate succeeded).
    """
    by_name = {c.name: c for c in cases}
    edges = np.append(r1["bins"]["X_lo"].to_numpy(), r1["bins"]["X_hi"].iloc[-1]) if len(r1["bins"]) else None
    values, heldout = bootstrap.run(
        cases, samples, lambda names: io.steady_values([by_name[n] for n in names]), replays,
        {"route1": r1, "route2": r2}, doc1,
        {"backsolve": settings.backsolve, "route2": settings.curves, "steady_weight": settings.steady_weight,
         "xc_margin": settings.xc_margin},
        n_boot=settings.n_boot, seed=settings.seed, boot_evals=settings.boot_evals, log=log, edges=edges)
    iv = bootstrap.intervals(values) if len(values) else pd.DataFrame(
        columns=["route", "block", "parameter", "low", "high"])
    return values, heldout, iv


def identify(replays, r1, r2, doc1, steady, iv, settings: Settings, log):
    """Step 6b, identifiability: profiles of X_c and the c_i, the sensitivity matrix's SVD, the verdict per parameter.

    Returns
    -------
    prof : DataFrame
        ``profiles.profile`` rows of both models (empty with ``profile.n_points = 0``).
    prof_iv : DataFrame
        ``profiles.intervals`` of ``prof``.
    svd, verdict : DataFrame
        ``identifiability.svd_table`` and ``identifiability.verdict`` of both models
        (``sensitivity_svd.csv``, ``identifiability.csv``).
    """
    xl = fits.xc_lower_bound(steady, settings.xc_margin)
    profs, svds, verdicts = [], [], []
    for model in ("model1", "model2"):
        c0 = time.process_time()
        if settings.profile.n_points > 0 and model in settings.profile.models:
            m = iv[(iv["route"] == "curves") & (iv["block"] == model)] if len(iv) else iv
            widths = dict(zip(m["parameter"], m["high"] - m["low"])) if len(m) else {}
            profs.append(profiles.profile(replays, doc1, model, r2[model].values, steady, r1["sigma_mu"],
                                          settings.curves, settings.profile, x_lower=xl, widths=widths))
            log(f"profiles {model}: {profiles.PROFILED[model]} x {settings.profile.n_points} points, "
                f"{time.process_time() - c0:.1f} s CPU")
        S, _, r0 = identifiability.sensitivity(replays, doc1, model, r2[model].values, r1["sigma_mu"],
                                               settings.curves)
        delta = profiles.threshold(r0, 0.5 * float(np.sum(r0**2)), S.shape[1], settings.profile.level)
        svds.append(identifiability.svd_table(S, identifiability.KEYS[model], model, delta))
    prof = pd.concat(profs, ignore_index=True) if profs else pd.DataFrame(columns=profiles.COLUMNS)
    prof_iv = profiles.intervals(prof, xl) if len(prof) else pd.DataFrame(
        columns=["model", "parameter", "low", "high", "identified", "note"])
    for model, svd in zip(("model1", "model2"), svds):
        m = iv[(iv["route"] == "curves") & (iv["block"] == model)] if len(iv) else iv
        boot = {r["parameter"]: (r["low"], r["high"]) for _, r in m.iterrows()}
        bounds = {k: profiles.bounds_of(model, k, xl) for k in identifiability.KEYS[model]}
        verdicts.append(identifiability.verdict(model, r2[model].values, boot, prof_iv[prof_iv["model"] == model],
                                                svd, bounds))
    return prof, prof_iv, pd.concat(svds, ignore_index=True), pd.concat(verdicts, ignore_index=True)


def reported_intervals(iv, values, doc1, doc2, prof_iv, cases) -> pd.DataFrame:
    """Step 6c, honest intervals: the bootstrap's widened to the t interval over seeds, joined with the profile's.

    Every row's ``low``/``high`` is the union of the bootstrap percentile
    interval and the t interval over the seeds of the smallest ensemble
    (``bootstrap.t_widened``); for a profiled route-2 parameter also the
    profile-likelihood interval (``profiles``). ``interval`` names what the row
    reports; ``boot_low``/``boot_high`` keep the percentile interval.
    """
    counts = {}
    for c in cases:
        counts[c.group] = counts.get(c.group, 0) + 1
    n = min(counts.values()) if counts else 0
    est = {}
    for route, doc in (("backsolve", doc1), ("curves", doc2)):
        for block in BLOCKS:
            for k, v in doc[block].items():
                est[(route, block, k)] = v
    out = bootstrap.t_widened(iv, values, est, n)
    base = (f"bootstrap over seeds (percentile) joined with the t interval over {n} seeds" if n >= 2 else
            "bootstrap over seeds (percentile; one seed: no t widening)")
    out["interval"] = base
    for _, p in prof_iv.iterrows():
        m = (out["route"] == "curves") & (out["block"] == p["model"]) & (out["parameter"] == p["parameter"])
        if not m.any() or np.isnan(p["low"]) or np.isnan(p["high"]):
            continue
        out.loc[m, "low"] = np.fmin(out.loc[m, "low"], p["low"])
        out.loc[m, "high"] = np.fmax(out.loc[m, "high"], p["high"])
        out.loc[m, "interval"] = base + " and the profile-likelihood interval"
    return out


def score_routes(replays, heldout, r1, r2, doc1, doc2, settings: Settings):
    """Step 7a: in-sample and held-out scores of both routes of each model, and each model's default route.

    Returns
    -------
    quality : list of dict
        One row per (model, route) of ``fit_quality.csv`` (the steady columns are added by ``compare_steady``).
    default_route : dict
        Block -> the route written to params.yaml.
    """
    sigma_mu = r1["sigma_mu"]
    quality, default_route = [], {"friction_eq2": "mu_vs_X", "friction_quadratic": "mu_vs_X"}
    n_used = int(r1["bins"].loc[r1["bins"]["used"], "n_samples"].sum())  # samples in the bins route 1 fits
    pairs = [(model, route, doc) for model in ("model1", "model2") for route, doc in (("backsolve", doc1), ("curves", doc2))]
    ins_all = dict(zip([(m, r) for m, r, _ in pairs], curves_fit.score_many(
        [(params_from_dict(doc), model) for model, _, doc in pairs], replays, settings.curves, sigma_mu)))
    for model in ("model1", "model2"):
        ins_scores = {}
        for route, doc in (("backsolve", doc1), ("curves", doc2)):
            ins = ins_all[(model, route)]
            ins_scores[route] = ins["score"]
            h = heldout[(heldout["route"] == route) & (heldout["model"] == model)] if len(heldout) else heldout
            fr = (r1[model] if route == "backsolve" else r2[model])
            quality.append({"model": model, "route": route,
                            **{f"insample_{k}": ins[k] if np.isfinite(ins[k]) else math.nan for k in SCORES},
                            **heldout_means(h), "fit_cost": fr.cost, "fit_message": fr.message,
                            "n_samples": n_used if route == "backsolve" else fr.n_data // 3,
                            "n_bins": int(r1["bins"]["used"].sum()) if route == "backsolve" else math.nan,
                            "score_note": score_note(ins, h)})
        default_route[model] = choose_route(heldout[heldout["model"] == model] if len(heldout) else heldout,
                                            ins_scores)
    for q in quality:
        q["default"] = default_route[q["model"]] == q["route"]
    return quality, default_route


class UnstableFit(ValueError):
    """Every route of a model fitted a set that cannot shear steadily: the calibration refuses it."""


def guard_shear_stability(quality, default_route, doc1, doc2, log) -> dict:
    """Step 7a': every fitted Model 1 and Model 2 set must shear steadily (``shear_stability.check``).

    Each row of ``quality`` gets ``shear_stable`` and ``shear_note`` (the failures in
    words), every failing set is named in the log, and a model's default route moves
    to the other route when its own set fails and the other's passes.

    Returns
    -------
    dict
        The default routes, after the guard.

    Raises
    ------
    UnstableFit
        Both routes of a model fitted sets that cannot shear steadily.
    """
    default_route = dict(default_route)
    verdicts = {}
    for q in quality:
        doc = doc1 if q["route"] == "backsolve" else doc2
        v = shear_stability.check_block(doc, q["model"])
        verdicts[(q["model"], q["route"])] = v
        q["shear_stable"], q["shear_note"] = v["stable"], v["note"]
        if not v["stable"]:
            log(f"shear stability: {q['model']} {q['route']} ({tables.ROUTE_NAMES[q['route']]}) refused: {v['note']}")
    for model in ("model1", "model2"):
        ok = [route for route in ("backsolve", "curves") if verdicts[(model, route)]["stable"]]
        if not ok:
            raise UnstableFit(f"{model}: no fitted set can shear steadily (backsolve: "
                              f"{verdicts[(model, 'backsolve')]['note']}; curves: {verdicts[(model, 'curves')]['note']}); "
                              f"the calibration refuses them")
        if default_route[model] not in ok:
            log(f"shear stability: {model} default route {default_route[model]} -> {ok[0]}")
            default_route[model] = ok[0]
    for q in quality:
        q["default"] = default_route[q["model"]] == q["route"]
    return default_route


def heldout_means(h: pd.DataFrame) -> dict:
    """Held-out columns of one (model, route): means over the replicates whose held-out runs could be integrated.

    ``heldout_replicates`` counts the replicates that held a seed out,
    ``heldout_failed`` those whose parameters could not be integrated on it
    (their scores are ``inf`` in ``bootstrap.run``'s table): they are left out
    of the means, which are NaN when no replicate is left (``score_note`` says why).
    """
    ok = h[np.isfinite(h["score"])] if len(h) else h
    out = {f"heldout_{k}": float(ok[k].mean()) if len(ok) else math.nan for k in SCORES}
    out.update(heldout_replicates=len(h), heldout_failed=len(h) - len(ok))
    return out


def score_note(ins: dict, h: pd.DataFrame) -> str:
    """Why a score of ``fit_quality.csv`` is NaN, or rests on fewer replicates than drawn ("" if neither)."""
    notes = []
    if not np.isfinite(ins["score"]):
        notes.append(f"in-sample scores NaN: the fitted parameters cannot be integrated on the calibration runs "
                     f"({ins.get('failure', '')})")
    if not len(h):
        notes.append("held-out scores NaN: no bootstrap replicate held a seed out (one seed per ensemble, "
                     "or no replicates)")
    else:
        failed = h[~np.isfinite(h["score"])]
        if len(failed) == len(h):
            notes.append(f"held-out scores NaN: no replicate's parameters could be integrated on its held-out "
                         f"runs ({failed['failure'].iloc[0]})")
        elif len(failed):
            notes.append(f"held-out scores average {len(h) - len(failed)} of {len(h)} replicates: the other "
                         f"{len(failed)} could not be integrated on their held-out runs ({failed['failure'].iloc[0]})")
    return "; ".join(notes)


def seed_warning(cases) -> str:
    """A warning when an ensemble has fewer than ``MIN_SEEDS`` seeds ("" otherwise).

    The bootstrap resamples seeds: with one seed every replicate is the same
    and the intervals have zero width; with two they take three values.
    """
    counts = {}
    for c in cases:
        counts[c.group] = counts.get(c.group, 0) + 1
    few = {g: n for g, n in sorted(counts.items()) if n < MIN_SEEDS}
    if not few:
        return ""
    listed = ", ".join(f"{g} ({n} seed{'s' if n > 1 else ''})" for g, n in few.items())
    return (f"bootstrap intervals rest on fewer than {MIN_SEEDS} seeds per ensemble: {listed}; they understate "
            f"the uncertainty (zero width with one seed)")


def final_document(doc1, doc2, default_route) -> dict:
    """Step 7b: the parameter document of each model's default route (friction laws from route 1)."""
    final = dict(doc1)
    for model in ("model1", "model2"):
        final[model] = (doc1 if default_route[model] == "backsolve" else doc2)[model]
    return final


def xc_lower_bounds(r1, steady, settings: Settings) -> dict:
    """The lower bound of Model 1's X_c each route fitted under."""
    return {"backsolve": r1["model1"].extra["X_c_lower_bound"],
            "curves": fits.xc_lower_bound(steady, settings.xc_margin)}


def compare_steady(quality, final, doc1, doc2, steady, xc_bound) -> None:
    """Step 7c: add to each model row of ``quality`` its steady state against the DEM's, and Model 1's pole checks."""
    for q in quality:
        doc = dict(final)
        doc[q["model"]] = (doc1 if q["route"] == "backsolve" else doc2)[q["model"]]
        s = steady_check(doc)[q["model"]]
        q.update({f"steady_{k}": v for k, v in s.items() if k != "error"})
        q["dem_steady_A_norm"], q["dem_steady_theta_A"], q["dem_steady_X"] = steady["A_norm"], steady["theta_A"], steady["X"]
        q.update(steady_angle_flag(steady["theta_A"]))
        if q["model"] == "model1":
            q["X_c"] = doc["model1"]["X_c"]
            q["mirrored_steady_X_below_X_c"] = bool("X" in s and -s["X"] < doc["model1"]["X_c"])
            q["dem_X_reversal_max"] = steady["X_reversal_max"]
            q["dem_X_reversal_bound"] = steady["X_reversal_bound"]
            q["X_c_lower_bound"] = xc_bound[q["route"]]
            q["X_c_at_lower_bound"] = bool(q["X_c"] <= q["X_c_lower_bound"] * (1 + 1e-6))


#: Largest steady theta_A (degrees, positive shear) Eq. 4 can reach with alpha2 < 0 (docs/model.md, "Steady state").
STEADY_THETA_LIMIT = 135.0


def steady_angle_flag(dem_theta: float) -> dict:
    r"""Whether the DEM's steady angle lies where no stable steady state of Eq. 4 can be.

    A stable steady state of Eq. 4 (:math:`\alpha_2 < 0`) with :math:`X_{ss} < 0`
    has :math:`a = \alpha_1/(2 + \alpha_2^2) < 0`, so for positive shear
    :math:`90^\circ < \theta_A \le 135^\circ` (docs/model.md). A DEM steady
    angle above 135 degrees (a cell biased by its walls) cannot be fitted: the
    fit trades the steady angle against the transients. Said here rather than
    hidden in the scores.

    Parameters
    ----------
    dem_theta : float
        The DEM's steady theta_A for positive shear, degrees (``io.steady_values``).

    Returns
    -------
    dict
        ``steady_theta_above_135`` (bool) and ``steady_note`` (the explanation, "" if below).
    """
    above = bool(dem_theta > STEADY_THETA_LIMIT)
    note = (f"the DEM's steady theta_A = {dem_theta:.1f} deg is above {STEADY_THETA_LIMIT:.0f} deg, where Eq. 4 "
            f"with alpha2 < 0 has no steady state: the models' steady angle cannot match it and the fit trades "
            f"it against the transients" if above else "")
    return {"steady_theta_above_135": above, "steady_note": note}


def friction_quality(r1) -> list:
    """Step 7d: the ``fit_quality.csv`` rows of the two friction laws."""
    return [{"model": name, "route": "mu_vs_X", "insample_rms_mu": r1[name].rms, "fit_cost": r1[name].cost,
             "fit_message": r1[name].message, "default": True, "n_samples": r1[name].n_data}
            for name in ("friction_eq2", "friction_quadratic")]


def parameter_table(doc1, doc2, iv, default_route, xc_bound) -> pd.DataFrame:
    """Step 8a: ``params_table.csv``: every route's values with intervals, defaults and constraint notes."""
    fitted = {("mu_vs_X", "friction_eq2"): doc1["friction_eq2"],
              ("mu_vs_X", "friction_quadratic"): doc1["friction_quadratic"],
              ("backsolve", "model1"): doc1["model1"], ("curves", "model1"): doc2["model1"],
              ("backsolve", "model2"): doc1["model2"], ("curves", "model2"): doc2["model2"]}
    bounds = {(route, block, name): b for (block, name), b in fits.SIGN_BOUNDS.items()
              for route in ("mu_vs_X", "backsolve", "curves")}
    bounds.update({(route, "model1", "X_c"): (xb, fits.XC_MAX) for route, xb in xc_bound.items()})
    return tables.params_table(fitted, iv, default_route, bounds)


def default_intervals(ptab) -> dict:
    """Step 8b: the intervals of the default rows, as params.yaml's ``intervals`` block."""
    intervals = {}
    for _, row in ptab[ptab["default"]].iterrows():
        if not (np.isfinite(row["low"]) and np.isfinite(row["high"])):
            continue   # an interval open to infinity: the data do not bound it (identifiability.csv)
        intervals.setdefault(row["block"], {})[row["parameter"]] = [float(row["low"]), float(row["high"])]
    return intervals


def provenance(cases, default_route, steady, settings: Settings, argv) -> dict:
    """Step 8c: params.yaml's ``provenance`` block (inputs, command, settings, date)."""
    return {
        "source": "calibrate (python -m calibrate)",
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": " ".join(argv) if argv else None,
        "cases": [str(c.path) for c in cases],
        "groups": sorted({c.group for c in cases}),
        "seeds": [c.seed for c in cases],
        "default_route": default_route,
        "routes": dict(tables.ROUTE_NAMES),
        "intervals": f"bootstrap over seeds, {settings.n_boot} replicates, 2.5-97.5 percentiles, joined with the "
                     f"t interval over seeds and, for route 2's profiled parameters, the profile-likelihood "
                     f"interval (params_table.csv, column 'interval'); only finite intervals are listed",
        "dem_steady_state": steady,
        "settings": settings.as_dict(),
        "synthetic_input": any(c.preshear.meta.get("synthetic") for c in cases),
    }


def write_tables(out: Path, final, ptab, btab, quality, heldout, values) -> None:
    """Step 9, write: params.yaml and the CSV tables under ``out``."""
    tables.write_params(final, out / "params.yaml")
    tables.write_csv(ptab, out / "params_table.csv")
    tables.write_csv(btab, out / "backsolve_alpha_vs_X.csv")
    tables.write_csv(pd.DataFrame(quality), out / "fit_quality.csv")
    if len(heldout):  # a failed replicate: NaN scores, the reason in 'failure'
        tables.write_csv(heldout.replace([np.inf, -np.inf], np.nan), out / "heldout_scores.csv")
    else:  # no replicate held a seed out (one seed): the header alone
        tables.write_csv(pd.DataFrame(columns=bootstrap.HELDOUT_COLUMNS), out / "heldout_scores.csv")
    tables.write_csv(values, out / "bootstrap_values.csv")


def write_identifiability(out: Path, prof, svd, verdict) -> None:
    """Step 9b: profiles.csv, sensitivity_svd.csv and identifiability.csv under ``out``."""
    tables.write_csv(prof, out / "profiles.csv")
    tables.write_csv(svd, out / "sensitivity_svd.csv")
    tables.write_csv(verdict, out / "identifiability.csv")


def write_figures(out: Path, samples, replays, btab, doc1, doc2, final, default_route, settings: Settings,
                  log, free=None, profile_tables=None) -> None:
    """Step 10: Fig. 2a, 2b, 3a, 3b, the default routes' curves against the DEM's and the profiles."""
    from . import figures   # matplotlib only where a figure is drawn: the pre-flight's options check imports this package
    X, mu = backsolve_fit.friction_data(samples, settings.backsolve)
    figures.fig2a(samples, out / "fig2a_stress_vs_Axy.png")
    figures.fig2b(X, mu, doc1["friction_eq2"], doc1["friction_quadratic"], out / "fig2b_mu_vs_X.png")
    m1 = {"back-solve": doc1["model1"], "curves": doc2["model1"]}
    m2 = {"back-solve": doc1["model2"], "curves": doc2["model2"]}
    figures.fig3(btab, 1, m1, m2, out / "fig3a_alpha1_vs_X.png", free)
    figures.fig3(btab, 2, m1, m2, out / "fig3b_alpha2_vs_X.png", free)
    preds = {}
    prm = params_from_dict(final)
    for model in ("model1", "model2"):
        fr = "eq2" if model == "model1" else "quadratic"
        try:
            preds[f"{model} ({default_route[model]})"] = {
                r.label: curves_integration.replay_run(prm, r, model, fr, settings.curves) for r in replays}
        except (ValueError, RuntimeError) as exc:
            log(f"figure: {model} cannot be integrated ({exc})")
    figures.fig_curves(replays, preds, out / "fig_curves_model_vs_dem.png")
    if profile_tables is not None:
        figures.fig_profiles(*profile_tables, out / "fig_profiles.png")


def run(case_dirs, out, settings: Settings = Settings(), log=print, argv=None) -> dict:
    """Calibrate on ``case_dirs`` and write every output under ``out``. Returns a summary dict.

    The steps, each a function above: read, smooth, fit friction, route 1,
    route 2, bootstrap, scores and default routes, tables, write, figures.
    """
    t0 = time.time()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    cases = read_inputs(case_dirs, settings)
    log(f"read {len(cases)} case(s): {', '.join(c.name for c in cases)}")
    warning = seed_warning(cases)
    if warning:
        log(f"warning: {warning}")
    samples, steady = smooth(cases, settings)
    friction = fit_friction(samples, steady, settings)
    r1, doc1 = fit_route1(samples, steady, friction, settings)
    log(f"route 1 done ({time.time() - t0:.1f} s): {int(r1['bins']['used'].sum())} of {len(r1['bins'])} bins used")
    replays, r2, doc2 = fit_route2(cases, samples, steady, r1, doc1, settings, log)
    free, free_row = fit_freeform(replays, doc2, steady, r1, out, settings, log)
    values, heldout, iv = run_bootstrap(cases, samples, replays, r1, r2, doc1, settings, log)
    log(f"bootstrap done ({time.time() - t0:.1f} s)")
    prof, prof_iv, svd, verdict = identify(replays, r1, r2, doc1, steady, iv, settings, log)
    log(f"identifiability done ({time.time() - t0:.1f} s)")
    iv = reported_intervals(iv, values, doc1, doc2, prof_iv, cases)
    quality, default_route = score_routes(replays, heldout, r1, r2, doc1, doc2, settings)
    default_route = guard_shear_stability(quality, default_route, doc1, doc2, log)
    final = final_document(doc1, doc2, default_route)
    xc_bound = xc_lower_bounds(r1, steady, settings)
    compare_steady(quality, final, doc1, doc2, steady, xc_bound)
    quality += friction_quality(r1) + ([free_row] if free_row else [])
    for q in quality:
        q["warning"] = warning
    ptab = parameter_table(doc1, doc2, iv, default_route, xc_bound)
    final["intervals"] = default_intervals(ptab)
    final["provenance"] = provenance(cases, default_route, steady, settings, argv)
    btab = tables.bins_table(r1["bins"], iv)
    write_tables(out, final, ptab, btab, quality, heldout, values)
    write_identifiability(out, prof, svd, verdict)
    if settings.figures:
        write_figures(out, samples, replays, btab, doc1, doc2, final, default_route, settings, log, free,
                      profile_tables=(prof, prof_iv))
    log(f"wrote {out} ({time.time() - t0:.1f} s); default routes: {default_route}")
    return {"default_route": default_route, "params": final, "route1": r1, "route2": r2, "intervals": iv,
            "quality": pd.DataFrame(quality), "steady": steady, "steady_check": steady_check(final),
            "profiles": prof, "profile_intervals": prof_iv, "svd": svd, "identifiability": verdict,
            "elapsed": time.time() - t0}
