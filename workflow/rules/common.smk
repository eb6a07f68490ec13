# Helpers shared by every rule file: the case table and the list of targets.
# The case table and the scenes come from the campaign package (campaign/).
import sys

from campaign.cases import cases
from campaign.scenes import result_key, scene_from_config, scene_of_result_key, write_scene

PY = sys.executable  # the venv's python that runs snakemake also runs the stages
RESULTS = config["results_dir"]  # the schema's default when the config has none (Snakefile: validate)
YADE = "yade"

CASES = cases(config)  # label -> dict(pressure, inertial_number, seed)
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


def campaign_series(wildcards=None):
    """Every pre-shear and reversal series of the campaign (all cases, all protocols)."""
    return [f"{case_dir(label)}/{stage}.csv" for label in CASES for stage in ["preshear", *PROTOCOLS]]


def all_targets():
    targets = dem_outputs() + [f"{RESULTS}/dem/campaign_summary.csv"]
    targets += calibration_targets() + compare_targets() + claims_targets() + accuracy_targets()
    targets += report_table_targets()  # report.smk: the verdict tables as HTML for the report
    return targets
