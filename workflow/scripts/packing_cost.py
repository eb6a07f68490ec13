"""What the packing costs in a DEM campaign: one row per campaign, from the stage sidecars.

Called by the Snakemake rule `packing_cost` (workflow/rules/accuracy.smk). For every case
the sidecars ``<stage>.json`` give ``cpu_time_s`` and ``steps``; the case's DEM cost is the
sum over its stages (pack, pre-shear, protocols), and the pack's fraction of it is

    f_case = pack / (pack + preshear + sum of the protocols),

in CPU time and in steps. The row gives the means and maxima over the cases.
"""
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository (Snakemake sets __file__)

from dem_contract import DEMInputError, read_sidecar  # noqa: E402

#: The issue's target: the pack at most this fraction of a case's DEM time.
TARGET_FRACTION = 0.10


def case_costs(case_dir: Path, stages: list[str]) -> dict:
    """CPU seconds and steps of each stage of one case, from its sidecars."""
    out = {}
    for stage in stages:
        side = read_sidecar(Path(case_dir) / f"{stage}.csv")
        missing = [k for k in ("cpu_time_s", "steps") if k not in side]
        if missing:
            raise DEMInputError(f"{Path(case_dir) / f'{stage}.json'}: sidecar missing or without {', '.join(missing)}")
        out[stage] = (float(side["cpu_time_s"]), int(side["steps"]))
    return out


def packing_cost(campaign: str, case_dirs: list[Path], stages: list[str]) -> pd.DataFrame:
    """One row: number of cases, pack CPU s and steps (mean, max), the case's DEM CPU s and steps
    (mean), the pack's fraction of the case in CPU and in steps (mean, max) and the target."""
    if "pack" not in stages:
        raise ValueError(f"stages {stages} must include pack")
    rows = []
    for d in case_dirs:
        c = case_costs(d, stages)
        cpu = sum(v[0] for v in c.values())
        steps = sum(v[1] for v in c.values())
        rows.append(dict(pack_cpu=c["pack"][0], pack_steps=c["pack"][1], case_cpu=cpu, case_steps=steps,
                         f_cpu=c["pack"][0] / cpu, f_steps=c["pack"][1] / steps))
    t = pd.DataFrame(rows)
    return pd.DataFrame([dict(
        campaign=campaign, n_cases=len(t), stages="+".join(stages),
        pack_cpu_s_mean=t["pack_cpu"].mean(), pack_cpu_s_max=t["pack_cpu"].max(),
        pack_steps_mean=t["pack_steps"].mean(), pack_steps_max=int(t["pack_steps"].max()),
        case_cpu_s_mean=t["case_cpu"].mean(), case_steps_mean=t["case_steps"].mean(),
        pack_cpu_fraction_mean=t["f_cpu"].mean(), pack_cpu_fraction_max=t["f_cpu"].max(),
        pack_steps_fraction_mean=t["f_steps"].mean(), pack_steps_fraction_max=t["f_steps"].max(),
        target_fraction=TARGET_FRACTION,
        within_target=bool(np.all(t[["f_cpu", "f_steps"]].to_numpy() <= TARGET_FRACTION)))])


def main(snakemake):
    stages = sorted({Path(p).stem for p in snakemake.input.sidecars},
                    key=["pack", "preshear", "heaviside", "sinusoidal"].index)
    case_dirs = sorted({Path(p).parent for p in snakemake.input.sidecars})
    table = packing_cost(snakemake.params.campaign, case_dirs, stages)
    table.to_csv(snakemake.output[0], index=False, float_format="%.6g")
    with open(snakemake.log[0], "w") as log:
        print(table.T.to_string(), file=log)


if "snakemake" in globals():
    main(snakemake)  # noqa: F821 (injected by Snakemake's script directive)
