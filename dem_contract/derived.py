r"""The quantities every stage derives from a DEM time series, each defined once.

Every consumer of the DEM files (the campaign summary, the calibration, the
comparison, the DEM study) takes these numbers from here, so two tables that
report the same quantity of the same run agree (docs/data-contract.md).

- ``steady_window`` / ``steady_values``: the steady state of a pre-shear, the
  mean over the last half of its strain path.
- ``fabric_norm`` / ``fabric_angle_deg``: |A| and theta_A of
  :math:`A = [[A_{xx}, A_{xy}], [A_{xy}, -A_{xx}]]`. They are the model's own
  (``model.laws``, the lowest layer that needs them; ``model`` never imports
  ``dem_contract``) and are re-exported here so DEM readers find them in one
  place.
- ``axial_mean``: the mean of axial angles (period 180 degrees), e.g. theta_A
  over seeds, across the 0/180 wrap.
- ``angle_difference``: the difference of two axial angles in (-90, 90].
- ``reversal_indices``: where the sign of the shear rate flips, ignoring noise.
- ``pre_reversal_state``: the state a reversal starts from (mean over the
  end of the pre-shear).
"""
from __future__ import annotations

import numpy as np
from scipy.stats import circmean

from model.laws import fabric_angle_deg, fabric_norm

__all__ = ["STEADY_FRACTION", "STEADY_COLUMNS", "PRE_REVERSAL_WINDOW", "MIN_PRE_REVERSAL_SAMPLES",
           "REVERSAL_DEAD_BAND", "REVERSAL_MIN_RUN", "steady_window", "steady_values", "fabric_norm",
           "fabric_angle_deg", "axial_mean", "angle_difference", "reversal_indices", "pre_reversal_state"]

#: Last fraction of a pre-shear's strain path taken as its steady state.
STEADY_FRACTION = 0.5
#: Columns averaged by ``steady_values`` when the series has them.
STEADY_COLUMNS = ("A_xx", "A_xy", "mu", "phi", "Z", "inertial_number")


def steady_window(strain, fraction: float = STEADY_FRACTION, last_strain: float | None = None) -> np.ndarray:
    r"""The samples of a pre-shear that make its steady state.

    With the strain path travelled since the first sample,
    :math:`s_i = |\gamma_i - \gamma_0|`, a sample belongs to the window when

    .. math:: s_i \ge (1 - f)\, s_{\mathrm{end}}

    (``fraction`` :math:`f`, default the last half of the strain), or, when
    ``last_strain`` :math:`w` is given, :math:`s_i \ge s_{\mathrm{end}} - w`
    (the DEM study's ``accuracy.steady_window``, configured as a strain).

    Parameters
    ----------
    strain : array_like
        The pre-shear's ``strain`` column, in time order (monotone: a
        pre-shear does not reverse).
    fraction : float
        Last fraction of the strain path, in (0, 1].
    last_strain : float, optional
        Last strain path instead of a fraction (> 0).

    Returns
    -------
    numpy.ndarray of bool
        True for the samples in the window.
    """
    strain = np.asarray(strain, dtype=float)
    s = np.abs(strain - strain[0])
    if last_strain is not None:
        if not last_strain > 0:
            raise ValueError(f"steady_window: last_strain = {last_strain!r} must be positive")
        return s >= s[-1] - last_strain
    if not 0 < fraction <= 1:
        raise ValueError(f"steady_window: fraction = {fraction!r} must lie in (0, 1]")
    return s >= (1.0 - fraction) * s[-1]


def steady_values(pre, fraction: float = STEADY_FRACTION, last_strain: float | None = None) -> dict:
    r"""Steady values of one pre-shear: window means, and |A|, theta_A of the mean fabric.

    Over the samples of ``steady_window``, each column of ``STEADY_COLUMNS``
    that ``pre`` has is averaged; the fabric's norm and angle are those of the
    mean tensor (the fabric of the pooled contacts, not the mean of per-sample
    norms):

    .. math::
        |A| = \sqrt{2 (\bar a^2 + \bar b^2)}, \qquad
        \theta_A = \tfrac12 \operatorname{atan2}(\bar b, \bar a) \bmod 180^\circ

    with :math:`\bar a, \bar b` the window means of ``A_xx``, ``A_xy``.

    Parameters
    ----------
    pre : pandas.DataFrame
        The pre-shear (``strain``, ``A_xx``, ``A_xy``; ``mu``, ``phi``, ``Z``,
        ``inertial_number`` when present).
    fraction, last_strain : float
        The window, see ``steady_window``.

    Returns
    -------
    dict
        The means under their column names, ``A_norm``, ``theta_A`` (degrees in
        [0, 180)) and ``n_samples`` (samples in the window).
    """
    win = steady_window(pre["strain"].to_numpy(), fraction, last_strain)
    out = {c: float(np.mean(pre[c].to_numpy()[win])) for c in STEADY_COLUMNS if c in pre}
    out["A_norm"] = float(fabric_norm(out["A_xx"], out["A_xy"]))
    out["theta_A"] = float(fabric_angle_deg(out["A_xx"], out["A_xy"]))
    out["n_samples"] = int(win.sum())
    return out


