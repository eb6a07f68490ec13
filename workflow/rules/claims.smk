# The paper's claims decided with statistics (python -m claims, see the claims package):
# results/claims/paper_claims.csv (one row per claim: statistic, 95 % interval, test,
# n, verdict), its forest plot and the Markdown section the README links to.
# Reads every calibration set's predictions.csv and errors.csv (the model comparisons
# use only runs a set was not calibrated on), the DEM series, and set "all"'s Eq. 2
# (and its freeform.csv with calibration.freeform: claims 8 and 9, the free-form upper bound).
# Optional config keys under `claims:` (all have defaults):
#   resamples: bootstrap resamples (2000)

CLAIMS = f"{RESULTS}/claims"
CLAIMS_CATEGORY = "The paper's claims"
CLAIMS_RESAMPLES = config.get("claims", {}).get("resamples", 2000)


rule claims:
    input:
        predictions=expand(f"{COMPARE}/{{calset}}/predictions.csv", calset=list(CALIBRATION_SETS)),
        errors=expand(f"{COMPARE}/{{calset}}/errors.csv", calset=list(CALIBRATION_SETS)),
        series=campaign_series,
        params=calibration_params("all"),
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
    params:
        dirs=[case_dir(label) for label in CASES],
        sets=list(CALIBRATION_SETS),
        resamples=CLAIMS_RESAMPLES,
        freeform=f"--freeform {RESULTS}/calibration/all/freeform.csv" if CALIBRATION_FREEFORM else "",
    resources:
        runtime=COST_CLAIMS.runtime,
        mem_mb=COST_CLAIMS.mem_mb,
    log:
        f"{RESULTS}/logs/claims/claims.log",
    benchmark:
        f"{RESULTS}/benchmarks/claims/claims.tsv"
    threads: 1
    shell:
        "{PY} -m claims --compare {COMPARE} --dem {params.dirs} --calibration {input.params}"
        " --sets {params.sets} --resamples {params.resamples} {params.freeform} --out {CLAIMS} > {log} 2>&1"


def claims_targets():
    """The claims table, its figure and its README section."""
    return list(rules.claims.output)
