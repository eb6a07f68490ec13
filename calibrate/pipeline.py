"""The calibration from DEM case directories to ``results/calibration/`` (what the command line runs).

``run`` is the chain: the problem is built once from the inputs (``problem.pose``,
steps 1-2), and each later step takes it and the records of the steps it needs
and returns its own (``calibrate.results``): the Eq. 2 fit, the back-solve, the
curve fit, the free-form bound, the bootstrap, identifiability, the reported
intervals, the route choice, the tables; then the writers.
"""
from __future__ import annotations

import datetime
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from model import default_params, params_from_dict

from . import (backsolve_fit, bootstrap, curves_fit, curves_integration, fits, freeform, identifiability,
               route_choice, shear_stability, tables)
from .problem import Problem, pose, seeds_per_ensemble
from .results import (BLOCKS, MODELS, BacksolveFit, Bootstrap, Calibration, CurvesFit, FreeformBound, FrictionFit,
                      Identifiability, RouteChoice, Tables)
from .settings import Settings


def run(case_dirs, out, settings: Settings = Settings(), log=print, argv=None) -> dict:
    """Calibrate on ``case_dirs`` and write every output under ``out``. Returns a summary dict.

    The steps, each a function of this module or of the module named: read and smooth (``pose``),
    the Eq. 2 fit, the back-solve, the curve fit, the free-form bound, the bootstrap (``bootstrap.run``),
    identifiability (``identifiability.identify``), the reported intervals, the route choice
    (``route_choice.choose``), the tables; then the tables and figures are written.
    """
    t0 = time.time()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    problem = pose(case_dirs, settings, argv)
    log(f"read {len(problem.cases)} case(s): {', '.join(c.name for c in problem.cases)}")
    if problem.warning:
        log(f"warning: {problem.warning}")
    friction = fit_friction(problem)
    backsolve = fit_backsolve(problem, friction)
    log(f"back-solve done ({time.time() - t0:.1f} s): {int(backsolve.bins['used'].sum())} of "
        f"{len(backsolve.bins)} bins used")
    curves = fit_curves(problem, backsolve, log)
    bound = fit_freeform(problem, curves, log)
    boot = bootstrap.run(problem, backsolve, curves, log)
    log(f"bootstrap done ({time.time() - t0:.1f} s)")
    ident = identifiability.identify(problem, backsolve, curves, boot, log)
    log(f"identifiability done ({time.time() - t0:.1f} s)")
    intervals = reported_intervals(problem, backsolve, curves, boot, ident)
    choice = route_choice.choose(problem, backsolve, curves, boot, log)
    outputs = tabulate(problem, backsolve, curves, intervals, choice)
    cal = Calibration(backsolve, curves, bound, boot, ident, intervals, choice, outputs)
    write_tables(out, problem, cal)
    if settings.figures:
        write_figures(out, problem, cal, log)
    log(f"wrote {out} ({time.time() - t0:.1f} s); default routes: {choice.default_route}")
    return summary(problem, cal, time.time() - t0)


# --------------------------------------------------------------------------- the steps of ``run``


def fit_friction(problem: Problem) -> FrictionFit:
    """Step 3, the Eq. 2 fit: Eq. 2 and the quadratic law to mu(X) (``backsolve_fit.fit_friction``)."""
    s = problem.settings
    return FrictionFit(backsolve_fit.fit_friction(problem.samples, problem.steady, problem.sigma_mu, s.backsolve,
                                                  s.steady_weight))


def fit_backsolve(problem: Problem, friction: FrictionFit) -> BacksolveFit:
    """Step 4, the back-solve: alpha(X) back-solved in bins, both models fitted to them; the route's document.

    The bins and the fits are ``backsolve_fit.fit_coefficients``'; the document holds every block of
    ``results.BLOCKS`` over ``problem.base_doc`` (the friction laws are ``friction``'s) and is range-checked.
    """
    s = problem.settings
    coef = backsolve_fit.fit_coefficients(problem.samples, problem.steady, s.backsolve, s.steady_weight, s.xc_margin)
    fitted = {**friction.fits, "model1": coef["model1"], "model2": coef["model2"]}
    doc = dict(problem.base_doc)
    for b in BLOCKS:
        doc[b] = fitted[b].values
    params_from_dict(doc, source="back-solve fit")  # range check
    return BacksolveFit(coef["bins"], fitted, doc)


