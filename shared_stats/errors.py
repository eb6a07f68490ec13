r"""A model curve's error against the DEM just after a reversal, shared by calibrate and claims.

The claims table (``claims.measures``) and the free-form calibration's scores
(``calibrate.freeform``) judge the early transient with the same measure.
"""
from __future__ import annotations

import math

import numpy as np


def early_mse(s, dem, model, window: float, start: float = 0.0) -> float:
    r"""Mean squared error of a model curve against the DEM over the first ``window`` strain (``early_rmse`` squared).

    The claims' model comparisons difference it per run: the DEM's own noise enters
    both models' MSE on the same run alike and cancels from the difference
    (``claims.ensemble``); an RMSE difference would compress the model error by it.
    """
    s = np.asarray(s, float)
    m = (s > start) & (s <= start + window)
    if m.sum() < 2:
        return math.nan
    return float(np.mean((np.asarray(model, float)[m] - np.asarray(dem, float)[m]) ** 2))


def early_rmse(s, dem, model, window: float, start: float = 0.0) -> float:
    r"""RMSE of a model curve against the DEM over the first ``window`` strain after the reversal.

    .. math:: \mathrm{RMSE} = \Big(\frac1{n}\sum_{s_0 < s_i \le s_0 + w} (m_i - d_i)^2\Big)^{1/2}

    over the ``n`` samples after the reversal at :math:`s_0` = ``start`` (the
    claims' ``s_rev`` starts at the reversal, 0; the free-form scores pass the
    path strain of the run's first reversal). The model is taken at the DEM's
    samples (interpolated onto them by the caller); the DEM raw, not smoothed.
    NaN with fewer than 2 samples in the window.
    """
    return math.sqrt(early_mse(s, dem, model, window, start))
