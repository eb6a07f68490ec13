"""One table of the DEM campaign: a row per case, from the sidecars and the pre-shear.

Called by the Snakemake rule `dem_summary`. Steady values are means over the
last third of the pre-shear strain (DESIGN.md: steady by strain 1).
"""
import json
from pathlib import Path

import numpy as np
import pandas as pd

STEADY_FRACTION = 1 / 3  # last third of the pre-shear


def steady_values(series: pd.DataFrame) -> dict:
    """Mean mu, |A|, theta_A, phi, Z over the last third of a pre-shear."""
    s = series["strain"]
    tail = series[s >= s.iloc[0] + (1 - STEADY_FRACTION) * (s.iloc[-1] - s.iloc[0])]
    a, b = tail["A_xx"].mean(), tail["A_xy"].mean()
    return {
        "mu_steady": tail["mu"].mean(),
        "mu_std": tail["mu"].std(),
        "A_norm_steady": float(np.sqrt(2 * (a**2 + b**2))),
        "theta_A_steady_deg": float(np.mod(np.degrees(0.5 * np.arctan2(b, a)), 180)),
        "phi_steady": tail["phi"].mean(),
        "Z_steady": tail["Z"].mean(),
    }


def case_row(label: str, case: dict, case_dir: Path, stages: list[str]) -> dict:
    sidecars = {stage: json.loads((case_dir / f"{stage}.json").read_text()) for stage in stages}
    pre = sidecars["preshear"]
    row = {"case": label, **case, "N": pre["N"], "kappa_achieved": pre["kappa_achieved"],
           "inertial_number_achieved": pre["inertial_number_achieved"],
           "dt_over_tc": pre["dt_over_tc"], "steps_preshear": pre["steps"]}
    for stage, side in sidecars.items():
        row[f"wall_time_s_{stage}"] = side["wall_time_s"]
    row["particle_steps_per_s"] = pre["particle_steps_per_s"]
    row.update(steady_values(pd.read_csv(case_dir / "preshear.csv")))
    return row


def main(snakemake):
    stages = sorted({Path(p).stem for p in snakemake.input.sidecars},
                    key=["pack", "preshear", "heaviside", "sinusoidal"].index)
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
