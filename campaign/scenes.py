"""The scene file of one DEM case, from the campaign config (format: docs/scene.md).

yade_scripts validates the scene again when it reads it.
"""
from __future__ import annotations

import copy
import json
from pathlib import Path

from .schema_defaults import cell_kind, dem_engine

# Config blocks copied into the scene as they are (the config's names are the scene's).
PASSTHROUGH = ["timestep", "pack", "preshear", "sampling", "effects", "run", "guards"]
# Scene blocks that cannot change a DEM result: wall-clock intervals of checkpoints and progress lines.
NOT_IN_RESULT = ["run"]
# Protocols with a scene section of their own name; every other protocol is a reversal schedule.
FIXED_PROTOCOLS = ("heaviside", "sinusoidal")
# Config cell keys that are the scene's geometry; cell.kind and cell.mass go to the scene's cell section.
GEOMETRY_KEYS = ("H_over_d", "W_over_H")


def scene_from_config(config: dict, case: dict, label: str) -> dict:
    """The scene of one case.

    Parameters
    ----------
    config : dict
        The campaign configuration (validated by the workflow's schema).
    case : dict
        ``pressure`` (Pa), ``inertial_number`` and ``seed`` of the case.
    label : str
        The case label, kept in ``meta`` for the sidecars.
    """
    cell = config["cell"]
    kind = cell_kind(config)
    scene = {
        "seed": case["seed"],
        "meta": {"case": label, "campaign": config["campaign"]},
        "geometry": {k: cell[k] for k in GEOMETRY_KEYS},
        "material": {**config["material"], "pressure": case["pressure"]},
        "loading": {"inertial_number": case["inertial_number"]},
    }
    if dem_engine(config) != "yade":   # a YADE scene stays as it was before engines existed (same rerun key)
        scene["engine"] = config["engine"]
    if kind != "walls":   # a wall cell's scene stays as it was before cell kinds existed (same rerun key)
        scene["cell"] = {k: cell[k] for k in ("kind", "mass") if k in cell}
    for block in PASSTHROUGH:
        if config.get(block):
            scene[block] = dict(config[block])
    if kind == "periodic":   # no walls, no band next to them: the schema's default is for the wall cell
        scene.get("sampling", {}).pop("bulk_exclusion_d", None)
    for protocol, spec in config["protocols"].items():
        if protocol in FIXED_PROTOCOLS:
            scene[protocol] = dict(spec)
        else:   # a reversal schedule (docs/scene.md): kept, shorthand and all, in the scene's schedules
            scene.setdefault("schedules", {})[protocol] = copy.deepcopy(spec)
    return scene


def scene_text(scene: dict) -> str:
    """The scene file's text: JSON with sorted keys, so equal scenes give equal files."""
    return json.dumps(scene, indent=2, sort_keys=True) + "\n"


def result_key(scene: dict) -> str:
    """The part of the scene a DEM result depends on, as canonical text.

    The workflow gives it to the ``scene`` rule as a parameter: Snakemake reruns
    a case when this text changes (its params trigger), and only then.
    """
    return json.dumps({k: v for k, v in scene.items() if k not in NOT_IN_RESULT}, sort_keys=True)


def scene_of_result_key(key: str, config: dict) -> dict:
    """The full scene back from ``result_key``'s text, with the config's blocks left out of it."""
    scene = json.loads(key)
    scene.update({block: dict(config[block]) for block in NOT_IN_RESULT if config.get(block)})
    return scene


def write_scene(scene: dict, path, log=None) -> bool:
    """Write the scene file at ``path`` unless it already holds this scene; True when written.

    ``log``, a path, receives one line saying what was done.
    """
    path, text = Path(path), scene_text(scene)
    path.parent.mkdir(parents=True, exist_ok=True)
    written = not (path.is_file() and path.read_text() == text)
    if written:
        path.write_text(text)
    if log is not None:
        Path(log).parent.mkdir(parents=True, exist_ok=True)
        Path(log).write_text(f"{'wrote' if written else 'unchanged'}: {path}\n")
    return written
