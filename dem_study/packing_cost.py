"""What the packing costs in a DEM campaign: one row per campaign, from the stage sidecars.

The Snakemake rule `packing_cost` (workflow/rules/accuracy.smk) runs ``python -m
dem_study.packing_cost --campaign NAME --sidecars <case>/<stage>.json ... --out FILE``. For every case
the sidecars ``<stage>.json`` give ``cpu_time_s`` and ``steps`` (``dem_contract.stage_costs``: a
missing sidecar or key is a ``DEMInputError``); the case's DEM cost is the sum over its stages
(pack, pre-shear, protocols), and the pack's fraction of it is

    f_case = pack / (pack + preshear + sum of the protocols),

in CPU time and in steps. The row gives the means and maxima over the cases.
"""
import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import DEMInputError, stage_costs

#: The issue's target: the pack at most this fraction of a case's DEM time.
TARGET_FRACTION = 0.10


def packing_cost(campaign: str, case_dirs: list[Path], stages: list[str]) -> pd.DataFrame:
    """One row: number of cases, pack CPU s and steps (mean, max), the case's DEM CPU s and steps
    (mean), the pack's fraction of the case in CPU and in steps (mean, max) and the target."""
    if "pack" not in stages:
        raise ValueError(f"stages {stages} must include pack")
    rows = []
    for d in case_dirs:
        c = stage_costs(d, stages, keys=("cpu_time_s", "steps"), missing="raise")
        rows.append(dict(pack_cpu=c["cpu_time_pack_s"], pack_steps=c["steps_pack"], case_cpu=c["cpu_time_s"],
                         case_steps=c["steps"], f_cpu=c["cpu_time_pack_s"] / c["cpu_time_s"],
                         f_steps=c["steps_pack"] / c["steps"]))
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


def stage_order(sidecars) -> list[str]:
    """The stages of the sidecar paths: pack and preshear first, then the protocols in their order
    (heaviside, sinusoidal or any reversal schedule's name)."""
    names = list(dict.fromkeys(Path(p).stem for p in sidecars))
    return [s for s in ("pack", "preshear") if s in names] + [s for s in names if s not in ("pack", "preshear")]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m dem_study.packing_cost", description=__doc__.splitlines()[0])
    ap.add_argument("--campaign", required=True, help="the campaign's name (config key campaign)")
    ap.add_argument("--sidecars", nargs="+", required=True, help="every <case>/<stage>.json of the campaign")
    ap.add_argument("--out", required=True, help="the one-row table (CSV)")
    args = ap.parse_args(argv)
    stages = stage_order(args.sidecars)
    case_dirs = sorted({Path(p).parent for p in args.sidecars})
    try:
        table = packing_cost(args.campaign, case_dirs, stages)
    except DEMInputError as exc:   # a missing sidecar or key (stage_costs)
        print(exc, file=sys.stderr)
        return 1
    table.to_csv(args.out, index=False, float_format="%.6g")
    print(table.T.to_string())
    return 0


if __name__ == "__main__":
    sys.exit(main())
