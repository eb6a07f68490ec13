"""A data release of finished DEM cases: make it, verify it, restore its cases as finished (docs/data-release.md).

A release folder ``data/<name>/`` holds, per case ``cases/<label>/``:

- ``<protocol>.csv.gz`` (or ``.csv.xz``, ``--compression xz``): one minimal CSV per
  reversal run (the pre-shear's rows followed by the run's, every contract column,
  gzip without a time stamp, or xz, which has none, so the bytes depend on the data
  only), the format ``python -m dem_contract import`` reads (docs/own-dem-data.md);
- ``case.yaml``: the importer's metadata (pressure, I, cell, N, simulator: the
  engine and its version, ``YADE 2023.02a`` or ``LAMMPS 20210929``, the runs and
  the time and strain of each reversal, the stages' costs);
- ``sidecars/<stage>.json``: the DEM stages' sidecars as the engine wrote them
  (provenance: the scene, its sha256, the engine's version, CPU and wall time, steps,
  N), restored verbatim, so the calibration, the comparison and the claims read
  the same costs and disks as from the original results; with
  ``preshear.census.json`` where the case has a contact census of its pre-shear's
  final state (``yade_scripts/contact_census.py``);
- ``preshear.final.yade.gz`` (a LAMMPS case: ``preshear.final.lammps``; optional,
  ``--states``): the pre-shear's final state, for new reversals branching from it;

and ``config.yaml`` (the campaign's config file as run; ``config-<k>.yaml``,
k = 1, 2, ..., when it ran with several, in their order) and ``manifest.yaml``
(the data license, CC-BY-4.0, data/LICENSE; the config, merged as Snakemake merges it, the commit of the code, the engine's version, the date, a sha256 and a size
per file, the commands that regenerate the DEM and the release). Nothing in a
release is edited by hand: ``verify`` reports a file whose checksum differs, and
``restore_case`` and ``released_cases`` (what the workflow's release rules use)
refuse the whole release before writing anything.
"""
from __future__ import annotations

import datetime
import gzip
import hashlib
import json
import lzma
import shutil
import subprocess
import tempfile
from pathlib import Path

import pandas as pd
import yaml

from .derived import reversal_kinds, split_transients
from .importer import import_cases
from .series import CONTRACT_COLUMNS, DEMInputError, read_series, read_sidecar, sidecar_engine

#: The manifest's file name, and the release's layout.
MANIFEST = "manifest.yaml"
CASES_DIR = "cases"
PUBLISHED_DIR = "published"      # the campaign's own tables, for comparison with a recomputation
STATE = "preshear.final.yade.gz"
#: The pre-shear's final state by engine (a YADE save; a LAMMPS restart file, lammps_scripts/shearing.py).
STATES = {"yade": STATE, "lammps": "preshear.final.lammps"}
#: The engines whose sidecars a release reads: the sidecar key of the engine's version, and its name in case.yaml.
ENGINES = {"yade": ("yade_version", "YADE"), "lammps": ("lammps_version", "LAMMPS")}
#: Stages whose sidecars every case has before its reversal runs.
BASE_STAGES = ("pack", "preshear")
#: A contact census of the pre-shear's final state (yade_scripts/contact_census.py), released with the
#: sidecars where a case has one: the fabric readings and rattlers, which need the state to measure.
CENSUS = "preshear.census"
#: The code a DEM result depends on, per engine (the last commit that changed it is named in the manifest):
#: the config -> scene mapping and the engine's stages; lammps_scripts/ runs the same scene under LAMMPS
#: and imports yade_scripts/' pure modules, so a LAMMPS result depends on both, a YADE result on its own.
SCENE_CODE = ("campaign/scenes.py", "campaign/scene_spec.py")
DEM_CODE = {"yade": ("yade_scripts", *SCENE_CODE), "lammps": ("yade_scripts", "lammps_scripts", *SCENE_CODE)}
#: Results sub-folders a released case can come from (the campaign's, the bulk study's).
SOURCES = ("dem", "accuracy/bulk")


