r"""The claims table: one row per claim of the paper (and per figure), with its statistic, interval, test and verdict.

Columns (``COLUMNS``): ``claim_id``, ``claim`` (the paper's words, shortened),
``source`` (the paper's section or figure), ``statistic`` (what is measured),
``unit``, ``null`` (the value of no effect), ``paper_side`` (``>`` or ``<``:
where the paper puts the statistic), ``estimate``, ``low``, ``high`` (the 90 %
interval: every verdict of the row is read off it, ``claims.stats``),
``margin`` (the smallest effect that matters, ``claims.margins``; NaN where
the claim compares no two models), ``sd`` (the seed-to-seed standard
deviation of the per-seed values: the planner's input), ``test``, ``n`` and
``n_unit`` (what was counted), ``adequacy`` (for a comparison of two models:
whether each lies within the DEM's ensemble band on the row's statistic),
``verdict`` and ``detail`` (the numbers behind it).

Decision rule (``claims.stats.verdict``, one level: one-sided tests at 5 %,
the 90 % interval): **reproduced** if the interval lies strictly on the
paper's side of the null, **contradicted** if strictly on the other side,
**negligible** if it lies inside null +- margin (with the first two:
"reproduced, negligible", a real effect too small to matter),
**inconclusive** otherwise (also when it cannot be computed). Two additions:
"theta_A *always* passes through 90 degrees" is contradicted by a run that
crosses the horizontal at family-wise 5 % over the runs (Holm,
``passage_row``); a comparison of two models both outside the DEM's ensemble
band reads **both fail** (``adequacy``): a difference between two wrong
answers is no finding about the claim.

Model error, not DEM noise (claims 4, 7, 9; ``claims.ensemble``): each run's
MSE against its DEM run is the model's error plus the DEM's noise floor, the
seed-to-seed variance measured at that reversal position; the two models'
difference on the same run, MSE_1 - MSE_2, is the difference of their
squared model errors (the floor cancels), so a perfect model scores what the
other model misses, whatever the noise. One row per figure: step reversals
(Fig. 4, the ``heaviside`` kind: the Heaviside run and every reversal of a
train) and the sinusoidal reversal (Fig. 5), each with its own margin; a
pooled row with the weights of ``margins.POOLED_WEIGHTS`` as a secondary line.

Units of resampling. Every interval (``stats.mean_interval``: percentile
bootstrap, at least as wide as the Student t interval) is over seeds (DEM
cases: one pre-shear and its reversal runs), pooled across ensembles
(pressures and inertial numbers; the claims are made for every ensemble): a
seed's value is the mean over its runs and, for the model comparisons, over
the calibration sets that did not see the run. A seed's reversals of one kind
scored by one set are averaged first, so a schedule's several reversals weigh
as one run of their kind (``per_seed``). Model comparisons use only
out-of-sample predictions: a run is scored with a set calibrated on another
protocol (e.g. ``heaviside_only`` scored on the sinusoidal run), another
inertial number, or other seeds (cross-fitting), and the two models are
paired on the same run (difference per run, then per seed).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.stats import t as student

from model import friction_eq2, load_params

from shared_stats.errors import early_mse

from . import ensemble, margins, measures, stats

COLUMNS = ["claim_id", "claim", "source", "statistic", "unit", "null", "paper_side", "estimate", "low", "high",
           "margin", "sd", "test", "n", "n_unit", "adequacy", "verdict", "detail"]
MODELS = ("model1", "model2")
NAMES = {"model1": "Model 1", "model2": "Model 2", "model1_start": "Model 1 (pole at start)",
         "freeform": "the free-form law"}
#: The figures the paper makes its comparisons on: a reversal kind -> (claim-id suffix, words).
FIGURES = {"heaviside": ("step", "step reversals (Fig. 4)"), "sinusoidal": ("sin", "the sinusoidal reversal (Fig. 5)")}
EARLY_A = 0.1      # strain window of the fall of |A| (the paper: "just after the reversal")
EARLY_MU = 0.05    # strain window of the start of the reversal for mu
EQ2_MARGIN = 1.1   # Eq. 2 counts as capturing the collapse if its scatter is within 10 % of the best curve's
STEADY_LIMIT = 135.0
SEED_UNIT = "seeds (pooled across ensembles)"


def _row(claim_id, claim, source, statistic, unit, null, side, est, low, high, test, n, n_unit, detail,
         verdict=None, margin=math.nan, sd=math.nan, adequacy=""):
    return dict(claim_id=claim_id, claim=claim, source=source, statistic=statistic, unit=unit, null=null,
                paper_side=side, estimate=est, low=low, high=high, margin=margin, sd=sd, test=test, n=n,
                n_unit=n_unit, adequacy=adequacy,
                verdict=verdict or stats.verdict(low, high, null, side, margin), detail=detail)


def _sd(values) -> float:
    """The seed-to-seed s.d. of per-seed values (``ddof=1``; NaN with fewer than 2)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(np.std(v, ddof=1)) if v.size >= 2 else math.nan


def per_seed(values: dict) -> tuple:
    r"""Per-seed means: (case -> list of values, or case -> {group -> list}) -> (cases, means).

    With groups (``_add``: a reversal kind, or a calibration set and a kind), a seed's
    value is the mean over its groups of the mean within each group,

    .. math:: v_{\mathrm{seed}} = \frac1{|G|} \sum_{g \in G} \frac1{n_g} \sum_{i \in g} v_i

    so the several reversals of one kind a schedule gives a seed count as one run of
    that kind (they share its packing: the seed stays the unit of every interval). NaN
    values are dropped, empty groups and seeds left out.
    """
    cases, means = [], []
    for case, v in sorted(values.items()):
        groups = v.values() if isinstance(v, dict) else [v]
        group_means = []
        for g in groups:
            g = np.asarray(g, float)
            g = g[np.isfinite(g)]
            if g.size:
                group_means.append(float(g.mean()))
        if group_means:
            cases.append(case)
            means.append(float(np.mean(group_means)))
    return cases, np.array(means)


