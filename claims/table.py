r"""The claims table: one row per claim of the paper, each with its statistic, interval, test and verdict.

Columns (``COLUMNS``): ``claim_id``, ``claim`` (the paper's words, shortened),
``source`` (the paper's section or figure), ``statistic`` (what is measured),
``unit``, ``null`` (the value of no effect), ``paper_side`` (``>`` or ``<``:
where the paper puts the statistic), ``estimate``, ``low``, ``high`` (95 %
interval), ``margin`` (the smallest effect that matters, ``claims.margins``;
NaN where the claim compares no two models), ``eq_low``, ``eq_high`` (the
90 % equivalence interval: two one-sided tests at 5 %), ``sd`` (the
seed-to-seed standard deviation of the per-seed values: the planner's input),
``test``, ``n`` and ``n_unit`` (what was counted), ``verdict`` and ``detail``
(the numbers behind it).

Decision rule (``claims.stats.verdict``): **reproduced** if the 95 % interval
lies strictly on the paper's side of the null, **contradicted** if strictly on
the other side, **negligible** if the equivalence interval lies inside
null +- margin (with the first two: "reproduced, negligible", a real effect too
small to matter), **inconclusive** otherwise (also when it cannot be computed).
The one addition: "theta_A *always* passes through 90 degrees" is also
contradicted by a single run that clearly crosses the horizontal.

Units of resampling. Every interval (``stats.mean_interval``: percentile
bootstrap, at least as wide as the Student t interval) is over seeds (DEM cases: one pre-shear
and its reversal runs), pooled across ensembles (pressures and inertial
numbers; the claims are made for every ensemble): a seed's value is the mean
over its runs (protocols) and, for the model comparisons, over the calibration
sets that did not see the run. Every reversal of every protocol is a run; a
seed's reversals of one kind (Heaviside step, half cosine: the ``kind`` of
``predictions.csv``; for the model comparisons, scored by one set) are averaged
first, so a schedule's several reversals weigh as one run of their kind
(``per_seed``). Model comparisons use only out-of-sample
predictions: a run is scored with a set calibrated on another protocol (e.g.
``heaviside_only`` scored on the sinusoidal run) or another inertial number
(``I<a>`` scored on the runs at ``I<b>``), and the two models are paired on
the same run (difference per run, then per seed).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from model import friction_eq2, load_params

from . import margins, measures, stats

COLUMNS = ["claim_id", "claim", "source", "statistic", "unit", "null", "paper_side", "estimate", "low", "high",
           "margin", "eq_low", "eq_high", "sd", "test", "n", "n_unit", "verdict", "detail"]
MODELS = ("model1", "model2")
EARLY_A = 0.1      # strain window of the fall of |A| (the paper: "just after the reversal")
EARLY_MU = 0.05    # strain window of the start of the reversal for mu
EQ2_MARGIN = 1.1   # Eq. 2 counts as capturing the collapse if its scatter is within 10 % of the best curve's
STEADY_LIMIT = 135.0
SEED_UNIT = "seeds (pooled across ensembles)"


def _row(claim_id, claim, source, statistic, unit, null, side, est, low, high, test, n, n_unit, detail,
         verdict=None, margin=math.nan, eq=(math.nan, math.nan), sd=math.nan):
    return dict(claim_id=claim_id, claim=claim, source=source, statistic=statistic, unit=unit, null=null,
                paper_side=side, estimate=est, low=low, high=high, margin=margin, eq_low=eq[0], eq_high=eq[1],
                sd=sd, test=test, n=n, n_unit=n_unit,
                verdict=verdict or stats.verdict(low, high, null, side, eq[0], eq[1], margin), detail=detail)


def _spread(boot, values) -> dict:
    """The equivalence interval (``eq``) and seed-to-seed s.d. (``sd``) of per-seed values, as ``_row`` takes them."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return dict(eq=boot.equivalence(v), sd=float(np.std(v, ddof=1)) if v.size >= 2 else math.nan)


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


