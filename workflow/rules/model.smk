# The continuum model against the DEM (python -m compare, see compare/README.md).
# Per calibration set: Model 1 and Model 2 integrated on every DEM run's own
# imposed history from its pre-reversal fabric -> errors, claims, Fig. 4 / Fig. 5.
# Across sets: in-sample against out-of-sample errors. For one set: sensitivity.
# Optional config keys under `model:` (all have defaults):
#   sensitivity_set: calibration set whose parameters are perturbed ("all")
#   compare_options: extra options of `compare predict` (e.g. "--zoom 0.05")

MODEL_FIGURES = {"heaviside": "fig4_heaviside", "sinusoidal": "fig5_sinusoidal"}
MODEL_TABLES = ["errors", "claims"]
SENSITIVITY_SET = config.get("model", {}).get("sensitivity_set", "all")


wildcard_constraints:
    calset="|".join(CALIBRATION_SETS) or "all",


def model_dem_inputs(wildcards=None):
    """Every pre-shear and reversal run the comparison reads (all cases, all protocols)."""
    return [
        f"{case_dir(label)}/{stage}.csv"
        for label in CASES
        for stage in ["preshear", *PROTOCOLS]
    ]


rule model_predict:
    input:
        params=lambda wc: calibration_params(wc.calset),
        series=model_dem_inputs,
    output:
        predictions=f"{RESULTS}/model/{{calset}}/predictions.csv",
        tables=[
            report(
                f"{RESULTS}/model/{{calset}}/{name}.csv",
                caption=f"../report/{name}.rst",
                category="Model against DEM",
                subcategory="{calset}",
            )
            for name in MODEL_TABLES
        ],
        figures=[
            report(
                f"{RESULTS}/model/{{calset}}/{MODEL_FIGURES[proto]}.png",
                caption=f"../report/{MODEL_FIGURES[proto]}.rst",
                category="Model against DEM",
                subcategory="{calset}",
            )
            for proto in PROTOCOLS
            if proto in MODEL_FIGURES
        ],
    params:
        dirs=[case_dir(label) for label in CASES],
        protocols=[p for p in PROTOCOLS if p in MODEL_FIGURES],
        train_cases=lambda wc: CALIBRATION_SETS[wc.calset]["cases"],
        train_protocols=lambda wc: CALIBRATION_SETS[wc.calset]["protocols"],
        out=lambda wc: f"{RESULTS}/model/{wc.calset}",
        options=config.get("model", {}).get("compare_options", ""),
    log:
        f"{RESULTS}/logs/model/predict_{{calset}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/model/predict_{{calset}}.tsv"
    threads: 1
    shell:
        "{PY} -m compare predict --dem {params.dirs} --params {input.params} --set {wildcards.calset}"
        " --protocols {params.protocols} --train-cases {params.train_cases}"
        " --train-protocols {params.train_protocols} --out {params.out} {params.options} > {log} 2>&1"


rule model_heldout:
    input:
        errors=expand(f"{RESULTS}/model/{{calset}}/errors.csv", calset=list(CALIBRATION_SETS)),
    output:
        report(
            f"{RESULTS}/model/heldout_errors.csv",
            caption="../report/heldout_errors.rst",
            category="Model against DEM",
        ),
    log:
        f"{RESULTS}/logs/model/heldout.log",
    benchmark:
        f"{RESULTS}/benchmarks/model/heldout.tsv"
    threads: 1
    shell:
        "{PY} -m compare heldout --errors {input.errors} --out {output} > {log} 2>&1"


rule model_sensitivity:
    input:
        params=calibration_params(SENSITIVITY_SET),
        series=model_dem_inputs,
    output:
        table=report(
            f"{RESULTS}/model/{SENSITIVITY_SET}/sensitivity.csv",
            caption="../report/sensitivity.rst",
            category="Model against DEM",
            subcategory=SENSITIVITY_SET,
        ),
        figure=report(
            f"{RESULTS}/model/{SENSITIVITY_SET}/sensitivity_band.png",
            caption="../report/sensitivity_band.rst",
            category="Model against DEM",
            subcategory=SENSITIVITY_SET,
        ),
    params:
        dirs=[case_dir(label) for label in CASES],
        protocols=[p for p in PROTOCOLS if p in MODEL_FIGURES],
        out=f"{RESULTS}/model/{SENSITIVITY_SET}",
    log:
        f"{RESULTS}/logs/model/sensitivity_{SENSITIVITY_SET}.log",
    benchmark:
        f"{RESULTS}/benchmarks/model/sensitivity_{SENSITIVITY_SET}.tsv"
    threads: 1
    shell:
        "{PY} -m compare sensitivity --dem {params.dirs} --params {input.params} --set {SENSITIVITY_SET}"
        " --protocols {params.protocols} --out {params.out} > {log} 2>&1"


def model_targets():
    """Per calibration set: predictions, errors, claims, Fig. 4/5; across sets: held-out table; sensitivity."""
    targets = []
    for calset in CALIBRATION_SETS:
        targets.append(f"{RESULTS}/model/{calset}/predictions.csv")
        targets += [f"{RESULTS}/model/{calset}/{name}.csv" for name in MODEL_TABLES]
        targets += [
            f"{RESULTS}/model/{calset}/{MODEL_FIGURES[p]}.png" for p in PROTOCOLS if p in MODEL_FIGURES
        ]
    targets.append(f"{RESULTS}/model/heldout_errors.csv")
    if SENSITIVITY_SET in CALIBRATION_SETS:
        targets += [
            f"{RESULTS}/model/{SENSITIVITY_SET}/sensitivity.csv",
            f"{RESULTS}/model/{SENSITIVITY_SET}/sensitivity_band.png",
        ]
    return targets
