# What accuracy costs in time: the packing's share of the DEM campaign (always on:
# reads the sidecars), the ODE work-precision study of the continuum model (always
# on: seconds), the batched integrator's and the calibration's cost. The DEM
# resolution study is dem_study.smk, the bulk-against-walls study bulk_study.smk;
# accuracy_targets() gathers all three.
import json


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
    params:
        out=f"{RESULTS}/accuracy",
    resources:
        runtime=COST_ODE_WORK_PRECISION.runtime,
        mem_mb=COST_ODE_WORK_PRECISION.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/ode_work_precision.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/ode_work_precision.tsv"
    threads: 1
    shell:
        "{PY:q} -m model.work_precision --out {params.out:q} > {log:q} 2>&1"


rule batched_cost:
    output:
        report(
            f"{RESULTS}/accuracy/batched_cost.csv",
            caption="../report/batched_cost.rst",
            category="Accuracy and cost",
        ),
    params:
        out=f"{RESULTS}/accuracy",
    resources:
        runtime=COST_BATCHED_COST.runtime,
        mem_mb=COST_BATCHED_COST.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/batched_cost.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/batched_cost.tsv"
    threads: 1
    shell:
        "OMP_NUM_THREADS=1 {PY:q} -m model.batched_benchmark --out {params.out:q} > {log:q} 2>&1"


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
        protocol_sets=[
            word
            for name, spec in config["calibration"].get("sets", {}).items()
            if "protocols" in spec and set(spec) == {"protocols"}
            for word in ("--protocol-set", f"{name}={','.join(spec['protocols'])}")
        ],
        results=RESULTS,
        out=f"{RESULTS}/accuracy",
    resources:
        runtime=COST_CALIBRATION_COST.runtime,
        mem_mb=COST_CALIBRATION_COST.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/calibration_cost.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/calibration_cost.tsv"
    threads: 1
    shell:
        "OMP_NUM_THREADS=1 {PY:q} -m calibrate.cost_benchmark --results {params.results:q} --out {params.out:q}"
        " {params.protocol_sets:q} > {log:q} 2>&1"


# The DEM stage against bare YADE (tools/stage_benchmark.py): paired runs of one pre-shear of a
# small cell (338 disks) from one packing, with the preset's sampling and run settings; run by
# `make bench` only (no preset's default target: a benchmark of the code, not of the study).
rule stage_overhead:
    output:
        table=f"{RESULTS}/accuracy/stage_overhead.csv",
        summary=f"{RESULTS}/accuracy/stage_overhead_summary.csv",
        wall=f"{RESULTS}/accuracy/stage_overhead_wall.csv",
    params:
        sampling=lambda wc: json.dumps(config["sampling"]),
        run=lambda wc: json.dumps(config["run"]),
    resources:
        runtime=COST_STAGE_OVERHEAD.runtime,
        mem_mb=COST_STAGE_OVERHEAD.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/stage_overhead.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/stage_overhead.tsv"
    threads: 1
    shell:
        "OMP_NUM_THREADS=1 YADE_LAUNCHER={YADE:q} python3 tools/stage_benchmark.py --out {output.table:q}"
        " --sampling {params.sampling:q} --run {params.run:q} > {log:q} 2>&1"


# The two DEM engines side by side (tools/engine_benchmark.py, issue 36): YADE's pre-shear stage and
# LAMMPS's, paired, on the quick preset's narrow cell (626 disks) and the paper's W = 4H cell (about
# 5,000 disks), and bare LAMMPS on 1 and 2 MPI ranks; run by `make bench` only.
rule engine_throughput:
    output:
        table=f"{RESULTS}/accuracy/engine_throughput.csv",
        summary=f"{RESULTS}/accuracy/engine_throughput_summary.csv",
    params:
        sampling=lambda wc: json.dumps(config["sampling"]),
    resources:
        runtime=COST_ENGINE_THROUGHPUT.runtime,
        mem_mb=COST_ENGINE_THROUGHPUT.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/engine_throughput.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/engine_throughput.tsv"
    threads: 2  # the bare LAMMPS run on 2 MPI ranks
    shell:
        "OMP_NUM_THREADS=1 YADE_LAUNCHER={YADE:q} python3 tools/engine_benchmark.py --out {output.table:q}"
        " --sampling {params.sampling:q} > {log:q} 2>&1"


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
    shell:
        "{PY:q} -m dem_study.packing_cost --campaign {params.campaign:q} --sidecars {input.sidecars:q}"
        " --out {output:q} > {log:q} 2>&1"


def accuracy_targets():
    targets = list(rules.packing_cost.output)  # always on: reads the campaign's sidecars
    if config["accuracy"]["ode_work_precision"]:
        targets += rules.ode_work_precision.output
    if config["accuracy"]["batched_cost"]:
        targets += rules.batched_cost.output
    if config["accuracy"]["calibration_cost"]:
        targets += rules.calibration_cost.output
    if DEM_STUDY:
        targets += rules.dem_study.output
    if BULK_STUDY:
        targets += bulk_study_targets()
    return targets