def axial_mean(theta_deg, axis=None):
    r"""Circular mean of axial angles in degrees (period 180), in [0, 180).

    An axial angle and the same angle plus 180 degrees are one direction, so
    the doubled angles are averaged on the circle
    (``scipy.stats.circmean``) and the mean halved:

    .. math:: \bar\theta = \tfrac12 \operatorname{atan2}\Big(\sum_i \sin 2\theta_i,\ \sum_i \cos 2\theta_i\Big) \bmod 180^\circ

    The mean of 179 and 1 degrees is 0 (not 90).

    Parameters
    ----------
    theta_deg : array_like
        Angles in degrees (any range).
    axis : int, optional
        Axis to average over (default: all values).
    """
    doubled = np.radians(2.0 * np.asarray(theta_deg, dtype=float))
    return np.mod(np.degrees(circmean(doubled, high=2 * np.pi, low=0.0, axis=axis)) / 2.0, 180.0)


def angle_difference(a, b):
    r"""Signed difference :math:`a - b` of axial angles in degrees, in (-90, 90].

    .. math:: \Delta = \big((a - b + 90) \bmod 180\big) - 90, \quad \text{then } -90 \mapsto 90

    so that 179 and 1 degrees differ by -2 (and 1 and 179 by +2).
    """
    d = np.mod(np.asarray(a, float) - np.asarray(b, float) + 90.0, 180.0) - 90.0
    return np.where(d == -90.0, 90.0, d)


#: Rates below this fraction of the median |gammadot| have no sign (``reversal_indices``).
REVERSAL_DEAD_BAND = 0.1
#: Samples of one sign in a row that a new direction needs (``reversal_indices``).
REVERSAL_MIN_RUN = 3


def reversal_indices(gammadot, dead_band: float = REVERSAL_DEAD_BAND, min_run: int = REVERSAL_MIN_RUN) -> np.ndarray:
    r"""Where the shear rate reverses: the first sample of each new direction.

    Noise must neither make nor hide a reversal. A sample has the sign of its
    rate when :math:`|\dot\gamma_i| > d \cdot \mathrm{median}_j |\dot\gamma_j|`
    (``dead_band`` :math:`d`) and none otherwise (it is at rest, or noise about
    zero). The direction is the sign of the first ``min_run`` signed samples in
    a row; it reverses at the first sample of a run of ``min_run`` signed
    samples in a row of the other sign (shorter runs are noise). Rests between
    two directions do not count: a rate that stops and resumes in the same
    direction is not a reversal.

    Parameters
    ----------
    gammadot : array_like
        The ``gammadot`` column, in time order (one run, or runs joined).
    dead_band : float
        Fraction of the median rate below which a sample has no sign, in [0, 1).
    min_run : int
        Samples of one sign in a row that make a direction (>= 1).

    Returns
    -------
    numpy.ndarray of int
        Indices of the first sample of each new direction (empty: no reversal).
    """
    g = np.asarray(gammadot, dtype=float)
    if not 0 <= dead_band < 1 or min_run < 1:
        raise ValueError(f"reversal_indices: dead_band = {dead_band!r} must lie in [0, 1) and min_run = {min_run!r} be >= 1")
    sign = np.where(np.abs(g) > dead_band * np.median(np.abs(g)), np.sign(g), 0.0)
    signed = np.nonzero(sign)[0]
    sg = sign[signed]
    # runs of one sign among the signed samples: their starts, lengths and signs
    starts = np.concatenate([[0], np.nonzero(sg[1:] != sg[:-1])[0] + 1]) if sg.size else np.array([], int)
    lengths = np.diff(np.append(starts, sg.size))
    out, current = [], 0.0
    for k, n in zip(starts, lengths):
        if n < min_run:
            continue
        if current != 0.0 and sg[k] != current:
            out.append(int(signed[k]))
        current = sg[k]
    return np.array(out, dtype=int)


#: Strain at the end of a pre-shear over which the fabric before a reversal is averaged.
PRE_REVERSAL_WINDOW = 0.1
#: Fewest samples in that average (the last ones are taken if the window holds fewer).
MIN_PRE_REVERSAL_SAMPLES = 10


def pre_reversal_state(pre, window: float = PRE_REVERSAL_WINDOW):
    r"""The DEM state just before a reversal, from the end of the pre-shear.

    Parameters
    ----------
    pre : pandas.DataFrame
        The pre-shear run (``strain``, ``gammadot``, ``A_xx``, ``A_xy``, ``mu``).
    window : float
        Strain at the end of the pre-shear to average over (at least
        ``MIN_PRE_REVERSAL_SAMPLES`` samples): the per-sample noise of the
        fabric is averaged down, the run's own offset from the ensemble is kept.

    Returns
    -------
    dict
        ``A_xx``, ``A_xy``, ``mu`` (means over the window), ``gammadot`` (the
        median rate of the last tenth of the run), its sign ``gammadot_sign``
        (0 if the run does not move) and ``X`` :math:`= \sqrt2 A_{xy}\,\mathrm{sign}(\dot\gamma)`
        (docs/model.md); a reversal starts from :math:`-X`, the *mirrored* X.
    """
    n = len(pre)
    rate = float(np.median(pre["gammadot"].to_numpy()[-max(MIN_PRE_REVERSAL_SAMPLES, n // 10):]))
    g = float(np.sign(rate))
    s = pre["strain"].to_numpy()
    win = s >= s[-1] - window if g >= 0 else s <= s[-1] + window
    if win.sum() < MIN_PRE_REVERSAL_SAMPLES:
        win = np.zeros(n, bool)
        win[-MIN_PRE_REVERSAL_SAMPLES:] = True
    a, b, mu = (float(pre[c].to_numpy()[win].mean()) for c in ("A_xx", "A_xy", "mu"))
    return {"A_xx": a, "A_xy": b, "mu": mu, "gammadot": rate, "gammadot_sign": g, "X": float(np.sqrt(2.0) * b * g)}