def _add(values: dict, case: str, group, value) -> None:
    """Append ``value`` to ``case``'s ``group`` (``per_seed`` averages within a group first)."""
    values.setdefault(case, {}).setdefault(group, []).append(value)


def kind_of(curve: pd.DataFrame) -> str:
    """The reversal kind of a curve of ``predictions.csv`` (heaviside: a step; sinusoidal: a half cosine)."""
    return str(curve["kind"].iloc[0])


def _fmt(x, digits=3):
    return "nan" if not np.isfinite(x) else f"{x:.{digits}g}"


# --------------------------------------------------------------------------- DEM-only claims


def fall_rows(dem: dict, steady: dict, boot) -> list:
    """Claim 1: |A| and mu fall abruptly after a reversal (depth beyond noise; strain of the minimum)."""
    rows = []
    for qid, q, label in (("1a", "A_norm", "|A|"), ("1b", "mu", "mu")):
        excess, depth, s_min = {}, {}, {}
        for (case, group, proto), d in dem.items():
            if case not in steady:
                continue
            a, b = measures.smooth(d["A_xx"]), measures.smooth(d["A_xy"])
            x = measures.norm_and_angle(a, b)[0] if q == "A_norm" else measures.smooth(d["mu"])
            ref = steady[case]["A_norm"] if q == "A_norm" else steady[case]["mu"]
            f = measures.fall(d["s_rev"].to_numpy(), x, ref, noisy=True)
            _add(excess, case, kind_of(d), f["excess"])
            _add(depth, case, kind_of(d), f["depth"])
            _add(s_min, case, kind_of(d), f["s_min"])
        _, e = per_seed(excess)
        est, lo, hi, n = boot(e)
        _, dd = per_seed(depth)
        _, sm = per_seed(s_min)
        sm_est, sm_lo, sm_hi, _ = boot(sm)
        rows.append(_row(
            qid, f"after a reversal {label} falls abruptly", "the paper, Sec. 4 and 5 (Figs. 4, 5)",
            f"depth of the minimum of {label} below its steady value, 1 - min/steady, minus the depth its noise "
            f"alone gives (3 s.d. of the smoothed DEM about a line over the last {measures.TAIL:.0%} of the run, "
            f"over steady); DEM runs, {measures.SMOOTH}-sample running mean",
            "fraction of the steady value", 0.0, ">", est, lo, hi, stats.bootstrap_test_name(boot.n_resamples), n,
            SEED_UNIT,
            f"mean depth {_fmt(np.mean(dd) if dd.size else math.nan)}; strain of the minimum {_fmt(sm_est)} "
            f"[{_fmt(sm_lo)}, {_fmt(sm_hi)}] (strain since the reversal)", sd=_sd(e)))
    return rows


def collapse_rows(dem_cases: list, eq2, boot) -> list:
    """Claim 2: mu is a one-to-one function of X (Fig. 2b), not of A_xy (Fig. 2a); Eq. 2 captures it."""
    ratio_axy, ratio_eq2, r_x = [], [], []
    for c in dem_cases:
        sm = c.samples
        if len(sm) < 4 * measures.N_BINS:
            continue
        rx = measures.binned_scatter(sm["X"], sm["mu"])
        ra = measures.binned_scatter(sm["A_xy"], sm["stress_ratio"])
        r_x.append(rx)
        ratio_axy.append(rx / ra if ra > 0 else math.nan)
        if eq2 is not None:
            fit = friction_eq2(sm["X"].to_numpy(), **eq2)
            ratio_eq2.append(float(np.sqrt(np.mean((sm["mu"].to_numpy() - fit) ** 2))) / rx if rx > 0 else math.nan)
    rows = []
    est, lo, hi, n = boot(np.array(ratio_axy))
    rows.append(_row(
        "2a", "mu is a one-to-one function of X = A:D'/|D'|, not of A_xy", "the paper, Sec. 3.1 and 5 (Figs. 2a, 2b)",
        f"per seed, RMS scatter of mu about its best single-valued curve of X (mean in {measures.N_BINS} quantile "
        f"bins) over the RMS scatter of sigma_xy/p about its best single-valued curve of A_xy (Fig. 2a's axes); "
        f"reversal runs, raw DEM samples", "ratio", 1.0, "<", est, lo, hi,
        stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"mean scatter of mu about the curve of X: {_fmt(np.mean(r_x) if r_x else math.nan)}",
        sd=_sd(ratio_axy)))
    if eq2 is None:
        rows.append(_row("2b", "Eq. 2 captures mu(X)", "the paper, Sec. 3.1 (Eq. 2, Fig. 2b)",
                         "not computed: no params.yaml of calibration set 'all'", "ratio", EQ2_MARGIN, "<",
                         math.nan, math.nan, math.nan, "none", 0, SEED_UNIT, "", verdict="inconclusive"))
        return rows
    est, lo, hi, n = boot(np.array(ratio_eq2))
    rows.append(_row(
        "2b", "Eq. 2 captures mu(X) (as well as any single-valued curve of X)", "the paper, Sec. 3.1 (Eq. 2, Fig. 2b)",
        f"per seed, RMS scatter of mu about Eq. 2 (calibration set 'all') over its scatter about the best "
        f"single-valued curve of X; null: within {EQ2_MARGIN - 1:.0%}", "ratio", EQ2_MARGIN, "<", est, lo, hi,
        stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT, "", sd=_sd(ratio_eq2)))
    return rows


