# Helpers shared by every rule file: the case table and the list of targets.
import sys
from itertools import product

PY = sys.executable  # the venv's python that runs snakemake also runs the stages
RESULTS = config.get("results_dir", "results")
YADE = "yade"


def _fmt(x):
    return f"{x:.6g}".replace("+", "")


def cases():
    """One row per (pressure, inertial number, seed): the DEM cases.

    Returns a dict label -> dict(pressure, inertial_number, seed).
    """
    loading, mat, cell = config["loading"], config["material"], config["cell"]
    table = {}
    for p in loading["pressures"]:
        if "inertial_numbers" in loading:
            rates = loading["inertial_numbers"]
        else:  # U -> I with the nominal gap
            d, rho, H = mat["diameter"], mat["density"], cell["H_over_d"] * mat["diameter"]
            rates = [2 * U / H * d / (p / rho) ** 0.5 for U in loading["wall_velocities"]]
        for I, seed in product(rates, config["seeds"]):
            label = f"p{_fmt(p)}_I{_fmt(I)}_s{seed}"
            table[label] = dict(pressure=float(p), inertial_number=float(I), seed=int(seed))
    return table


CASES = cases()
PROTOCOLS = list(config["protocols"])


def case_dir(label):
    return f"{RESULTS}/dem/{label}"


def dem_outputs(protocols=None):
    """Every reversal time series of the campaign."""
    return [
        f"{case_dir(label)}/{proto}.csv"
        for label in CASES
        for proto in (protocols or PROTOCOLS)
    ]


def all_targets():
    targets = dem_outputs() + [f"{RESULTS}/dem/campaign_summary.csv"]
    targets += calibration_targets() + model_targets() + accuracy_targets()
    return targets


wildcard_constraints:
    calset="[A-Za-z0-9.-]+(_[A-Za-z0-9.-]+)*",
