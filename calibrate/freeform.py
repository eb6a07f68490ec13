r"""Free-form alpha1(X), alpha2(X): the upper bound of any X-dependent Eq. 4 (issue 13, part 3).

Method
------
Eq. 4 with alpha1, alpha2 any smooth functions of X (``model.laws.AlphaSpline``:
cubic B-splines on breaks over the X the samples visit, from their 0.5th to
their 99.5th percentile, continued linearly outside; how many breaks and how
they crowd toward the largest X visited, where a pole would act, is chosen by
cross-validation, ``breaks_for``) is fitted by trajectory fitting on the
residuals of the curves route (``curves_integration.curves``, ``curves_fit.residual_vector`` and the
steady residuals of ``fits``), plus a roughness penalty

.. math::
    \lambda \sum_{i=1,2} \int_{x_0}^{x_m} \alpha_i''(X)^2\, dX = \lambda \sum_i |R c_i|^2

over the breaks, exact (``roughness_matrix``): a straight line costs nothing,
so the penalty shrinks toward linear alphas (Model 2's law, with alpha1 free
to have a slope), not toward zero. The friction law is held as the curve fit
holds Model 2's (the quadratic law of [15]), so the free-form fit and Model 2
differ only in their alphas. The start is Model 2's curve fit, represented
exactly (``laws.spline_of_linear``).

Breaks and penalty by cross-validation: leave one seed (DEM case) out; for
every knot layout of ``knot_layouts`` (number of breaks, crowding toward the
largest X) and every :math:`\lambda` of ``penalties`` the fit on the other
seeds predicts the held-out seed's runs; the pair with the lowest held-out
mean squared normalised residual (the curve fit's objective) wins and is refitted
on every seed. Evenly spaced breaks with too few of them limit the bound
exactly where a pole acts (one cubic piece over the last fifth of the X
range); the layouts crowded toward the largest X let the data ask for a bend
there.
Model 1 and Model 2 are refitted by the curve fit on the same folds (from their
full-data fits, ``cv_evals`` evaluations), so every held-out run is predicted
by the three laws calibrated without its seed: paired errors per run, averaged
per seed, with a bootstrap interval over seeds (``shared_stats.mean_interval``).

Scores per held-out run: RMS error of |A| over the first ``early_strain`` of
path strain after the first reversal (the claims table's window) and its
square (``early_A_mse``: the claims difference it per run, where the DEM's
noise cancels; ``freeform.csv`` keeps it per run, section ``heldout``), and
the RMS errors of |A|, theta_A (degrees, axial) and the signed friction over
the whole run.

Band: the leave-one-seed-out fits at the chosen :math:`\lambda` are a
jackknife; the band is the full fit :math:`\pm t_{0.975,\,n-1}` jackknife standard
errors, :math:`\mathrm{se}^2 = \frac{n-1}{n}\sum_j (\hat\alpha_{(j)} - \bar\alpha)^2`
(``t95``: Student's t of the n seeds, not the normal 1.96: with 5 seeds it is
2.78).

Pole: the bend of each alpha at the largest X visited beyond its tangent at
X = 0, :math:`e_i = \alpha_i(X_{hi}) - \alpha_i(0) - \alpha_i'(0) X_{hi}`
(Model 1's pole term :math:`c_i X^4/(X_c - X)` is such a bend), with its
jackknife interval.

Everything runs under an ``integration_batcher.IntegrationBatcher`` (each fit a thread; their
integrations one ``simulate_batch`` call per round).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np
import pandas as pd
from scipy import stats
from scipy.optimize import least_squares

from dem_contract import angle_difference, fabric_angle_deg, fabric_norm
from model import params_from_dict
from model.laws import AlphaSpline, spline_basis, spline_of_linear, spline_size
from shared_stats import early_rmse, mean_interval

from . import curves_fit, curves_integration, fits, shear_stability
from .integration_batcher import IntegrationBatcher

SCORES = ("early_A_norm", "early_A_mse", "A_norm", "theta_A", "mu")
LAWS = ("freeform", "model1", "model2")


def t95(n: int) -> float:
    r"""Student's :math:`t_{0.975,\,n-1}` of a jackknife over ``n`` seeds (NaN for n < 2)."""
    return float(stats.t.ppf(0.975, n - 1)) if n >= 2 else math.nan


