r"""The statistics of the claims table and its decision rule (scipy.stats, nothing hand-written).

- ``mean_interval``: the mean of per-seed values (a paired difference is
  formed per seed first) and its 95 % interval over seeds: the percentile
  bootstrap (``scipy.stats.bootstrap``, ``N_RESAMPLES`` resamples), widened to
  the Student t interval (``scipy.stats.ttest_1samp``) where that is wider.
  With a handful of seeds the percentile bootstrap cannot reach beyond the
  range of the values (with 3 seeds all on one side, a 1-in-4 chance under no
  effect, it would exclude 0): the t interval keeps the 95 % honest there, and
  the bootstrap guards against skewed values with many seeds.
- ``clopper_pearson``: a fraction k/n and its exact binomial 95 % interval
  (``scipy.stats.binomtest(...).proportion_ci(method="exact")``).
- ``verdict``: the decision rule. Each claim has a *null* value (no effect) and
  the side of it the paper asserts (``">"`` or ``"<"``):

  * **reproduced** if the whole 95 % interval lies strictly on the paper's side
    of the null;
  * **contradicted** if it lies strictly on the other side;
  * **negligible** (issue 25) if the 90 % equivalence interval
    (``equivalence_interval``: two one-sided tests at 5 %) lies inside
    null +- the claim's margin (``claims.margins``): whatever its sign the effect
    is too small to matter. It can hold with the first two ("reproduced,
    negligible": real but too small);
  * **inconclusive** otherwise (the interval contains the null, or it could not
    be computed: too few seeds or runs).
- ``equivalence_interval``: the 90 % interval of the same per-seed mean (the
  same bootstrap, widened to the Student t interval where wider): it lies
  inside +-margin exactly when both one-sided tests at 5 % reject "the effect
  is at least the margin" (TOST, Schuirmann 1987).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from shared_stats.intervals import CONFIDENCE, N_RESAMPLES, mean_interval  # noqa: F401 (shared with calibrate)

EQUIVALENCE_CONFIDENCE = 0.90   # two one-sided tests at 5 % each
VERDICTS = ("reproduced", "contradicted", "negligible", "inconclusive")


def bootstrap_test_name(n_resamples: int = N_RESAMPLES) -> str:
    return (f"bootstrap over seeds, {n_resamples} resamples, percentile 95 % interval "
            f"(widened to the Student t interval where wider)")


def equivalence_interval(values, n_resamples: int = N_RESAMPLES, seed: int = 0):
    r"""The 90 % interval of the mean of per-seed values: two one-sided tests at 5 % (TOST).

    The interval of ``mean_interval`` at ``EQUIVALENCE_CONFIDENCE``: the
    percentile bootstrap of the same resamples (the same ``seed``) widened to
    the Student t interval

    .. math:: \hat\mu \pm t_{0.95,\,n-1}\, s/\sqrt n

    where wider. The effect is declared smaller than a margin :math:`m` at 5 %
    when the interval lies inside :math:`(-m, m)` about the null (both one-sided
    tests reject, Schuirmann 1987).

    Returns
    -------
    (float, float)
        Low, high; NaN with fewer than 2 finite values.
    """
    d = np.asarray(values, float)
    d = d[np.isfinite(d)]
    if d.size < 2:
        return math.nan, math.nan
    est = float(d.mean())
    if np.all(d == d[0]):
        return est, est
    res = stats.bootstrap((d,), np.mean, n_resamples=n_resamples, confidence_level=EQUIVALENCE_CONFIDENCE,
                          method="percentile", vectorized=True, rng=np.random.default_rng(seed))
    ci = res.confidence_interval
    t = stats.ttest_1samp(d, 0.0).confidence_interval(confidence_level=EQUIVALENCE_CONFIDENCE)
    return float(min(ci.low, t.low)), float(max(ci.high, t.high))


def clopper_pearson(k: int, n: int):
    r"""Fraction k/n and its exact (Clopper-Pearson) 95 % interval.

    The bounds are the Beta quantiles

    .. math:: p_{lo} = B(0.025;\ k,\ n - k + 1), \qquad p_{hi} = B(0.975;\ k + 1,\ n - k)

    (``scipy.stats.binomtest(k, n).proportion_ci(method="exact")``).

    Returns
    -------
    (float, float, float, int)
        Estimate, low, high, n (NaN for n = 0).
    """
    if n == 0:
        return math.nan, math.nan, math.nan, 0
    ci = stats.binomtest(int(k), int(n)).proportion_ci(confidence_level=CONFIDENCE, method="exact")
    return k / n, float(ci.low), float(ci.high), int(n)


def negligible(eq_low: float, eq_high: float, null: float, margin: float) -> bool:
    """True when the equivalence interval lies strictly inside ``null`` +- ``margin`` (False if any is NaN)."""
    if not all(np.isfinite(v) for v in (eq_low, eq_high, null, margin)) or margin <= 0:
        return False
    return bool(null - margin < eq_low and eq_high < null + margin)


def verdict(low: float, high: float, null: float, side: str, eq_low: float = math.nan, eq_high: float = math.nan,
            margin: float = math.nan) -> str:
    """The decision rule of the module docstring.

    Parameters
    ----------
    low, high : float
        The 95 % interval of the statistic.
    null : float
        The value of no effect.
    side : {">", "<"}
        Where the paper puts the statistic with respect to ``null``.
    eq_low, eq_high : float, optional
        The 90 % equivalence interval (``equivalence_interval``).
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
    small = negligible(eq_low, eq_high, null, margin)
    sided = "inconclusive"
    if np.isfinite(low) and np.isfinite(high):
        above, below = low > null, high < null
        if (above and side == ">") or (below and side == "<"):
            sided = "reproduced"
        elif above or below:
            sided = "contradicted"
    if small:
        return "negligible" if sided == "inconclusive" else f"{sided}, negligible"
    return sided


def verdict_counts(verdicts) -> dict:
    """How many verdicts say each of ``VERDICTS`` ("reproduced, negligible" counts for both)."""
    parts = [p.strip() for v in verdicts for p in str(v).split(",")]
    return {v: parts.count(v) for v in VERDICTS}
