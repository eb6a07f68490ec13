r"""Errors of a model against the DEM, and the paper's claims as numbers.

Quantities: ``A_norm`` (|A|), ``theta_A`` (degrees) and ``mu``. Angle errors are
taken modulo 180 degrees (``dem_contract.angle_difference``), so 179 and 1
degree differ by 2; |A| and theta_A are ``dem_contract.fabric_norm`` and
``fabric_angle_deg``.
"""
from __future__ import annotations

import numpy as np

from dem_contract import angle_difference, fabric_angle_deg, fabric_norm
from dem_contract.passage import passage

QUANTITIES = ("A_norm", "theta_A", "mu")


def errors(dem: dict, model: dict) -> dict:
    """RMSE and largest absolute error of |A|, theta_A and mu on a common grid.

    Parameters
    ----------
    dem, model : mapping
        Arrays ``A_norm``, ``theta_A``, ``mu`` of equal length (one value per
        DEM sample).

    Returns
    -------
    dict
        ``rmse_<q>`` and ``max_<q>`` for each quantity q.
    """
    out = {}
    for q in QUANTITIES:
        d = np.asarray(dem[q], float)
        m = np.asarray(model[q], float)
        if d.shape != m.shape or d.size == 0:
            raise ValueError(f"errors: '{q}' has {d.size} DEM and {m.size} model values; they must match and be > 0")
        e = angle_difference(m, d) if q == "theta_A" else m - d
        out[f"rmse_{q}"] = float(np.sqrt(np.mean(e ** 2)))
        out[f"max_{q}"] = float(np.max(np.abs(e)))
    return out


def theta_passage(theta_deg) -> str:
    r"""Which axis the fabric's major direction turns through between the ends.

    The axial angle is unwrapped (on the doubled angle, period 360 degrees), and
    the vertical (90 + 180 k) and horizontal (180 k) directions lying strictly
    between its first and last values are the ones the direction has passed;
    back-and-forth jitter across an axis does not count.

    Parameters
    ----------
    theta_deg : array_like
        Angle history in degrees in [0, 180), in order of strain.

    Returns
    -------
    {"90", "0/180", "both", "neither"}
    """
    th = np.asarray(theta_deg, float)
    th = th[np.isfinite(th)]
    if th.size < 2:
        return "neither"
    u = np.degrees(np.unwrap(np.radians(2.0 * th))) / 2.0
    lo, hi = sorted((u[0], u[-1]))
    k = np.arange(np.floor(lo / 90.0) - 1, np.ceil(hi / 90.0) + 2)
    levels = 90.0 * k
    passed = levels[(levels > lo) & (levels < hi)]
    vertical = np.any(np.mod(passed, 180.0) == 90.0)
    horizontal = np.any(np.mod(passed, 180.0) == 0.0)
    return {(True, False): "90", (False, True): "0/180", (True, True): "both"}.get((vertical, horizontal), "neither")


def running_mean(x, width: int):
    """Centred running mean over ``width`` samples (odd), shrinking at the ends."""
    x = np.asarray(x, float)
    if width <= 1:
        return x.copy()
    half = width // 2
    c = np.concatenate([[0.0], np.cumsum(x)])
    i = np.arange(x.size)
    lo = np.maximum(i - half, 0)
    hi = np.minimum(i + half + 1, x.size)
    return (c[hi] - c[lo]) / (hi - lo)


def minimum(x, s):
    """Smallest value of ``x`` and the strain ``s`` where it occurs."""
    x = np.asarray(x, float)
    k = int(np.nanargmin(x))
    return float(x[k]), float(np.asarray(s, float)[k])


def recovery_strain(x, s, steady: float, fraction: float = 0.9) -> float:
    """First strain after the minimum of ``x`` where ``x >= fraction * steady`` (NaN if never)."""
    x = np.asarray(x, float)
    s = np.asarray(s, float)
    k = int(np.nanargmin(x))
    hit = np.nonzero(x[k:] >= fraction * steady)[0]
    return float(s[k + hit[0]]) if hit.size else float("nan")


def claims(s, A_xx, A_xy, mu, steady_A: float, steady_mu: float, smooth: int = 1, fraction: float = 0.9,
           noisy: bool | None = None) -> dict:
    r"""The paper's claims about one reversal curve, as numbers.

    Parameters
    ----------
    s : array
        Strain travelled since the reversal (monotone).
    A_xx, A_xy, mu : array
        The fabric components and friction along ``s``.
    steady_A, steady_mu : float
        Steady values the curve recovers towards.
    smooth : int
        Centred running mean (samples) applied to A_xx, A_xy and mu before
        anything is measured: 1 for the models, a few samples for noisy DEM.
    fraction : float
        Recovery level (0.9: 90 % of the steady values).
    noisy : bool, optional
        Whether the curve is the DEM's (its passage judged against its noise);
        default: ``smooth > 1``.

    Returns
    -------
    dict
        ``theta_passage``: which axis theta_A turns through, "90", "0/180",
        "unclear" or "none" (``dem_contract.passage.passage``: the sign of A_xx
        where A_xy changes sign, against the noise; the claims stage uses the
        same function), ``theta_start``,
        ``theta_end``, ``min_A``, ``s_min_A``, ``min_mu``, ``s_min_mu``,
        ``s_recover_A``, ``s_recover_mu`` (NaN if not reached within the run).
    """
    a, b, m = (running_mean(v, smooth) for v in (A_xx, A_xy, mu))
    A = fabric_norm(a, b)
    th = fabric_angle_deg(a, b)
    min_A, s_min_A = minimum(A, s)
    min_mu, s_min_mu = minimum(m, s)
    return dict(
        theta_passage=passage(s, A_xx, A_xy, noisy=smooth > 1 if noisy is None else noisy, width=smooth)["axis"],
        theta_start=float(th[0]), theta_end=float(th[-1]),
        min_A=min_A, s_min_A=s_min_A, min_mu=min_mu, s_min_mu=s_min_mu,
        s_recover_A=recovery_strain(A, s, steady_A, fraction),
        s_recover_mu=recovery_strain(m, s, steady_mu, fraction),
    )
