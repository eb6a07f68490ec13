# What accuracy costs in time: the packing's share of the DEM campaign (always on:
# reads the sidecars), the ODE work-precision study of the continuum model (always
# on: seconds) and the DEM resolution study (config accuracy.dem_study).


rule ode_work_precision:
    output:
        table=report(
            f"{RESULTS}/accuracy/ode_work_precision.csv",
            caption="../report/ode_work_precision.rst",
            category="Accuracy and cost",
        ),
        figure=report(
            f"{RESULTS}/accuracy/ode_work_precision.png",
            caption="../report/ode_work_precision.rst",
            category="Accuracy and cost",
        ),
    resources:
        runtime=COST_ODE_WORK_PRECISION.runtime,
        mem_mb=COST_ODE_WORK_PRECISION.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/ode_work_precision.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/ode_work_precision.tsv"
    threads: 1
    shell:
        "{PY} -m model.work_precision --out {RESULTS}/accuracy > {log} 2>&1"


rule batched_cost:
    output:
        report(
            f"{RESULTS}/accuracy/batched_cost.csv",
            caption="../report/batched_cost.rst",
            category="Accuracy and cost",
        ),
    resources:
        runtime=COST_BATCHED_COST.runtime,
        mem_mb=COST_BATCHED_COST.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/batched_cost.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/batched_cost.tsv"
    threads: 1
    shell:
        "OMP_NUM_THREADS=1 {PY} -m model.batched_benchmark --out {RESULTS}/accuracy > {log} 2>&1"


rule calibration_cost:
    input:
        series=campaign_series,
    output:
        table=report(
            f"{RESULTS}/accuracy/calibration_cost.csv",
            caption="../report/calibration_cost.rst",
            category="Accuracy and cost",
        ),
        params=f"{RESULTS}/accuracy/calibration_cost_params.csv",
    params:
        protocol_sets=" ".join(
            f"--protocol-set {name}={','.join(spec['protocols'])}"
            for name, spec in config.get("calibration", {}).get("sets", {}).items()
            if "protocols" in spec and set(spec) == {"protocols"}
        ),
    resources:
        runtime=COST_CALIBRATION_COST.runtime,
        mem_mb=COST_CALIBRATION_COST.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/calibration_cost.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/calibration_cost.tsv"
    threads: 1
    shell:
        "OMP_NUM_THREADS=1 {PY} -m calibrate.cost_benchmark --results {RESULTS} --out {RESULTS}/accuracy"
        " {params.protocol_sets} > {log} 2>&1"


rule packing_cost:
    input:
        sidecars=[
            f"{case_dir(label)}/{stage}.json"
            for label in CASES
            for stage in ["pack", "preshear", *PROTOCOLS]
        ],
    output:
        report(
            f"{RESULTS}/accuracy/packing_cost.csv",
            caption="../report/packing_cost.rst",
            category="Accuracy and cost",
        ),
    params:
        campaign=config["campaign"],
    resources:
        runtime=COST_SMALL.runtime,
        mem_mb=COST_SMALL.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/packing_cost.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/packing_cost.tsv"
    threads: 1
    script:
        "../scripts/packing_cost.py"


# --- DEM resolution study ------------------------------------------------------
# One factor at a time around accuracy.base (dem_study/grid.py): each point is a
# DEM case under {RESULTS}/accuracy/dem/<point>/, run by the campaign's own YADE
# rules (dem.smk, reused below), with the campaign's scene
# (campaign.scenes.scene_from_config) changed in one key.
#
# Cost of the default subset of config/config.yaml, estimated from the measured
# throughput (dem_study/grid.py THROUGHPUT: 2.3 M particle-steps/s at 500 disks,
# 0.8 M at 5,000, one thread), steps per unit strain sqrt(4 kappa/pi)/(I dt_over_tc)
# over 1.9 strain, plus a pack of grid.PACK_TIME time units: with the 3 repeated
# kappa = 1e5 seeds 19 DEM cases, about 1.4 core-hours (measured with the former,
# undamped packing, several times longer: 36 min + 13 min on 2 cores).
# `python -m dem_study estimate --configfile config/config.yaml [--subset full]`
# prints the estimate per point.
from dem_study import grid as dem_grid

ACCURACY = config.get("accuracy", {})
DEM_STUDY = bool(ACCURACY.get("dem_study", False))
ACC_DEM = f"{RESULTS}/accuracy/dem"
DEM_POINTS = dem_grid.expand(ACCURACY) if DEM_STUDY else None
DEM_POINT_NAMES = list(dem_grid.unique_points(DEM_POINTS)["point"]) if DEM_STUDY else []


wildcard_constraints:
    point="base_s[0-9]+|[A-Za-z]+-[0-9.e-]+_s[0-9]+",


