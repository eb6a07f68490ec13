# DEM stages under YADE: scene -> pack -> preshear -> heaviside | sinusoidal.
# One pre-shear per case feeds every reversal protocol. YADE runs on one thread,
# so `-j2` runs two cases side by side. The DEM study (accuracy.smk) reuses these
# rules on its own points (`use rule ... with:`).

wildcard_constraints:
    case="p[^/_]+_I[^/_]+_s[0-9]+",
    protocol="|".join(PROTOCOLS),


# One YADE stage: run_stage.py reads the scene, resumes from a checkpoint in
# <case_dir>/.partial/ if there is one, and writes the stage's outputs. It imports
# YADE as a library (no `yade -x`: no remote servers) and opens its own log only
# once it holds the stage lock, so a refused run (exit 5) leaves the log alone.
YADE_STAGE = (
    "OMP_NUM_THREADS=1 YADE_LAUNCHER={YADE} python3 yade_scripts/run_stage.py"
    " {input.scene} {params.stage} {params.case_dir} --log {log}"
)


def case_scene(label):
    return scene_from_config(config, CASES[label], label)


# The scene's result-relevant content is the rule's parameter: editing any config
# value that enters it (material, cell, pack, sampling, a protocol's strain, ...)
# reruns the scene and so every DEM stage of every case (Snakemake's params
# trigger); other edits (calibration, compare, run intervals) rerun no DEM.
rule scene:
    output:
        f"{RESULTS}/dem/{{case}}/scene.json",
    params:
        result=lambda wc: result_key(case_scene(wc.case)),
    log:
        f"{RESULTS}/logs/dem/{{case}}/scene.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/{{case}}/scene.tsv"
    localrule: True
    run:
        write_scene(scene_of_result_key(params.result, config), output[0], log[0])


rule dem_pack:
    input:
        scene=rules.scene.output[0],
    output:
        state=f"{RESULTS}/dem/{{case}}/pack.final.yade.gz",
        series=f"{RESULTS}/dem/{{case}}/pack.csv",
        sidecar=f"{RESULTS}/dem/{{case}}/pack.json",
    params:
        stage="pack",
        case_dir=lambda wc: case_dir(wc.case),
    resources:
        runtime=dem_runtime("pack"),
        mem_mb=dem_mem_mb,
    log:
        f"{RESULTS}/logs/dem/{{case}}/pack.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/{{case}}/pack.tsv"
    threads: 1
    shell:
        YADE_STAGE


rule dem_preshear:
    input:
        scene=rules.scene.output[0],
        state=rules.dem_pack.output.state,
    output:
        state=f"{RESULTS}/dem/{{case}}/preshear.final.yade.gz",
        series=f"{RESULTS}/dem/{{case}}/preshear.csv",
        sidecar=f"{RESULTS}/dem/{{case}}/preshear.json",
    params:
        stage="preshear",
        case_dir=lambda wc: case_dir(wc.case),
    resources:
        runtime=dem_runtime("preshear"),
        mem_mb=dem_mem_mb,
    log:
        f"{RESULTS}/logs/dem/{{case}}/preshear.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/{{case}}/preshear.tsv"
    threads: 1
    shell:
        YADE_STAGE


rule dem_reversal:
    input:
        scene=rules.scene.output[0],
        state=rules.dem_preshear.output.state,
    output:
        state=f"{RESULTS}/dem/{{case}}/{{protocol}}.final.yade.gz",
        series=f"{RESULTS}/dem/{{case}}/{{protocol}}.csv",
        sidecar=f"{RESULTS}/dem/{{case}}/{{protocol}}.json",
    params:
        stage=lambda wc: wc.protocol,
        case_dir=lambda wc: case_dir(wc.case),
    resources:
        runtime=dem_runtime(),
        mem_mb=dem_mem_mb,
    log:
        f"{RESULTS}/logs/dem/{{case}}/{{protocol}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/{{case}}/{{protocol}}.tsv"
    threads: 1
    shell:
        YADE_STAGE


rule dem_summary:
    input:
        sidecars=[
            f"{case_dir(label)}/{stage}.json"
            for label in CASES
            for stage in ["pack", "preshear", *PROTOCOLS]
        ],
        series=[f"{case_dir(label)}/preshear.csv" for label in CASES],
    output:
        report(
            f"{RESULTS}/dem/campaign_summary.csv",
            caption="../report/campaign_summary.rst",
            category="DEM campaign",
        ),
    params:
        cases=CASES,
    resources:
        runtime=COST_SMALL.runtime,
        mem_mb=COST_SMALL.mem_mb,
    log:
        f"{RESULTS}/logs/dem/summary.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/summary.tsv"
    script:
        "../scripts/summarize_campaign.py"