def dem_passages(dem: dict) -> dict:
    """Which axis each DEM run's theta_A turns through (``dem_contract.passage``): the curve key of
    ``inputs.dem_curves`` (case, group, protocol) -> its ``passage`` dict."""
    return {key: measures.passage(d["s_rev"].to_numpy(), d["A_xx"].to_numpy(), d["A_xy"].to_numpy(), noisy=True)
            for key, d in dem.items()}


def crossing_tests(dem: dict, passages: dict | None = None) -> dict:
    r"""Every DEM run's crossing judged at family-wise 5 % over the runs: (case, group, protocol) -> dict.

    Per run with a crossing, ``z`` (its A_xx over the other runs' pooled seed-to-seed scatter,
    ``claims.ensemble.crossing_z``) and ``dof``, and the one-sided p-values of Student's t:
    ``p_horizontal`` = P(T > z) (small: the run crosses the horizontal, 0/180) and
    ``p_vertical`` = P(T < z) (small: through 90). Holm's step-down over the runs (``stats.holm``)
    gives ``horizontal`` (claim 3's counter-examples: the chance of a false one stays at most 5 %
    whatever the number of runs) and ``axis``: "90" or "0/180" where Holm rejects the other side
    over both sides of every run (two-sided family, claim 5), "unclear" otherwise.
    """
    passages = passages if passages is not None else dem_passages(dem)
    zs = ensemble.crossing_z({k: p["A_xx_cross"] for k, p in passages.items()})
    keys = sorted(zs)
    z = np.array([zs[k][0] for k in keys], float)
    dof = np.array([zs[k][1] for k in keys], float)
    ok = np.isfinite(z) & (dof > 0)
    p_h = np.where(ok, student.sf(np.where(ok, z, 0.0), np.maximum(dof, 1)), np.nan)
    p_v = np.where(ok, student.cdf(np.where(ok, z, 0.0), np.maximum(dof, 1)), np.nan)
    horizontal = stats.holm(p_h)
    both = stats.holm(np.concatenate([p_h, p_v]))
    out = {}
    for i, k in enumerate(keys):
        axis = "0/180" if both[i] else "90" if both[len(keys) + i] else "unclear"
        out[k] = dict(z=float(z[i]), dof=int(dof[i]), p_horizontal=float(p_h[i]), p_vertical=float(p_v[i]),
                      horizontal=bool(horizontal[i]), axis=axis)
    return out


def passage_row(dem: dict, boot) -> dict:
    r"""Claim 3: in the DEM theta_A always passes through 90 degrees.

    Statistic: A_xx at the first sign change of A_xy (``dem_contract.passage``, the DEM smoothed), averaged per
    seed over its reversals of one kind (``per_seed``), mean over seeds with its 90 % interval. "Always" is a
    claim on every run, tested on every run at family-wise 5 % (``crossing_tests``: Holm over the runs' one-sided
    t tests of "crosses at A_xx <= 0"): contradicted when a run crosses the horizontal at that level, or when the
    interval lies above 0; reproduced when the interval lies below 0 and no run is a counter-example. The
    per-run labels of ``dem_contract.passage`` (2 noise s.d. of the run's tail, one run at a time) are reported,
    not decided on: with 40 runs and no effect one of them would pass 2 s.d. in most campaigns.
    """
    passages = dem_passages(dem)
    tests = crossing_tests(dem, passages)
    values = {}
    for key, c in passages.items():
        if c["axis"] != "none":
            _add(values, key[0], kind_of(dem[key]), c["A_xx_cross"])
    _, v = per_seed(values)
    est, lo, hi, n = boot(v)
    axes = [c["axis"] for c in passages.values()]
    against = sorted(k for k, c in tests.items() if c["horizontal"])
    zs = [c["z"] for c in tests.values() if np.isfinite(c["z"])]
    dofs = sorted({c["dof"] for c in tests.values()})
    return _row(
        "3", "in the DEM theta_A always passes through 90 degrees", "the paper, Sec. 4",
        f"A_xx where A_xy first changes sign ({measures.SMOOTH}-sample running mean; theta_A is 90 degrees there "
        f"if A_xx < 0, 0/180 if A_xx > 0), mean per seed over its reversals of one kind; 'always' tested on every "
        f"run: a run crossing the horizontal at family-wise {stats.ALPHA:.0%} (Holm over the runs; each run's A_xx "
        f"over the pooled seed-to-seed scatter of the other runs' crossings at the same reversal position, "
        f"Student t) contradicts it", "A_xx", 0.0, "<", est, lo, hi,
        stats.bootstrap_test_name(boot.n_resamples) + f"; Holm over {len(tests)} runs at family-wise "
        f"{stats.ALPHA:.0%}", n, SEED_UNIT,
        f"runs through 90: {axes.count('90')}; through 0/180: {axes.count('0/180')}; unclear: "
        f"{axes.count('unclear')}; no crossing: {axes.count('none')}; clear runs "
        f"{axes.count('90') + axes.count('0/180')} of {len(axes)} (each run at 2 s.d. of its tail's noise, "
        f"dem_contract.passage: reported, not decided on); crossing the horizontal at family-wise "
        f"{stats.ALPHA:.0%}: {len(against)}" + (f" ({', '.join('/'.join(k[::2]) for k in against)})" if against else "")
        + f" of {len(tests)} with a crossing (largest z {_fmt(max(zs) if zs else math.nan)}, t with "
        f"{'-'.join(map(str, dofs[::max(1, len(dofs) - 1)])) if dofs else 0} d.f.; Holm's first threshold "
        f"p <= {stats.ALPHA / max(len(tests), 1):.2g})",
        verdict="contradicted" if against else None, sd=_sd(v))


