"""The config file's text: read as Snakemake would, but refusing what YAML lets pass.

A key given twice in one mapping (YAML keeps the last one silently), a missing
file, a folder, malformed YAML or a top level that is not a mapping are named
with the file and, where known, the line.
"""
from __future__ import annotations

from pathlib import Path

import yaml


class ConfigProblem(ValueError):
    """Bad config: its message is one line per problem."""


class _UniqueKeyLoader(yaml.SafeLoader):
    """PyYAML's safe loader that refuses a key given twice in one mapping."""


def _construct_mapping(loader, node, deep=False):
    first = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in first:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key '{key}' (first given on line {first[key] + 1}; "
                f"YAML would keep only the last one)", key_node.start_mark)
        first[key] = key_node.start_mark.line
    return loader.construct_mapping(node, deep=deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def load_configfile(path) -> dict:
    """The config file as a dict; ConfigProblem naming the file and line when it cannot be read.

    A missing file, a folder, malformed YAML, a duplicated key or a top level
    that is not a mapping are all refused.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigProblem(f"config error: {path}: no such file") from None
    except IsADirectoryError:
        raise ConfigProblem(f"config error: {path}: is a folder, not a config file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigProblem(f"config error: {path}: cannot be read ({exc})") from None
    try:
        doc = yaml.load(text, Loader=_UniqueKeyLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark
        where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
        raise ConfigProblem(f"config error: {where}: {exc.problem}"
                            + (f" ({exc.context})" if exc.context else "")) from None
    except yaml.YAMLError as exc:
        raise ConfigProblem(f"config error: {path}: not valid YAML ({exc})") from None
    if not isinstance(doc, dict):
        raise ConfigProblem(f"config error: {path}: the config must be a mapping of keys (campaign:, loading:, ...)")
    return doc


def configfile_problems(paths) -> list[str]:
    """Problems of the config files' text (``load_configfile``), one per file."""
    out = []
    for path in paths:
        try:
            load_configfile(path)
        except ConfigProblem as exc:
            out.append(str(exc))
    return out
