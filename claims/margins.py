r"""The margin of every comparative claim: the smallest effect that would matter physically (one home).

A claim whose 90 % equivalence interval (``stats.equivalence_interval``) lies
inside null +- margin is **negligible**: whatever its sign, the effect is too
small to matter (``stats.verdict``). Each margin is declared here, before any
campaign's data are looked at, as a fraction of a physical scale of the
reversal (the reasons: ``docs/model.md``, "The claims' margins"). Where the
scale is a property of the runs (how far |A| falls, how wide the DEM's
transition is) the table computes it from the scored DEM curves: the fraction
is fixed, the scale is the run's own; nothing is tuned on a verdict.

- claims 4 and 9 (early |A|) and 7 (early mu): ``FALL_FRACTION`` of the DEM's
  fall over the window (``fall_size``): an RMSE difference below 5 % of the
  fall the models have to follow would not show on the paper's Figs. 4 and 5
  (it is under a line width at their scale);
- claim 5 (opposite turns, fraction of runs): ``TURN_FRACTION``: the paper's
  "in some cases" is a statement about a visible share of reversals; fewer
  than one run in ten more turning the wrong way is not "some cases" in a
  campaign of the paper's size (a handful of reversals);
- claim 6 (sinusoidal transition width): ``WIDTH_FRACTION`` of the DEM's
  own transition width (10 %-90 % of the turn of theta_A): a model closer to
  the DEM by less than a tenth of the width draws the same transition;
- claim 8 (steady theta_A against Eq. 4's 135-degree limit):
  ``STEADY_ANGLE_DEG``: one degree is below the resolution at which the paper
  reads theta_A (its figures span 0-180 degrees) and below the spread of the
  steady angle over the last half of one pre-shear; a steady angle within a
  degree of 135 is "at the limit", neither clearly reachable nor out of reach.

Claim 2b carries its margin in its null (Eq. 2 within 10 % of the best curve,
``table.EQ2_MARGIN``); claims 1a, 1b, 2a, 3 and 10 are not comparisons of two
models and have none (NaN).
"""
from __future__ import annotations

import math

import numpy as np

from . import measures

FALL_FRACTION = 0.05      # claims 4, 7, 9: of the DEM's fall over the window
TURN_FRACTION = 0.10      # claim 5: share of runs
WIDTH_FRACTION = 0.10     # claim 6: of the DEM's transition width
STEADY_ANGLE_DEG = 1.0    # claim 8: degrees


def fall_size(pairs, column: str) -> float:
    r"""Mean over the scored runs of the DEM fall :math:`\bar x(0) - \min_s \bar x(s)` (running mean, ``SMOOTH``).

    Parameters
    ----------
    pairs : list
        (key, curves) of ``claims.table._oos``: ``curves["dem"]`` holds ``column``.
    column : str
        ``A_norm`` or ``mu``.
    """
    sizes = []
    for _, cur in pairs:
        x = measures.smooth(cur["dem"][column].to_numpy())
        sizes.append(float(x[0] - np.nanmin(x)))
    v = np.asarray(sizes, float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else math.nan


def fall_margin(pairs, column: str) -> float:
    """Claims 4, 7, 9: ``FALL_FRACTION`` of the DEM's mean fall of ``column`` (``fall_size``)."""
    return FALL_FRACTION * fall_size(pairs, column)


def width_margin(dem_widths) -> float:
    """Claim 6: ``WIDTH_FRACTION`` of the DEM's mean sinusoidal transition width (NaN if none measured)."""
    w = np.asarray(dem_widths, float)
    w = w[np.isfinite(w)]
    return WIDTH_FRACTION * float(w.mean()) if w.size else math.nan
