# The bulk-against-walls study (config accuracy.bulk_vs_walls).
# Named cells of config accuracy.bulk_vs_walls (dem_study/bulk_cells.py), each
# run with every seed as a DEM case under {RESULTS}/accuracy/bulk/<cell>_s<seed>/
# by the DEM chain of dem.smk (rules bulk_study_scene, ..., _heaviside, _train), the campaign's scene
# with the cell, kappa, I and the study's strains changed.
# `python -m dem_study.bulk_cli estimate --configfile ...` prints the cost per
# cell; `snakemake -j2 bulk_study_dem ...` runs only the study's DEM cases,
# `snakemake -j2 bulk_vs_walls ...` them and the analysis (results/accuracy/
# bulk_vs_walls.csv, .png; dem_study/README.md "Bulk against walls").
import preflight as _preflight

BULK_STUDY = bulk_cells.enabled(config)
ACC_BULK = f"{RESULTS}/accuracy/bulk"
if BULK_STUDY:
    _preflight.stop_on_problems(bulk_cells.problems(config))
BULK_CASES = bulk_cells.cases(config) if BULK_STUDY else None
BULK_CASE_NAMES = list(BULK_CASES["case"]) if BULK_STUDY else []


wildcard_constraints:
    bulkcase="[A-Za-z0-9][A-Za-z0-9-]*_s[0-9]+",


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
        "{PY:q} -m dem_study.bulk_cli cost --cases {input.cases:q} --bulk-dir {ACC_BULK:q} --out {output:q} > {log:q} 2>&1"


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
        references=list(BULK.get("references", [])),
        tall=["--tall-reference", BULK["tall_reference"]] if BULK.get("tall_reference") else [],
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
        "{PY:q} -m dem_study.bulk_cli analyse --cases {input.cases:q} --bulk-dir {ACC_BULK:q}"
        " --out-table {output.table:q} --out-figure {output.figure:q} --out-summary {output.summary:q}"
        " --references {params.references:q}"
        " {params.tall:q} --steady-window {params.steady_window:q} --heaviside-strain {params.heaviside_strain:q}"
        " --transient-bin {params.transient_bin:q} --early-strain {params.early_strain:q}"
        " --match-se {params.match_se:q} > {log:q} 2>&1"


def bulk_study_targets():
    return [*rules.bulk_study_dem.output, *rules.bulk_vs_walls.output]