@dataclass(frozen=True)
class FreeformSettings:
    n_breaks: int = 5                                   # breaks over the X range visited (K = n_breaks + 2 per alpha)
    penalties: tuple = (1e-6, 1e-4, 1e-2, 1.0)           # lambda grid of the cross-validation
    layouts: tuple | None = None                        # (breaks, crowding) pairs the CV chooses among; None:
    #                                                     even n_breaks, n_breaks crowded and n_breaks + 2 crowded
    max_evals: int = 180                                # model evaluations of the final fit (Jacobian points count)
    cv_evals: int = 60                                  # ... of each cross-validation fit
    early_strain: float = 0.1
    friction: str = "quadratic"                         # Model 2's, as the curve fit holds it
    n_resamples: int = 2000

    def __post_init__(self):
        if not (isinstance(self.n_breaks, int) and self.n_breaks >= 2):
            raise ValueError(f"free-form fit: n_breaks = {self.n_breaks!r} must be an integer >= 2")
        if not (len(self.penalties) and all(p > 0 for p in self.penalties)):
            raise ValueError(f"free-form fit: penalties = {self.penalties!r} must be positive numbers")
        for n, crowd in self.knot_layouts():
            if not (int(n) == n and n >= 2 and crowd >= 1.0):
                raise ValueError(f"free-form fit: knot layout ({n!r}, {crowd!r}) needs an integer number of breaks "
                                 f">= 2 and a crowding >= 1 (1: evenly spaced)")

    def knot_layouts(self) -> tuple:
        """The (number of breaks, crowding) pairs the cross-validation chooses among (``breaks_for``)."""
        if self.layouts is not None:
            return tuple((int(n), float(c)) for n, c in self.layouts)
        return ((self.n_breaks, 1.0), (self.n_breaks, CROWDING), (self.n_breaks + 2, CROWDING))

    def as_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


def sample_X(replays) -> np.ndarray:
    """X = sqrt2 g A_xy of every sample of every replay."""
    return np.concatenate([np.sqrt(2.0) * r.g * r.b for r in replays])


#: Percentiles of the samples' X spanned by the breaks (single noisy samples do not stretch the range).
X_RANGE = (0.5, 99.5)


#: Crowding of the breaks toward the largest X in the default layouts (2: spacing falls linearly to 0 there).
CROWDING = 2.0


def breaks_for(replays, n_breaks: int, crowding: float = 1.0) -> tuple:
    r"""``n_breaks`` breaks over the X the samples visit (percentiles ``X_RANGE``), crowded toward the largest.

    .. math:: x_k = x_{lo} + (x_{hi} - x_{lo})\,\big(1 - (1 - u_k)^{p}\big), \qquad u_k = k/(n - 1)

    with :math:`p` = ``crowding``: 1 evenly spaced; above 1 the spacing shrinks toward :math:`x_{hi}`,
    where Model 1's pole acts.
    """
    lo, hi = np.percentile(sample_X(replays), X_RANGE)
    return breaks_over(float(lo), float(hi), n_breaks, crowding)


def breaks_over(lo: float, hi: float, n_breaks: int, crowding: float = 1.0) -> tuple:
    """The breaks of ``breaks_for`` between ``lo`` and ``hi`` (its equation)."""
    u = np.linspace(0.0, 1.0, n_breaks)
    return tuple(float(x) for x in lo + (hi - lo) * (1.0 - (1.0 - u) ** crowding))


def roughness_matrix(breaks) -> np.ndarray:
    r"""R with :math:`\int_{x_0}^{x_m} \alpha''(X)^2\,dX = |R c|^2` for the cubic B-splines on ``breaks``.

    :math:`\alpha''` is linear on each interval, so two-point Gauss-Legendre
    quadrature per interval is exact: the rows of R are :math:`\sqrt{w_q} B_k''(x_q)`.
    """
    from scipy.interpolate import BSpline

    from model.laws import spline_knots

    b = np.asarray(breaks, dtype=float)
    g, w = np.polynomial.legendre.leggauss(2)
    mid, half = 0.5 * (b[1:] + b[:-1]), 0.5 * np.diff(b)
    xq = (mid[:, None] + half[:, None] * g[None, :]).ravel()
    wq = (half[:, None] * w[None, :]).ravel()
    d2 = BSpline(spline_knots(b), np.eye(spline_size(b)), 3).derivative(2)(xq)   # (n_q, K)
    return np.sqrt(wq)[:, None] * d2