def steady_angle_row(steady: dict, boot) -> dict:
    """Claim 8 (issue 13, part 6): the DEM's steady theta_A lies where Eq. 4 (alpha2 < 0) can reach it, at or below 135 degrees."""
    cases = sorted(steady)
    th = np.array([steady[c]["theta_A"] for c in cases])
    est, lo, hi, n = boot(th)
    above = [c for c, t in zip(cases, th) if t > STEADY_LIMIT]
    return _row(
        "8", "Eq. 4 reaches the DEM's steady fabric angle (theta_A <= 135 degrees for positive shear)",
        "the paper, Eq. 4 (docs/model.md, 'Steady state')",
        "mean over seeds of the pre-shear's steady theta_A (last half of its strain, mirrored to positive shear); "
        "Eq. 4 with alpha2 < 0 has no steady state above 135 degrees", "degrees", STEADY_LIMIT, "<", est, lo, hi,
        stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"seeds above 135 degrees: {', '.join(above) if above else 'none'}; margin: "
        f"{margins.STEADY_ANGLE_DEG:g} degree", margin=margins.STEADY_ANGLE_DEG, sd=_sd(th))


# --------------------------------------------------------------------------- model comparisons (out of sample)


def _oos(runs: dict, models=MODELS):
    """Out-of-sample runs that have a DEM curve and every one of ``models``' curves; and how many lacked a model."""
    ok, missing = [], 0
    for key, cur in runs.items():
        if key[4] or "dem" not in cur:
            continue
        if all(m in cur for m in models):
            ok.append((key, cur))
        else:
            missing += 1
    return ok, missing


def _on_dem(cur, model, column):
    d, m = cur["dem"], cur[model]
    return np.interp(d["s_rev"].to_numpy(), m["s_rev"].to_numpy(), m[column].to_numpy())


def _oos_detail(pairs, missing):
    sets = sorted({k[0] for k, _ in pairs})
    return (f"{len(pairs)} out-of-sample runs from sets {', '.join(sets) if sets else 'none'}"
            + (f"; {missing} run(s) left out: a model could not be integrated" if missing else ""))


def dem_of(runs: dict) -> dict:
    """The DEM curves of ``runs`` keyed as ``inputs.dem_curves`` keys them: (case, group, protocol) -> curve."""
    out = {}
    for key, cur in runs.items():
        if "dem" in cur:
            out.setdefault((key[1], key[2], key[3]), cur["dem"])
    return out


def early_scores(runs: dict, dem: dict, column: str, window: float, models=MODELS) -> tuple:
    """Every out-of-sample run's early MSE of ``column`` per model and its DEM noise floor (``claims.ensemble``).

    Returns
    -------
    (list of dict, int)
        Per run: ``key`` (set, case, group, protocol, in_sample), ``kind``, ``floor`` (the noise floor N
        of its reversal position over the window) and ``mse`` (model -> MSE over the first ``window``
        strain); and how many runs lacked a model.
    """
    floors = ensemble.noise_floors(dem, column, window)
    pairs, missing = _oos(runs, models)
    out = []
    for key, cur in pairs:
        s, d = cur["dem"]["s_rev"].to_numpy(), cur["dem"][column].to_numpy()
        floor = floors.get((key[2], key[3]))
        out.append(dict(key=key, kind=kind_of(cur["dem"]), floor=floor.mean if floor else math.nan,
                        mse={m: early_mse(s, d, _on_dem(cur, m, column), window) for m in models}))
    return out, missing


def _per_seed_of(scores, value) -> tuple:
    """(cases, per-seed means) of ``value(run)`` over ``scores``: a seed's runs of one set averaged first."""
    values = {}
    for r in scores:
        _add(values, r["key"][1], r["key"][0], value(r))
    return per_seed(values)


def _pooled(scores, value) -> tuple:
    """(cases, per-seed values) of a pooled row: each seed's per-figure means weighted by ``margins.POOLED_WEIGHTS``
    (renormalised over the figures the seed has)."""
    per_kind = {}
    for kind in FIGURES:
        cases, v = _per_seed_of([r for r in scores if r["kind"] == kind], value)
        for c, x in zip(cases, v):
            per_kind.setdefault(c, {})[kind] = x
    cases = sorted(per_kind)
    w = margins.POOLED_WEIGHTS
    return cases, np.array([sum(w[k] * x for k, x in per_kind[c].items()) / sum(w[k] for k in per_kind[c])
                            for c in cases])


def adequacy(values, boot) -> dict:
    r"""Whether a model lies within the DEM's ensemble band, from per-seed estimates of :math:`B^2 - N`.

    ``word``: "within" if the 90 % interval of their mean lies below 0 (the model error below the DEM's
    seed-to-seed scatter at 5 %), "outside" if above 0, "undecided" otherwise or when not computed.
    """
    est, lo, hi, n = boot(values)
    word = "within" if hi < 0 else "outside" if lo > 0 else "undecided"
    return dict(word=word, estimate=est, low=lo, high=hi, n=n)


def band_adequacy(deviations, band: float, boot) -> dict:
    """Whether a model lies within the DEM's ensemble band on a scalar statistic, from per-seed deviations.

    ``deviations``: per seed, the mean over its runs of the model's value minus the DEM run's (an estimate of
    the model's bias from the ensemble's mean); ``band``: the DEM's seed-to-seed s.d. of the statistic (the
    band's half-width). "within" if the 90 % interval of the mean deviation lies inside +-band (the two
    one-sided tests at 5 %), "outside" if it lies wholly beyond +band or -band, "undecided" otherwise.
    """
    est, lo, hi, n = boot(deviations)
    ok = np.isfinite(band) and np.isfinite(lo) and np.isfinite(hi)
    word = ("within" if ok and -band < lo and hi < band else
            "outside" if ok and (lo > band or hi < -band) else "undecided")
    return dict(word=word, estimate=est, low=lo, high=hi, n=n)