def curves_start(problem: Problem, backsolve: BacksolveFit, model: str) -> dict:
    """The curve fit's start of ``model``: the first with a finite score that can shear steadily.

    The candidates, in order: the back-solve's values, their linear part, the defaults (as they are, with
    their pole above every run's start, and their linear part: the defaults' pole can sit where a run
    starts, and a set that cannot be integrated is no start); all scored in one batch (``curves_fit.score_many``).
    """
    solved, doc, steady = backsolve.fits[model].values, backsolve.doc, problem.steady
    cands = [solved]
    if model == "model1":
        x_free = fits.xc_lower_bound(steady, problem.settings.xc_margin) + 0.01    # a pole no run's start reaches
        lin = dict(solved, c1=-1.0, c2=1.0, X_c=max(solved["X_c"], x_free))
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
    scores = curves_fit.score_many([(prm, model) for _, prm in valid], problem.replays, problem.settings.curves,
                                   problem.sigma_mu)   # one batch
    for (c, prm), sc in zip(valid, scores):   # a start that cannot shear steadily would be a flat, failed objective
        if math.isfinite(sc["score"]) and shear_stability.check_block(prm, model)["stable"]:
            return dict(c)
    return dict(solved)


def fit_curves(problem: Problem, backsolve: BacksolveFit, log) -> CurvesFit:
    """Step 5, the curve fit: each model fitted to the DEM curves from its best start (``curves_start``,
    ``curves_fit.fit``), with the back-solve's friction laws."""
    t0 = time.time()
    fitted, doc = {}, dict(backsolve.doc)
    for model in MODELS:
        start = curves_start(problem, backsolve, model)
        fitted[model] = curves_fit.fit(problem.replays, backsolve.doc, model, start, problem.steady,
                                       problem.sigma_mu, problem.settings.curves)
        doc[model] = fitted[model].values
        log(f"curves {model}: {fitted[model].extra['evaluations']} evaluations, {fitted[model].message} "
            f"({time.time() - t0:.1f} s in the curve fit)")
    return CurvesFit(fitted, doc, fits.xc_lower_bound(problem.steady, problem.settings.xc_margin))


def fit_freeform(problem: Problem, curves: CurvesFit, log) -> FreeformBound:
    """Step 5b (only with ``settings.freeform``): free-form alphas against Models 1 and 2 (``freeform.run``).

    Returns ``freeform.csv``'s table, the curves for Figs. 3a, 3b (``freeform.curves_for_figure``) and the
    ``fit_quality.csv`` row of the free-form set's shear stability (``shear_stability.check``); without
    the step, or with fewer than two seeds, the table is one note row that says so.
    """
    if problem.settings.freeform is None:
        return FreeformBound(freeform.not_requested_table())
    seeds = sorted({r.case for r in problem.replays})
    if len(seeds) < 2:
        note = f"free-form fit skipped: its cross-validation leaves one seed out and needs 2 or more, got {seeds}"
        log(f"warning: {note}")
        return FreeformBound(freeform.note_table(note))
    t0 = time.process_time()
    res = freeform.run(problem, curves.doc, log)
    log(f"free-form fit done ({time.process_time() - t0:.1f} s CPU)")
    v = shear_stability.check(res["spline"])
    if not v["stable"]:
        log(f"shear stability: freeform curves (free-form alphas) refused: {v['note']}")
    row = {"model": "freeform", "route": "curves", "default": False, "shear_stable": v["stable"],
           "shear_note": v["note"], "fit_message": res["fit"]["message"]}
    br = res["spline"].breaks
    return FreeformBound(res["table"], freeform.curves_for_figure(res, np.linspace(br[0], br[-1], 200)), (row,))


