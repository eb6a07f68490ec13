"""The DEM time-series contract between ``yade_scripts/`` and the analysis stages (docs/data-contract.md).

One CSV per run and stage, a header naming ``CONTRACT_COLUMNS`` (more may
follow), and an optional JSON sidecar ``<stage>.json``. This package holds what
every reader of that layout shares: the column names, the one error type
(``DEMInputError``, whose message names the file and the problem), the
checked readers ``read_series`` and ``read_sidecar`` (``series``), the case
labels (``labels``), and the quantities every stage derives from a series
(``derived``: the steady state of a pre-shear, the fabric's norm and angle,
the mean and difference of axial angles, reversal detection, and
``pre_reversal_state``, the fabric a reversal starts from). The checks a stage
adds on top (calibrate: positive pressure, a reversal in each reversal run, a
steady pre-shear; compare: the reversal start from the sidecar) stay in that
stage. It needs numpy, pandas, scipy and ``model.laws`` (``model`` never
imports ``dem_contract``).

``dem_contract.synthetic`` (it needs ``model``) writes model-made cases in the
same layout, for tests and trial runs; ``dem_contract.importer`` (``python -m
dem_contract import``) writes external runs, a minimal CSV per run (or a
pre-shear file and branches starting at the reversal) and a YAML of case
metadata, into it (docs/own-dem-data.md), holding them to the signs of
steady shear (``dem_contract.steady_signs``) and writing nothing unless every
case is read back (``dem_contract.folders``).
"""
from .costs import COST_KEYS, stage_costs
from .derived import (MIN_PRE_REVERSAL_SAMPLES, PRE_REVERSAL_WINDOW, STEADY_FRACTION, angle_difference, axial_mean,
                      Transient, fabric_angle_deg, fabric_norm, pre_reversal_state, reversal_indices,
                      reversal_times, split_transients, steady_values, steady_window)
from .labels import LABEL_RE, case_label, parse_case_label, split_case_label
from .series import CONTRACT_COLUMNS, REVERSAL_PROTOCOLS, DEMInputError, read_series, read_sidecar, sidecar_engine

__all__ = ["CONTRACT_COLUMNS", "REVERSAL_PROTOCOLS", "DEMInputError", "read_series", "read_sidecar", "sidecar_engine",
           "LABEL_RE", "case_label", "parse_case_label", "split_case_label",
           "STEADY_FRACTION", "PRE_REVERSAL_WINDOW", "MIN_PRE_REVERSAL_SAMPLES", "steady_window", "steady_values",
           "fabric_norm", "fabric_angle_deg", "axial_mean", "angle_difference", "reversal_indices",
           "pre_reversal_state", "Transient", "reversal_times", "split_transients", "COST_KEYS", "stage_costs"]