def _adequacy_text(ad: dict, names) -> str:
    return "; ".join(f"{names[m]} {a['word']}" for m, a in ad.items())


def _both_fail(ad: dict) -> bool:
    return len(ad) >= 2 and all(a["word"] == "outside" for a in ad.values())


def _decide(est, lo, hi, null, side, margin, ad) -> str:
    """The row's verdict: the rule of ``stats.verdict``, or "both fail" when both models lie outside the band."""
    return "both fail" if _both_fail(ad) else stats.verdict(lo, hi, null, side, margin)


def _rms(x) -> float:
    return math.sqrt(x) if np.isfinite(x) and x > 0 else (0.0 if np.isfinite(x) else math.nan)


def model_error_rows(scores, missing, claim_id, claim, source, label, window, boot, models=MODELS,
                     pooled=True) -> list:
    r"""Claims 4 and 7 (and the pole-at-start variant): per figure, the difference of squared model errors.

    Per run :math:`\mathrm{MSE}_1 - \mathrm{MSE}_2` (``early_scores``; the first of ``models`` minus the second),
    per seed the mean over its runs of the figure's kind; the margin :math:`(f\bar\sigma)^2`
    (``margins.band_margin``); each model's adequacy from :math:`\mathrm{MSE} - 2N`; with ``pooled``, a secondary
    row over both figures (``margins.POOLED_WEIGHTS``). Row ids ``<claim_id>-step``, ``-sin``, ``-pooled``.
    """
    first, second = models
    diff = lambda r: r["mse"][first] - r["mse"][second]        # noqa: E731
    rows, figure_margins, all_sub = [], {}, []
    for kind, (suffix, words) in FIGURES.items():
        sub = [r for r in scores if r["kind"] == kind]
        if not sub:
            continue
        all_sub += sub
        floors = [r["floor"] for r in sub]
        figure_margins[kind] = margins.band_margin(floors)
        rows.append(_model_error_row(sub, diff, figure_margins[kind], floors, _per_seed_of, f"{claim_id}-{suffix}",
                                     claim, f"{source}; {words}", label, window, boot, models, missing,
                                     f"{words}: {len(sub)} runs"))
    if pooled and len(figure_margins) > 1:
        w = ", ".join(f"{FIGURES[k][1]} {margins.POOLED_WEIGHTS[k]:g}" for k in figure_margins)
        rows.append(_model_error_row(all_sub, diff, margins.pooled_margin(figure_margins),
                                     [r["floor"] for r in all_sub], _pooled, f"{claim_id}-pooled",
                                     claim + " (both figures pooled: secondary)", source, label, window, boot,
                                     models, missing, f"pooled, per seed the weighted mean of the figures ({w}: "
                                     f"margins.POOLED_WEIGHTS), margin the same weighting of theirs"))
    return rows


def _model_error_row(sub, diff, margin, floors, seeds_of, cid, claim, source, label, window, boot, models,
                     missing, scope) -> dict:
    first, second = models
    _, v = seeds_of(sub, diff)
    est, lo, hi, n = boot(v)
    ad = {m: adequacy(seeds_of(sub, lambda r, m=m: r["mse"][m] - 2.0 * r["floor"])[1], boot) for m in models}
    noise = float(np.nanmean(floors)) if np.isfinite(floors).any() else math.nan
    b2 = {m: float(np.nanmean([r["mse"][m] - r["floor"] for r in sub])) for m in models}
    edge = stats.decisive_margin(lo, hi, 0.0)
    return _row(
        cid, claim, source,
        f"squared model error of {label} over the first {window:g} strain after the reversal, {NAMES[first]} minus "
        f"{NAMES[second]}: MSE against the DEM run, paired on each run (the DEM's noise floor cancels), out of "
        f"sample, mean per seed", f"difference of squared model error of {label}", 0.0, "<", est, lo, hi,
        "paired " + stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"{scope}; RMS model error sqrt(MSE - N): {NAMES[first]} {_fmt(_rms(b2[first]))}, {NAMES[second]} "
        f"{_fmt(_rms(b2[second]))}, the DEM's ensemble band (seed-to-seed s.d. over the window) "
        f"{_fmt(_rms(noise))}; margin ({margins.BAND_FRACTION:g} x band)^2 = {_fmt(margin)}; negligible for any "
        f"margin above {_fmt(edge)} (band fraction {_fmt(margins.band_fraction_of(edge, floors))}); "
        f"{_oos_detail([(r['key'], None) for r in sub], missing)}",
        verdict=_decide(est, lo, hi, 0.0, "<", margin, ad), margin=margin, sd=_sd(v),
        adequacy=_adequacy_text(ad, NAMES) + " the DEM's ensemble band (MSE - 2N per run, 90 % interval)")


def turn_count_interval(k2: int, k1: int, n_runs: int, level: float = stats.LEVEL) -> tuple:
    r"""The widest difference of two fractions of ``n_runs`` runs (or units) that the counts k2, k1 allow at ``level``.

    Each fraction's exact interval at level :math:`1 - (1 - \mathrm{level})/2` (``stats.clopper_pearson``;
    Bonferroni over the two, so that both hold together at ``level``), then

    .. math:: [\,p_{2,lo} - p_{1,hi},\; p_{2,hi} - p_{1,lo}\,]

    Zero of 2 runs gives [-0.84, 0.84] at 90 %, zero of 80 runs [-0.045, 0.045]: a zero count bounds a
    fraction only as tightly as its number of runs does. (NaN, NaN) without runs.
    """
    if n_runs == 0:
        return math.nan, math.nan
    each = 1.0 - (1.0 - level) / 2
    _, lo2, hi2, _ = stats.clopper_pearson(k2, n_runs, each)
    _, lo1, hi1, _ = stats.clopper_pearson(k1, n_runs, each)
    return lo2 - hi1, hi2 - lo1