def dem_code(engines) -> list:
    """The paths whose last change dates the DEM code of a release made by ``engines`` (``DEM_CODE``)."""
    return sorted({path for engine in engines for path in DEM_CODE[engine]})


def sha256(path) -> str:
    """The file's SHA-256, hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_csv_gz(frame: pd.DataFrame, path) -> None:
    """A table as gzip-compressed CSV with no time stamp (equal data give equal bytes)."""
    text = frame.to_csv(index=False).encode()
    with open(path, "wb") as raw, gzip.GzipFile(fileobj=raw, mode="wb", mtime=0, filename="") as f:
        f.write(text)


#: xz's fixed preset, the strongest: 12-15 % fewer bytes than gzip -9 on the releases' series (data/bulk-decide's:
#: 12.7 %). Its 64 MiB dictionary exceeds any series (a 4 MiB one gives the same bytes).
XZ_PRESET = 9 | lzma.PRESET_EXTREME


def write_csv_xz(frame: pd.DataFrame, path) -> None:
    """A table as xz-compressed CSV (fixed preset ``XZ_PRESET``; the xz container holds no time stamp or file
    name, so equal data give equal bytes with the same liblzma)."""
    Path(path).write_bytes(lzma.compress(frame.to_csv(index=False).encode(), format=lzma.FORMAT_XZ,
                                         check=lzma.CHECK_CRC64, preset=XZ_PRESET))


#: A release's compression of its series: the file suffix and the writer (gz, the default, or xz).
COMPRESSIONS = {"gz": (".csv.gz", write_csv_gz), "xz": (".csv.xz", write_csv_xz)}


def case_engine(sidecar: dict, where) -> str:
    """The engine that wrote a case's sidecar (``sidecar_engine``), one a release knows (``ENGINES``)."""
    engine = sidecar_engine(sidecar)
    if engine not in ENGINES:
        raise DEMInputError(f"{where}: engine {engine!r}, a release knows {sorted(ENGINES)}")
    return engine


def case_protocols(case_dir) -> list:
    """The reversal runs of a finished case: every ``<stem>.csv`` with a sidecar, but the pack and pre-shear."""
    case_dir = Path(case_dir)
    return sorted(p.stem for p in case_dir.glob("*.csv")
                  if p.stem not in BASE_STAGES and p.with_suffix(".json").is_file())


def merge_config(base: dict, overlay: dict) -> dict:
    """``overlay`` over ``base``, mappings merged key by key (Snakemake's merge of several --configfile)."""
    out = dict(base)
    for key, value in overlay.items():
        out[key] = merge_config(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) \
            else value
    return out


