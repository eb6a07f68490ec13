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
  * **inconclusive** otherwise (the interval contains the null, or it could not
    be computed: too few seeds or runs).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from shared_stats.intervals import CONFIDENCE, N_RESAMPLES, mean_interval  # noqa: F401 (shared with calibrate)

VERDICTS = ("reproduced", "contradicted", "inconclusive")


def bootstrap_test_name(n_resamples: int = N_RESAMPLES) -> str:
    return (f"bootstrap over seeds, {n_resamples} resamples, percentile 95 % interval "
            f"(widened to the Student t interval where wider)")


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


def verdict(low: float, high: float, null: float, side: str) -> str:
    """The decision rule of the module docstring.

    Parameters
    ----------
    low, high : float
        The 95 % interval of the statistic.
    null : float
        The value of no effect.
    side : {">", "<"}
        Where the paper puts the statistic with respect to ``null``.
    """
    if side not in (">", "<"):
        raise ValueError(f"verdict: side {side!r} must be '>' or '<'")
    if not (np.isfinite(low) and np.isfinite(high)):
        return "inconclusive"
    above, below = low > null, high < null
    if (above and side == ">") or (below and side == "<"):
        return "reproduced"
    if above or below:
        return "contradicted"
    return "inconclusive"