def _penalty_rows(spline: AlphaSpline, lam: float) -> np.ndarray:
    r"""Residual rows of the roughness penalty: :math:`\sqrt\lambda\, R c_i` for both alphas (``roughness_matrix``)."""
    R = roughness_matrix(spline.breaks)
    return math.sqrt(lam) * np.concatenate([R @ spline.c1, R @ spline.c2])


def fit_spline(replays, doc: dict, start: AlphaSpline, steady: dict, sigma_mu: float, lam: float,
               settings: FreeformSettings, s2: curves_integration.CurvesSettings, max_evals: int, batcher=None):
    r"""Penalised least-squares fit of the spline coefficients to the replays (module Notes).

    Returns
    -------
    spline : AlphaSpline
        The best point seen (the start if nothing better was integrated).
    info : dict
        ``cost``, ``evaluations``, ``failed_evaluations``, ``message``.
    """
    prm = params_from_dict(doc)
    K = spline_size(start.breaks)
    n_res = sum(3 * len(r.s) for r in replays) + fits.N_STEADY + 2 * len(roughness_matrix(start.breaks))
    def unpack(p):
        return AlphaSpline(start.breaks, p[:K], p[K:])

    def evaluate(points):
        sps = [unpack(p) for p in points]
        got = curves_integration.curves([(prm, "model2", settings.friction, sp) for sp in sps], replays, s2, batcher)
        out = []
        for sp, c in zip(sps, got):
            if isinstance(c, Exception):
                out.append(None)
                continue
            r = np.concatenate([curves_fit.fit_residuals(c, replays, sigma_mu, s2, sp(float(steady["X"])), steady),
                                _penalty_rows(sp, lam)])
            stable = shear_stability.check(sp)["stable"]     # a law that cannot shear steadily: excluded
            out.append(r if np.all(np.isfinite(r)) and stable else None)
        return out

    res, workers, state = curves_fit.counted_objective(evaluate, n_res, max_evals)
    x0 = np.concatenate([start.c1, start.c2])
    message = ""
    try:
        sol = least_squares(res, x0, x_scale="jac", diff_step=s2.diff_step, max_nfev=max_evals, workers=workers)
        message = sol.message
    except curves_fit.BudgetExhausted:
        message = f"budget of {max_evals} model evaluations used up; best point kept"
    best = state["best"] if state["best"] is not None else x0
    return unpack(best), {"cost": state["best_cost"], "evaluations": state["n"],
                          "failed_evaluations": state["fails"], "message": message}


def reversal_strain(replay) -> float:
    """Path strain of the run's first reversal: the end of its leading pieces sheared as the pre-shear was.

    The pre-shear's sign is the one for which the run's start is a steady state,
    X = sqrt2 g A_xy < 0 (docs/model.md, Sec. 3): g = -sign(A_xy at the start).
    """
    g_pre = -np.sign(replay.A0[1])
    s = 0.0
    for g, length in replay.pieces:
        if g != g_pre:
            return s
        s += length
    return s


def run_errors(c, replay, early_strain: float) -> dict:
    """RMS errors of one run's model curve ``c`` (a, b, signed mu at the samples) against its DEM samples.

    ``early_A_norm``: |A| over the first ``early_strain`` after the run's first reversal, the claims'
    measure (``shared_stats.early_rmse``); the others over the whole run.
    """
    model_A, dem_A = fabric_norm(c[:, 0], c[:, 1]), fabric_norm(replay.a, replay.b)
    dth = angle_difference(fabric_angle_deg(c[:, 0], c[:, 1]), fabric_angle_deg(replay.a, replay.b))
    rms = lambda v: float(np.sqrt(np.mean(v**2))) if v.size else math.nan  # noqa: E731
    early = early_rmse(replay.s, dem_A, model_A, early_strain, start=reversal_strain(replay))
    return {"early_A_norm": early, "early_A_mse": early ** 2, "A_norm": rms(model_A - dem_A), "theta_A": rms(dth),
            "mu": rms(c[:, 2] - replay.mu)}


def _heldout(items, held, s2, sigma_mu, early_strain, batcher) -> list:
    """Per item (params, model, friction[, spline]): (mean squared normalised residual, per-run errors) on ``held``."""
    out = []
    for c in curves_integration.curves(items, held, s2, batcher):
        if isinstance(c, Exception):
            out.append((math.inf, [{k: math.nan for k in SCORES} for _ in held]))
            continue
        z = curves_fit.residual_vector(c, held, sigma_mu, s2)
        out.append((float(np.mean(z**2)), [run_errors(m, r, early_strain) for m, r in zip(c, held)]))
    return out