rule dem_study_points:
    output:
        f"{ACC_DEM}/points.csv",
    params:
        rows=DEM_POINTS.to_dict("records") if DEM_STUDY else [],  # reruns when the grid changes
    log:
        f"{RESULTS}/logs/accuracy/dem_study_points.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/dem_study_points.tsv"
    localrule: True
    run:
        DEM_POINTS.to_csv(output[0], index=False)
        with open(log[0], "w") as fh:
            print(f"{len(DEM_POINTS)} rows, {len(DEM_POINT_NAMES)} DEM cases", file=fh)


def point_scene(point):
    return dem_grid.point_scene(config, point)


use rule scene as dem_study_scene with:
    output:
        f"{ACC_DEM}/{{point}}/scene.json",
    params:
        result=lambda wc: result_key(point_scene(wc.point)),
    log:
        f"{RESULTS}/logs/accuracy/dem/{{point}}/scene.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/dem/{{point}}/scene.tsv"


use rule dem_pack as dem_study_pack with:
    input:
        scene=rules.dem_study_scene.output[0],
    output:
        state=f"{ACC_DEM}/{{point}}/pack.final.yade.gz",
        series=f"{ACC_DEM}/{{point}}/pack.csv",
        sidecar=f"{ACC_DEM}/{{point}}/pack.json",
    params:
        stage="pack",
        case_dir=lambda wc: f"{ACC_DEM}/{wc.point}",
    log:
        f"{RESULTS}/logs/accuracy/dem/{{point}}/pack.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/dem/{{point}}/pack.tsv"


use rule dem_preshear as dem_study_preshear with:
    input:
        scene=rules.dem_study_scene.output[0],
        state=rules.dem_study_pack.output.state,
    output:
        state=f"{ACC_DEM}/{{point}}/preshear.final.yade.gz",
        series=f"{ACC_DEM}/{{point}}/preshear.csv",
        sidecar=f"{ACC_DEM}/{{point}}/preshear.json",
    params:
        stage="preshear",
        case_dir=lambda wc: f"{ACC_DEM}/{wc.point}",
    log:
        f"{RESULTS}/logs/accuracy/dem/{{point}}/preshear.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/dem/{{point}}/preshear.tsv"


use rule dem_reversal as dem_study_heaviside with:
    input:
        scene=rules.dem_study_scene.output[0],
        state=rules.dem_study_preshear.output.state,
    output:
        state=f"{ACC_DEM}/{{point}}/heaviside.final.yade.gz",
        series=f"{ACC_DEM}/{{point}}/heaviside.csv",
        sidecar=f"{ACC_DEM}/{{point}}/heaviside.json",
    params:
        stage="heaviside",
        case_dir=lambda wc: f"{ACC_DEM}/{wc.point}",
    resources:
        runtime=dem_runtime("heaviside"),
        mem_mb=dem_mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/dem/{{point}}/heaviside.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/dem/{{point}}/heaviside.tsv"


rule dem_study:
    input:
        points=rules.dem_study_points.output[0],
        runs=[
            f"{ACC_DEM}/{point}/{name}"
            for point in DEM_POINT_NAMES
            for name in ["pack.json", "preshear.json", "preshear.csv", "heaviside.json", "heaviside.csv"]
        ],
    output:
        table=report(
            f"{RESULTS}/accuracy/dem_cost.csv",
            caption="../report/dem_cost.rst",
            category="Accuracy and cost",
        ),
        figure=report(
            f"{RESULTS}/accuracy/dem_cost.png",
            caption="../report/dem_cost.rst",
            category="Accuracy and cost",
        ),
        transients=report(
            f"{RESULTS}/accuracy/dem_transients.png",
            caption="../report/dem_transients.rst",
            category="Accuracy and cost",
        ),
        mu_table=report(
            f"{RESULTS}/accuracy/mu_of_I.csv",
            caption="../report/mu_of_I.rst",
            category="Accuracy and cost",
        ),
        mu_figure=report(
            f"{RESULTS}/accuracy/mu_of_I.png",
            caption="../report/mu_of_I.rst",
            category="Accuracy and cost",
        ),
        repeats=report(
            f"{RESULTS}/accuracy/dem_repeats.csv",
            caption="../report/dem_repeats.rst",
            category="Accuracy and cost",
        ),
        summary=f"{RESULTS}/accuracy/dem_study.json",
    params:
        campaign_I=sorted({case["inertial_number"] for case in CASES.values()}),
        tolerance=" ".join(f"{k}={v}" for k, v in ACCURACY.get("tolerance", {}).items()),
        steady_window=ACCURACY.get("steady_window", 0.5),
        heaviside_strain=ACCURACY.get("heaviside_strain", 0.4),
        transient_bin=ACCURACY.get("transient_bin", 0.01),
        quasi_static_tolerance=ACCURACY.get("quasi_static_tolerance", 0.05),
    resources:
        runtime=COST_DEM_STUDY_ANALYSIS.runtime,
        mem_mb=COST_DEM_STUDY_ANALYSIS.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/dem_study.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/dem_study.tsv"
    threads: 1
    shell:
        "{PY} -m dem_study analyse --points {input.points} --dem-dir {ACC_DEM} --out {RESULTS}/accuracy"
        " --steady-window {params.steady_window} --heaviside-strain {params.heaviside_strain}"
        " --transient-bin {params.transient_bin} --campaign-I {params.campaign_I}"
        " --quasi-static-tolerance {params.quasi_static_tolerance}"
        " --tolerance {params.tolerance} > {log} 2>&1"


