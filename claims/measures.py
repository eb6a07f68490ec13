r"""Per-run measures behind the claims: falls, crossings, transition widths, early errors, the collapse.

All take the curves of one reversal run against ``s`` (strain travelled since
the reversal, the ``s_rev`` of ``predictions.csv``). DEM curves are first
smoothed by a centred running mean of ``SMOOTH`` samples (its per-sample noise
would otherwise set the minima and the crossings); model curves are used as
they are (``smooth=1``). The noise level a DEM measure is judged against is
``tail_noise``: the scatter of the *smoothed* series about a straight line over
the last ``TAIL`` of the run, where the run is close to its new steady state.
It includes the serial correlation of the DEM samples, which a
sample-to-sample difference would miss.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import uniform_filter1d
from scipy.stats import binned_statistic

from dem_contract import fabric_angle_deg, fabric_norm
from shared_stats.errors import early_rmse  # noqa: F401 (re-exported)

SMOOTH = 5          # samples of the running mean on DEM curves (compare's claims use the same)
TAIL = 0.4          # last fraction of the run's strain judged for the noise
Z_CLEAR = 2.0       # |A_xx| / noise above which a crossing is clear
N_BINS = 20         # bins of the single-valued curves of the collapse


def smooth(x, width: int = SMOOTH):
    """Centred running mean over ``width`` samples (edges: the nearest value repeated)."""
    x = np.asarray(x, float)
    return x.copy() if width <= 1 else uniform_filter1d(x, size=width, mode="nearest")


def tail_noise(s, x) -> float:
    r"""Standard deviation of ``x`` about its least-squares line over the last ``TAIL`` of ``s``.

    .. math:: \sigma = \operatorname{sd}\big(x_i - (\beta_0 + \beta_1 s_i)\big), \quad s_i \ge s_{end} - T (s_{end} - s_0)
    """
    s, x = np.asarray(s, float), np.asarray(x, float)
    m = s >= s[-1] - TAIL * (s[-1] - s[0])
    if m.sum() < 5:
        return math.nan
    coef = np.polyfit(s[m], x[m], 1)
    return float(np.std(x[m] - np.polyval(coef, s[m]), ddof=2))


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
    r"""Which axis theta_A turns through: the sign of A_xx where A_xy changes sign.

    theta_A = atan2(A_xy, A_xx)/2 leaves one half of the circle (A_xy < 0:
    90-180 degrees) for the other only through A_xy = 0, where theta_A is 90
    degrees if A_xx < 0 (the vertical) and 0/180 if A_xx > 0 (the horizontal).
    At the first sign change of A_xy, A_xx is interpolated and compared with
    its noise (``tail_noise``): :math:`z = A_{xx} / \sigma`.

    Returns
    -------
    dict
        ``axis``: "90" (z < -Z_CLEAR), "0/180" (z > Z_CLEAR), "unclear", or
        "none" (A_xy never changes sign); ``s_cross``, ``A_xx_cross``, ``z``
        (for a noiseless curve z is +-inf by the sign of A_xx).
    """
    s, a, b = (np.asarray(v, float) for v in (s, A_xx, A_xy))
    sign0 = np.sign(b[0]) if b[0] != 0 else np.sign(b[np.nonzero(b)[0][0]]) if np.any(b) else 0.0
    idx = np.nonzero(np.sign(b) == -sign0)[0] if sign0 else np.array([], int)
    if not idx.size:
        return {"axis": "none", "s_cross": math.nan, "A_xx_cross": math.nan, "z": math.nan}
    k = int(idx[0])
    w = b[k - 1] / (b[k - 1] - b[k])     # linear interpolation to A_xy = 0
    a_c = a[k - 1] + w * (a[k] - a[k - 1])
    s_c = s[k - 1] + w * (s[k] - s[k - 1])
    if noisy:
        sigma = tail_noise(s, a)
        z = a_c / sigma if sigma > 0 else math.copysign(math.inf, a_c)
    else:
        z = math.copysign(math.inf, a_c) if a_c != 0 else 0.0
    axis = "90" if z < -Z_CLEAR else "0/180" if z > Z_CLEAR else "unclear"
    return {"axis": axis, "s_cross": float(s_c), "A_xx_cross": float(a_c), "z": float(z)}


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
