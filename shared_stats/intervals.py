r"""The mean of per-seed values and its interval over seeds (95 % unless asked), shared by calibrate and claims.

The percentile bootstrap (``scipy.stats.bootstrap``, ``N_RESAMPLES`` resamples),
widened to the Student t interval (``scipy.stats.ttest_1samp``) where that is
wider: with a handful of seeds the percentile bootstrap cannot reach beyond the
range of the values, the t interval keeps the 95 % honest there, and the
bootstrap guards against skewed values with many seeds. The claims table
(``claims.stats``) decides its verdicts on it; the free-form calibration
(``calibrate.freeform``) reports its cross-validated gains with it.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

N_RESAMPLES = 2000
CONFIDENCE = 0.95


def mean_interval(values, n_resamples: int = N_RESAMPLES, seed: int = 0, confidence: float = CONFIDENCE):
    r"""Mean of per-seed values and its interval over seeds (bootstrap, at least the t interval).

    .. math:: \hat\mu = \frac1n \sum_i d_i, \qquad
              [\min(\hat\mu^*_{(a)},\ \hat\mu - t s/\sqrt n),\
               \max(\hat\mu^*_{(1-a)},\ \hat\mu + t s/\sqrt n)]

    with :math:`a = (1 - c)/2` for the ``confidence`` :math:`c` (95 % by
    default: calibrate's intervals; the claims table asks for 90 %),
    :math:`\hat\mu^*` the means of ``n_resamples`` resamples (with
    replacement) of the :math:`n` seeds, :math:`s` their standard deviation
    and :math:`t = t_{1-a,\,n-1}`.

    Parameters
    ----------
    values : array_like
        One value per seed (NaN values are dropped).
    n_resamples : int
    seed : int
        Seeds the resampling (the table is reproducible).
    confidence : float
        Two-sided level of the interval.

    Returns
    -------
    (float, float, float, int)
        Estimate, low, high, n. The interval is NaN with fewer than 2 values.
    """
    d = np.asarray(values, float)
    d = d[np.isfinite(d)]
    n = int(d.size)
    if n == 0:
        return math.nan, math.nan, math.nan, 0
    est = float(d.mean())
    if n < 2:
        return est, math.nan, math.nan, n
    if np.all(d == d[0]):   # every resample has the same mean: a zero-width interval
        return est, est, est, n
    res = stats.bootstrap((d,), np.mean, n_resamples=n_resamples, confidence_level=confidence,
                          method="percentile", vectorized=True, rng=np.random.default_rng(seed))
    ci = res.confidence_interval
    t = stats.ttest_1samp(d, 0.0).confidence_interval(confidence_level=confidence)
    return est, float(min(ci.low, t.low)), float(max(ci.high, t.high)), n