def _kind(curve: pd.DataFrame) -> str:
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
            _add(excess, case, _kind(d), f["excess"])
            _add(depth, case, _kind(d), f["depth"])
            _add(s_min, case, _kind(d), f["s_min"])
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
            f"[{_fmt(sm_lo)}, {_fmt(sm_hi)}] (strain since the reversal)", sd=_spread(boot, e)["sd"]))
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
        sd=_spread(boot, ratio_axy)["sd"]))
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
        stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT, "", sd=_spread(boot, ratio_eq2)["sd"]))
    return rows


def dem_passages(dem: dict) -> dict:
    """Which axis each DEM run's theta_A turns through (``dem_contract.passage``): the curve key of
    ``inputs.dem_curves`` (case, group, protocol) -> its ``passage`` dict."""
    return {key: measures.passage(d["s_rev"].to_numpy(), d["A_xx"].to_numpy(), d["A_xy"].to_numpy(), noisy=True)
            for key, d in dem.items()}


def passage_row(dem: dict, boot) -> dict:
    r"""Claim 3: in the DEM theta_A always passes through 90 degrees.

    Statistic: A_xx at the first sign change of A_xy (``dem_contract.passage``, the DEM smoothed), averaged per
    seed over its reversals of one kind (``per_seed``), mean over seeds with its interval. Reproduced when the
    interval lies below 0 and no run crosses clearly through 0/180; contradicted when it lies above 0 or one run
    clearly crosses the horizontal ('always'); a run too close to isotropic to call (unclear) counts neither way:
    its A_xx enters its seed's mean with its own small weight, and it is no counter-example.
    """
    values, axes = {}, []
    for (case, *_), c in zip(dem, dem_passages(dem).values()):
        axes.append(c["axis"])
        if c["axis"] != "none":
            _add(values, case, _kind(dem[(case, *_)]), c["A_xx_cross"])
    _, v = per_seed(values)
    est, lo, hi, n = boot(v)
    against = axes.count("0/180")
    clear = axes.count("90") + against
    frac, f_lo, f_hi, n_runs = stats.clopper_pearson(clear, len(axes))
    return _row(
        "3", "in the DEM theta_A always passes through 90 degrees", "the paper, Sec. 4",
        f"A_xx where A_xy first changes sign ({measures.SMOOTH}-sample running mean; theta_A is 90 degrees there "
        f"if A_xx < 0, 0/180 if A_xx > 0), mean per seed over its reversals of one kind; a run clearly crossing "
        f"the horizontal (A_xx > {measures.Z_CLEAR:g} noise s.d.) contradicts 'always'; unclear runs count "
        f"neither way", "A_xx", 0.0, "<", est, lo, hi, stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"runs through 90: {axes.count('90')}; through 0/180: {against}; unclear: {axes.count('unclear')}; no "
        f"crossing: {axes.count('none')}; clear runs {clear} of {n_runs} ({_fmt(frac)} [{_fmt(f_lo)}, "
        f"{_fmt(f_hi)}])", verdict="contradicted" if against else None, sd=_spread(boot, v)["sd"])


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
        f"{margins.STEADY_ANGLE_DEG:g} degree", margin=margins.STEADY_ANGLE_DEG, **_spread(boot, th))


# --------------------------------------------------------------------------- model comparisons (out of sample)


def _oos(runs: dict):
    """Out-of-sample runs that have a DEM curve and both models' curves; and how many lacked a model."""
    ok, missing = [], 0
    for key, cur in runs.items():
        if key[4] or "dem" not in cur:
            continue
        if all(m in cur for m in MODELS):
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


