r"""Which axis theta_A turns through after a reversal: the one rule every stage reports (compare, claims).

theta_A = atan2(A_xy, A_xx)/2 leaves one half of the circle (A_xy < 0: 90-180
degrees) for the other only through A_xy = 0, where theta_A is 90 degrees if
A_xx < 0 (the vertical) and 0/180 if A_xx > 0 (the horizontal). So the axis is
the sign of A_xx at the first sign change of A_xy (linearly interpolated),
judged against the noise of the curve:

- a DEM curve (``noisy=True``) is first smoothed by a centred running mean of
  ``smooth`` samples (``SMOOTH``; edges: the nearest value repeated), and its
  A_xx at the crossing is compared with ``tail_noise``, the scatter of the
  smoothed A_xx about a straight line over the last ``TAIL`` of the run (where
  it is close to its new steady state; the scatter includes the serial
  correlation of the samples): :math:`z = A_{xx}/\sigma`; the crossing is
  clear when :math:`|z| > ` ``Z_CLEAR``, "unclear" otherwise;
- a model curve (``noisy=False``, no smoothing) is judged by the sign alone.

``compare``'s ``claims.csv`` (column ``theta_passage``) and the claims stage
(claims 3 and 5) both call ``passage``: one rule, one answer per run.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import uniform_filter1d

SMOOTH = 5          # samples of the running mean on DEM curves
TAIL = 0.4          # last fraction of the run's strain judged for the noise
Z_CLEAR = 2.0       # |A_xx| / noise above which a crossing is clear
AXES = ("90", "0/180", "unclear", "none")


def smooth(x, width: int = SMOOTH):
    """Centred running mean over ``width`` samples (edges: the nearest value repeated)."""
    x = np.asarray(x, float)
    return x.copy() if width <= 1 else uniform_filter1d(x, size=width, mode="nearest")


def tail_noise(s, x) -> float:
    r"""Standard deviation of ``x`` about its least-squares line over the last ``TAIL`` of ``s``.

    .. math:: \sigma = \operatorname{sd}\big(x_i - (\beta_0 + \beta_1 s_i)\big),
              \quad s_i \ge s_{end} - T (s_{end} - s_0)

    NaN with fewer than 5 samples there.
    """
    s, x = np.asarray(s, float), np.asarray(x, float)
    m = s >= s[-1] - TAIL * (s[-1] - s[0])
    if m.sum() < 5:
        return math.nan
    coef = np.polyfit(s[m], x[m], 1)
    return float(np.std(x[m] - np.polyval(coef, s[m]), ddof=2))


def passage(s, A_xx, A_xy, noisy: bool = True, width: int | None = None) -> dict:
    r"""Which axis theta_A turns through: the sign of A_xx where A_xy first changes sign (module docstring).

    Parameters
    ----------
    s : array_like
        Strain since the reversal (monotone).
    A_xx, A_xy : array_like
        The fabric along ``s``, raw (a DEM curve is smoothed here).
    noisy : bool
        True for a DEM curve (smoothed, judged against its noise), False for a model curve.
    width : int, optional
        Samples of the running mean; default ``SMOOTH`` if ``noisy``, else 1.

    Returns
    -------
    dict
        ``axis``: "90" (z < -Z_CLEAR), "0/180" (z > Z_CLEAR), "unclear", or
        "none" (A_xy never changes sign); ``s_cross``, ``A_xx_cross`` (of the
        smoothed curve), ``z`` (for a noiseless curve +-inf by the sign of A_xx).
    """
    w = (SMOOTH if noisy else 1) if width is None else int(width)
    s = np.asarray(s, float)
    a, b = smooth(A_xx, w), smooth(A_xy, w)
    sign0 = np.sign(b[0]) if b[0] != 0 else np.sign(b[np.nonzero(b)[0][0]]) if np.any(b) else 0.0
    idx = np.nonzero(np.sign(b) == -sign0)[0] if sign0 else np.array([], int)
    if not idx.size:
        return {"axis": "none", "s_cross": math.nan, "A_xx_cross": math.nan, "z": math.nan}
    k = int(idx[0])
    f = b[k - 1] / (b[k - 1] - b[k])     # linear interpolation to A_xy = 0
    a_c = a[k - 1] + f * (a[k] - a[k - 1])
    s_c = s[k - 1] + f * (s[k] - s[k - 1])
    if noisy:
        sigma = tail_noise(s, a)
        z = a_c / sigma if sigma > 0 else math.copysign(math.inf, a_c)
    else:
        z = math.copysign(math.inf, a_c) if a_c != 0 else 0.0
    axis = "90" if z < -Z_CLEAR else "0/180" if z > Z_CLEAR else "unclear"
    return {"axis": axis, "s_cross": float(s_c), "A_xx_cross": float(a_c), "z": float(z)}
