"""Which route each model defaults to, and why: step 7 of ``pipeline.run``, the rows of ``fit_quality.csv``.

Both routes of each model (``backsolve``, ``curves``) are scored in sample and
on held-out seeds (``score_routes``); the default is the curve fit unless the
back-solve predicts clearly better (``choose_route``), and never a set that
cannot shear steadily (``guard_shear_stability``); each row then states its
steady state against the DEM's (``compare_steady``). ``choose`` chains them.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from dem_contract import fabric_angle_deg, fabric_norm
from model import params_from_dict, steady_state

from . import curves_fit, shear_stability, tables
from .results import MODELS, RouteChoice

SCORES = ("score", "rms_A_norm", "rms_theta_A", "rms_mu")


def choose(problem, backsolve, curves, boot, log) -> RouteChoice:
    """Step 7: score both routes of each model, choose each model's default route, guard it, compare steady states.

    Parameters
    ----------
    problem : calibrate.problem.Problem
    backsolve, curves : results.BacksolveFit, results.CurvesFit
    boot : results.Bootstrap
        Its held-out scores.
    log : callable

    Returns
    -------
    RouteChoice
        The ``fit_quality.csv`` rows of both routes of each model (``score_routes``, ``guard_shear_stability``,
        ``compare_steady``) then of the friction laws (``friction_quality``); the default routes; their document.
    """
    quality, default_route = score_routes(problem, backsolve, curves, boot.heldout)
    default_route = guard_shear_stability(quality, default_route, backsolve.doc, curves.doc, log)
    final = final_document(backsolve.doc, curves.doc, default_route)
    compare_steady(quality, final, backsolve, curves, problem.steady)
    return RouteChoice(tuple(quality + friction_quality(backsolve)), default_route, final)


def choose_route(heldout: pd.DataFrame, insample: dict) -> str:
    """The default route of a model: ``curves`` unless ``backsolve`` predicts held-out seeds *clearly* better.

    The route whose replicates fail to predict fewer held-out runs (a pole, a
    diverging fabric) wins. Otherwise the curve fit minimises the prediction error
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


def score_routes(problem, backsolve, curves, heldout: pd.DataFrame):
    """Step 7a: in-sample and held-out scores of both routes of each model, and each model's default route.

    The in-sample scores are ``curves_fit.score_many``'s on ``problem.replays``, the held-out ones the means of
    ``heldout`` (``bootstrap.run``'s table, ``heldout_means``); the default route is ``choose_route``'s.

    Returns
    -------
    quality : list of dict
        One row per (model, route) of ``fit_quality.csv`` (the steady columns are added by ``compare_steady``).
    default_route : dict
        Block -> the route written to params.yaml.
    """
    routes = {"backsolve": backsolve, "curves": curves}
    quality, default_route = [], {"friction_eq2": "mu_vs_X", "friction_quadratic": "mu_vs_X"}
    bins = backsolve.bins
    n_used = int(bins.loc[bins["used"], "n_samples"].sum())  # samples in the bins the back-solve fits
    pairs = [(model, route) for model in MODELS for route in routes]
    ins_all = dict(zip(pairs, curves_fit.score_many(
        [(params_from_dict(routes[route].doc), model) for model, route in pairs], problem.replays,
        problem.settings.curves, problem.sigma_mu)))
    for model in MODELS:
        ins_scores = {}
        for route in routes:
            ins = ins_all[(model, route)]
            ins_scores[route] = ins["score"]
            h = heldout[(heldout["route"] == route) & (heldout["model"] == model)] if len(heldout) else heldout
            fr = routes[route].fits[model]
            quality.append({"model": model, "route": route,
                            **{f"insample_{k}": ins[k] if np.isfinite(ins[k]) else math.nan for k in SCORES},
                            **heldout_means(h), "fit_cost": fr.cost, "fit_message": fr.message,
                            "n_samples": n_used if route == "backsolve" else fr.n_data // 3,
                            "n_bins": int(bins["used"].sum()) if route == "backsolve" else math.nan,
                            "score_note": score_note(ins, h)})
        default_route[model] = choose_route(heldout[heldout["model"] == model] if len(heldout) else heldout,
                                            ins_scores)
    for q in quality:
        q["default"] = default_route[q["model"]] == q["route"]
    return quality, default_route


class UnstableFit(ValueError):
    """Every route of a model fitted a set that cannot shear steadily: the calibration refuses it."""


def guard_shear_stability(quality, default_route, backsolve_doc, curves_doc, log) -> dict:
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
        doc = backsolve_doc if q["route"] == "backsolve" else curves_doc
        v = shear_stability.check_block(doc, q["model"])
        verdicts[(q["model"], q["route"])] = v
        q["shear_stable"], q["shear_note"] = v["stable"], v["note"]
        if not v["stable"]:
            log(f"shear stability: {q['model']} {q['route']} ({tables.ROUTE_NAMES[q['route']]}) refused: {v['note']}")
    for model in MODELS:
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


def final_document(backsolve_doc, curves_doc, default_route) -> dict:
    """Step 7b: the parameter document of each model's default route (friction laws from the back-solve's)."""
    final = dict(backsolve_doc)
    for model in MODELS:
        final[model] = (backsolve_doc if default_route[model] == "backsolve" else curves_doc)[model]
    return final


def xc_lower_bounds(backsolve, curves) -> dict:
    """The lower bound of Model 1's X_c each route fitted under, by route."""
    return {"backsolve": backsolve.x_lower, "curves": curves.x_lower}


def compare_steady(quality, final, backsolve, curves, steady) -> None:
    """Step 7c: add to each model row of ``quality`` its steady state against the DEM's, and Model 1's pole checks."""
    xc_bound = xc_lower_bounds(backsolve, curves)
    for q in quality:
        doc = dict(final)
        doc[q["model"]] = (backsolve if q["route"] == "backsolve" else curves).doc[q["model"]]
        s = steady_check(doc)[q["model"]]
        q.update({f"steady_{k}": v for k, v in s.items() if k != "error"})
        q["dem_steady_A_norm"], q["dem_steady_theta_A"] = steady["A_norm"], steady["theta_A"]
        q["dem_steady_X"] = steady["X"]
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


def friction_quality(backsolve) -> list:
    """Step 7d: the ``fit_quality.csv`` rows of the two friction laws (the back-solve's document carries them)."""
    fitted = backsolve.fits
    return [{"model": name, "route": "mu_vs_X", "insample_rms_mu": fitted[name].rms, "fit_cost": fitted[name].cost,
             "fit_message": fitted[name].message, "default": True, "n_samples": fitted[name].n_data}
            for name in ("friction_eq2", "friction_quadratic")]


def steady_check(doc) -> dict:
    """Steady state implied by each model block of ``doc`` (``model.steady_state``): |A|, theta_A, X or an error."""
    out = {}
    prm = params_from_dict(doc)
    for model in MODELS:
        try:
            a, b, X = steady_state(prm, model)
            out[model] = {"A_norm": float(fabric_norm(a, b)), "theta_A": float(fabric_angle_deg(a, b)), "X": float(X)}
        except ValueError as exc:
            out[model] = {"error": str(exc)}
    return out