def early_error_differences(runs, column, window):
    """Claims 4 and 7's paired differences: per case, the out-of-sample runs' RMSE, Model 1 minus Model 2.

    Returns
    -------
    (dict, dict, list, int)
        case -> (set, kind) -> differences of its runs (``per_seed`` makes the per-seed means: a
        seed's reversals of one kind scored by one set averaged first), model -> RMSE of every
        run, the out-of-sample (key, curves) pairs and how many runs lacked a model (``_oos``).
    """
    pairs, missing = _oos(runs)
    diffs, r = {}, {m: [] for m in MODELS}
    for key, cur in pairs:
        s, d = cur["dem"]["s_rev"].to_numpy(), cur["dem"][column].to_numpy()
        e = {m: measures.early_rmse(s, d, _on_dem(cur, m, column), window) for m in MODELS}
        for m in MODELS:
            r[m].append(e[m])
        _add(diffs, key[1], (key[0], _kind(cur["dem"])), e["model1"] - e["model2"])
    return diffs, r, pairs, missing


def early_error_row(runs, claim_id, claim, source, column, label, window, boot) -> dict:
    """Claims 4 and 7: RMSE over the first ``window`` strain, Model 1 minus Model 2, paired per run."""
    diffs, r, pairs, missing = early_error_differences(runs, column, window)
    _, v = per_seed(diffs)
    est, lo, hi, n = boot(v)
    margin = margins.fall_margin(pairs, column)
    return _row(
        claim_id, claim, source,
        f"RMSE of {label} over the first {window:g} strain after the reversal, Model 1 minus Model 2, out of "
        f"sample, paired on each run, mean per seed", f"difference of RMSE of {label} (dimensionless)", 0.0, "<",
        est, lo, hi,
        "paired " + stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"mean RMSE Model 1 {_fmt(np.nanmean(r['model1']) if pairs else math.nan)}, Model 2 "
        f"{_fmt(np.nanmean(r['model2']) if pairs else math.nan)}; margin: {margins.FALL_FRACTION:.0%} of the DEM's "
        f"fall of {label}, {_fmt(margin / margins.FALL_FRACTION)}; {_oos_detail(pairs, missing)}",
        margin=margin, **_spread(boot, v))


def turning_row(runs, boot) -> dict:
    """Claim 5: Model 2's theta_A turns opposite to the DEM in some runs, Model 1's does not."""
    pairs, missing = _oos(runs)
    diffs, count, n_runs = {}, {m: 0 for m in MODELS}, 0
    for key, cur in pairs:
        d = cur["dem"]
        ref = measures.passage(d["s_rev"].to_numpy(), d["A_xx"].to_numpy(), d["A_xy"].to_numpy(), noisy=True)["axis"]
        if ref not in ("90", "0/180"):     # an unclear DEM run counts neither way
            continue
        n_runs += 1
        opp = {}
        for m in MODELS:
            c = cur[m]
            ax = measures.passage(c["s_rev"].to_numpy(), c["A_xx"].to_numpy(), c["A_xy"].to_numpy(),
                                  noisy=False)["axis"]
            opp[m] = float(ax in ("90", "0/180") and ax != ref)
            count[m] += int(opp[m])
        _add(diffs, key[1], (key[0], _kind(d)), opp["model2"] - opp["model1"])
    _, v = per_seed(diffs)
    est, lo, hi, n = boot(v)
    return _row(
        "5", "Model 2's theta_A turns the opposite way in some cases, Model 1's does not", "the paper, Sec. 4",
        "fraction of runs in which Model 2's theta_A crosses the other axis than the DEM's (sign of A_xx where "
        "A_xy changes sign) minus the same fraction for Model 1, out of sample, per seed; runs whose DEM crossing "
        "is unclear are left out", "fraction of runs", 0.0, ">", est, lo, hi,
        "paired " + stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"opposite to the DEM: Model 1 in {count['model1']} of {n_runs} runs, Model 2 in {count['model2']} of "
        f"{n_runs}; {_oos_detail(pairs, missing)}", margin=margins.TURN_FRACTION, **_spread(boot, v))


