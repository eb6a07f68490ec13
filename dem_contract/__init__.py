"""The DEM time-series contract between ``yade_scripts/`` and the analysis stages (docs/data-contract.md).

One CSV per run and stage, a header naming ``CONTRACT_COLUMNS`` (more may
follow), and an optional JSON sidecar ``<stage>.json``. This package holds what
every reader of that layout shares: the column names, the one error type
(``DEMInputError``, whose message names the file and the problem), and the
checked readers ``read_series`` and ``read_sidecar``, and ``pre_reversal_state``
(the fabric a reversal starts from, the same for every stage). It needs numpy and pandas
only. The checks a stage adds on top (calibrate: positive pressure, a reversal
in each reversal run, a steady pre-shear; compare: the reversal start from the
sidecar) stay in that stage.

``dem_contract.synthetic`` (it needs ``model``) writes model-made cases in the
same layout, for tests and trial runs.
"""
from .series import (CONTRACT_COLUMNS, PRE_REVERSAL_WINDOW, REVERSAL_PROTOCOLS, DEMInputError, pre_reversal_state,
                     read_series, read_sidecar)

__all__ = ["CONTRACT_COLUMNS", "PRE_REVERSAL_WINDOW", "REVERSAL_PROTOCOLS", "DEMInputError", "pre_reversal_state",
           "read_series", "read_sidecar"]
