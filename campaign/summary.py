"""One table of the DEM campaign: a row per case, from the sidecars and the pre-shear.

The Snakemake rule `dem_summary` runs ``python -m campaign.summary --dem DIR
--cases LABEL=PRESSURE,I,SEED ... --stages STAGE ... --out FILE``. The files are
read through the contract's readers and the steady values are
``dem_contract.steady_values`` (the last half of the pre-shear strain), the same
numbers the calibration takes for each run.
"""
import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import DEMInputError, read_series, read_sidecar, stage_costs, steady_values, steady_window

#: The pre-shear columns the summary averages.
SUMMARY_COLUMNS = ("t", "strain", "A_xx", "A_xy", "mu", "phi", "Z")


def steady_row(series: pd.DataFrame) -> dict:
    """Steady mu (and its standard deviation over the window), |A|, theta_A, phi, Z of a pre-shear."""
    st = steady_values(series)
    mu = series["mu"].to_numpy()[steady_window(series["strain"].to_numpy())]
    return {
        "mu_steady": st["mu"],
        "mu_std": float(np.std(mu, ddof=1)),
        "A_norm_steady": st["A_norm"],
        "theta_A_steady_deg": st["theta_A"],
        "phi_steady": st["phi"],
        "Z_steady": st["Z"],
    }


def case_row(label: str, case: dict, case_dir: Path, stages: list[str]) -> dict:
    """The case's row: its stage costs (``dem_contract.stage_costs``), the pre-shear's sidecar and steady values."""
    cost = stage_costs(case_dir, stages, keys=("wall_time_s", "steps"), missing="raise")
    pre = read_sidecar(case_dir / "preshear.csv")
    row = {"case": label, **case, "N": cost["N"], "kappa_achieved": pre["kappa_achieved"],
           "inertial_number_achieved": pre["inertial_number_achieved"],
           "dt_over_tc": pre["dt_over_tc"], "steps_preshear": cost["steps_preshear"]}
    for stage in stages:
        row[f"wall_time_s_{stage}"] = cost[f"wall_time_{stage}_s"]
    row["particle_steps_per_s"] = pre["particle_steps_per_s"]
    row.update(steady_row(read_series(case_dir / "preshear.csv", SUMMARY_COLUMNS, what="the pre-shear of the case")))
    return row


def summary_table(dem_dir: Path, cases: dict, stages) -> pd.DataFrame:
    """A row per case (label -> dict(pressure, inertial_number, seed)) of ``dem_dir``/<label>/, in ``cases`` order.

    The stages' columns come pack, preshear, heaviside, sinusoidal first, then the reversal schedules by name.
    """
    order = ["pack", "preshear", "heaviside", "sinusoidal"]
    stages = sorted(set(stages), key=lambda s: (order.index(s) if s in order else len(order), s))
    return pd.DataFrame([case_row(label, case, Path(dem_dir) / label, stages) for label, case in cases.items()])


def parse_case(text: str) -> tuple[str, dict]:
    """``LABEL=PRESSURE,I,SEED`` -> (label, dict(pressure, inertial_number, seed))."""
    try:
        label, values = text.split("=", 1)
        pressure, inertial_number, seed = values.split(",")
        return label, dict(pressure=float(pressure), inertial_number=float(inertial_number), seed=int(seed))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--cases {text!r}: expected LABEL=PRESSURE,I,SEED, "
                                         "e.g. p100000_I0.01_s1=100000.0,0.01,1") from None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m campaign.summary", description=__doc__.splitlines()[0])
    ap.add_argument("--dem", required=True, help="the campaign's DEM folder (one sub-folder per case)")
    ap.add_argument("--cases", nargs="+", required=True, type=parse_case, metavar="LABEL=PRESSURE,I,SEED")
    ap.add_argument("--stages", nargs="+", required=True, help="pack, preshear and the protocols")
    ap.add_argument("--out", required=True, help="the table (CSV)")
    args = ap.parse_args(argv)
    try:
        table = summary_table(Path(args.dem), dict(args.cases), args.stages)
    except DEMInputError as exc:
        print(exc, file=sys.stderr)
        return 1
    table.to_csv(args.out, index=False, float_format="%.6g")
    print(table.to_string())
    return 0


if __name__ == "__main__":
    sys.exit(main())