def accuracy_targets():
    targets = list(rules.packing_cost.output)  # always on: reads the campaign's sidecars
    if ACCURACY.get("ode_work_precision", True):
        targets += rules.ode_work_precision.output
    if ACCURACY.get("batched_cost", True):
        targets += rules.batched_cost.output
    if ACCURACY.get("calibration_cost", True):
        targets += rules.calibration_cost.output
    if DEM_STUDY:
        targets += rules.dem_study.output
    if BULK_STUDY:
        targets += bulk_study_targets()
    return targets


# --- Bulk against walls (issue 16) ---------------------------------------------
# Named cells of config accuracy.bulk_vs_walls (dem_study/bulk_cells.py), each
# run with every seed as a DEM case under {RESULTS}/accuracy/bulk/<cell>_s<seed>/
# by the campaign's own YADE rules (dem.smk, reused below), the campaign's scene
# with the cell, kappa, I and the study's strains changed.
# `python -m dem_study.bulk_cli estimate --configfile ...` prints the cost per
# cell; `snakemake -j2 bulk_study_dem ...` runs only the study's DEM cases,
# `snakemake -j2 bulk_vs_walls ...` them and the analysis (results/accuracy/
# bulk_vs_walls.csv, .png; dem_study/README.md "Bulk against walls").
import preflight as _preflight
from dem_study import bulk_cells

BULK_STUDY = bulk_cells.enabled(config)
ACC_BULK = f"{RESULTS}/accuracy/bulk"
if BULK_STUDY:
    _preflight.stop_on_problems(bulk_cells.problems(config))
BULK_CASES = bulk_cells.cases(config) if BULK_STUDY else None
BULK_CASE_NAMES = list(BULK_CASES["case"]) if BULK_STUDY else []


wildcard_constraints:
    bulkcase="[A-Za-z0-9][A-Za-z0-9-]*_s[0-9]+",


def bulk_scene(label):
    return bulk_cells.case_scene(config, label)


rule bulk_study_cases:
    output:
        f"{ACC_BULK}/cases.csv",
    params:
        rows=BULK_CASES.to_dict("records") if BULK_STUDY else [],  # reruns when the cells change
    log:
        f"{RESULTS}/logs/accuracy/bulk_study_cases.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/bulk_study_cases.tsv"
    localrule: True
    run:
        BULK_CASES.to_csv(output[0], index=False)
        with open(log[0], "w") as fh:
            print(f"{len(BULK_CASES)} DEM cases", file=fh)


use rule scene as bulk_study_scene with:
    output:
        f"{ACC_BULK}/{{bulkcase}}/scene.json",
    params:
        result=lambda wc: result_key(bulk_scene(wc.bulkcase)),
    log:
        f"{RESULTS}/logs/accuracy/bulk/{{bulkcase}}/scene.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/bulk/{{bulkcase}}/scene.tsv"


use rule dem_pack as bulk_study_pack with:
    input:
        scene=rules.bulk_study_scene.output[0],
    output:
        state=f"{ACC_BULK}/{{bulkcase}}/pack.final.yade.gz",
        series=f"{ACC_BULK}/{{bulkcase}}/pack.csv",
        sidecar=f"{ACC_BULK}/{{bulkcase}}/pack.json",
    params:
        stage="pack",
        case_dir=lambda wc: f"{ACC_BULK}/{wc.bulkcase}",
    log:
        f"{RESULTS}/logs/accuracy/bulk/{{bulkcase}}/pack.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/bulk/{{bulkcase}}/pack.tsv"


use rule dem_preshear as bulk_study_preshear with:
    input:
        scene=rules.bulk_study_scene.output[0],
        state=rules.bulk_study_pack.output.state,
    output:
        state=f"{ACC_BULK}/{{bulkcase}}/preshear.final.yade.gz",
        series=f"{ACC_BULK}/{{bulkcase}}/preshear.csv",
        sidecar=f"{ACC_BULK}/{{bulkcase}}/preshear.json",
    params:
        stage="preshear",
        case_dir=lambda wc: f"{ACC_BULK}/{wc.bulkcase}",
    log:
        f"{RESULTS}/logs/accuracy/bulk/{{bulkcase}}/preshear.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/bulk/{{bulkcase}}/preshear.tsv"


