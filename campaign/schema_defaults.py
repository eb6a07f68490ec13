"""The defaults the workflow's config schema declares, for code that reads a config without it.

The schema (``workflow/schemas/config.schema.yaml``) is the one home of every config
default: Snakemake's ``validate`` fills them in for the workflow, and a command-line
tool that reads a preset directly (``python -m dem_study.bulk_cli``) takes them from
here rather than repeating them.
"""
from __future__ import annotations

import functools
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = ROOT / "workflow" / "schemas" / "config.schema.yaml"


@functools.lru_cache(maxsize=None)
def schema(path=SCHEMA) -> dict:
    """The config schema, parsed once."""
    return yaml.safe_load(Path(path).read_text())


def block_defaults(*keys: str, path=SCHEMA) -> dict:
    """The ``default`` of every property of the config block at ``keys`` that declares one.

    ``block_defaults("accuracy", "bulk_vs_walls")`` -> ``{"run": False, "preshear_strain": 1.5, ...}``.
    """
    node = schema(path)
    for key in keys:
        node = node["properties"][key]
    return {name: prop["default"] for name, prop in node.get("properties", {}).items() if "default" in prop}


def default(*keys: str, path=SCHEMA):
    """The ``default`` the schema declares for the config key at ``keys``: ``default("cell", "kind")`` -> ``"walls"``."""
    node = schema(path)
    for key in keys:
        node = node["properties"][key]
    return node["default"]


def cell_kind(config: dict) -> str:
    """The campaign cell's kind (``cell.kind``), the schema's default where the config (not yet validated) has none."""
    return (config.get("cell") or {}).get("kind", default("cell", "kind"))


def dem_engine(config: dict) -> str:
    """The campaign's DEM engine (``engine``), the schema's default where the config (not yet validated) has none."""
    return config.get("engine", default("engine"))


def with_defaults(config: dict, path=SCHEMA) -> dict:
    """``config`` with the schema's defaults filled in, in place, as the Snakefile's ``validate`` fills them
    (``snakemake.utils.validate``): for a command that reads config files without Snakemake. It raises
    Snakemake's WorkflowError on a config the schema refuses (the pre-flight check names those first)."""
    from snakemake.utils import validate

    validate(config, str(path))
    return config
