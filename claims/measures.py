r"""Per-run measures behind the claims: falls, crossings, transition widths, early errors, the collapse.

All take the curves of one reversal run against ``s`` (strain travelled since
the reversal, the ``s_rev`` of ``predictions.csv``). DEM curves are first
smoothed by a centred running mean of ``SMOOTH`` samples (its per-sample noise
would otherwise set the minima and the crossings); model curves are used as
they are (``smooth=1``). The noise level a DEM measure is judged against is
``tail_noise``: the scatter of the *smoothed* series about a straight line over
the last ``TAIL`` of the run, where the run is close to its new steady state.
It includes the serial correlation of the DEM samples, which a
sample-to-sample difference would miss. The smoothing, the noise and the
passage of theta_A live in ``dem_contract.passage`` (the comparison reports
the same passage from the same function).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.stats import binned_statistic

from dem_contract import fabric_angle_deg, fabric_norm
from dem_contract.passage import SMOOTH, TAIL, Z_CLEAR, passage, smooth, tail_noise  # noqa: F401  (one home)
from shared_stats.errors import early_rmse  # noqa: F401 (re-exported)

N_BINS = 20         # bins of the single-valued curves of the collapse


def fall(s, x, steady: float, noisy: bool) -> dict:
    r"""Depth and strain of the minimum of ``x`` after the reversal, and the depth noise alone gives.

    .. math:: D = 1 - \frac{\min_s x}{x_{steady}}, \qquad D_{noise} = \frac{3\,\sigma_{tail}}{x_{steady}}

    Returns ``depth``, ``s_min``, ``noise_depth`` (0 for a noiseless curve) and
    ``excess`` = depth - noise_depth (positive: a fall beyond the noise).
    """
    s, x = np.asarray(s, float), np.asarray(x, float)
    k = int(np.nanargmin(x))
    depth = 1.0 - x[k] / steady
    nd = 3.0 * tail_noise(s, x) / steady if noisy else 0.0
    return {"depth": float(depth), "s_min": float(s[k]), "noise_depth": float(nd), "excess": float(depth - nd)}


def crossing(s, A_xx, A_xy, noisy: bool) -> dict:
    """Which axis theta_A turns through, for curves already smoothed: ``dem_contract.passage.passage`` (width 1).

    The claims stage calls ``passage`` on the raw DEM (it smooths with ``SMOOTH``), as ``compare`` does.
    """
    return passage(s, A_xx, A_xy, noisy=noisy, width=1)


def transition_width(s, A_xx, A_xy, low: float = 0.1, high: float = 0.9, end_fraction: float = 0.1) -> float:
    r"""Strain over which theta_A makes the middle of its change (from ``low`` to ``high`` of it).

    The axial angle is unwrapped on the doubled angle; its change
    :math:`\Delta = \bar\theta_{end} - \theta_0` (end: mean over the last
    ``end_fraction`` of the strain, where the angle has settled if the run is
    long enough) and the width

    .. math:: w = s\big(f \ge h\big) - s\big(f \ge l\big), \qquad f = (\theta - \theta_0)/\Delta

    at the first samples reaching each level. NaN if the angle turns by less
    than 20 degrees.
    """
    s = np.asarray(s, float)
    th = fabric_angle_deg(np.asarray(A_xx, float), np.asarray(A_xy, float))
    u = np.degrees(np.unwrap(np.radians(2.0 * th))) / 2.0
    end = s >= s[-1] - end_fraction * (s[-1] - s[0])
    delta = float(np.mean(u[end]) - u[0])
    if abs(delta) < 20.0:
        return math.nan
    f = (u - u[0]) / delta
    i_lo, i_hi = np.nonzero(f >= low)[0], np.nonzero(f >= high)[0]
    if not (i_lo.size and i_hi.size):
        return math.nan
    return float(s[i_hi[0]] - s[i_lo[0]])


def binned_scatter(x, y, n_bins: int = N_BINS) -> float:
    r"""RMS scatter of ``y`` about its best single-valued curve of ``x``: the mean of y in quantile bins of x.

    .. math:: r = \Big(\frac1n \sum_i \big(y_i - \bar y_{b(i)}\big)^2\Big)^{1/2}

    (``scipy.stats.binned_statistic``; the bins hold equal numbers of samples).
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    edges = np.unique(np.quantile(x, np.linspace(0.0, 1.0, n_bins + 1)))
    mean, _, idx = binned_statistic(x, y, statistic="mean", bins=edges)
    fitted = mean[np.clip(idx - 1, 0, mean.size - 1)]
    return float(np.sqrt(np.mean((y - fitted) ** 2)))


def norm_and_angle(A_xx, A_xy):
    """|A| and theta_A (``dem_contract``)."""
    return fabric_norm(A_xx, A_xy), fabric_angle_deg(A_xx, A_xy)
