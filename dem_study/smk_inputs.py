"""Inputs of the study's DEM cases, written by the Snakemake rules of
workflow/rules/accuracy.smk (script directive): the points table and each
point's scene file."""
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import pandas as pd  # noqa: E402

from dem_study import grid  # noqa: E402


def main(snakemake):
    out = Path(snakemake.output[0])
    out.parent.mkdir(parents=True, exist_ok=True)
    if snakemake.rule == "dem_study_points":
        table = grid.expand(snakemake.config["accuracy"])
        table.to_csv(out, index=False)
        message = f"{len(table)} rows, {table['point'].nunique()} DEM cases"
    else:
        scene = grid.point_scene(snakemake.config, snakemake.wildcards.point)
        out.write_text(json.dumps(scene, indent=2) + "\n")
        message = f"wrote {out}"
    with open(snakemake.log[0], "w") as log:
        print(message, file=log)


if "snakemake" in globals():
    main(snakemake)  # noqa: F821 (injected by Snakemake's script directive)
