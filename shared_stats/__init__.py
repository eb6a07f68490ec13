"""Statistics two stages share, below both: calibrate and claims import them, they import no stage.

- ``intervals.mean_interval``: the mean of per-seed values and its interval (95 % unless asked)
  (bootstrap over seeds, at least the Student t interval);
- ``errors.early_rmse``, ``errors.early_mse``: the RMSE (MSE) of a model curve
  against the DEM over the first strain window after a reversal.

It needs numpy and scipy only.
"""
from .errors import early_mse, early_rmse
from .intervals import CONFIDENCE, N_RESAMPLES, mean_interval

__all__ = ["CONFIDENCE", "N_RESAMPLES", "early_mse", "early_rmse", "mean_interval"]
