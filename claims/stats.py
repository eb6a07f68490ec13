r"""The statistics of the claims table and its decision rule (scipy.stats, nothing hand-written).

One level (issue 32). Every interval of the table is the two-sided **90 %**
interval of its statistic, and every verdict is a one-sided test at **5 %**
read off that one interval:

- direction: the paper asserts a side of a null (no effect); the interval
  lying wholly on that side rejects "no effect or the other side" at 5 %
  one-sided (the paper's claims are one-sided: "better", "falls", "below");
- equivalence: the interval lying inside null +- the claim's margin
  (``claims.margins``) rejects both "the effect is at least +margin" and
  "at most -margin" at 5 % each: the two one-sided tests (TOST, Schuirmann
  1987) use the same 90 % interval.

So a verdict's words always match the interval printed beside it; with two
levels (a 95 % interval for the direction, 90 % for equivalence) an interval
wholly on one side could read "negligible, whatever its sign". The level is
5 % per claim; the table does not correct across its rows (each row answers
its own claim of the paper), it does correct within a row that tests a claim
on every run ("always": ``holm``).

- ``mean_interval``: the mean of per-seed values (a paired difference is
  formed per seed first) and its 90 % interval over seeds: the percentile
  bootstrap (``scipy.stats.bootstrap``, ``N_RESAMPLES`` resamples), widened to
  the Student t interval (``scipy.stats.ttest_1samp``) where that is wider
  (with a handful of seeds the t interval; the table never has 30).
- ``t_interval``: an estimate +- t_{n-1} standard errors (the jackknife of
  claim 10), ``rescaled_interval``: a 95 % t-based interval of ``n`` seeds
  brought to this level by the ratio of the t quantiles.
- ``clopper_pearson``: a fraction k/n and its exact binomial interval.
- ``holm``: Holm's step-down rejections of per-run one-sided p-values: the
  chance of one false rejection stays at most ``ALPHA`` whatever the number
  of runs.
- ``verdict``: the decision rule. **reproduced** if the interval lies strictly
  on the paper's side of the null, **contradicted** if strictly on the other,
  **negligible** if inside null +- margin (with one of the first two:
  "reproduced, negligible", a real effect too small to matter),
  **inconclusive** otherwise (also when it could not be computed). A
  comparison of two models whose both lie outside the DEM's ensemble band
  reads **both fail** (``claims.table``, ``adequacy``).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from shared_stats.intervals import N_RESAMPLES, mean_interval as _mean_interval

LEVEL = 0.90          # every interval of the table, two-sided
ALPHA = 0.05          # every test: one-sided, (1 - LEVEL) / 2
VERDICTS = ("reproduced", "contradicted", "negligible", "inconclusive", "both fail")


def bootstrap_test_name(n_resamples: int = N_RESAMPLES) -> str:
    return (f"bootstrap over seeds, {n_resamples} resamples, percentile {LEVEL:.0%} interval "
            f"(widened to the Student t interval where wider); one-sided tests at {ALPHA:.0%}")


def mean_interval(values, n_resamples: int = N_RESAMPLES, seed: int = 0):
    """``shared_stats.mean_interval`` at the table's ``LEVEL``: (estimate, low, high, n)."""
    return _mean_interval(values, n_resamples, seed, confidence=LEVEL)


def t_quantile(n: int, level: float = LEVEL) -> float:
    """:math:`t_{(1+level)/2,\\,n-1}` (NaN for n < 2)."""
    return float(stats.t.ppf(0.5 + level / 2.0, n - 1)) if n >= 2 else math.nan


def t_interval(estimate: float, se: float, n: int, level: float = LEVEL):
    r"""(low, high) = :math:`\hat\theta \pm t_{(1+level)/2,\,n-1}\ \mathrm{se}` (a jackknife's over ``n`` seeds)."""
    h = t_quantile(n, level) * se
    return float(estimate - h), float(estimate + h)


