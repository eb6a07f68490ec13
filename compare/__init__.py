"""Model 1 and Model 2 against the DEM: predictions on each run's own history, errors, claims, figures.

Reads only the DEM time series (docs/data-contract.md) and the calibration's
``params.yaml``; uses ``model``'s public API. See ``compare/README.md``.
"""
from .comparison import Comparison, ensemble_curves, run
from .dem import DEMInputError, Reversal, load_reversal
from .metrics import claims, errors, theta_passage
from .predict import DEFAULT_FRICTION, Prediction, clean_rate, imposed_history, predict

__all__ = [
    "Comparison", "ensemble_curves", "run", "DEMInputError", "Reversal", "load_reversal",
    "claims", "errors", "theta_passage", "DEFAULT_FRICTION", "Prediction", "clean_rate",
    "imposed_history", "predict",
]