def reported_intervals(problem: Problem, backsolve: BacksolveFit, curves: CurvesFit, boot: Bootstrap,
                       ident: Identifiability) -> pd.DataFrame:
    """Step 6c, honest intervals: the bootstrap's widened to the t interval over seeds, joined with the profile's.

    Every row's ``low``/``high`` is the union of the bootstrap percentile
    interval and the t interval over the seeds of the smallest ensemble
    (``bootstrap.t_widened``); for a profiled parameter of the curve fit also the
    profile-likelihood interval (``profiles``). ``interval`` names what the row
    reports; ``boot_low``/``boot_high`` keep the percentile interval.
    """
    n = min(seeds_per_ensemble(problem.cases).values(), default=0)
    est = {}
    for route, fit in (("backsolve", backsolve), ("curves", curves)):
        for block in BLOCKS:
            for k, v in fit.doc[block].items():
                est[(route, block, k)] = v
    out = bootstrap.t_widened(boot.intervals, boot.values, est, n)
    base = (f"bootstrap over seeds (percentile) joined with the t interval over {n} seeds" if n >= 2 else
            "bootstrap over seeds (percentile; one seed: no t widening)")
    out["interval"] = base
    for _, p in ident.intervals.iterrows():
        m = (out["route"] == "curves") & (out["block"] == p["model"]) & (out["parameter"] == p["parameter"])
        if not m.any() or np.isnan(p["low"]) or np.isnan(p["high"]):
            continue
        out.loc[m, "low"] = np.fmin(out.loc[m, "low"], p["low"])
        out.loc[m, "high"] = np.fmax(out.loc[m, "high"], p["high"])
        out.loc[m, "interval"] = base + " and the profile-likelihood interval"
    return out


def tabulate(problem: Problem, backsolve: BacksolveFit, curves: CurvesFit, intervals: pd.DataFrame,
             choice: RouteChoice) -> Tables:
    """Step 8: params.yaml's document (the default routes', their ``intervals``, the ``provenance``),
    ``params_table.csv`` (``parameter_table``) and ``backsolve_alpha_vs_X.csv`` (``tables.bins_table``)."""
    ptab = parameter_table(backsolve, curves, intervals, choice.default_route)
    params = dict(choice.params)
    params["intervals"] = default_intervals(ptab)
    params["provenance"] = provenance(problem, choice.default_route)
    return Tables(params, ptab, tables.bins_table(backsolve.bins, intervals))


def parameter_table(backsolve: BacksolveFit, curves: CurvesFit, intervals: pd.DataFrame,
                    default_route: dict) -> pd.DataFrame:
    """Step 8a: ``params_table.csv``: every route's values with intervals, defaults and constraint notes."""
    fitted = {("mu_vs_X", "friction_eq2"): backsolve.doc["friction_eq2"],
              ("mu_vs_X", "friction_quadratic"): backsolve.doc["friction_quadratic"]}
    for model in MODELS:
        fitted.update({("backsolve", model): backsolve.doc[model], ("curves", model): curves.doc[model]})
    bounds = {(route, block, name): b for (block, name), b in fits.SIGN_BOUNDS.items()
              for route in ("mu_vs_X", "backsolve", "curves")}
    bounds.update({(route, "model1", "X_c"): (xb, fits.XC_MAX)
                   for route, xb in route_choice.xc_lower_bounds(backsolve, curves).items()})
    return tables.params_table(fitted, intervals, default_route, bounds)


def default_intervals(ptab) -> dict:
    """Step 8b: the intervals of the default rows, as params.yaml's ``intervals`` block."""
    intervals = {}
    for _, row in ptab[ptab["default"]].iterrows():
        if not (np.isfinite(row["low"]) and np.isfinite(row["high"])):
            continue   # an interval open to infinity: the data do not bound it (identifiability.csv)
        intervals.setdefault(row["block"], {})[row["parameter"]] = [float(row["low"]), float(row["high"])]
    return intervals


def provenance(problem: Problem, default_route: dict) -> dict:
    """Step 8c: params.yaml's ``provenance`` block (inputs, command, settings, date)."""
    cases, settings = problem.cases, problem.settings
    return {
        "source": "calibrate (python -m calibrate)",
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": " ".join(problem.command) if problem.command else None,
        "cases": [str(c.path) for c in cases],
        "groups": sorted({c.group for c in cases}),
        "seeds": [c.seed for c in cases],
        "default_route": default_route,
        "routes": dict(tables.ROUTE_NAMES),
        "intervals": f"bootstrap over seeds, {settings.n_boot} replicates, 2.5-97.5 percentiles, joined with the "
                     f"t interval over seeds and, for route 2's profiled parameters, the profile-likelihood "
                     f"interval (params_table.csv, column 'interval'); only finite intervals are listed",
        "dem_steady_state": problem.steady,
        "settings": settings.as_dict(),
        "synthetic_input": any(c.preshear.meta.get("synthetic") for c in cases),
    }


