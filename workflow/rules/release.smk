# Released cases as finished (docs/data-release.md): config `release: data/<name>` (or a list)
# names data releases; a campaign case released with every protocol of the config, from the
# scene this config makes for it (result_key: the same physics, cell, sampling and protocols),
# is written into <results_dir>/dem/<case>/ from the release (python -m dem_contract restore:
# the series through the importer, the DEM's own sidecars verbatim) by rule release_case,
# preferred over the DEM rules, so its DEM never runs and adding seeds runs only the new seeds' DEM.
# The same for the bulk-vs-walls study's cells (<results_dir>/accuracy/bulk/<cell>_s<seed>/, rule
# release_bulk_case): a released cell with its Heaviside reversal, from the scene this config makes.
import json
import re
import sys
from pathlib import Path

from dem_contract import release as dem_release


def released_scene_matches(label, folder, scene_of=case_scene):
    """The released case's scene is the one this config makes (``scene_of(label)``; else its DEM runs, with a note)."""
    released = json.loads((Path(folder) / "cases" / label / "sidecars" / "scene.json").read_text())
    if result_key(released) == result_key(scene_of(label)):
        return True
    print(f"release: {folder}: case {label} was run with another scene than this config's; its DEM runs",
          file=sys.stderr)
    return False


def released_bulk_cells():
    """Bulk-study case label -> release folder: released with its Heaviside reversal, from this config's scene."""
    if not bulk_cells.enabled(config):
        return {}
    rows = bulk_cells.cases(config)
    heaviside = set(rows.loc[rows["stage"] == "heaviside", "case"])
    return {label: folder
            for label, folder in dem_release.released_cases(config["release"], ("heaviside",), workflow.basedir).items()
            if label in heaviside and released_scene_matches(label, folder, bulk_scene)}


try:
    RELEASED = {label: folder
                for label, folder in dem_release.released_cases(config["release"], PROTOCOLS, workflow.basedir).items()
                if label in CASES and released_scene_matches(label, folder)}
    BULK_RELEASED = released_bulk_cells()
except (OSError, dem_release.DEMInputError) as exc:     # like the pre-flight check: exit 2 naming the file
    print(f"config key 'release': {exc}", file=sys.stderr, flush=True)
    sys.exit(2)

if RELEASED:

    rule release_case:
        input:
            lambda wc: dem_release.case_files(RELEASED[wc.case], wc.case),
        output:
            scene=f"{RESULTS}/dem/{{case}}/scene.json",
            sidecars=[f"{RESULTS}/dem/{{case}}/{stage}.json" for stage in ["pack", "preshear", *PROTOCOLS]],
            series=[f"{RESULTS}/dem/{{case}}/{stage}.csv" for stage in ["preshear", *PROTOCOLS]],
        wildcard_constraints:
            case="|".join(re.escape(label) for label in RELEASED),
        params:
            release=lambda wc: RELEASED[wc.case],
            out=lambda wc: f"{RESULTS}/dem/{wc.case}",
        resources:
            runtime=COST_SMALL.runtime,
            mem_mb=COST_SMALL.mem_mb,
        log:
            f"{RESULTS}/logs/dem/{{case}}/release.log",
        benchmark:
            f"{RESULTS}/benchmarks/dem/{{case}}/release.tsv"
        localrule: True
        shell:
            "{PY:q} -m dem_contract restore --release {params.release:q} --case {wildcards.case:q}"
            " --out {params.out:q} > {log:q} 2>&1"

    ruleorder: release_case > scene
    ruleorder: release_case > dem_pack
    ruleorder: release_case > dem_preshear
    ruleorder: release_case > dem_reversal


if BULK_RELEASED:

    rule release_bulk_case:
        input:
            lambda wc: dem_release.case_files(BULK_RELEASED[wc.bulkcase], wc.bulkcase),
        output:
            scene=f"{RESULTS}/accuracy/bulk/{{bulkcase}}/scene.json",
            sidecars=[f"{RESULTS}/accuracy/bulk/{{bulkcase}}/{stage}.json" for stage in ["pack", "preshear", "heaviside"]],
            series=[f"{RESULTS}/accuracy/bulk/{{bulkcase}}/{stage}.csv" for stage in ["preshear", "heaviside"]],
        wildcard_constraints:
            bulkcase="|".join(re.escape(label) for label in BULK_RELEASED),
        params:
            release=lambda wc: BULK_RELEASED[wc.bulkcase],
            out=lambda wc: f"{RESULTS}/accuracy/bulk/{wc.bulkcase}",
        resources:
            runtime=COST_SMALL.runtime,
            mem_mb=COST_SMALL.mem_mb,
        log:
            f"{RESULTS}/logs/accuracy/bulk/{{bulkcase}}/release.log",
        benchmark:
            f"{RESULTS}/benchmarks/accuracy/bulk/{{bulkcase}}/release.tsv"
        localrule: True
        shell:
            "{PY:q} -m dem_contract restore --release {params.release:q} --case {wildcards.bulkcase:q}"
            " --out {params.out:q} > {log:q} 2>&1"

    ruleorder: release_bulk_case > bulk_study_scene
    ruleorder: release_bulk_case > bulk_study_pack
    ruleorder: release_bulk_case > bulk_study_preshear
    ruleorder: release_bulk_case > bulk_study_heaviside