def turning_row(runs, dem, boot) -> dict:
    """Claim 5: Model 2's theta_A turns opposite to the DEM in some runs, Model 1's does not.

    A DEM run's axis is the family-wise one of ``crossing_tests`` (Holm over both sides of every run): a run is
    classified only where its crossing is clear at 5 % over the whole campaign; the others are left out.
    Adequacy: a model lies within the DEM's band when it turns opposite to a run no more often than another
    seed of the same reversal position does (the DEM's own disagreement, among the classified runs).

    The statistic is a difference of two fractions of few runs, often every one zero, whose per-seed bootstrap
    interval then has zero width whatever the number of runs (two clear runs would read "negligible"). The
    row's interval is therefore at least as wide as the counts allow (``turn_count_interval``), counted over
    the units the per-seed means average (a seed's runs of one kind scored by one set: a schedule's several
    reversals are one unit, as in ``per_seed``), a unit counting as turned where any of its runs turned.
    """
    pairs, missing = _oos(runs)
    tests = crossing_tests(dem)
    by_pos = {}
    for (case, group, proto), c in tests.items():
        if c["axis"] != "unclear":
            by_pos.setdefault((group, proto), {})[case] = c["axis"]
    diffs, count, n_runs, excess = {}, {m: 0 for m in MODELS}, 0, {m: {} for m in MODELS}
    turned = {m: {} for m in MODELS}   # per unit of the per-seed means (seed, set, kind): any opposite turn
    for key, cur in pairs:
        st, case, group, proto, _ = key
        ref = by_pos.get((group, proto), {}).get(case)
        if ref is None:           # an unclear DEM run counts neither way
            continue
        n_runs += 1
        others = [a for c, a in by_pos[(group, proto)].items() if c != case]
        own = float(np.mean([a != ref for a in others])) if others else math.nan
        opp, group_key = {}, (st, kind_of(cur["dem"]))   # the run's group within its seed (per_seed)
        for m in MODELS:
            c = cur[m]
            ax = measures.passage(c["s_rev"].to_numpy(), c["A_xx"].to_numpy(), c["A_xy"].to_numpy(),
                                  noisy=False)["axis"]
            opp[m] = float(ax in ("90", "0/180") and ax != ref)
            count[m] += int(opp[m])
            turned[m][(case, *group_key)] = turned[m].get((case, *group_key), False) or bool(opp[m])
            _add(excess[m], case, group_key, opp[m] - own)
        _add(diffs, case, group_key, opp["model2"] - opp["model1"])
    _, v = per_seed(diffs)
    est, lo, hi, n = boot(v)
    count_lo, count_hi = turn_count_interval(sum(turned["model2"].values()), sum(turned["model1"].values()),
                                             len(turned["model1"]))
    if np.isfinite(lo) and np.isfinite(hi):
        lo, hi = min(lo, count_lo), max(hi, count_hi)
    ad = {m: adequacy(per_seed(excess[m])[1], boot) for m in MODELS}
    return _row(
        "5", "Model 2's theta_A turns the opposite way in some cases, Model 1's does not", "the paper, Sec. 4",
        "fraction of runs in which Model 2's theta_A crosses the other axis than the DEM's (sign of A_xx where "
        "A_xy changes sign) minus the same fraction for Model 1, out of sample, per seed; a DEM run's axis counts "
        f"only where it is clear at family-wise {stats.ALPHA:.0%} over the runs (Holm), the others are left out",
        "fraction of runs", 0.0, ">", est, lo, hi,
        "paired " + stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"opposite to the DEM: Model 1 in {count['model1']} of {n_runs} runs, Model 2 in {count['model2']} of "
        f"{n_runs} (DEM runs clear at family-wise 5 %: {sum(len(x) for x in by_pos.values())} of {len(tests)}; "
        f"the Clopper-Pearson bound of the counts over {len(turned['model1'])} seed-set-kind units "
        f"[{count_lo:.3g}, {count_hi:.3g}]); "
        f"{_oos_detail(pairs, missing)}", verdict=_decide(est, lo, hi, 0.0, ">", margins.TURN_FRACTION, ad),
        margin=margins.TURN_FRACTION, sd=_sd(v),
        adequacy=_adequacy_text(ad, NAMES) + " the DEM's own disagreement between seeds (opposite turns minus "
        "the DEM's, per run, 90 % interval)")