def _fold_job(problem, curves_doc, case, candidates, models=True):
    """One fold: spline fits at every candidate (start on its breaks, penalty; the candidates share their breaks:
    one batch) and, with ``models``, curve-fit refits of both models without ``case``; held-out scores."""
    steady, sigma_mu = problem.steady, problem.sigma_mu
    settings, s2 = problem.settings.freeform, problem.settings.curves
    train = [r for r in problem.replays if r.case != case]
    held = [r for r in problem.replays if r.case == case]

    def job(batcher):
        sps = [fit_spline(train, curves_doc, start, steady, sigma_mu, lam, settings, s2, settings.cv_evals, batcher)[0]
               for start, lam in candidates]
        prm = params_from_dict(curves_doc)
        items = [(prm, "model2", settings.friction, sp) for sp in sps]
        if models:
            s2m = replace(s2, max_evals=settings.cv_evals)
            refit = {m: curves_fit.fit(train, curves_doc, m, curves_doc[m], steady, sigma_mu, s2m,
                                       batcher=batcher).values
                     for m in ("model1", "model2")}
            for m in ("model1", "model2"):
                d = dict(curves_doc)
                d[m] = refit[m]
                items.append((params_from_dict(d), m, "eq2" if m == "model1" else "quadratic"))
        scores = _heldout(items, held, s2, sigma_mu, settings.early_strain, batcher)
        errors = {"spline": [s[1] for s in scores[:len(sps)]]}
        if models:
            errors.update(model1=scores[-2][1], model2=scores[-1][1])
        return {"case": case, "splines": sps, "held": [r.label for r in held],
                "cv": [s[0] for s in scores[:len(sps)]], "errors": errors}
    return job


def run(problem, curves_doc: dict, log=print) -> dict:
    """Cross-validate the penalty, fit the free-form law on every seed, score it against Models 1 and 2.

    Parameters
    ----------
    problem : calibrate.problem.Problem
        The replays, steady state and friction noise to fit; its settings' ``freeform`` (``FreeformSettings``)
        and ``curves`` (tolerances; the integrator must be "batched").
    curves_doc : dict
        The curve fit's parameter document (friction laws and both models' fits).

    Returns
    -------
    dict
        ``spline`` (AlphaSpline, final fit), ``penalty`` and ``layout`` (number of breaks, crowding)
        chosen, ``cv_all`` (DataFrame: n_breaks, crowding, penalty, cv_score, failed_folds, chosen),
        ``cv`` (its rows of the chosen layout: penalty, cv_score, failed_folds),
        ``folds`` (jackknife AlphaSplines at the chosen grid point), ``errors`` (DataFrame: one row
        per held-out run and law), ``table`` (the ``freeform.csv`` DataFrame), ``fit`` (info).
    """
    replays, steady, sigma_mu = problem.replays, problem.steady, problem.sigma_mu
    settings, s2 = problem.settings.freeform, problem.settings.curves
    if s2.integrator != "batched":
        raise ValueError("free-form fit: needs the batched integrator (--integrator batched)")
    m2 = curves_doc["model2"]
    layouts = settings.knot_layouts()
    grid = [(n, crowd, lam) for n, crowd in layouts for lam in settings.penalties]
    cases = sorted({r.case for r in replays})
    if len(cases) < 2:
        raise ValueError(f"free-form fit: cross-validation leaves one seed out and needs 2 or more, got {cases}")
    by_layout = []      # per layout, its folds (one batcher each: a batch shares its breaks); models on the first
    for i, (n, crowd) in enumerate(layouts):
        start = spline_of_linear(breaks_for(replays, n, crowd), m2["c1"], 0.0, m2["c2"], m2["c3"])
        cands = [(start, lam) for lam in settings.penalties]
        jobs = [_fold_job(problem, curves_doc, c, cands, models=i == 0) for c in cases]
        by_layout.append(IntegrationBatcher().run(jobs))
    folds = []          # per fold, every grid point in grid order (layouts outer, penalties inner)
    for f, base in enumerate(by_layout[0]):
        folds.append(dict(base, cv=[c for lay in by_layout for c in lay[f]["cv"]],
                          splines=[sp for lay in by_layout for sp in lay[f]["splines"]],
                          errors=dict(base["errors"],
                                      spline=[e for lay in by_layout for e in lay[f]["errors"]["spline"]])))
    cv = np.array([sum(f["cv"][j] * len(f["held"]) for f in folds) / sum(len(f["held"]) for f in folds)
                   for j in range(len(grid))])
    j = int(np.nanargmin(np.where(np.isfinite(cv), cv, np.nan))) if np.isfinite(cv).any() else 0
    lam = grid[j][2]
    start = spline_of_linear(breaks_for(replays, *grid[j][:2]), m2["c1"], 0.0, m2["c2"], m2["c3"])
    final = [lambda batcher: fit_spline(replays, curves_doc, start, steady, sigma_mu, lam, settings, s2,
                                        settings.max_evals, batcher)]
    spline, info = IntegrationBatcher().run(final)[0]
    log(f"free-form: {grid[j][0]} breaks (crowding {grid[j][1]:g}) and penalty {lam:g} chosen by leave-one-seed-out "
        f"CV ({', '.join(f'{n}/{c:g}/{p:g}: {v:.4g}' for (n, c, p), v in zip(grid, cv))}); final fit "
        f"{info['message']}")
    rows = []
    for f in folds:
        for law, errs in (("freeform", f["errors"]["spline"][j]), ("model1", f["errors"]["model1"]),
                          ("model2", f["errors"]["model2"])):
            for label, e in zip(f["held"], errs):
                rows.append({"case": f["case"], "run": label, "law": law, **e})
    errors = pd.DataFrame(rows)
    fold_splines = [f["splines"][j] for f in folds]
    cv_all = pd.DataFrame({"n_breaks": [g[0] for g in grid], "crowding": [g[1] for g in grid],
                           "penalty": [g[2] for g in grid], "cv_score": cv,
                           "failed_folds": [sum(not np.isfinite(f["cv"][k]) for f in folds) for k in range(len(grid))],
                           "chosen": [k == j for k in range(len(grid))]})
    same_layout = (cv_all["n_breaks"] == grid[j][0]) & (cv_all["crowding"] == grid[j][1])
    out = {"spline": spline, "penalty": lam, "layout": grid[j][:2], "fit": info, "folds": fold_splines,
           "errors": errors, "cv_all": cv_all,
           "cv": cv_all.loc[same_layout, ["penalty", "cv_score", "failed_folds"]].reset_index(drop=True)}
    out["table"] = table(out, settings)
    return out