def pre_tail_rows(n_pre: int, n_run: int) -> int:
    r"""Pre-shear rows a case's second and later runs carry: its last :math:`K` rows, not all :math:`n_p`.

    The first run holds the whole pre-shear (the importer's ``preshear.csv``); a
    later one needs only the row at its reversal and enough rows before it for
    the importer to see the pre-shear's direction, which it takes from the
    median rate of a file's first :math:`\max(10, n/10)` rows:
    :math:`K = \min(n_p, \max(11, \lceil n_r/9 \rceil + 2))` rows make all of
    them pre-shear rows (:math:`K \ge \max(10, (K + n_r)/10)`).
    """
    return min(n_pre, max(11, -(-n_run // 9) + 2))


def git_output(*args, cwd) -> str:
    """``git *args`` in ``cwd``: its output, stripped, or ``"unknown"`` without git or a repository."""
    try:
        return subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def excluded_from_status(out: Path, repo: Path) -> list:
    """``git status`` pathspecs leaving out the release folder ``out`` when it lies in ``repo`` (else none)."""
    try:
        return [f":(exclude){Path(out).resolve().relative_to(Path(repo).resolve())}"]
    except ValueError:
        return []


def reverses_at_once(sidecar: dict, pre) -> bool:
    """Whether a run's first reversal is at the pre-shear's end (its sidecar's ``reversal_t``, within 1e-9)."""
    t = sidecar.get("reversal_t")
    return t is not None and abs(float(t) - float(pre["t"].iloc[-1])) <= 1e-9 * max(1.0, abs(float(t)))


def _release_case(case_dir: Path, out: Path, with_state: bool, compression: str = "gz") -> dict:
    """One finished case into ``out``: its minimal CSVs, case YAML, sidecars (and state). Returns its summary.

    A YADE case's ``case.yaml`` and summary are as they always were (``simulator: YADE <version>``,
    ``yade_version``); a LAMMPS case's name LAMMPS and its version (``simulator: LAMMPS 20210929``;
    ``engine: lammps``, ``lammps_version``).
    """
    label = case_dir.name
    suffix, write_series = COMPRESSIONS[compression]
    scene = read_sidecar(case_dir / "scene.json")
    pre_side = read_sidecar(case_dir / "preshear.json")
    if not scene or not pre_side:
        raise DEMInputError(f"{case_dir}: not a finished DEM case (scene.json and preshear.json expected)")
    engine = case_engine(pre_side, case_dir / "preshear.json")
    version_key, simulator = ENGINES[engine]
    version = pre_side.get(version_key, "unknown")
    protocols = case_protocols(case_dir)
    if not protocols:
        raise DEMInputError(f"{case_dir}: no finished reversal run (<protocol>.csv with its .json)")
    pre = read_series(case_dir / "preshear.csv", what="the case's pre-shear")
    # the importer ends the pre-shear at the first run's first reversal: first a run that reverses at once
    # (a schedule may first go on shearing the pre-shear's way)
    sides = {p: read_sidecar(case_dir / f"{p}.json") for p in protocols}
    at_once = [p for p in protocols if reverses_at_once(sides[p], pre)]
    if not at_once:
        raise DEMInputError(f"{case_dir}: no run reverses at the end of the pre-shear; the import format needs one")
    protocols = [at_once[0], *(p for p in protocols if p != at_once[0])]
    out.mkdir(parents=True, exist_ok=True)
    (out / "sidecars").mkdir(exist_ok=True)
    runs = []
    for protocol in protocols:
        path = case_dir / f"{protocol}.csv"
        run = read_series(path, what="a reversal run")
        side = sides[protocol]
        kinds = reversal_kinds(side, protocol, what=str(path))
        reversals = []
        for tr, kind in zip(split_transients(pre, run, side, what=str(path)), kinds):
            entry = {"strain": float(tr.strain0), "t": float(tr.t0)}
            if kind["kind"] == "sinusoidal":
                entry.update(transition="half_cosine", transition_strain=float(kind["transition_strain"]))
            else:
                entry["transition"] = "heaviside"
            reversals.append(entry)
        lead = pre if not runs else pre.iloc[-pre_tail_rows(len(pre), len(run)):]
        write_series(pd.concat([lead, run], ignore_index=True)[list(CONTRACT_COLUMNS)], out / f"{protocol}{suffix}")
        runs.append({"file": f"{protocol}{suffix}", "protocol": protocol, "reversals": reversals})
    stages = [*BASE_STAGES, *protocols]
    costs = {}
    for stage in ["scene", *stages, CENSUS]:
        src = case_dir / f"{stage}.json"
        if src.is_file():
            shutil.copyfile(src, out / "sidecars" / src.name)
        side = read_sidecar(src) if stage != "scene" else {}
        cost = {k: side[k] for k in ("cpu_time_s", "wall_time_s", "steps") if k in side}
        if cost:
            costs[stage] = cost
    geometry = scene.get("geometry") or {}
    material = scene.get("material") or {}
    meta = {"pressure": float(material.get("pressure", pre_side.get("pressure_Pa", 0.0))),
            "inertial_number": float((scene.get("loading") or {}).get("inertial_number",
                                                                       pre_side.get("inertial_number", 0.0))),
            "simulator": f"{simulator} {version}",
            "cell": {k: float(geometry[k]) for k in ("H_over_d", "W_over_H") if k in geometry},
            "notes": f"data release of case {label}; the DEM sidecars as written are in sidecars/",
            "cases": [{"seed": int(scene.get("seed", pre_side.get("seed", 0))), "runs": runs, "costs": costs}]}
    if "N" in pre_side:
        meta["N"] = int(pre_side["N"])
    if not meta["cell"]:
        del meta["cell"]
    (out / "case.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    if with_state:
        state = STATES[engine]
        if not (case_dir / state).is_file():
            raise DEMInputError(f"{case_dir / state}: file not found (asked for with --states)")
        shutil.copyfile(case_dir / state, out / state)
    return {"protocols": protocols, "seed": meta["cases"][0]["seed"], "N": meta.get("N"),
            **({} if engine == "yade" else {"engine": engine}), version_key: version,
            "cpu_time_s": sum(c.get("cpu_time_s", 0.0) for c in costs.values())}


DATA_LICENSE = "CC-BY-4.0"     # the data releases' license (data/LICENSE; the code's is GPL-3.0-or-later, LICENSE)


def resolve_run_commit(run_commit: str, repo) -> str:
    """The full hash of ``run_commit``, once it is a commit and an ancestor of ``repo``'s HEAD (or HEAD itself).

    Raises
    ------
    DEMInputError
        ``run_commit`` is not a commit of the repository, or not in HEAD's history.
    """
    full = git_output("rev-parse", "--verify", "--quiet", f"{run_commit}^{{commit}}", cwd=repo)
    if not full or full == "unknown":
        raise DEMInputError(f"--run-commit {run_commit}: not a commit of the repository {repo}")
    try:
        ancestor = subprocess.run(["git", "merge-base", "--is-ancestor", full, "HEAD"], cwd=repo,
                                  capture_output=True).returncode == 0
    except OSError:
        ancestor = False
    if not ancestor:
        raise DEMInputError(f"--run-commit {run_commit}: not an ancestor of HEAD "
                            f"({git_output('rev-parse', 'HEAD', cwd=repo)}); a release is made from a commit that "
                            "holds the code that ran its DEM in its history")
    return full


def manifest_blocks(text: str) -> dict:
    """A manifest's top-level blocks as written: key -> its lines (the key's line and every line up to the next
    top-level key), comments kept, so a block can be carried into a remade manifest unchanged."""
    blocks, key = {}, None
    for line in text.splitlines(keepends=True):
        head = line.split(":", 1)[0]
        if line[:1] not in (" ", "#", "-", "\n", "") and ":" in line and head.isidentifier():
            key = head
            blocks[key] = ""
        if key is not None:
            blocks[key] += line
    return blocks


def carry_over(new: dict, old_text: str, carried) -> str:
    """The manifest ``new`` as YAML with the blocks ``carried`` of the old manifest's text spliced in verbatim.

    Each carried block goes after the block that precedes it in the old manifest (the first of ``new``'s
    blocks before it there), so it keeps its place and its comments.
    """
    old = yaml.safe_load(old_text)
    old_keys = list(old)
    after, head = {}, []
    for i, key in enumerate(old_keys):
        if key in carried:
            prev = next((k for k in reversed(old_keys[:i]) if k in new), None)
            (after.setdefault(prev, []) if prev else head).append(key)
    old_blocks = manifest_blocks(old_text)
    new_blocks = manifest_blocks(yaml.safe_dump(new, sort_keys=False))
    text = "".join(old_blocks[k] for k in head)
    for key in new_blocks:
        text += new_blocks[key] + "".join(old_blocks[k] for k in after.get(key, []))
    merged = yaml.safe_load(text)
    if list(merged) != [*head, *(k for key in new for k in (key, *after.get(key, [])))] or \
            any(merged[k] != old[k] for k in carried) or any(merged[k] != v for k, v in new.items()):
        raise DEMInputError("carry-over: the merged manifest does not read back as the new one plus the old "
                            f"blocks {sorted(carried)}")
    return text


def remade_record(new_files: dict, old: dict, old_commit: str, reason: str, restore_commands, command: str) -> dict:
    """The ``remade`` entry of a release remade from an older one: when, from which, why, its files compared."""
    old_files = old.get("files") or {}
    kept = [n for n in new_files if n in old_files]
    changed = [n for n in kept if (new_files[n]["sha256"], new_files[n]["bytes"])
               != (old_files[n]["sha256"], old_files[n]["bytes"])]
    return {
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "from": {k: v for k, v in (("release", old.get("release")), ("date", old.get("date")),
                                   ("code_commit", old.get("code_commit")), ("manifest_commit", old_commit),
                                   ("command", (old.get("regenerate") or {}).get("release")))
                 if v not in (None, "", "unknown")},
        "reason": reason,
        "files": {"kept_with_equal_sha256": len(kept) - len(changed), "changed": changed,
                  "dropped": [n for n in old_files if n not in new_files],
                  "added": [n for n in new_files if n not in old_files],
                  "bytes_before": old.get("total_bytes"), "bytes_after": sum(f["bytes"] for f in new_files.values())},
        "commands": [*restore_commands, command],
    }


def make_release(case_dirs, out, config, command: str, with_states: bool = False, repo=None,
                 published=(), compression: str = "gz", run_commit: str | None = None, carry_from=None,
                 reason: str | None = None) -> Path:
    """Write a data release of finished DEM cases into ``out`` (a new or empty folder).

    Parameters
    ----------
    case_dirs : sequence of str or Path
        Finished cases: ``<results>/dem/<case>/`` or ``<results>/accuracy/bulk/<cell>_s<seed>/``.
    out : str or Path
        The release folder, e.g. ``data/<campaign>``.
    config : str or Path, or a sequence of them
        The campaign's config file(s) as run, in the order given to ``--configfile``
        (copied to ``config.yaml``, or ``config-1.yaml``, ``config-2.yaml``, ...; merged into the manifest).
    command : str
        The command line that made the release (named in the manifest).
    with_states : bool
        Also release each case's pre-shear final state (``preshear.final.yade.gz``; a LAMMPS case's
        ``preshear.final.lammps``).
    repo : str or Path, optional
        The repository whose commit is recorded (default: this package's).
    published : sequence of str or Path
        Tables the campaign's own run wrote from these cases (for instance its
        ``claims/paper_claims.csv``), copied to ``published/<file name>`` and checksummed
        like the data, so that a recomputation from the release can be compared with them.
    compression : {"gz", "xz"}
        The series' compression: gzip (``.csv.gz``, the default, as every release before xz) or xz
        (``.csv.xz``, ``XZ_PRESET``: 14-15 % fewer bytes). Both lossless; the manifest names xz
        (``compression: xz``), a gzip release's manifest keys are as they always were.
    run_commit : str, optional
        The commit whose code ran the DEM, when the release is made from a later one (a campaign run
        from a pinned worktree): an ancestor of HEAD; ``dem_code_commit`` is then the last commit at or
        before it that changed the engines' ``DEM_CODE``, and the manifest records it as ``run_commit``.
    carry_from : str or Path, optional
        The manifest of the release this one remakes (a copy: the folder is deleted to remake it):
        every top-level block the command does not write (``seeds``, ``republished``, ...) is carried
        over verbatim, comments included, the ``published`` provenance (where each table came from in
        the campaign) replaces the paths given here, and a ``remade`` entry records the date, the
        release it was restored from, ``reason``, every kept file's sha256 against the old manifest
        and the commands (the cases are taken to be restored from that release, at ``out``).
    reason : str, optional
        Why the release is remade (required with ``carry_from``).

    Returns
    -------
    Path
        The release folder.
    """
    out = Path(out)
    configs = [Path(config)] if isinstance(config, (str, Path)) else [Path(c) for c in config]
    repo = Path(repo) if repo else Path(__file__).resolve().parents[1]
    if compression not in COMPRESSIONS:
        raise DEMInputError(f"compression {compression!r}: expected one of {sorted(COMPRESSIONS)}")
    if out.exists() and any(out.iterdir()):
        raise DEMInputError(f"{out}: exists and is not empty; a release is written once (delete it to remake it)")
    run_commit = resolve_run_commit(run_commit, repo) if run_commit else None
    old_text = old = None
    if carry_from is not None:
        if not reason:
            raise DEMInputError("--carry-from: give --reason (why the release is remade)")
        carry_from = Path(carry_from)
        carry_from = carry_from / MANIFEST if carry_from.is_dir() else carry_from
        try:
            old_text = carry_from.read_text()
        except OSError as exc:
            raise DEMInputError(f"{carry_from}: not readable ({exc.strerror or exc})") from None
        old = yaml.safe_load(old_text)
        if not isinstance(old, dict) or "files" not in old:
            raise DEMInputError(f"{carry_from}: not a release manifest (no 'files')")
    cfg = {}
    for path in configs:
        cfg = merge_config(cfg, yaml.safe_load(path.read_text()) or {})
    sources = {}
    for case_dir in map(Path, case_dirs):
        parent, grand = case_dir.parent.name, case_dir.parent.parent.name
        source = ("accuracy/bulk" if (grand, parent) == ("accuracy", "bulk")
                  else "dem" if parent == "dem" and grand != "accuracy" else None)
        if source is None:
            raise DEMInputError(f"{case_dir}: not a case of a results folder's {' or '.join(SOURCES)}/ "
                                f"(<results>/dem/<case> or <results>/accuracy/bulk/<cell>_s<seed>)")
        if case_dir.name in {d.name for d in sources}:
            raise DEMInputError(f"{case_dir}: case {case_dir.name} given twice")
        sources[case_dir] = source
    out.mkdir(parents=True, exist_ok=True)
    names = ["config.yaml"] if len(configs) == 1 else [f"config-{k}.yaml" for k in range(1, len(configs) + 1)]
    try:
        for path, name in zip(configs, names):
            shutil.copyfile(path, out / name)
        tables = {}
        for path in map(Path, published):
            if path.name in tables:
                raise DEMInputError(f"{path}: a published table named {path.name} is given twice")
            (out / PUBLISHED_DIR).mkdir(exist_ok=True)
            shutil.copyfile(path, out / PUBLISHED_DIR / path.name)
            tables[path.name] = str(path)
        cases = {case_dir.name: {"source": source,
                                 **_release_case(case_dir, out / CASES_DIR / case_dir.name, with_states, compression)}
                 for case_dir, source in sources.items()}
    except BaseException:       # no half-made release is left behind
        shutil.rmtree(out)
        raise
    files = {str(p.relative_to(out)): {"sha256": sha256(p), "bytes": p.stat().st_size}
             for p in sorted(out.rglob("*")) if p.is_file() and p.name != MANIFEST}
    engines = sorted({c.get("engine", "yade") for c in cases.values()})
    versions = {}
    for engine in engines:
        key = ENGINES[engine][0]
        found = sorted({c[key] for c in cases.values() if key in c}, key=str)
        versions[key] = found[0] if len(found) == 1 else found
    targets = " ".join(f"<results_dir>/{c['source']}/{label}/{p}.csv"
                       for label, c in cases.items() for p in c["protocols"])
    if old is not None and old.get("published"):
        # where each table came from in the campaign's own run, not the restored copy it was taken from now
        tables = {name: old["published"].get(name, path) for name, path in tables.items()}
    manifest = {
        "release": out.name,
        "license": DATA_LICENSE,
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "code_commit": git_output("rev-parse", "HEAD", cwd=repo),
        # tracked files differing from the commit, but for this release's own folder (remade: deleted first)
        "code_dirty": bool(git_output("status", "--porcelain", "--untracked-files=no", "--", ".",
                                *excluded_from_status(out, repo), cwd=repo)),
        **({"run_commit": run_commit} if run_commit else {}),
        # the last commit that changed the DEM's code (the engines' stages, the config -> scene mapping),
        # at or before the commit that ran the DEM
        "dem_code_commit": git_output("log", "-1", "--format=%H", *([run_commit] if run_commit else []),
                                      "--", *dem_code(engines), cwd=repo),
        # a YADE release: yade_version alone, as always; else the engine(s) and each one's version
        **({} if engines == ["yade"] else {"engine": engines[0] if len(engines) == 1 else engines}),
        **versions,
        **({} if compression == "gz" else {"compression": compression}),
        "states": with_states,
        "regenerate": {
            "dem": f"snakemake -j2 --configfile {' '.join(f'{out}/{n}' for n in names)}"
                   f" --config results_dir=<results_dir> {targets}",
            "release": command,
        },
        "cases": cases,
        **({"published": tables} if tables else {}),
        "config": cfg,
        "files": files,
        "total_bytes": sum(f["bytes"] for f in files.values()),
    }
    if old is None:
        (out / MANIFEST).write_text(yaml.safe_dump(manifest, sort_keys=False))
        return out
    restores = [f"python -m dem_contract restore --release {out} --case {d.name} --out {d}" for d in sources]
    old_commit = git_output("log", "-1", "--format=%H", "--", str(out.resolve() / MANIFEST), cwd=repo)
    entry = remade_record(files, old, old_commit, reason, restores, command)
    at = list(manifest).index("regenerate")        # the remake's record before the commands, after the states
    items = list(manifest.items())
    manifest = dict([*items[:at], ("remade", [*(old.get("remade") or []), entry]), *items[at:]])
    carried = [k for k in old if k not in manifest]
    (out / MANIFEST).write_text(carry_over(manifest, old_text, carried))
    return out


def read_manifest(release) -> dict:
    """A release's manifest, checked for its keys."""
    path = Path(release) / MANIFEST
    try:
        manifest = yaml.safe_load(path.read_text())
    except OSError as exc:
        raise DEMInputError(f"{path}: not readable ({exc.strerror or exc})") from None
    if not isinstance(manifest, dict) or not {"files", "cases", "config"} <= set(manifest):
        raise DEMInputError(f"{path}: expected a mapping with 'files', 'cases' and 'config'")
    return manifest


def checksum_problems(release) -> list:
    """Every file of the release whose sha256 or size differs from the manifest, is missing, or is not listed."""
    release = Path(release)
    listed = read_manifest(release)["files"]
    problems = []
    for name, entry in listed.items():
        path = release / name
        if not path.is_file():
            problems.append(f"{path}: listed in the manifest, missing")
        elif path.stat().st_size != entry["bytes"] or sha256(path) != entry["sha256"]:
            problems.append(f"{path}: sha256 {sha256(path)} ({path.stat().st_size} bytes), the manifest says "
                            f"{entry['sha256']} ({entry['bytes']} bytes): edited after the release")
    for path in sorted(release.rglob("*")):
        name = str(path.relative_to(release))
        if path.is_file() and name != MANIFEST and name not in listed:
            problems.append(f"{path}: not in the manifest")
    return problems


def require_intact(release) -> Path:
    """The release folder, once every file's sha256 and size are those of its manifest.

    A release is used (restored, or named by a preset's ``release:``) only as it
    was released: an edited, missing or added file stops its use before anything
    is written (``checksum_problems`` names each).

    Raises
    ------
    DEMInputError
        Naming every file that differs from the manifest.
    """
    problems = checksum_problems(release)
    if problems:
        raise DEMInputError(f"{release}: {len(problems)} file(s) differ from the manifest; a release is used only "
                            "as released (restore it from git, or remake it: docs/data-release.md):\n  "
                            + "\n  ".join(problems))
    return Path(release)


def restore_case(release, label, out) -> Path:
    """Write a released case into ``out`` (``<results>/dem/<label>/``) as a finished DEM case.

    Every file of the release is checked against its manifest first
    (``require_intact``); nothing is written unless all match. The series then go
    through the importer (``import_cases``: the contract's checked reader and its
    reversal splitter), then the DEM's own sidecars replace the importer's, so
    every stage reads the costs, disks and scene as the DEM wrote them.

    Raises
    ------
    DEMInputError
        A file that differs from the manifest, an unknown case, a file the contract
        refuses, or a released sidecar whose reversal time disagrees with the series.
    """
    return _restore_checked_case(require_intact(release), label, out)


def _restore_checked_case(release, label, out) -> Path:
    """``restore_case`` after the checksums (``verify`` reports them itself, then reads every case back)."""
    release, out = Path(release), Path(out)
    src = release / CASES_DIR / label
    if not (src / "case.yaml").is_file():
        raise DEMInputError(f"{release}: no released case {label!r} (no {src / 'case.yaml'})")
    with tempfile.TemporaryDirectory(prefix="release-") as tmp:
        (imported,) = import_cases(src / "case.yaml", tmp)
        for side in sorted((src / "sidecars").glob("*.json")):
            ours = read_sidecar(imported / side.name)
            theirs = json.loads(side.read_text())
            if "reversal_t" in theirs and abs(ours.get("reversal_t", float("nan")) - theirs["reversal_t"]) > 1e-9:
                raise DEMInputError(f"{side}: reversal_t {theirs['reversal_t']} but the series reverse at "
                                    f"{ours.get('reversal_t')}")
            shutil.copyfile(side, imported / side.name)
        out.mkdir(parents=True, exist_ok=True)
        for path in imported.iterdir():
            shutil.move(str(path), out / path.name)
    for state in STATES.values():
        if (src / state).is_file():
            shutil.copyfile(src / state, out / state)
    return out


def verify(release) -> list:
    """Checksums against the manifest, then every case restored into a scratch folder (the contract's reader)."""
    problems = checksum_problems(release)
    for label in read_manifest(release)["cases"]:
        with tempfile.TemporaryDirectory(prefix="verify-") as tmp:
            try:
                _restore_checked_case(release, label, Path(tmp) / label)
            except DEMInputError as exc:
                problems.append(str(exc))
    return problems


def released_cases(releases, protocols=(), base=".") -> dict:
    """Case label -> release folder, over the releases named (a folder or a list), for cases holding ``protocols``.

    A case released without one of ``protocols`` is left out: its DEM runs as usual.
    Each release is checked against its manifest first (``require_intact``), so
    a workflow naming an edited release stops while it is parsed, naming the file.
    """
    if isinstance(releases, (str, Path)):
        releases = [releases]
    found = {}
    for release in releases or []:
        release = require_intact(Path(base) / release)
        for label, case in read_manifest(release)["cases"].items():
            if set(protocols) <= set(case["protocols"]):
                found.setdefault(label, str(release))
    return found


def release_bytes(root) -> int:
    """Bytes of every release under ``root`` (``data/``): the repository's budget is 20 MB."""
    return sum(p.stat().st_size for p in Path(root).rglob("*") if p.is_file())


def case_files(release, label) -> list:
    """The files of one released case (a Snakemake rule's input)."""
    return sorted(str(p) for p in (Path(release) / CASES_DIR / label).rglob("*") if p.is_file())


__all__ = ["DEMInputError", "MANIFEST", "DATA_LICENSE", "sha256", "git_output", "write_csv_gz", "write_csv_xz",
           "COMPRESSIONS", "case_engine", "resolve_run_commit", "case_protocols", "make_release",
           "read_manifest", "checksum_problems", "require_intact", "restore_case", "verify", "released_cases",
           "release_bytes", "case_files"]
