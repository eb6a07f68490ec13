# DEM stages under YADE: scene -> pack -> preshear -> heaviside | sinusoidal.
# One pre-shear per case feeds every reversal protocol. YADE runs on one thread,
# so `-j2` runs two cases side by side.

wildcard_constraints:
    case="p[^/_]+_I[^/_]+_s[0-9]+",
    protocol="|".join(PROTOCOLS),


rule scene:
    output:
        f"{RESULTS}/dem/{{case}}/scene.json",
    params:
        case=lambda wc: CASES[wc.case],
    log:
        f"{RESULTS}/logs/scene/{{case}}.log",
    localrule: True
    script:
        "../scripts/write_scene.py"


rule dem_pack:
    input:
        scene=rules.scene.output[0],
    output:
        state=f"{RESULTS}/dem/{{case}}/pack.final.yade.gz",
        sidecar=f"{RESULTS}/dem/{{case}}/pack.json",
    params:
        case_dir=lambda wc: case_dir(wc.case),
    log:
        f"{RESULTS}/logs/dem/{{case}}/pack.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/{{case}}/pack.tsv"
    threads: 1
    shell:
        "OMP_NUM_THREADS=1 {YADE} -n -x yade_scripts/run_stage.py {input.scene} pack {params.case_dir} > {log} 2>&1"


rule dem_preshear:
    input:
        scene=rules.scene.output[0],
        state=rules.dem_pack.output.state,
    output:
        state=f"{RESULTS}/dem/{{case}}/preshear.final.yade.gz",
        series=f"{RESULTS}/dem/{{case}}/preshear.csv",
        sidecar=f"{RESULTS}/dem/{{case}}/preshear.json",
    params:
        case_dir=lambda wc: case_dir(wc.case),
    log:
        f"{RESULTS}/logs/dem/{{case}}/preshear.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/{{case}}/preshear.tsv"
    threads: 1
    shell:
        "OMP_NUM_THREADS=1 {YADE} -n -x yade_scripts/run_stage.py {input.scene} preshear {params.case_dir} > {log} 2>&1"


rule dem_reversal:
    input:
        scene=rules.scene.output[0],
        state=rules.dem_preshear.output.state,
    output:
        state=f"{RESULTS}/dem/{{case}}/{{protocol}}.final.yade.gz",
        series=f"{RESULTS}/dem/{{case}}/{{protocol}}.csv",
        sidecar=f"{RESULTS}/dem/{{case}}/{{protocol}}.json",
    params:
        case_dir=lambda wc: case_dir(wc.case),
    log:
        f"{RESULTS}/logs/dem/{{case}}/{{protocol}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/{{case}}/{{protocol}}.tsv"
    threads: 1
    shell:
        "OMP_NUM_THREADS=1 {YADE} -n -x yade_scripts/run_stage.py {input.scene} {wildcards.protocol} {params.case_dir} > {log} 2>&1"


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
    log:
        f"{RESULTS}/logs/dem/summary.log",
    script:
        "../scripts/summarize_campaign.py"
