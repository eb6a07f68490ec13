"""What each case of the bulk-vs-walls study cost: CPU and wall time per stage, from its sidecars.

One row per case (``<cell>_s<seed>``): ``N``, ``cpu_time_<stage>_s`` and
``wall_time_<stage>_s`` for pack, preshear and the reversal stage (heaviside,
or train for a cell with a reversal train: the cases table's ``stage``), their sums
``cpu_time_s``, ``wall_time_s``, and ``core_hours`` = cpu_time_s / 3600 (the
CPU time of the one-thread YADE process: immune to other jobs on the machine).
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from dem_contract import DEMInputError, stage_costs

from .analysis import StudyInputError

STAGES = ("pack", "preshear", "heaviside")


def case_cost(case_dir, stages=STAGES) -> dict:
    """CPU and wall seconds per stage of one case and their sums (``dem_contract.stage_costs``), and core-hours.

    Every sidecar must exist and record ``N``, ``cpu_time_s`` and ``wall_time_s`` (the study's cases
    are run by ``yade_scripts`` since the sidecars record the CPU time): else ``StudyInputError``
    naming the file and the key.
    """
    try:
        row = stage_costs(case_dir, stages, keys=("cpu_time_s", "wall_time_s"), missing="raise")
    except DEMInputError as exc:
        raise StudyInputError(str(exc)) from None
    row["core_hours"] = row["cpu_time_s"] / 3600
    return row


def reversal_stages(cases: pd.DataFrame) -> list:
    """Each case's reversal stage: the cases table's ``stage`` (heaviside or train), heaviside in
    a table written before reversal trains existed."""
    return list(cases["stage"]) if "stage" in cases else ["heaviside"] * len(cases)


def cost_table(cases: pd.DataFrame, bulk_dir) -> pd.DataFrame:
    """``cases`` (``bulk_cells.cases``: case, cell, seed, ...) with each case's cost columns."""
    costs = pd.DataFrame([case_cost(Path(bulk_dir) / case, (*STAGES[:2], stage))
                          for case, stage in zip(cases["case"], reversal_stages(cases))], index=cases.index)
    return pd.concat([cases.drop(columns=["N"], errors="ignore"), costs], axis=1)
