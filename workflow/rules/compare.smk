# The comparison stage: the continuum models against the DEM (python -m compare,
# see compare/README.md), outputs under {RESULTS}/compare/.
# Per calibration set: Model 1 and Model 2 integrated on every reversal of every DEM
# run (every protocol: a schedule's reversals too) on its own imposed history from
# its pre-reversal fabric -> errors, claims, Fig. 4 (every Heaviside step) / Fig. 5
# (every half cosine).
# Across sets: in-sample against out-of-sample errors. For one set: sensitivity.
# Optional config keys under `compare:` (all have defaults):
#   sensitivity_set: calibration set whose parameters are perturbed ("all")
#   options: extra options of `compare predict` (e.g. "--zoom 0.05")

from campaign import stage_options
from campaign.scene_spec import protocol_segments
from compare.cli import FIGURE_NAMES
from dem_contract.derived import reversal_kinds

COMPARE = f"{RESULTS}/compare"
# reversal kind -> its figure's stem (one home: compare/cli.py's FIGURE_NAMES): every reversal of
# that kind (a Heaviside step, a half cosine) of every protocol
COMPARE_FIGURES = {kind: name.removesuffix(".png") for kind, name in FIGURE_NAMES.items()}


def protocol_kinds(protocols):
    """The reversal kinds the protocols hold (a schedule's from its segments), in COMPARE_FIGURES order."""
    kinds = set()
    for name in protocols:
        segs = protocol_segments(name, config["protocols"][name])
        kinds |= {k["kind"] for k in reversal_kinds({"segments": segs}, name)} if segs else set()
    return [k for k in COMPARE_FIGURES if k in kinds]


COMPARE_KINDS = protocol_kinds(PROTOCOLS)
COMPARE_TABLES = ["errors", "claims"]
COMPARE_CATEGORY = "Models against the DEM"
SENSITIVITY_SET = config["compare"]["sensitivity_set"]
# compare.options as words, each one argument of the command (campaign/stage_options.py)
COMPARE_OPTIONS = stage_options.words(config, "compare.options")


rule compare_predict:
    input:
        params=lambda wc: calibration_params(wc.calset),
        series=campaign_series,
    output:
        predictions=f"{COMPARE}/{{calset}}/predictions.csv",
        tables=[
            report(
                f"{COMPARE}/{{calset}}/{name}.csv",
                caption=f"../report/{name}.rst",
                category=COMPARE_CATEGORY,
                subcategory="{calset}",
            )
            for name in COMPARE_TABLES
        ],
        figures=[
            report(
                f"{COMPARE}/{{calset}}/{COMPARE_FIGURES[proto]}.png",
                caption=f"../report/{COMPARE_FIGURES[proto]}.rst",
                category=COMPARE_CATEGORY,
                subcategory="{calset}",
            )
            for proto in COMPARE_KINDS
        ],
    params:
        dirs=[case_dir(label) for label in CASES],
        protocols=PROTOCOLS,
        kinds=COMPARE_KINDS,
        train_cases=lambda wc: CALIBRATION_SETS[wc.calset]["cases"],
        train_protocols=lambda wc: CALIBRATION_SETS[wc.calset]["protocols"],
        out=lambda wc: f"{COMPARE}/{wc.calset}",
        options=COMPARE_OPTIONS,
    resources:
        runtime=COST_COMPARE.runtime,
        mem_mb=COST_COMPARE.mem_mb,
    log:
        f"{RESULTS}/logs/compare/predict_{{calset}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/compare/predict_{{calset}}.tsv"
    threads: 1
    shell:
        "{PY:q} -m compare predict --dem {params.dirs:q} --params {input.params:q} --set {wildcards.calset:q}"
        " --protocols {params.protocols:q} --train-cases {params.train_cases:q}"
        " --train-protocols {params.train_protocols:q} --figures {params.kinds:q} --out {params.out:q}"
        " {params.options:q} > {log:q} 2>&1"


rule compare_heldout:
    input:
        errors=expand(f"{COMPARE}/{{calset}}/errors.csv", calset=list(CALIBRATION_SETS)),
    output:
        report(
            f"{COMPARE}/heldout_errors.csv",
            caption="../report/heldout_errors.rst",
            category=COMPARE_CATEGORY,
        ),
    resources:
        runtime=COST_SMALL.runtime,
        mem_mb=COST_SMALL.mem_mb,
    log:
        f"{RESULTS}/logs/compare/heldout.log",
    benchmark:
        f"{RESULTS}/benchmarks/compare/heldout.tsv"
    threads: 1
    shell:
        "{PY:q} -m compare heldout --errors {input.errors:q} --out {output:q} > {log:q} 2>&1"


rule compare_sensitivity:
    input:
        params=calibration_params(SENSITIVITY_SET),
        series=campaign_series,
    output:
        table=report(
            f"{COMPARE}/{SENSITIVITY_SET}/sensitivity.csv",
            caption="../report/sensitivity.rst",
            category=COMPARE_CATEGORY,
            subcategory=SENSITIVITY_SET,
        ),
        figure=report(
            f"{COMPARE}/{SENSITIVITY_SET}/sensitivity_band.png",
            caption="../report/sensitivity_band.rst",
            category=COMPARE_CATEGORY,
            subcategory=SENSITIVITY_SET,
        ),
    params:
        dirs=[case_dir(label) for label in CASES],
        protocols=[p for p in PROTOCOLS if p in COMPARE_FIGURES],
        out=f"{COMPARE}/{SENSITIVITY_SET}",
    resources:
        runtime=COST_COMPARE.runtime,
        mem_mb=COST_COMPARE.mem_mb,
    log:
        f"{RESULTS}/logs/compare/sensitivity_{SENSITIVITY_SET}.log",
    benchmark:
        f"{RESULTS}/benchmarks/compare/sensitivity_{SENSITIVITY_SET}.tsv"
    threads: 1
    shell:
        "{PY:q} -m compare sensitivity --dem {params.dirs:q} --params {input.params:q} --set {SENSITIVITY_SET:q}"
        " --protocols {params.protocols:q} --out {params.out:q} > {log:q} 2>&1"


def compare_targets():
    """Per calibration set: predictions, errors, claims, Fig. 4/5; across sets: held-out table; sensitivity."""
    targets = []
    for calset in CALIBRATION_SETS:
        targets.append(f"{COMPARE}/{calset}/predictions.csv")
        targets += [f"{COMPARE}/{calset}/{name}.csv" for name in COMPARE_TABLES]
        targets += [f"{COMPARE}/{calset}/{COMPARE_FIGURES[k]}.png" for k in COMPARE_KINDS]
    targets.append(f"{COMPARE}/heldout_errors.csv")
    if SENSITIVITY_SET in CALIBRATION_SETS:
        targets += rules.compare_sensitivity.output
    return targets