def width_row(runs, boot) -> dict:
    """Claim 6: the sinusoidal transition of theta_A, too sharp in Model 2, closer in Model 1.

    Adequacy on the logarithm of the width (a positive scale whose misfit and seed-to-seed scatter are
    ratios: "20 times too sharp"; on the linear scale one sharp DEM seed puts the band's lower edge below
    0): ``band_adequacy`` of log(w_model / w_DEM) per run against the DEM's seed-to-seed s.d. of log w.
    """
    pairs, missing = _oos({k: v for k, v in runs.items() if "dem" in v and kind_of(v["dem"]) == "sinusoidal"})
    widths = {}
    for key, cur in pairs:
        d = cur["dem"]
        wd = measures.transition_width(d["s_rev"].to_numpy(), measures.smooth(d["A_xx"]), measures.smooth(d["A_xy"]))
        wm = {m: measures.transition_width(cur[m]["s_rev"].to_numpy(), cur[m]["A_xx"].to_numpy(),
                                           cur[m]["A_xy"].to_numpy()) for m in MODELS}
        widths[key] = dict(dem=wd, **wm)
    log_dem = {}       # one DEM width per seed and position (every set scores the same DEM run)
    for key, w in widths.items():
        if np.isfinite(w["dem"]) and w["dem"] > 0:
            log_dem.setdefault((key[2], key[3]), {})[key[1]] = math.log(w["dem"])
    ss = sum(float(((np.array(list(v.values())) - np.mean(list(v.values()))) ** 2).sum()) for v in log_dem.values())
    dof = sum(len(v) - 1 for v in log_dem.values())
    band = math.sqrt(ss / dof) if dof else math.nan
    diffs, dev = {}, {m: {} for m in MODELS}
    for key, w in widths.items():
        _add(diffs, key[1], (key[0], "sinusoidal"), abs(w["model1"] - w["dem"]) - abs(w["model2"] - w["dem"]))
        for m in MODELS:
            ok = w[m] > 0 and w["dem"] > 0
            _add(dev[m], key[1], (key[0], "sinusoidal"), math.log(w[m] / w["dem"]) if ok else math.nan)
    _, v = per_seed(diffs)
    est, lo, hi, n = boot(v)
    ad = {m: band_adequacy(per_seed(dev[m])[1], band, boot) for m in MODELS}
    mean = {k: float(np.nanmean([w[k] for w in widths.values()])) if widths else math.nan
            for k in ("dem", *MODELS)}
    sharper = sum(w["model2"] < w["dem"] for w in widths.values())
    margin = margins.width_margin([w["dem"] for w in widths.values()])
    ratio = {m: math.exp(a["estimate"]) if np.isfinite(a["estimate"]) else math.nan for m, a in ad.items()}
    return _row(
        "6", "the sinusoidal theta_A transition is too sharp in Model 2 and closer to the DEM in Model 1",
        "the paper, Sec. 4 (Fig. 5)",
        "transition width of theta_A (strain from 10 % to 90 % of its change), |Model 1 - DEM| minus "
        "|Model 2 - DEM|, sinusoidal runs out of sample, per seed", "strain", 0.0, "<", est, lo, hi,
        "paired " + stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"mean width DEM {_fmt(mean['dem'])} (seed-to-seed s.d. of log width {_fmt(band)}: a factor "
        f"{_fmt(math.exp(band) if np.isfinite(band) else math.nan)}), Model 1 {_fmt(mean['model1'])}, Model 2 "
        f"{_fmt(mean['model2'])}; model over DEM width (geometric mean over seeds): Model 1 {_fmt(ratio['model1'])}, "
        f"Model 2 {_fmt(ratio['model2'])}; Model 2 sharper than the DEM in {sharper} of {len(widths)} runs; margin: "
        f"{margins.WIDTH_FRACTION:.0%} of the DEM's width; {_oos_detail(pairs, missing)}",
        verdict=_decide(est, lo, hi, 0.0, "<", margin, ad), margin=margin, sd=_sd(v),
        adequacy=_adequacy_text(ad, NAMES) + " the DEM's ensemble band of the width (log(w / w_DEM) per run "
        "against +-1 seed-to-seed s.d. of log w_DEM, 90 % interval)")


FREEFORM_LAWS = ("freeform", "model1", "model2")


def freeform_scores(ff: pd.DataFrame, dem: dict) -> list:
    """Claim 9's runs as ``early_scores`` gives them, from ``freeform.csv``'s ``heldout`` rows.

    Each row is one held-out run's early MSE of |A| for one law (key ``<law>|<case>/<run>``; the window
    after the run's first reversal). The run's kind and noise floor are those of its reversal position in
    the comparison's DEM curves: the run itself (``train03_r2``: the calibration replays every reversal of
    a train as a run) or a protocol's first reversal (``train03`` -> ``train03_r1``).
    """
    held = ff[ff["section"] == "heldout"]
    floors = ensemble.noise_floors(dem, "A_norm", EARLY_A)
    position = {}        # (case, run) -> (group, position): the run is a position (train03_r2), or a
    for case, group, proto in dem:     # protocol whose first reversal is (train03 -> train03_r1)
        position[(case, proto)] = (group, proto)
        base, _, r = proto.partition("_r")
        if r == "1":
            position.setdefault((case, base), (group, proto))
    mse = {}
    for key, value in zip(held["key"], held["value"]):
        law, _, run = str(key).partition("|")
        case, _, proto = run.rpartition("/")
        mse.setdefault((case, proto), {})[law] = float(value)
    out = []
    for (case, proto), m in sorted(mse.items()):
        if (case, proto) not in position or not all(law in m for law in FREEFORM_LAWS):
            continue
        group, pos = position[(case, proto)]
        floor = floors.get((group, pos))
        out.append(dict(key=("leave-one-seed-out", case, group, pos, False), kind=kind_of(dem[(case, group, pos)]),
                        floor=floor.mean if floor else math.nan, mse=m))
    return out


