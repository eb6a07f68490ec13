# DEM stages under YADE (or LAMMPS, config engine): scene -> pack -> preshear -> heaviside | sinusoidal | <schedule>.
# One pre-shear per case feeds every reversal protocol. YADE runs on one thread,
# so `-j2` runs two cases side by side. The chain is written once (DEM_CHAINS
# below) and instantiated for every results folder that holds DEM cases: the
# campaign's, the DEM resolution study's (dem_study.smk) and the bulk study's
# (bulk_study.smk).
from dem_contract.labels import WILDCARD_CONSTRAINT as CASE_LABEL
from dem_study import bulk_cells
from dem_study import grid as dem_grid

wildcard_constraints:
    case=CASE_LABEL,  # the label's one writing (dem_contract/labels.py)
    protocol="|".join(PROTOCOLS),


# One YADE stage: run_stage.py reads the scene, resumes from a checkpoint in
# <case_dir>/.partial/ if there is one, and writes the stage's outputs. It imports
# YADE as a library (no `yade -x`: no remote servers) and opens its own log only
# once it holds the stage lock, so a refused run (exit 5) leaves the log alone.
YADE_STAGE = (
    "OMP_NUM_THREADS=1 YADE_LAUNCHER={YADE:q} python3 yade_scripts/run_stage.py"
    " {input.scene:q} {params.stage:q} {params.case_dir:q} --log {log:q}"
)
# One LAMMPS stage (config engine: lammps): the same scene, lock, log and exit codes; LAMMPS is
# loaded as a library by the interpreter Debian's python3-lammps is installed for (lammpslib).
LAMMPS_STAGE = (
    "OMP_NUM_THREADS=1 python3 lammps_scripts/run_stage.py"
    " {input.scene:q} {params.stage:q} {params.case_dir:q} --log {log:q}"
)
ENGINE = config["engine"]  # the schema's default filled in (the Snakefile's validate)
DEM_STAGE = {"yade": YADE_STAGE, "lammps": LAMMPS_STAGE}[ENGINE]
# A stage's final state, the next stage's input: YADE's O.save, or a LAMMPS restart file
# (lammps_scripts/shearing.py STATE_SUFFIX).
STATE_SUFFIX = {"yade": ".final.yade.gz", "lammps": ".final.lammps"}[ENGINE]


def case_scene(label):
    """A campaign case's scene (campaign.scenes.scene_from_config)."""
    return scene_from_config(config, CASES[label], label)


def point_scene(point):
    """A DEM-study point's scene: the campaign's with one key changed (dem_study/grid.py)."""
    return dem_grid.point_scene(config, point)


def bulk_scene(label):
    """A bulk-study case's scene: the campaign's with the cell's settings (dem_study/bulk_cells.py)."""
    return bulk_cells.case_scene(config, label)


# Each folder of DEM cases under RESULTS: its wildcard, the scene of a case, and its
# rules' names (the reversal rules: name -> stage, None for the campaign's {protocol}).
DEM_CHAINS = [
    dict(folder="dem", wildcard="case", scene_of=case_scene,
         scene="scene", pack="dem_pack", preshear="dem_preshear", reversals={"dem_reversal": None}),
    dict(folder="accuracy/dem", wildcard="point", scene_of=point_scene,
         scene="dem_study_scene", pack="dem_study_pack", preshear="dem_study_preshear",
         reversals={"dem_study_heaviside": "heaviside"}),
    # a bulk cell with a reversal train runs it (stage `train`) in place of the Heaviside reversal
    dict(folder="accuracy/bulk", wildcard="bulkcase", scene_of=bulk_scene,
         scene="bulk_study_scene", pack="bulk_study_pack", preshear="bulk_study_preshear",
         reversals={"bulk_study_heaviside": "heaviside", "bulk_study_train": "train"}),
]


def scene_result(chain):
    """The scene rule's parameter: the scene's result-relevant content (a params trigger, below)."""
    return lambda wc: result_key(chain["scene_of"](getattr(wc, chain["wildcard"])))


def stage_case_dir(chain):
    return lambda wc: f"{RESULTS}/{chain['folder']}/{getattr(wc, chain['wildcard'])}"


def protocol_stage(wc):
    return wc.protocol


# The scene's result-relevant content is the scene rule's parameter: editing any config
# value that enters it (material, cell, pack, sampling, a protocol's strain, ...)
# reruns the scene and so every DEM stage of every case (Snakemake's params
# trigger); other edits (calibration, compare, run intervals) rerun no DEM.
for dem_chain in DEM_CHAINS:
    dem_where = f"{dem_chain['folder']}/{{{dem_chain['wildcard']}}}"   # e.g. dem/{case}

    rule:
        name:
            dem_chain["scene"]
        output:
            f"{RESULTS}/{dem_where}/scene.json",
        params:
            result=scene_result(dem_chain),
        log:
            f"{RESULTS}/logs/{dem_where}/scene.log",
        benchmark:
            f"{RESULTS}/benchmarks/{dem_where}/scene.tsv"
        priority: dem_priority("scene")
        localrule: True
        run:
            write_scene(scene_of_result_key(params.result, config), output[0], log[0])

    dem_stages = [(dem_chain["pack"], "pack", None), (dem_chain["preshear"], "preshear", "pack")]
    dem_stages += [(dem_name, dem_stage, "preshear") for dem_name, dem_stage in dem_chain["reversals"].items()]
    for dem_rule_name, dem_stage, dem_previous in dem_stages:
        dem_stem = dem_stage or "{protocol}"

        rule:
            name:
                dem_rule_name
            input:
                scene=f"{RESULTS}/{dem_where}/scene.json",
                **({"state": f"{RESULTS}/{dem_where}/{dem_previous}{STATE_SUFFIX}"} if dem_previous else {}),
            output:
                state=f"{RESULTS}/{dem_where}/{dem_stem}{STATE_SUFFIX}",
                series=f"{RESULTS}/{dem_where}/{dem_stem}.csv",
                sidecar=f"{RESULTS}/{dem_where}/{dem_stem}.json",
            params:
                stage=dem_stage or protocol_stage,
                case_dir=stage_case_dir(dem_chain),
            priority: dem_priority(dem_stage)
            resources:
                runtime=dem_runtime(dem_stage),
                mem_mb=dem_mem_mb,
            log:
                f"{RESULTS}/logs/{dem_where}/{dem_stem}.log",
            benchmark:
                f"{RESULTS}/benchmarks/{dem_where}/{dem_stem}.tsv"
            threads: 1
            shell:
                DEM_STAGE


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
        cases=[f"{label}={c['pressure']!r},{c['inertial_number']!r},{c['seed']}" for label, c in CASES.items()],
        stages=["pack", "preshear", *PROTOCOLS],
        dem=f"{RESULTS}/dem",
    resources:
        runtime=COST_SMALL.runtime,
        mem_mb=COST_SMALL.mem_mb,
    log:
        f"{RESULTS}/logs/dem/summary.log",
    benchmark:
        f"{RESULTS}/benchmarks/dem/summary.tsv"
    threads: 1
    shell:
        "{PY:q} -m campaign.summary --dem {params.dem:q} --cases {params.cases:q} --stages {params.stages:q}"
        " --out {output:q} > {log:q} 2>&1"
