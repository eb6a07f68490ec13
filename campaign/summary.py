"""One table of the DEM campaign: a row per case, from the sidecars and the pre-shear.

Called by the Snakemake rule `dem_summary`. The files are read through the
contract's readers and the steady values are ``dem_contract.steady_values``
(the last half of the pre-shear strain), the same numbers the calibration
takes for each run.
"""
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository (Snakemake sets __file__)

from dem_contract import read_series, read_sidecar, stage_costs, steady_values, steady_window  # noqa: E402

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


def main(snakemake):
    order = ["pack", "preshear", "heaviside", "sinusoidal"]   # then the reversal schedules, by name
    stages = sorted({Path(p).stem for p in snakemake.input.sidecars},
                    key=lambda s: (order.index(s) if s in order else len(order), s))
    rows = [
        case_row(label, case, Path(snakemake.input.series[i]).parent, stages)
        for i, (label, case) in enumerate(snakemake.params.cases.items())
    ]
    table = pd.DataFrame(rows)
    table.to_csv(snakemake.output[0], index=False, float_format="%.6g")
    with open(snakemake.log[0], "w") as log:
        print(table.to_string(), file=log)


if "snakemake" in globals():
    main(snakemake)  # noqa: F821 (injected by Snakemake's script directive)
