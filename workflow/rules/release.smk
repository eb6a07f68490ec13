# Released cases as finished (docs/data-release.md): config `release: data/<name>` (or a list)
# names data releases; a campaign case released with every protocol of the config, from the
# scene this config makes for it (result_key: the same physics, cell, sampling and protocols),
# is written into <results_dir>/dem/<case>/ from the release (python -m dem_contract restore:
# the series through the importer, the DEM's own sidecars verbatim) by rule release_case,
# preferred over the DEM rules, so its DEM never runs and adding seeds runs only the new seeds' DEM.
import json
import re
import sys
from pathlib import Path

from dem_contract import release as dem_release


def released_scene_matches(label, folder):
    """The released case's scene is the one this config makes (else its DEM runs, with a note)."""
    released = json.loads((Path(folder) / "cases" / label / "sidecars" / "scene.json").read_text())
    if result_key(released) == result_key(case_scene(label)):
        return True
    print(f"release: {folder}: case {label} was run with another scene than this config's; its DEM runs",
          file=sys.stderr)
    return False


try:
    RELEASED = {label: folder
                for label, folder in dem_release.released_cases(config["release"], PROTOCOLS, workflow.basedir).items()
                if label in CASES and released_scene_matches(label, folder)}
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
        resources:
            runtime=COST_SMALL.runtime,
            mem_mb=COST_SMALL.mem_mb,
        log:
            f"{RESULTS}/logs/dem/{{case}}/release.log",
        benchmark:
            f"{RESULTS}/benchmarks/dem/{{case}}/release.tsv"
        localrule: True
        shell:
            "{PY} -m dem_contract restore --release {params.release} --case {wildcards.case}"
            " --out {RESULTS}/dem/{wildcards.case} > {log} 2>&1"

    ruleorder: release_case > scene
    ruleorder: release_case > dem_pack
    ruleorder: release_case > dem_preshear
    ruleorder: release_case > dem_reversal
