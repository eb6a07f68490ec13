"""Calibration: DEM time series -> alpha1, alpha2 vs X -> fits of Eq. 6, Eq. 2, Model 2 -> parameter tables.

``pipeline.run`` is the chain: ``problem.pose`` reads the inputs once into a
frozen ``problem.Problem`` (under ``settings.Settings``), and each step takes it
and the records of the steps it needs and returns its own (``results``).
Modules, one job each: ``io`` (read the DEM runs: the contract's checks from
``dem_contract``, plus the calibration's own: pressure, reversal, steady state),
``smoothing`` (Savitzky-Golay in strain), ``backsolve`` (Eq. 4, conditioning-aware),
``fits`` (least squares of the laws), ``backsolve_fit`` (the back-solve route, the
tables' ``backsolve``, and the friction laws, ``mu_vs_X``), ``dem_replays`` (the runs
in path strain), ``curves_integration`` (the model along them, for many parameter
sets), ``integration_batcher`` (jobs side by side, their integrations batched),
``curves_fit`` (the curves route: the integrated model fitted to the DEM curves),
``freeform`` (the free-form bound), ``bootstrap`` (over seeds), ``profiles`` and
``identifiability`` (what the data determine), ``route_choice`` (each model's
default route), ``tables`` and ``figures`` (outputs), ``synthetic`` (model-made
test cases: ``dem_contract.synthetic`` with the calibration's defaults).
Command line: ``python -m calibrate --dem <case_dir> ... --out results/calibration``.
"""
from dem_contract import DEMInputError

__all__ = ["DEMInputError"]
