# Model 1 as the paper configured it: the pole a fitted offset delta above each run's start
# (X_c = max(X_rev, 0) + delta, model/pole_start.py; docs/model.md, Sec. 7b). Beside the
# stages, in files of its own, so the tables of Models 1 and 2 do not change:
#   results/calibration/<set>/pole_start.yaml, pole_start_profile.csv   (calibrate.pole_start_fit)
#   results/compare/<set>/pole_start_predictions.csv, pole_start_errors.csv  (compare.pole_start_predict)
#   results/claims/pole_start.csv: claim 4's statistic, the variant against Model 1 and Model 2
# The fit's budget follows the calibration options (--route2-evals, --profile-points): the words
# calibrate itself gets (CALIBRATE_OPTIONS, calibrate.smk), read by calibrate's own parser
# (calibrate.pole_start_fit.budget), its defaults included.
from calibrate.pole_start_fit import budget as pole_start_budget

POLE_START_EVALS, POLE_START_POINTS = pole_start_budget(CALIBRATE_OPTIONS)


rule pole_start_calibrate:
    input:
        params=lambda wc: calibration_params(wc.calset),
        series=lambda wc: [
            f"{case_dir(label)}/{stage}.csv"
            for label in CALIBRATION_SETS[wc.calset]["cases"]
            for stage in ["preshear", *CALIBRATION_SETS[wc.calset]["protocols"]]
        ],
    output:
        fit=f"{RESULTS}/calibration/{{calset}}/pole_start.yaml",
        profile=f"{RESULTS}/calibration/{{calset}}/pole_start_profile.csv",
    params:
        dirs=lambda wc: [case_dir(label) for label in CALIBRATION_SETS[wc.calset]["cases"]],
        protocols=lambda wc: CALIBRATION_SETS[wc.calset]["protocols"],
        evals=POLE_START_EVALS,
        points=POLE_START_POINTS,
    priority: set_priority
    resources:
        runtime=COST_CALIBRATE.runtime,
        mem_mb=COST_CALIBRATE.mem_mb,
    log:
        f"{RESULTS}/logs/calibration/pole_start_{{calset}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/calibration/pole_start_{{calset}}.tsv"
    threads: 1
    shell:
        "{PY:q} -m calibrate.pole_start_fit --dem {params.dirs:q} --params {input.params:q} --protocols {params.protocols:q}"
        " --max-evals {params.evals:q} --profile-points {params.points:q} --out {output.fit:q} > {log:q} 2>&1"


rule pole_start_compare:
    input:
        fit=f"{RESULTS}/calibration/{{calset}}/pole_start.yaml",
        series=campaign_series,
    output:
        predictions=f"{COMPARE}/{{calset}}/pole_start_predictions.csv",
        errors=f"{COMPARE}/{{calset}}/pole_start_errors.csv",
    params:
        dirs=[case_dir(label) for label in CASES],
        protocols=PROTOCOLS,
        train_cases=lambda wc: CALIBRATION_SETS[wc.calset]["cases"],
        train_protocols=lambda wc: CALIBRATION_SETS[wc.calset]["protocols"],
        out=lambda wc: f"{COMPARE}/{wc.calset}",
    resources:
        runtime=COST_COMPARE.runtime,
        mem_mb=COST_COMPARE.mem_mb,
    log:
        f"{RESULTS}/logs/compare/pole_start_{{calset}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/compare/pole_start_{{calset}}.tsv"
    threads: 1
    shell:
        "{PY:q} -m compare.pole_start_predict --dem {params.dirs:q} --fit {input.fit:q} --set {wildcards.calset:q}"
        " --protocols {params.protocols:q} --train-cases {params.train_cases:q}"
        " --train-protocols {params.train_protocols:q} --out {params.out:q} > {log:q} 2>&1"


rule pole_start_claims:
    input:
        predictions=expand(f"{COMPARE}/{{calset}}/predictions.csv", calset=list(CALIBRATION_SETS)),
        errors=expand(f"{COMPARE}/{{calset}}/errors.csv", calset=list(CALIBRATION_SETS)),
        variant=expand(f"{COMPARE}/{{calset}}/pole_start_predictions.csv", calset=list(CALIBRATION_SETS)),
        variant_errors=expand(f"{COMPARE}/{{calset}}/pole_start_errors.csv", calset=list(CALIBRATION_SETS)),
    output:
        f"{CLAIMS}/pole_start.csv",
    params:
        sets=list(CALIBRATION_SETS),
        resamples=CLAIMS_RESAMPLES,
    resources:
        runtime=COST_CLAIMS.runtime,
        mem_mb=COST_CLAIMS.mem_mb,
    log:
        f"{RESULTS}/logs/claims/pole_start.log",
    benchmark:
        f"{RESULTS}/benchmarks/claims/pole_start.tsv"
    threads: 1
    shell:
        "{PY:q} -m claims.pole_start_claim --compare {COMPARE:q} --sets {params.sets:q} --resamples {params.resamples:q}"
        " --out {output:q} > {log:q} 2>&1"


def pole_start_targets():
    """The variant's claims rows (and through them its fits and predictions for every set)."""
    return list(rules.pole_start_claims.output)
