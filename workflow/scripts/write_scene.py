"""Write the scene file of one DEM case from the validated config.

Called by the Snakemake rule `scene` (``snakemake.params.case`` holds the
case's pressure, inertial number and seed). The scene format is documented in
``yade_scripts/SCENE.md``; yade_scripts validates it again on reading.
"""
import json
import sys
from pathlib import Path

# Config blocks copied into the scene as they are (the config's names are the scene's).
PASSTHROUGH = ["timestep", "pack", "preshear", "sampling", "effects", "run", "guards"]


def scene_from_config(config: dict, case: dict, label: str) -> dict:
    """The scene of one case.

    Parameters
    ----------
    config : dict
        The campaign configuration (validated by Snakemake's schema).
    case : dict
        ``pressure`` (Pa), ``inertial_number`` and ``seed`` of the case.
    label : str
        The case label, kept in ``meta`` for the sidecars.
    """
    scene = {
        "seed": case["seed"],
        "meta": {"case": label, "campaign": config["campaign"]},
        "geometry": dict(config["cell"]),
        "material": {**config["material"], "pressure": case["pressure"]},
        "loading": {"inertial_number": case["inertial_number"]},
    }
    for block in PASSTHROUGH:
        if config.get(block):
            scene[block] = dict(config[block])
    for protocol, spec in config["protocols"].items():
        scene[protocol] = dict(spec)
    return scene


def main(snakemake):
    scene = scene_from_config(snakemake.config, snakemake.params.case, snakemake.wildcards.case)
    out = Path(snakemake.output[0])
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(scene, indent=2) + "\n")
    with open(snakemake.log[0], "w") as log:
        print(f"wrote {out}", file=log)


if "snakemake" in globals():
    main(snakemake)  # noqa: F821 (injected by Snakemake's script directive)
