# Shear reversal of a dense 2D granular layer: DEM campaign -> calibration -> comparison.
# `snakemake -j2` runs the paper's campaign (config/config.yaml);
# `snakemake -j2 --configfile config/quick.yaml` the quick one.
import sys

from snakemake.utils import min_version, validate

min_version("9.0")

# The repository's packages (campaign, dem_contract, dem_study) import from here.
sys.path.insert(0, workflow.basedir)


# The paper preset is the default; a --configfile replaces it (presets are
# complete, so nothing of the paper preset leaks into the quick or CI one).
if not workflow.overwrite_configfiles:

    configfile: "config/config.yaml"


# Pre-flight: every bad input is named (key, value, allowed) before any job, exit code 2.
import preflight

preflight.stop_on_problems(preflight.check(config, workflow.configfiles))
validate(config, "workflow/schemas/config.schema.yaml")  # fills the schema's defaults

# The price of the campaign's DEM on the cores given (-j), before any job; once, not in a cluster job.
from preflight import price as preflight_price

if workflow.is_main_process:
    preflight_price.print_price(config, preflight_price.workflow_cores(workflow))


include: "workflow/rules/common.smk"
include: "workflow/rules/resources.smk"
include: "workflow/rules/dem.smk"
include: "workflow/rules/release.smk"
include: "workflow/rules/calibrate.smk"
include: "workflow/rules/compare.smk"
include: "workflow/rules/claims.smk"
include: "workflow/rules/pole_start.smk"
include: "workflow/rules/accuracy.smk"
include: "workflow/rules/dem_study.smk"
include: "workflow/rules/bulk_study.smk"
include: "workflow/rules/report.smk"


# One writer per results folder, from any working directory (campaign/results_lock.py): only a
# run that executes jobs takes the lock (not -n, --summary, --report); a second one exits with 5.
from campaign import results_lock


onstart:
    results_lock.take_or_exit(RESULTS)


onsuccess:
    results_lock.give_back()


onerror:
    results_lock.give_back()


rule all:
    input:
        all_targets() + pole_start_targets(),
    default_target: True
