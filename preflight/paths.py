"""Where ``results_dir`` and ``release`` may point, checked before any job.

The rule (docs/running.md, "Where results and releases may lie"):

- **characters**: letters, digits and ``. _ - /`` only (the schema's ``safe_path``);
- **inside the working tree** without more ado: a relative path that does not climb out
  with ``..``, or an absolute path inside the repository;
- **outside it** (an absolute path elsewhere, ``../x``) only with ``allow_outside_tree: true``
  in the config, e.g. ``results_dir: /scratch/me/k1e05`` on a scratch disk;
- **never**, not even then: ``/``, a folder directly under it (``/tmp``, ``/work``: a
  results folder is a folder of its own), a system folder or anything in one (``SYSTEM``,
  but ``/var/tmp``), the home folder itself, or a hidden folder (a part starting with
  ``.``: ``.git``, ``.snakemake``, ``~/.ssh``), whether written so or reached through a
  symbolic link.

``results_dir`` is also not the repository, a folder above it or one of its code folders.
"""
from __future__ import annotations

import os
from pathlib import Path

from .problems import problem

#: System folders: no results folder or release in them, whatever the config allows (the set-up runs as root).
SYSTEM = ("/bin", "/boot", "/dev", "/etc", "/lib", "/lib32", "/lib64", "/libx32", "/proc", "/run", "/sbin", "/sys",
          "/usr", "/var")
#: Scratch folders inside a system folder.
SCRATCH = ("/var/tmp",)
#: Top-level folders of the repository that hold code or inputs: never a results folder.
SOURCE_FOLDERS = {"campaign", "calibrate", "claims", "compare", "config", "dem_contract", "dem_study", "docs", "model",
                  "preflight", "profiles", "shared_stats", "tests", "tools", "workflow", "yade_scripts", "data"}
OPT_IN = "allow_outside_tree"
ALLOWED = (f"a folder inside the working tree (e.g. results-mine), or with {OPT_IN}: true one elsewhere "
           "(e.g. /scratch/me/results), never /, a folder directly under it, a system folder, "
           "the home folder or a hidden folder")


def _under(path: Path, folder: str) -> bool:
    return path == Path(folder) or Path(folder) in path.parents


def where_problem(value: str, root: Path, home: Path) -> str | None:
    """Why ``value`` may never be used (system, home, top-level, hidden folder), or None."""
    lexical = Path(os.path.normpath(root / value))
    for path in dict.fromkeys((lexical, lexical.resolve())):
        own = path.relative_to(root) if _under(path, str(root)) else path   # (the tree may lie in a hidden folder)
        hidden = [part for part in own.parts if part.startswith(".") and part != "."]
        if hidden:
            return f"names a hidden folder ({hidden[0]}: a program's own files or settings)"
        if path == Path(path.anchor):
            return "is the root of the file system"
        system = next((s for s in SYSTEM if _under(path, s) and not any(_under(path, t) for t in SCRATCH)), None)
        if system:
            return f"is in the system folder {system}" + (f" (through a link: {path})" if path != lexical else "")
        if path == home.resolve() or path == home:
            return "is the home folder"
        if len(path.parts) == 2:
            return f"is a folder directly under {path.anchor} (a folder of its own is needed)"
    return None


def outside_tree(value: str, root: Path) -> bool:
    """``value`` leaves the working tree: an absolute path outside ``root``, or a relative one climbing out."""
    if os.path.isabs(value):
        return not _under(Path(os.path.normpath(value)), str(root))
    return os.path.normpath(value).split(os.sep)[0] == ".."


def path_problems(key: str, value: str, config: dict, root: Path, home: Path | None = None) -> list[str]:
    """The problems of one path of the config (``results_dir``, ``release[i]``) against the module's rule."""
    root, home = Path(root).resolve(), Path(home) if home is not None else Path.home()
    why = where_problem(value, root, home)
    if why is None and outside_tree(value, root) and config.get(OPT_IN) is not True:
        why = f"lies outside the working tree {root} (say {OPT_IN}: true to use it)"
    return [problem(key, value, why, ALLOWED)] if why else []


def results_dir_problems(config: dict, root, home: Path | None = None) -> list[str]:
    """A results folder of its own: the path rule, and neither the repository nor above it nor its code."""
    value = config.get("results_dir", "results")
    out = path_problems("results_dir", value, config, root, home)
    if out:
        return out
    root = Path(root).resolve()
    path = (root / value).resolve()
    if path == root or path in root.parents:
        return [problem("results_dir", value, "is the repository or a folder above it: outputs would mix with the code",
                        ALLOWED)]
    if root in path.parents and path.relative_to(root).parts[0] in SOURCE_FOLDERS:
        return [problem("results_dir", value, f"lies in the repository's {path.relative_to(root).parts[0]}/ folder",
                        ALLOWED)]
    return []


def release_problems(config: dict, root, home: Path | None = None) -> list[str]:
    """Every release folder (relative to the repository) against the path rule."""
    release = config.get("release") or []
    items = [("release", release)] if isinstance(release, str) else [
        (f"release[{i}]", value) for i, value in enumerate(release)]
    return [line for key, value in items for line in path_problems(key, value, config, root, home)]
