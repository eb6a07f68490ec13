# Calibration: DEM time series -> alpha1, alpha2 vs X -> fits of Eq. 6, Eq. 2, Model 2.
# One calibration per "set" of config["calibration"]["sets"]: which cases and
# protocols it learns from (the held-out comparisons use the others).


from campaign import stage_options
from campaign.calibration_sets import calibration_sets

CALIBRATION_SETS = calibration_sets(config, CASES)  # name -> dict(cases, protocols)
# calibration.options as words, each one argument of the command (campaign/stage_options.py)
CALIBRATE_OPTIONS = stage_options.words(config, "calibration.options")


# The {calset} wildcard of every rule (calibration, comparison): one of the campaign's sets
# (their names are checked by the pre-flight, preflight.checks.SET_NAME).
wildcard_constraints:
    calset="|".join(CALIBRATION_SETS),


CALIBRATION_FIGURES = [
    "fig2a_stress_vs_Axy",
    "fig2b_mu_vs_X",
    "fig3a_alpha1_vs_X",
    "fig3b_alpha2_vs_X",
]
CALIBRATION_TABLES = ["params_table", "backsolve_alpha_vs_X", "fit_quality"]
# Also written by python -m calibrate (calibrate/pipeline.py), not in the report:
# the bootstrap replicates, their held-out scores, the fitted curves on the DEM,
# and what the data determine (calibrate/profiles.py, calibrate/identifiability.py):
# the curve fit's objective profiled over X_c and the c_i, its figure, the sensitivity
# matrix's singular values, and the verdict per parameter.
CALIBRATION_EXTRA = {
    "bootstrap": "bootstrap_values.csv",
    "heldout": "heldout_scores.csv",
    "curves": "fig_curves_model_vs_dem.png",
    "profiles": "profiles.csv",
    "profile_figure": "fig_profiles.png",
    "svd": "sensitivity_svd.csv",
    "identifiability": "identifiability.csv",
}
# calibration.freeform: the free-form alpha1(X), alpha2(X) fit (calibrate/freeform.py), its table
# beside the others and its curves on Figs. 3a, 3b. freeform.csv is declared either way (without
# the option calibrate writes its header and one note row, as it does for a fit it cannot run),
# so a toggle changes only params and the params trigger reruns every set: an output declared
# only with the option has no metadata in a finished set, and Snakemake then checks neither its
# params nor, unless a target asks for it, that the file is missing. Likewise calibrate writes
# heldout_scores.csv always: its header alone when no bootstrap replicate held a seed out (one seed).
CALIBRATION_FREEFORM = config["calibration"]["freeform"]


def calibration_params(calset):
    return f"{RESULTS}/calibration/{calset}/params.yaml"


rule calibrate:
    input:
        series=lambda wc: [
            f"{case_dir(label)}/{stage}.csv"
            for label in CALIBRATION_SETS[wc.calset]["cases"]
            for stage in ["preshear", *CALIBRATION_SETS[wc.calset]["protocols"]]
        ],
    output:
        params=f"{RESULTS}/calibration/{{calset}}/params.yaml",
        tables=[
            report(
                f"{RESULTS}/calibration/{{calset}}/{name}.csv",
                caption=f"../report/{name}.rst",
                category="Calibration",
                subcategory="{calset}",
            )
            for name in CALIBRATION_TABLES
        ],
        figures=[
            report(
                f"{RESULTS}/calibration/{{calset}}/{name}.png",
                caption=f"../report/{name}.rst",
                category="Calibration",
                subcategory="{calset}",
            )
            for name in CALIBRATION_FIGURES
        ],
        **{key: f"{RESULTS}/calibration/{{calset}}/{name}" for key, name in CALIBRATION_EXTRA.items()},
        freeform=(
            report(
                f"{RESULTS}/calibration/{{calset}}/freeform.csv",
                caption="../report/freeform.rst",
                category="Calibration",
                subcategory="{calset}",
            )
            if CALIBRATION_FREEFORM
            else f"{RESULTS}/calibration/{{calset}}/freeform.csv"
        ),
    params:
        dirs=lambda wc: [case_dir(label) for label in CALIBRATION_SETS[wc.calset]["cases"]],
        protocols=lambda wc: CALIBRATION_SETS[wc.calset]["protocols"],
        options=CALIBRATE_OPTIONS,
        freeform=["--freeform"] if CALIBRATION_FREEFORM else [],
        out=lambda wc: f"{RESULTS}/calibration/{wc.calset}",
    priority: set_priority
    resources:
        runtime=COST_CALIBRATE.runtime,
        mem_mb=COST_CALIBRATE.mem_mb,
    log:
        f"{RESULTS}/logs/calibration/{{calset}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/calibration/{{calset}}.tsv"
    threads: 1
    shell:
        "{PY:q} -m calibrate --dem {params.dirs:q} --protocols {params.protocols:q}"
        " --out {params.out:q} {params.freeform:q} {params.options:q} > {log:q} 2>&1"


def calibration_targets():
    """Every declared output of every set: a missing one (an output new to the rule) reruns its set."""
    return [str(path) for name in CALIBRATION_SETS for path in expand(rules.calibrate.output, calset=name)]