def width_row(runs, boot) -> dict:
    """Claim 6: the sinusoidal transition of theta_A, too sharp in Model 2, closer in Model 1."""
    pairs, missing = _oos({k: v for k, v in runs.items() if "dem" in v and _kind(v["dem"]) == "sinusoidal"})
    diffs, w = {}, {"dem": [], "model1": [], "model2": []}
    for key, cur in pairs:
        d = cur["dem"]
        wd = measures.transition_width(d["s_rev"].to_numpy(), measures.smooth(d["A_xx"]), measures.smooth(d["A_xy"]))
        wm = {m: measures.transition_width(cur[m]["s_rev"].to_numpy(), cur[m]["A_xx"].to_numpy(),
                                           cur[m]["A_xy"].to_numpy()) for m in MODELS}
        w["dem"].append(wd)
        for m in MODELS:
            w[m].append(wm[m])
        _add(diffs, key[1], (key[0], "sinusoidal"), abs(wm["model1"] - wd) - abs(wm["model2"] - wd))
    _, v = per_seed(diffs)
    est, lo, hi, n = boot(v)
    mean = {k: np.nanmean(x) if np.isfinite(x).any() else math.nan for k, x in ((k, np.asarray(x, float))
                                                                               for k, x in w.items())}
    sharper = int(np.sum(np.asarray(w["model2"]) < np.asarray(w["dem"])))
    return _row(
        "6", "the sinusoidal theta_A transition is too sharp in Model 2 and closer to the DEM in Model 1",
        "the paper, Sec. 4 (Fig. 5)",
        "transition width of theta_A (strain from 10 % to 90 % of its change), |Model 1 - DEM| minus "
        "|Model 2 - DEM|, sinusoidal runs out of sample, per seed", "strain", 0.0, "<", est, lo, hi,
        "paired " + stats.bootstrap_test_name(boot.n_resamples), n, SEED_UNIT,
        f"mean width DEM {_fmt(mean['dem'])}, Model 1 {_fmt(mean['model1'])}, Model 2 {_fmt(mean['model2'])}; "
        f"Model 2 sharper than the DEM in {sharper} of {len(pairs)} runs; margin: "
        f"{margins.WIDTH_FRACTION:.0%} of the DEM's width; {_oos_detail(pairs, missing)}",
        margin=margins.width_margin(w["dem"]), **_spread(boot, v))


def _from_interval(value, low, high, n) -> dict:
    r"""Equivalence interval and s.d. per seed of a row given only as a value and its 95 % interval.

    Normal scaling: :math:`\hat\mu \pm (z_{0.95}/z_{0.975})\,h` with :math:`h` each half-width, and
    :math:`s = (high - low)\sqrt n / (2 z_{0.975})`.
    """
    from scipy.stats import norm
    k = norm.ppf(0.95) / norm.ppf(0.975)
    sd = (high - low) * math.sqrt(n) / (2.0 * norm.ppf(0.975)) if n >= 2 else math.nan
    return dict(eq=(value - k * (value - low), value + k * (high - value)), sd=float(sd))