def fit_quality(problem: Problem, cal: Calibration) -> pd.DataFrame:
    """``fit_quality.csv``: the route choice's rows and the free-form bound's, each with the problem's warning."""
    rows = [*cal.choice.quality, *cal.freeform.quality]
    return pd.DataFrame([{**q, "warning": problem.warning} for q in rows])


def write_tables(out: Path, problem: Problem, cal: Calibration) -> None:
    """Step 9, write: params.yaml and every CSV table under ``out``."""
    tables.write_params(cal.tables.params, out / "params.yaml")
    tables.write_csv(cal.tables.params_table, out / "params_table.csv")
    tables.write_csv(cal.tables.bins, out / "backsolve_alpha_vs_X.csv")
    tables.write_csv(fit_quality(problem, cal), out / "fit_quality.csv")
    heldout = cal.bootstrap.heldout
    if len(heldout):  # a failed replicate: NaN scores, the reason in 'failure'
        tables.write_csv(heldout.replace([np.inf, -np.inf], np.nan), out / "heldout_scores.csv")
    else:  # no replicate held a seed out (one seed): the header alone
        tables.write_csv(pd.DataFrame(columns=bootstrap.HELDOUT_COLUMNS), out / "heldout_scores.csv")
    tables.write_csv(cal.bootstrap.values, out / "bootstrap_values.csv")
    tables.write_csv(cal.identifiability.profiles, out / "profiles.csv")
    tables.write_csv(cal.identifiability.svd, out / "sensitivity_svd.csv")
    tables.write_csv(cal.identifiability.verdict, out / "identifiability.csv")
    tables.write_csv(cal.freeform.table, out / "freeform.csv")


def write_figures(out: Path, problem: Problem, cal: Calibration, log) -> None:
    """Step 10: Fig. 2a, 2b, 3a, 3b, the default routes' curves against the DEM's and the profiles."""
    from . import figures   # matplotlib only where a figure is drawn: the pre-flight's options check imports this package
    samples, replays, settings = problem.samples, problem.replays, problem.settings
    solved, fitted, btab = cal.backsolve.doc, cal.curves.doc, cal.tables.bins
    X, mu = backsolve_fit.friction_data(samples, settings.backsolve)
    figures.fig2a(samples, out / "fig2a_stress_vs_Axy.png")
    figures.fig2b(X, mu, solved["friction_eq2"], solved["friction_quadratic"], out / "fig2b_mu_vs_X.png")
    m1 = {"back-solve": solved["model1"], "curves": fitted["model1"]}
    m2 = {"back-solve": solved["model2"], "curves": fitted["model2"]}
    figures.fig3(btab, 1, m1, m2, out / "fig3a_alpha1_vs_X.png", cal.freeform.curves)
    figures.fig3(btab, 2, m1, m2, out / "fig3b_alpha2_vs_X.png", cal.freeform.curves)
    preds, default_route = {}, cal.choice.default_route
    prm = params_from_dict(cal.tables.params)
    for model in MODELS:
        fr = "eq2" if model == "model1" else "quadratic"
        try:
            preds[f"{model} ({default_route[model]})"] = {
                r.label: curves_integration.replay_run(prm, r, model, fr, settings.curves) for r in replays}
        except (ValueError, RuntimeError) as exc:
            log(f"figure: {model} cannot be integrated ({exc})")
    figures.fig_curves(replays, preds, out / "fig_curves_model_vs_dem.png")
    figures.fig_profiles(cal.identifiability.profiles, cal.identifiability.intervals, out / "fig_profiles.png")


def summary(problem: Problem, cal: Calibration, elapsed: float) -> dict:
    """What ``run`` returns: the default routes, params.yaml's document, every step's record, the tables."""
    return {"default_route": cal.choice.default_route, "params": cal.tables.params, "backsolve": cal.backsolve,
            "curves": cal.curves, "intervals": cal.intervals, "quality": fit_quality(problem, cal),
            "steady": problem.steady, "steady_check": route_choice.steady_check(cal.tables.params),
            "profiles": cal.identifiability.profiles, "profile_intervals": cal.identifiability.intervals,
            "svd": cal.identifiability.svd, "identifiability": cal.identifiability.verdict, "elapsed": elapsed}
