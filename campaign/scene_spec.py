"""What the DEM scene accepts, read from yade_scripts/scene.py: its defaults, ranges and protocol segments.

yade_scripts/ runs under YADE and is not a package; ``scene.py`` is pure Python,
so it is loaded here from its file (``scene_module``) and its ``SPEC`` table,
``segments`` and validator are the one source of what a scene may hold. The
workflow (rule resources, the comparison's reversal strains), the DEM studies
and the pre-flight check (``preflight``) ask through these functions.
"""
from __future__ import annotations

import functools
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@functools.lru_cache(maxsize=None)
def scripts_module(folder: str, name: str, root=ROOT):
    """The pure-Python ``<folder>/<name>.py`` of an engine's scripts (no YADE or LAMMPS import), loaded from its
    file: yade_scripts and lammps_scripts are not packages."""
    spec = importlib.util.spec_from_file_location(f"{folder}_{name}", Path(root) / folder / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def yade_scripts_module(name: str, root=ROOT):
    """The pure-Python ``yade_scripts/<name>.py`` (``scripts_module``)."""
    return scripts_module("yade_scripts", name, root)


def lammps_refusals(root=ROOT):
    """lammps_scripts/refusals.py: what the lammps engine does not run yet, by scene key."""
    return scripts_module("lammps_scripts", "refusals", root)


def scene_module(root=ROOT):
    """yade_scripts/scene.py: what a scene accepts, its defaults and its validator."""
    return yade_scripts_module("scene", root)


def scene_default(section: str, key: str):
    """The default the DEM takes for a scene key the config leaves out (yade_scripts/scene.py SPEC)."""
    return scene_module().SPEC[section][key][1]


def inertial_number_range() -> tuple[float, float]:
    """The inertial numbers the DEM accepts (yade_scripts/scene.py SPEC, loading.inertial_number)."""
    spec = scene_module().SPEC["loading"]["inertial_number"][0]
    return spec["lo"], spec["hi"]


def protocol_segments(name: str, spec: dict) -> list[dict] | None:
    """The segments of one protocol (yade_scripts/scene.py ``segments``); None when the DEM's validator refuses it.

    heaviside and sinusoidal are one segment; a schedule's train shorthand is expanded.
    """
    module = scene_module()
    try:
        if name in ("heaviside", "sinusoidal"):
            return module.segments({name: spec}, name)
        return module.segments({"schedules": module.check_schedules({name: spec})}, name)
    except (module.SceneError, KeyError, TypeError):
        return None  # scene_problems names it


def protocol_strain(name: str, spec: dict) -> float:
    """The strain at full rate a protocol runs (the sum of its segments')."""
    segs = protocol_segments(name, spec)
    return sum(seg["strain"] for seg in segs) if segs else float(spec.get("strain", 0.0))
