# The paper's claims decided with statistics (python -m claims, see the claims package):
# results/claims/paper_claims.csv (one row per claim, and per figure for claims 4, 7, 9:
# statistic, 90 % interval, test, n, adequacy, verdict), its forest plot and the Markdown
# section the README links to, and power.csv: seeds (and DEM volume, core-hours) needed to
# decide every model comparison with 80 % power, with whether the paper (and bulk) preset
# reach it.
# Reads every calibration set's predictions.csv and errors.csv (the model comparisons
# use only runs a set was not calibrated on) and pole_start_predictions.csv (the paper's
# configuration of Model 1, rows 4-start-*), the DEM series of every protocol (each
# reversal of a schedule is one run of its kind), and set "all"'s Eq. 2
# (and its freeform.csv with calibration.freeform: claims 9 and 10, the free-form upper bound).
# Optional config keys under `claims:` (all have defaults):
#   resamples: bootstrap resamples (2000)

from pathlib import Path

CLAIMS = f"{RESULTS}/claims"
CLAIMS_CATEGORY = "The paper's claims"
CLAIMS_RESAMPLES = config["claims"]["resamples"]
# Presets whose power the README section states (those whose config file exists), found
# beside the Snakefile whatever the working directory (snakemake -d elsewhere).
CLAIMS_PRESETS = {name: str(Path(workflow.basedir) / path)
                  for name, path in (("paper", "config/config.yaml"), ("bulk", "config/bulk.yaml"))
                  if (Path(workflow.basedir) / path).exists()}


def dem_sidecars(wildcards=None):
    """The stage sidecars and scenes of every case: disks and CPU time of the DEM (claims/power.py)."""
    return [f"{case_dir(label)}/{stage}.json" for label in CASES for stage in ["pack", "preshear", *PROTOCOLS]] + [
        f"{case_dir(label)}/scene.json" for label in CASES]


rule claims:
    input:
        predictions=expand(f"{COMPARE}/{{calset}}/predictions.csv", calset=list(CALIBRATION_SETS)),
        errors=expand(f"{COMPARE}/{{calset}}/errors.csv", calset=list(CALIBRATION_SETS)),
        variant=expand(f"{COMPARE}/{{calset}}/pole_start_predictions.csv", calset=list(CALIBRATION_SETS)),
        variant_errors=expand(f"{COMPARE}/{{calset}}/pole_start_errors.csv", calset=list(CALIBRATION_SETS)),
        series=campaign_series,
        params=calibration_params("all"),
        sidecars=dem_sidecars,
        presets=list(CLAIMS_PRESETS.values()),
        **({"freeform": f"{RESULTS}/calibration/all/freeform.csv"} if CALIBRATION_FREEFORM else {}),
    output:
        table=report(
            f"{CLAIMS}/paper_claims.csv",
            caption="../report/paper_claims.rst",
            category=CLAIMS_CATEGORY,
        ),
        figure=report(
            f"{CLAIMS}/paper_claims.png",
            caption="../report/paper_claims_figure.rst",
            category=CLAIMS_CATEGORY,
        ),
        section=f"{CLAIMS}/README_section.md",
        power=report(
            f"{CLAIMS}/power.csv",
            caption="../report/claims_power.rst",
            category=CLAIMS_CATEGORY,
        ),
        design=report(
            f"{CLAIMS}/reversal_design.csv",
            caption="../report/reversal_design.rst",
            category=CLAIMS_CATEGORY,
        ),
        eq2=f"{CLAIMS}/eq2_vs_paper.csv",
        eq2_figure=report(
            f"{CLAIMS}/eq2_vs_paper.png",
            caption="../report/eq2_vs_paper.rst",
            category=CLAIMS_CATEGORY,
        ),
    params:
        dirs=[case_dir(label) for label in CASES],
        protocols=PROTOCOLS,
        sets=list(CALIBRATION_SETS),
        resamples=CLAIMS_RESAMPLES,
        presets=[f"{name}={path}" for name, path in CLAIMS_PRESETS.items()],
        freeform=["--freeform", f"{RESULTS}/calibration/all/freeform.csv"] if CALIBRATION_FREEFORM else [],
        out=CLAIMS,
    resources:
        runtime=COST_CLAIMS.runtime,
        mem_mb=COST_CLAIMS.mem_mb,
    log:
        f"{RESULTS}/logs/claims/claims.log",
    benchmark:
        f"{RESULTS}/benchmarks/claims/claims.tsv"
    threads: 1
    shell:
        "{PY:q} -m claims --compare {COMPARE:q} --dem {params.dirs:q} --protocols {params.protocols:q}"
        " --calibration {input.params:q}"
        " --sets {params.sets:q} --resamples {params.resamples:q} --preset {params.presets:q} {params.freeform:q}"
        " --pole-start --out {params.out:q} > {log:q} 2>&1"


# The planner (python -m claims plan): for every claim the table leaves undecided, the seeds and
# core-hours (the campaign's measured stage costs; 'unknown' when not measured) that decide it
# at 80 % power: reproduced, contradicted or negligible. Extending `seeds:` reruns no finished seed.
rule claims_plan:
    input:
        table=f"{CLAIMS}/paper_claims.csv",
        sidecars=dem_sidecars,
    output:
        report(f"{CLAIMS}/plan.csv", caption="../report/claims_plan.rst", category=CLAIMS_CATEGORY),
    params:
        dirs=[case_dir(label) for label in CASES],
        protocols=PROTOCOLS,
    resources:
        runtime=COST_CLAIMS.runtime,     # an upper bound: the plan reads one table and the sidecars
        mem_mb=COST_CLAIMS.mem_mb,
    log:
        f"{RESULTS}/logs/claims/claims_plan.log",
    benchmark:
        f"{RESULTS}/benchmarks/claims/claims_plan.tsv"
    threads: 1
    shell:
        "{PY:q} -m claims plan --table {input.table:q} --dem {params.dirs:q} --protocols {params.protocols:q}"
        " --out {output:q} > {log:q} 2>&1"


def claims_targets():
    """The claims table, its figure, its README section, the power table and the plan."""
    return list(rules.claims.output) + list(rules.claims_plan.output)
