"""Calibration: DEM time series -> alpha1, alpha2 vs X -> fits of Eq. 6, Eq. 2, Model 2 -> parameter tables.

Stages (one module each): ``io`` (read the DEM runs: the contract's checks from
``dem_contract``, plus the calibration's own: pressure, reversal, steady state),
``smoothing`` (Savitzky-Golay in strain), ``backsolve`` (Eq. 4, conditioning-aware),
``fits`` (least squares of the laws), ``backsolve_fit`` (the back-solve route), ``curves_fit``
(fit the integrated model to the DEM curves), ``bootstrap`` (over seeds),
``tables`` and ``figures`` (outputs), ``synthetic`` (model-made test cases:
``dem_contract.synthetic`` with the calibration's defaults).
Command line: ``python -m calibrate --dem <case_dir> ... --out results/calibration``.
"""
from dem_contract import DEMInputError

__all__ = ["DEMInputError"]
