r"""The margin of every comparative claim, and the weighting of every pooled row (one home).

A claim whose 90 % interval (``stats.verdict``: the one level of the table)
lies inside null +- margin is **negligible**: the effect is too small to
matter. Each margin is a fraction of a physical scale of the reversal
measured on the scored runs (the fraction is fixed here, the scale is the
runs' own; nothing is tuned on a verdict). The reasons, the date they were
fixed and what data existed then: ``docs/model.md``, "The claims' margins".

- claims 4, 7, 9 (early |A|, early mu; one row per figure): the statistic is
  the difference of the two models' squared model errors, B_1^2 - B_2^2
  (``claims.ensemble``: the noise floor cancels). Margin: the squared model
  error of a curve ``BAND_FRACTION`` of the DEM's ensemble band from the
  ensemble's mean, :math:`(f\,\bar\sigma)^2`, with :math:`\bar\sigma^2` the
  noise floor (the DEM's seed-to-seed variance over the window, mean over
  the row's scored runs; ``band_margin``). Figs. 4-5 draw the DEM as that
  band, mean +- sigma; a model inside its inner half (error below
  sigma/2) is as close to the DEM's mean as the DEM's seeds are to it, and
  an improvement smaller than such a model's whole squared error is not a
  difference the DEM ranks at the figures' scale;
- claim 5 (opposite turns, fraction of runs): ``TURN_FRACTION``;
- claim 6 (sinusoidal transition width): ``WIDTH_FRACTION`` of the DEM's
  own transition width;
- claim 8 (steady theta_A against Eq. 4's 135-degree limit):
  ``STEADY_ANGLE_DEG``.

Pooled rows (``POOLED_WEIGHTS``): claims 4, 7 and 9 are made figure by
figure (Fig. 4: step reversals; Fig. 5: the sinusoidal reversal) and decided
per figure; the pooled row is a secondary line, each seed's value the
weighted mean of its per-figure values, ``POOLED_WEIGHTS`` (one half each:
the paper gives the two figures equal standing, one figure each). Its margin
is the same weighting of the figures' margins.

Claim 2b carries its margin in its null (Eq. 2 within 10 % of the best curve,
``table.EQ2_MARGIN``); claims 1a, 1b, 2a, 3 and 10 are not comparisons of two
models and have none (NaN).
"""
from __future__ import annotations

import math

import numpy as np

BAND_FRACTION = 0.5       # claims 4, 7, 9: of the DEM's seed-to-seed s.d. over the window (ensemble band)
TURN_FRACTION = 0.10      # claim 5: share of runs
WIDTH_FRACTION = 0.10     # claim 6: of the DEM's transition width
STEADY_ANGLE_DEG = 1.0    # claim 8: degrees
#: The weight of each figure's value in a pooled row (claims 4, 7, 9), fixed before use (issue 32).
POOLED_WEIGHTS = {"heaviside": 0.5, "sinusoidal": 0.5}


def band_margin(floors) -> float:
    r"""Claims 4, 7, 9: :math:`(f\,\bar\sigma)^2`, ``BAND_FRACTION`` of the band's half-width, squared.

    Parameters
    ----------
    floors : sequence of float
        The noise floor :math:`N` (``claims.ensemble.Floor.mean``) of every scored run of the row;
        :math:`\bar\sigma^2` is their mean.
    """
    v = np.asarray(list(floors), float)
    v = v[np.isfinite(v)]
    return BAND_FRACTION ** 2 * float(v.mean()) if v.size else math.nan


def band_fraction_of(margin: float, floors) -> float:
    r"""The band fraction :math:`f` a margin on the squared scale corresponds to: :math:`\sqrt{m}/\bar\sigma`."""
    v = np.asarray(list(floors), float)
    v = v[np.isfinite(v)]
    if not (v.size and np.isfinite(margin) and margin >= 0):
        return math.nan
    return float(math.sqrt(margin / v.mean()))


def pooled_margin(margins: dict) -> float:
    """A pooled row's margin: ``POOLED_WEIGHTS`` over the figures' margins present (kind -> margin)."""
    w = {k: POOLED_WEIGHTS[k] for k, m in margins.items() if k in POOLED_WEIGHTS and np.isfinite(m)}
    if not w:
        return math.nan
    return float(sum(w[k] * margins[k] for k in w) / sum(w.values()))


def width_margin(dem_widths) -> float:
    """Claim 6: ``WIDTH_FRACTION`` of the DEM's mean sinusoidal transition width (NaN if none measured)."""
    w = np.asarray(dem_widths, float)
    w = w[np.isfinite(w)]
    return WIDTH_FRACTION * float(w.mean()) if w.size else math.nan