def rescaled_interval(estimate: float, low: float, high: float, n: int, from_level: float = 0.95,
                      to_level: float = LEVEL):
    r"""A t-based interval of ``n`` seeds at ``from_level`` brought to ``to_level``: each half-width times
    :math:`t_{(1+to)/2,\,n-1} / t_{(1+from)/2,\,n-1}`; and the seed-to-seed s.d. it implies,
    :math:`s = (high - low)\sqrt n / (2\, t_{(1+from)/2,\,n-1})`.

    Returns
    -------
    (float, float, float)
        Low, high, s.d. (NaN for n < 2).
    """
    if n < 2:
        return math.nan, math.nan, math.nan
    t_from, t_to = t_quantile(n, from_level), t_quantile(n, to_level)
    k = t_to / t_from
    sd = (high - low) * math.sqrt(n) / (2.0 * t_from)
    return float(estimate - k * (estimate - low)), float(estimate + k * (high - estimate)), float(sd)


def clopper_pearson(k: int, n: int, level: float = LEVEL):
    r"""Fraction k/n and its exact (Clopper-Pearson) interval.

    The bounds are the Beta quantiles

    .. math:: p_{lo} = B(a;\ k,\ n - k + 1), \qquad p_{hi} = B(1 - a;\ k + 1,\ n - k), \quad a = (1 - level)/2

    (``scipy.stats.binomtest(k, n).proportion_ci(method="exact")``).

    Returns
    -------
    (float, float, float, int)
        Estimate, low, high, n (NaN for n = 0).
    """
    if n == 0:
        return math.nan, math.nan, math.nan, 0
    ci = stats.binomtest(int(k), int(n)).proportion_ci(confidence_level=level, method="exact")
    return k / n, float(ci.low), float(ci.high), int(n)


def holm(pvalues, alpha: float = ALPHA) -> np.ndarray:
    r"""Holm's step-down rejections: sort the :math:`m` p-values, reject while :math:`p_{(j)} \le \alpha/(m - j + 1)`.

    The chance of rejecting at least one true hypothesis is at most ``alpha`` under any
    dependence between them (Holm 1979). NaN p-values are never rejected but count in
    :math:`m` (conservative).

    Returns
    -------
    ndarray of bool
        Rejected, in the order given.
    """
    p = np.asarray(pvalues, float)
    m = p.size
    out = np.zeros(m, bool)
    order = np.argsort(np.where(np.isfinite(p), p, np.inf), kind="stable")
    for j, i in enumerate(order):
        if not (np.isfinite(p[i]) and p[i] <= alpha / (m - j)):
            break
        out[i] = True
    return out


def negligible(low: float, high: float, null: float, margin: float) -> bool:
    """True when the interval lies strictly inside ``null`` +- ``margin`` (False if any is NaN)."""
    if not all(np.isfinite(v) for v in (low, high, null, margin)) or margin <= 0:
        return False
    return bool(null - margin < low and high < null + margin)


def verdict(low: float, high: float, null: float, side: str, margin: float = math.nan) -> str:
    """The decision rule of the module docstring, on the one 90 % interval.

    Parameters
    ----------
    low, high : float
        The 90 % interval of the statistic.
    null : float
        The value of no effect.
    side : {">", "<"}
        Where the paper puts the statistic with respect to ``null``.
    margin : float, optional
        The smallest effect that matters (``claims.margins``); NaN: the claim has none.

    Returns
    -------
    str
        "reproduced", "contradicted", "negligible", "inconclusive", or
        "reproduced, negligible" / "contradicted, negligible" (a real effect too small to matter).
    """
    if side not in (">", "<"):
        raise ValueError(f"verdict: side {side!r} must be '>' or '<'")
    sided = "inconclusive"
    if np.isfinite(low) and np.isfinite(high):
        above, below = low > null, high < null
        if (above and side == ">") or (below and side == "<"):
            sided = "reproduced"
        elif above or below:
            sided = "contradicted"
    if negligible(low, high, null, margin):
        return "negligible" if sided == "inconclusive" else f"{sided}, negligible"
    return sided


def decisive_margin(low: float, high: float, null: float) -> float:
    """The smallest margin at which the interval reads "negligible": max(|low - null|, |high - null|).

    A verdict "negligible" holds for every margin above it, none below: the knife edge a reader checks.
    """
    if not (np.isfinite(low) and np.isfinite(high)):
        return math.nan
    return float(max(abs(low - null), abs(high - null)))


def verdict_counts(verdicts) -> dict:
    """How many verdicts say each of ``VERDICTS`` ("reproduced, negligible" counts for both)."""
    parts = [p.strip() for v in verdicts for p in str(v).split(",")]
    return {v: parts.count(v) for v in VERDICTS}