def freeform_rows(ff: pd.DataFrame, margin: float = math.nan) -> list:
    """Claims 9 and 10 from the free-form fit (``calibrate.freeform``'s ``freeform.csv`` of one calibration set).

    9: any X-dependent Eq. 4 (free-form alpha1(X), alpha2(X)) beats Model 2 on the fall of |A|: the upper
    bound of the paper's improvement. 10: the data ask for a pole: alpha1 bends down toward the largest X
    visited (Model 1's c1 <= 0). Both from leave-one-seed-out fits, paired per held-out run (``freeform.csv``).
    ``margin``: claim 9's (claim 4's: ``margins.fall_margin`` of |A|); its equivalence interval is the 95 %
    interval of ``freeform.csv`` scaled to 90 % (``_from_interval``).
    """
    if ff is None or "section" not in ff or not (ff["section"] == "difference").any():
        return []
    by_key = ff.set_index("key")
    up = by_key.loc["early_A_norm: freeform - model2"]
    m1 = by_key.loc["early_A_norm: model1 - model2"]
    b1, b2 = by_key.loc["alpha1 bend at X_hi"], by_key.loc["alpha2 bend at X_hi"]
    chosen = ff[(ff["section"] == "cv") & ff["detail"].astype(str).str.contains("chosen")]["key"]
    pen = (chosen.iloc[0].replace("penalty_", "").replace("_breaks_", ", breaks ").replace("_crowding_", ", crowding ")
           if len(chosen) else "?")
    return [
        _row("9", "an X-dependent Eq. 4 can capture the fall of |A| better than Model 2 (upper bound of the "
             "paper's improvement)", "the paper, Sec. 3.2 (Eq. 4, 6)",
             f"RMSE of |A| over the first {EARLY_A:g} strain after the reversal, free-form alpha1(X), alpha2(X) "
             "(penalised splines) minus Model 2, leave-one-seed-out, paired per run, mean per seed",
             "|A|", 0.0, "<", up["value"], up["low"], up["high"],
             "paired " + stats.bootstrap_test_name(), int(up["n"]), "seeds (leave-one-seed-out)",
             f"Model 1 - Model 2 on the same runs {_fmt(m1['value'])} [{_fmt(m1['low'])}, {_fmt(m1['high'])}]; "
             f"penalty {pen} (toward the largest X) by cross-validation; margin: claim 4's; 90 % interval: "
             f"the 95 % one scaled (normal)", margin=margin,
             **_from_interval(up["value"], up["low"], up["high"], int(up["n"]))),
        _row("10", "the data ask for a pole: alpha1 bends toward the largest X visited (Model 1's c1 <= 0)",
             "the paper, Sec. 3.2 (Eq. 6, Fig. 3)",
             "free-form alpha1(X_hi) - alpha1(0) - alpha1'(0) X_hi, X_hi the largest X visited",
             "alpha1", 0.0, "<", b1["value"], b1["low"], b1["high"],
             "jackknife over seeds (leave-one-seed-out fits), +-1.96 s.e.", int(b1["n"]), "seeds",
             f"alpha2's bend (a pole with c2 >= 0 bends it up): {_fmt(b2['value'])} [{_fmt(b2['low'])}, "
             f"{_fmt(b2['high'])}]; {b1['detail']}", sd=_from_interval(b1["value"], b1["low"], b1["high"],
                                                                      int(b1["n"]))["sd"]),
    ]


# --------------------------------------------------------------------------- the table


class Bootstrap:
    """``stats.mean_interval`` with the table's resample count and seed."""

    def __init__(self, n_resamples=stats.N_RESAMPLES, seed=0):
        self.n_resamples, self.seed = n_resamples, seed

    def __call__(self, values):
        return stats.mean_interval(values, self.n_resamples, self.seed)

    def equivalence(self, values):
        """The 90 % equivalence interval of the same resamples (``stats.equivalence_interval``)."""
        return stats.equivalence_interval(values, self.n_resamples, self.seed)


def eq2_params(params_path):
    """Eq. 2's coefficients from a calibration's params.yaml (None if the file is absent)."""
    if params_path is None or not params_path.exists():
        return None
    f = load_params(params_path).friction_eq2
    return dict(X0=f.X0, k1=f.k1, k3=f.k3, k5=f.k5)


def claims_table(pred: pd.DataFrame, dem_cases: list, eq2=None, n_resamples=stats.N_RESAMPLES,
                 seed=0, freeform=None) -> pd.DataFrame:
    """Every claim's row (``COLUMNS``) from the comparison's curves and the DEM cases.

    Parameters
    ----------
    pred : DataFrame
        ``inputs.read_comparison``.
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
    rows.append(early_error_row(runs, "4", "Model 1 captures the fall of |A| just after the reversal better than "
                                "Model 2", "the paper, Sec. 4 (Figs. 4, 5)", "A_norm", "|A|", EARLY_A, boot))
    rows.append(turning_row(runs, boot))
    rows.append(width_row(runs, boot))
    rows.append(early_error_row(runs, "7", "Model 1's friction is better at the start of the reversal",
                                "the paper, Sec. 4 (zoom of Fig. 4c)", "mu", "mu", EARLY_MU, boot))
    rows.append(steady_angle_row(steady, boot))
    rows += freeform_rows(freeform, margins.fall_margin(_oos(runs)[0], "A_norm"))
    return pd.DataFrame(rows, columns=COLUMNS)