def freeform_rows(ff: pd.DataFrame, dem: dict, boot) -> list:
    """Claims 9 and 10 from the free-form fit (``calibrate.freeform``'s ``freeform.csv`` of one calibration set).

    9: any X-dependent Eq. 4 (free-form alpha1(X), alpha2(X)) beats Model 2 on the fall of |A|: the upper
    bound of the paper's improvement; per figure on the model-error scale as claim 4 (``model_error_rows`` on
    ``freeform_scores``: leave-one-seed-out fits, paired per held-out run). 10: the data ask for a pole:
    alpha1 bends down toward the largest X visited (Model 1's c1 <= 0): the jackknife over seeds, its 95 %
    t interval of ``freeform.csv`` brought to the table's 90 % (``stats.rescaled_interval``: +-t_{n-1} s.e.).
    """
    if ff is None or "section" not in ff or not (ff["section"] == "pole").any():
        return []
    by_key = ff.set_index("key")
    b1, b2 = by_key.loc["alpha1 bend at X_hi"], by_key.loc["alpha2 bend at X_hi"]
    chosen = ff[(ff["section"] == "cv") & ff["detail"].astype(str).str.contains("chosen")]["key"]
    pen = (chosen.iloc[0].replace("penalty_", "").replace("_breaks_", ", breaks ").replace("_crowding_", ", crowding ")
           if len(chosen) else "?")
    scores = freeform_scores(ff, dem)
    rows = model_error_rows(scores, 0, "9", CLAIM9, "the paper, Sec. 3.2 (Eq. 4, 6)", "|A|", EARLY_A, boot,
                            ("freeform", "model2"))
    for r in rows:
        r["statistic"] += (f"; the free-form law (penalised splines, penalty {pen} toward the largest X by "
                           f"cross-validation) and Model 2 refitted without the run's seed, the window after the "
                           f"run's first reversal")
        r["n_unit"] = "seeds (leave-one-seed-out)"
    if not rows:
        rows = [_row("9", CLAIM9, "the paper, Sec. 3.2 (Eq. 4, 6)", "not computed: freeform.csv holds no per-run "
                     "held-out errors (section heldout)", "|A|^2", 0.0, "<", math.nan, math.nan, math.nan, "none", 0,
                     "seeds (leave-one-seed-out)", "", verdict="inconclusive")]
    n10 = int(b1["n"])
    lo10, hi10, sd10 = stats.rescaled_interval(b1["value"], b1["low"], b1["high"], n10)
    lo2, hi2, _ = stats.rescaled_interval(b2["value"], b2["low"], b2["high"], n10)
    rows.append(_row(
        "10", "the data ask for a pole: alpha1 bends toward the largest X visited (Model 1's c1 <= 0)",
        "the paper, Sec. 3.2 (Eq. 6, Fig. 3)",
        "free-form alpha1(X_hi) - alpha1(0) - alpha1'(0) X_hi, X_hi the largest X visited",
        "alpha1", 0.0, "<", b1["value"], lo10, hi10,
        f"jackknife over seeds (leave-one-seed-out fits), +-t_{n10 - 1} s.e. ({stats.LEVEL:.0%}: "
        f"{_fmt(stats.t_quantile(n10))} s.e.)", n10, "seeds",
        f"alpha2's bend (a pole with c2 >= 0 bends it up): {_fmt(b2['value'])} [{_fmt(lo2)}, {_fmt(hi2)}]; "
        f"{b1['detail']}", sd=sd10))
    return rows


# --------------------------------------------------------------------------- the table


class Bootstrap:
    """``stats.mean_interval`` (90 %) with the table's resample count and seed."""

    def __init__(self, n_resamples=stats.N_RESAMPLES, seed=0):
        self.n_resamples, self.seed = n_resamples, seed

    def __call__(self, values):
        return stats.mean_interval(values, self.n_resamples, self.seed)


def eq2_params(params_path):
    """Eq. 2's coefficients from a calibration's params.yaml (None if the file is absent)."""
    if params_path is None or not params_path.exists():
        return None
    f = load_params(params_path).friction_eq2
    return dict(X0=f.X0, k1=f.k1, k3=f.k3, k5=f.k5)


CLAIM4 = "Model 1 captures the fall of |A| just after the reversal better than Model 2"
CLAIM4_START = ("Model 1 as the paper configures it (pole at each reversal's start) captures the fall of |A| just "
                "after the reversal better than Model 2")
CLAIM7 = "Model 1's friction is better at the start of the reversal"
CLAIM9 = ("an X-dependent Eq. 4 can capture the fall of |A| better than Model 2 (upper bound of the paper's "
          "improvement)")
MODEL_START = "model1_start"


def claims_table(pred: pd.DataFrame, dem_cases: list, eq2=None, n_resamples=stats.N_RESAMPLES,
                 seed=0, freeform=None) -> pd.DataFrame:
    """Every claim's row (``COLUMNS``) from the comparison's curves and the DEM cases.

    Parameters
    ----------
    pred : DataFrame
        ``inputs.read_comparison`` (with ``claims.pole_start_claim.read_variant``'s rows of source
        ``model1_start``: adds the rows of the paper's configuration of Model 1, ``4-start-*``).
    dem_cases : list of inputs.DemCase
    eq2 : dict, optional
        Eq. 2's coefficients (``eq2_params``); row 2b is "not computed" without.
    n_resamples, seed : int
        Bootstrap resamples and their random seed.
    freeform : DataFrame, optional
        A calibration set's ``freeform.csv``: adds claims 9 and 10 (``freeform_rows``).
    """
    from .inputs import dem_curves, runs as run_curves
    boot = Bootstrap(n_resamples, seed)
    steady = {c.label: c.steady for c in dem_cases}
    dem = dem_curves(pred)
    runs = run_curves(pred)
    rows = fall_rows(dem, steady, boot)
    rows += collapse_rows(dem_cases, eq2, boot)
    rows.append(passage_row(dem, boot))
    scores, missing = early_scores(runs, dem, "A_norm", EARLY_A)
    rows += model_error_rows(scores, missing, "4", CLAIM4, "the paper, Sec. 4", "|A|", EARLY_A, boot)
    if (pred["source"] == MODEL_START).any():
        rows += model_error_rows(*early_scores(runs, dem, "A_norm", EARLY_A, (MODEL_START, "model2")), "4-start",
                                 CLAIM4_START, "the paper, Sec. 3.3 (X_c = 0.0827) and Sec. 4", "|A|", EARLY_A, boot,
                                 (MODEL_START, "model2"), pooled=False)
    rows.append(turning_row(runs, dem, boot))
    rows.append(width_row(runs, boot))
    rows += model_error_rows(*early_scores(runs, dem, "mu", EARLY_MU), "7", CLAIM7,
                             "the paper, Sec. 4 (zoom of Fig. 4c)", "mu", EARLY_MU, boot)
    rows.append(steady_angle_row(steady, boot))
    rows += freeform_rows(freeform, dem, boot)
    return pd.DataFrame(rows, columns=COLUMNS)
