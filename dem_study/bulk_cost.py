"""What each case of the bulk-vs-walls study cost: CPU and wall time per stage, from its sidecars.

One row per case (``<cell>_s<seed>``): ``N``, ``cpu_time_<stage>_s`` and
``wall_time_<stage>_s`` for pack, preshear and the reversal stage (heaviside,
or train for a cell with a reversal train: the cases table's ``stage``), their sums
``cpu_time_s``, ``wall_time_s``, and ``core_hours`` = cpu_time_s / 3600 (the
CPU time of the one-thread YADE process: immune to other jobs on the machine).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import DEMInputError, read_sidecar

from .analysis import StudyInputError

STAGES = ("pack", "preshear", "heaviside")


def case_cost(case_dir, stages=STAGES) -> dict:
    """CPU and wall seconds per stage of one case (NaN where a sidecar lacks ``cpu_time_s``)."""
    case_dir = Path(case_dir)
    row = {}
    for stage in stages:
        try:
            side = read_sidecar(case_dir / f"{stage}.csv")
        except DEMInputError as exc:
            raise StudyInputError(str(exc)) from None
        if not side:
            raise StudyInputError(f"{case_dir / (stage + '.json')}: file not found")
        row["N"] = int(side["N"])
        row[f"cpu_time_{stage}_s"] = float(side.get("cpu_time_s", np.nan))
        row[f"wall_time_{stage}_s"] = float(side["wall_time_s"])
    row["cpu_time_s"] = sum(row[f"cpu_time_{s}_s"] for s in stages)
    row["wall_time_s"] = sum(row[f"wall_time_{s}_s"] for s in stages)
    row["core_hours"] = row["cpu_time_s"] / 3600
    return row


def cost_table(cases: pd.DataFrame, bulk_dir) -> pd.DataFrame:
    """``cases`` (``bulk_cells.cases``: case, cell, seed, ...) with each case's cost columns."""
    stages = cases["stage"] if "stage" in cases else ["heaviside"] * len(cases)
    costs = pd.DataFrame([case_cost(Path(bulk_dir) / case, (*STAGES[:2], stage))
                          for case, stage in zip(cases["case"], stages)], index=cases.index)
    return pd.concat([cases.drop(columns=["N"], errors="ignore"), costs], axis=1)