def jackknife_band(full: AlphaSpline, folds, X) -> tuple:
    """(alpha1, alpha2) of the full fit at X and their jackknife standard errors (module Notes)."""
    a = np.array(full(X))                                        # (2, len(X))
    reps = np.array([f(X) for f in folds])                       # (n, 2, len(X))
    n = len(folds)
    se = np.sqrt((n - 1) / n * ((reps - reps.mean(axis=0)) ** 2).sum(axis=0)) if n > 1 else np.full_like(a, np.nan)
    return a, se


def pole_bend(spline: AlphaSpline, X_hi: float) -> np.ndarray:
    """e_i = alpha_i(X_hi) - alpha_i(0) - alpha_i'(0) X_hi for i = 1, 2 (module Notes); NaN if X_hi <= 0."""
    if not X_hi > 0:
        return np.full(2, np.nan)
    h = 1e-6
    v0, vp, vm, vhi = (np.array(spline(x)) for x in (0.0, h, -h, X_hi))
    return vhi - v0 - (vp - vm) / (2 * h) * X_hi


def paired(errors: pd.DataFrame, law: str, ref: str, score: str, n_resamples: int):
    """Estimate, low, high, n of the per-seed mean of ``law - ref`` (paired per run), over seeds."""
    wide = errors.pivot_table(index=["case", "run"], columns="law", values=score)
    d = (wide[law] - wide[ref]).groupby(level="case").mean()
    return mean_interval(d.to_numpy(), n_resamples=n_resamples)


def note_table(note: str) -> pd.DataFrame:
    """``freeform.csv`` when the fit cannot run (e.g. one seed): one row, ``section`` = note."""
    return pd.DataFrame([dict(section="note", key="not fitted", value=math.nan, low=math.nan, high=math.nan,
                              n=math.nan, detail=note)])


def not_requested_table() -> pd.DataFrame:
    """``freeform.csv`` when the fit was not asked for (no ``--freeform``; the workflow's
    ``calibration.freeform`` false): one row, ``section`` = note, so the file exists either way."""
    return pd.DataFrame([dict(section="note", key="not requested", value=math.nan, low=math.nan, high=math.nan,
                              n=math.nan, detail="calibration.freeform is false")])