use rule dem_reversal as bulk_study_heaviside with:
    input:
        scene=rules.bulk_study_scene.output[0],
        state=rules.bulk_study_preshear.output.state,
    output:
        state=f"{ACC_BULK}/{{bulkcase}}/heaviside.final.yade.gz",
        series=f"{ACC_BULK}/{{bulkcase}}/heaviside.csv",
        sidecar=f"{ACC_BULK}/{{bulkcase}}/heaviside.json",
    params:
        stage="heaviside",
        case_dir=lambda wc: f"{ACC_BULK}/{wc.bulkcase}",
    resources:
        runtime=dem_runtime("heaviside"),
        mem_mb=dem_mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/bulk/{{bulkcase}}/heaviside.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/bulk/{{bulkcase}}/heaviside.tsv"


# A cell with a reversal train runs it (stage `train`) in place of the Heaviside reversal.
use rule bulk_study_heaviside as bulk_study_train with:
    output:
        state=f"{ACC_BULK}/{{bulkcase}}/train.final.yade.gz",
        series=f"{ACC_BULK}/{{bulkcase}}/train.csv",
        sidecar=f"{ACC_BULK}/{{bulkcase}}/train.json",
    params:
        stage="train",
        case_dir=lambda wc: f"{ACC_BULK}/{wc.bulkcase}",
    resources:
        runtime=dem_runtime("train"),
        mem_mb=dem_mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/bulk/{{bulkcase}}/train.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/bulk/{{bulkcase}}/train.tsv"


BULK_RUNS = [
    f"{ACC_BULK}/{row.case}/{name}"
    for row in (BULK_CASES.itertuples() if BULK_STUDY else [])
    for name in ["pack.json", "preshear.json", "preshear.csv", f"{row.stage}.json", f"{row.stage}.csv"]
]


# The study's DEM cases and what each cost (CPU time from the sidecars);
# `snakemake -j2 bulk_study_dem ...` runs only these (no campaign, no analysis).
rule bulk_study_dem:
    input:
        cases=rules.bulk_study_cases.output[0],
        runs=BULK_RUNS,
    output:
        f"{RESULTS}/accuracy/bulk_cost.csv",
    resources:
        runtime=COST_SMALL.runtime,
        mem_mb=COST_SMALL.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/bulk_study_dem.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/bulk_study_dem.tsv"
    threads: 1
    shell:
        "{PY} -m dem_study.bulk_cli cost --cases {input.cases} --bulk-dir {ACC_BULK} --out {output} > {log} 2>&1"


BULK = bulk_cells.settings(config)


rule bulk_vs_walls:
    input:
        cases=rules.bulk_study_cases.output[0],
        cost=rules.bulk_study_dem.output[0],
        runs=BULK_RUNS,
    output:
        table=report(
            f"{RESULTS}/accuracy/bulk_vs_walls.csv",
            caption="../report/bulk_vs_walls.rst",
            category="Accuracy and cost",
        ),
        figure=report(
            f"{RESULTS}/accuracy/bulk_vs_walls.png",
            caption="../report/bulk_vs_walls.rst",
            category="Accuracy and cost",
        ),
        summary=f"{RESULTS}/accuracy/bulk_vs_walls.json",
    params:
        references=" ".join(BULK.get("references", [])),
        tall=f"--tall-reference {BULK['tall_reference']}" if BULK.get("tall_reference") else "",
        steady_window=BULK["steady_window"],
        heaviside_strain=BULK["heaviside_strain"],
        transient_bin=BULK["transient_bin"],
        early_strain=BULK["early_strain"],
        match_se=BULK["match_se"],
    resources:
        runtime=COST_DEM_STUDY_ANALYSIS.runtime,
        mem_mb=COST_DEM_STUDY_ANALYSIS.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/bulk_vs_walls.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/bulk_vs_walls.tsv"
    threads: 1
    shell:
        "{PY} -m dem_study.bulk_cli analyse --cases {input.cases} --bulk-dir {ACC_BULK}"
        " --out-table {output.table} --out-figure {output.figure} --out-summary {output.summary}"
        " --references {params.references}"
        " {params.tall} --steady-window {params.steady_window} --heaviside-strain {params.heaviside_strain}"
        " --transient-bin {params.transient_bin} --early-strain {params.early_strain}"
        " --match-se {params.match_se} > {log} 2>&1"


def bulk_study_targets():
    return [*rules.bulk_study_dem.output, *rules.bulk_vs_walls.output]