def table(res: dict, settings: FreeformSettings) -> pd.DataFrame:
    """``freeform.csv``: breaks, coefficients, CV scores, paired held-out scores and the pole bends.

    Columns: ``section`` (breaks, coefficients, cv, score, difference, pole, heldout), ``key``, ``value``,
    ``low``, ``high`` (95 %), ``n`` (seeds, or samples), ``detail``. Section ``heldout``: one row per held-out
    run and law, key ``<law>|<case>/<protocol>``, value its ``early_A_mse`` (the claims table's claim 9).
    """
    sp, rows = res["spline"], []
    add = lambda section, key, value, low=math.nan, high=math.nan, n=math.nan, detail="": rows.append(  # noqa: E731
        dict(section=section, key=key, value=value, low=low, high=high, n=n, detail=detail))
    for k, x in enumerate(sp.breaks):
        add("breaks", f"X_{k}", x)
    for name, c in (("alpha1", sp.c1), ("alpha2", sp.c2)):
        for k, v in enumerate(c):
            add("coefficients", f"{name}_c{k}", float(v), detail="cubic B-spline, clamped knots on the breaks")
    for r in res["cv_all"].itertuples():
        add("cv", f"penalty_{r.penalty:g}_breaks_{r.n_breaks}_crowding_{r.crowding:g}", float(r.cv_score),
            n=len(res["folds"]),
            detail="; ".join(x for x in ("chosen" if r.chosen else "",
                                         f"{r.n_breaks} breaks, crowding {r.crowding:g} toward the largest X",
                                         f"{r.failed_folds} fold(s) whose fit cannot be integrated on the held-out "
                                         f"seed (score inf)" if r.failed_folds else "") if x))
    err, nr = res["errors"], settings.n_resamples
    for score in SCORES:
        for law in LAWS:
            per_seed = err[err["law"] == law].groupby("case")[score].mean().to_numpy()
            est, lo, hi, n = mean_interval(per_seed, n_resamples=nr)
            failed = int(err.loc[err["law"] == law, score].isna().sum())
            add("score", f"{score}: {law}", est, lo, hi, n, "held-out RMS error, mean over seeds"
                + (f"; {failed} held-out run(s) could not be integrated (left out)" if failed else ""))
        for law in ("freeform", "model1"):
            est, lo, hi, n = paired(err, law, "model2", score, nr)
            add("difference", f"{score}: {law} - model2", est, lo, hi, n,
                "paired per held-out run, mean per seed; < 0: better than Model 2")
    for r in err.itertuples():
        add("heldout", f"{r.law}|{r.run}", float(r.early_A_mse), n=1,
            detail="held-out run: MSE of |A| over the early window after its first reversal")
    X_hi = sp.breaks[-1]
    e = pole_bend(sp, X_hi)
    reps = np.array([pole_bend(f, X_hi) for f in res["folds"]])
    n = len(reps)
    se = np.sqrt((n - 1) / n * ((reps - reps.mean(axis=0)) ** 2).sum(axis=0)) if n > 1 else np.full(2, np.nan)
    for i in range(2):
        add("pole", f"alpha{i + 1} bend at X_hi", float(e[i]), float(e[i] - t95(n) * se[i]),
            float(e[i] + t95(n) * se[i]), n,
            f"alpha(X_hi) - alpha(0) - alpha'(0) X_hi, X_hi = {X_hi:.4g}; jackknife over seeds, +-t_{n - 1} s.e.")
    return pd.DataFrame(rows)


def curves_for_figure(res: dict, X) -> dict:
    """``{"X", "alpha1", "alpha2", "se1", "se2", "t", "label"}`` for ``figures.fig3`` (band: +-t se)."""
    a, se = jackknife_band(res["spline"], res["folds"], X)
    k = t95(len(res["folds"]))
    return {"X": np.asarray(X), "alpha1": a[0], "alpha2": a[1], "se1": se[0], "se2": se[1], "t": k,
            "label": f"free-form ({len(res['spline'].breaks)} breaks, penalty {res['penalty']:g}, band: "
                     f"t_{len(res['folds']) - 1} = {k:.2f} jackknife s.e.)"}


__all__ = ["FreeformSettings", "run", "fit_spline", "breaks_for", "table", "curves_for_figure", "pole_bend",
           "spline_basis"]
