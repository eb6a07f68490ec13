r"""Import DEM data the project did not make: minimal CSVs plus a YAML of case metadata -> the contract's layout.

A user with shear-reversal runs from another simulator (or another cell)
writes, per run, one CSV holding the whole history from the start of the
pre-shear through its reversals, in the minimal columns ``MINIMAL_COLUMNS``
(optional ones ``OPTIONAL_COLUMNS``), and one YAML file naming the cases, their
runs and the strains at which each run reverses (docs/own-dem-data.md). This
module writes them as the DEM stage would (docs/data-contract.md):
``<out>/<label>/preshear.csv`` (the first run's rows up to its first reversal,
the state just before it included), ``<out>/<label>/<protocol>.csv`` (each
run's rows after its first reversal), their sidecars (``reversal_t``,
``reversal_strain``, ``reversals``; the costs when the YAML gives them) and a
``scene.json`` with the cell's geometry, and reads every file back through
``read_series`` and ``split_transients``: what the import writes, the
calibration, the comparison and the claims read.

Conventions of the minimal CSV (the contract's units, dimensionless):

- ``t`` in :math:`d\sqrt{\rho/p}`, ``strain`` accumulated since the start of the
  pre-shear (signed), ``gammadot`` in :math:`\sqrt{p/\rho}/d` (signed, the wall
  speed difference over the gap), ``A_xx``, ``A_xy`` the deviatoric fabric
  (paper Eq. 1), ``sigma_xy`` and ``p`` in the imposed pressure (``p > 0`` in
  compression, ``sigma_xy`` with the sign of the rate in steady shear).
- A pre-shear towards -x (a negative rate) is mirrored (x -> -x,
  ``derived.mirror_reversal``) into the contract's frame, where the pre-shear
  shears towards +x.
- A start from rest (a first row at t = 0 with ``gammadot`` = 0) is kept: the
  reader accepts the step of the wall speed from 0.
- What the contract implies is checked on the input, each refusal naming the
  input file: a given ``mu`` is |sigma_xy|/p and the stresses are of order p
  (``series.check_stresses``); in the pre-shear's steady window sigma_xy has
  the rate's sign and A_xy the opposite one (``steady_signs``). Nothing is
  written under ``out`` unless every case is (``folders.staged``).
- Missing optional columns are derived where the contract defines them
  (``mu = |sigma_xy|/p``; ``inertial_number = |gammadot|/sqrt(p)``, the
  contract's definition in these units; ``U_top = -U_bottom = gammadot gap/2``
  when ``gap`` is given) and are NaN otherwise (the bulk band's columns, which
  no analysis stage needs).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from .derived import mirror_reversal, reversal_kinds, split_transients
from .folders import staged
from .labels import case_label
from .series import CONTRACT_COLUMNS, DEMInputError, check_stresses, read_series
from .steady_signs import check_steady_signs

#: Columns every minimal CSV must carry (calibration, comparison and claims read them).
MINIMAL_COLUMNS = ("t", "strain", "gammadot", "A_xx", "A_xy", "sigma_xy", "p")
#: Columns a minimal CSV may carry; the rest of ``CONTRACT_COLUMNS`` is derived or NaN.
OPTIONAL_COLUMNS = tuple(c for c in CONTRACT_COLUMNS if c not in MINIMAL_COLUMNS)
#: A reversal's transition (docs/data-contract.md: a step, or a half cosine over transition_strain).
TRANSITIONS = ("heaviside", "half_cosine")
#: Sidecar cost keys the YAML may give per stage (dem_contract.costs reads them).
COST_KEYS = ("cpu_time_s", "wall_time_s", "steps")
#: Top-level keys of the metadata YAML: required, then optional.
REQUIRED_KEYS = ("pressure", "inertial_number", "cases")
OPTIONAL_KEYS = ("cell", "N", "simulator", "notes")


def _fail(where, message):
    raise DEMInputError(f"{where}: {message}")


def load_metadata(path) -> dict:
    """The metadata YAML, checked: keys, types and ranges, each error naming the file and the key.

    Returns
    -------
    dict
        The YAML as read, with ``_dir`` (the folder the run files are relative to).
    """
    path = Path(path)
    try:
        meta = yaml.safe_load(path.read_text())
    except OSError as exc:
        _fail(path, f"metadata not readable ({exc.strerror or exc})")
    except yaml.YAMLError as exc:
        _fail(path, f"not valid YAML ({exc})")
    if not isinstance(meta, dict):
        _fail(path, "expected a mapping with keys " + ", ".join(REQUIRED_KEYS))
    unknown = sorted(set(meta) - set(REQUIRED_KEYS) - set(OPTIONAL_KEYS))
    if unknown:
        _fail(path, f"unknown key(s) {unknown}; allowed: {list(REQUIRED_KEYS + OPTIONAL_KEYS)}")
    for key in REQUIRED_KEYS:
        if key not in meta:
            _fail(path, f"missing key '{key}'")
    for key in ("pressure", "inertial_number"):
        if not (isinstance(meta[key], (int, float)) and meta[key] > 0):
            _fail(path, f"'{key}' = {meta[key]!r}: expected a positive number (pressure in Pa)")
    cell = meta.get("cell") or {}
    for key, value in cell.items():
        if key not in ("H_over_d", "W_over_H") or not (isinstance(value, (int, float)) and value > 0):
            _fail(path, f"cell.{key} = {value!r}: expected H_over_d and W_over_H, positive numbers")
    if not isinstance(meta["cases"], list) or not meta["cases"]:
        _fail(path, "'cases' must be a non-empty list (one entry per seed)")
    seeds = set()
    for i, case in enumerate(meta["cases"]):
        where = f"{path}: cases[{i}]"
        if not isinstance(case, dict) or not isinstance(case.get("seed"), int) or case["seed"] < 0:
            _fail(where, "expected a mapping with an integer 'seed' >= 0 and 'runs'")
        if case["seed"] in seeds:
            _fail(where, f"seed {case['seed']} appears twice")
        seeds.add(case["seed"])
        runs = case.get("runs")
        if not isinstance(runs, list) or not runs:
            _fail(where, "'runs' must be a non-empty list of {file, protocol, reversals}")
        protocols = set()
        for j, run in enumerate(runs):
            _check_run(f"{where}.runs[{j}]", run)
            if run["protocol"] in protocols:
                _fail(f"{where}.runs[{j}]", f"protocol {run['protocol']!r} appears twice in the case")
            protocols.add(run["protocol"])
        for stage, costs in (case.get("costs") or {}).items():
            if not isinstance(costs, dict) or set(costs) - set(COST_KEYS):
                _fail(f"{where}.costs.{stage}", f"expected a mapping of {list(COST_KEYS)}")
    return {**meta, "_dir": path.parent}


def _check_run(where, run):
    if not isinstance(run, dict) or not {"file", "protocol", "reversals"} <= set(run):
        _fail(where, "expected a mapping with 'file', 'protocol' and 'reversals'")
    name = run["protocol"]
    if not (isinstance(name, str) and name.replace("_", "").isalnum() and name.islower() and name[0].isalpha()
            and name not in ("preshear", "pack")):
        _fail(where, f"protocol {name!r}: expected heaviside, sinusoidal or a schedule's name "
                     "(lower-case letters, digits, '_')")
    revs = run["reversals"]
    if not isinstance(revs, list) or not revs:
        _fail(where, "'reversals' must be a non-empty list of {strain[, transition, transition_strain]}")
    if name in ("heaviside", "sinusoidal") and len(revs) != 1:
        _fail(where, f"a {name} run reverses once; got {len(revs)} reversals (name the protocol after the schedule)")
    for k, rev in enumerate(revs):
        if not isinstance(rev, dict) or not isinstance(rev.get("strain"), (int, float)):
            _fail(f"{where}.reversals[{k}]", "expected a mapping with the strain of the reversal ('strain')")
        if "t" in rev and not isinstance(rev["t"], (int, float)):
            _fail(f"{where}.reversals[{k}]", f"t = {rev['t']!r}: expected the time of the reversal's row, a number")
        transition = rev.get("transition", "half_cosine" if name == "sinusoidal" else "heaviside")
        if transition not in TRANSITIONS:
            _fail(f"{where}.reversals[{k}]", f"transition {transition!r}: expected one of {list(TRANSITIONS)}")
        ts = rev.get("transition_strain")
        if transition == "half_cosine" and not (isinstance(ts, (int, float)) and ts > 0):
            _fail(f"{where}.reversals[{k}]", f"a half cosine needs a positive transition_strain (got {ts!r})")


def read_minimal(path, cell=None) -> pd.DataFrame:
    """One minimal CSV as a contract table: required columns checked, optional ones derived or NaN.

    Raises
    ------
    DEMInputError
        Naming the file: missing file or required column, a non-finite value in a
        required column (with its row), a given ``mu`` that is not |sigma_xy|/p or a
        bulk stress not of order p (``check_stresses``), and everything ``read_series`` refuses.
    """
    path = Path(path)
    data = read_series(path, columns=MINIMAL_COLUMNS, min_samples=10, what="a run of the metadata's cases")
    raw = pd.read_csv(path)
    raw.columns = [str(c).strip() for c in raw.columns]
    out = data.copy()
    for c in OPTIONAL_COLUMNS:
        out[c] = pd.to_numeric(raw[c], errors="coerce").to_numpy(float) if c in raw else np.nan
    if "mu" not in raw:
        out["mu"] = np.abs(out["sigma_xy"]) / out["p"]
    if "inertial_number" not in raw:
        out["inertial_number"] = np.abs(out["gammadot"]) / np.sqrt(out["p"])
    if "gap" not in raw and cell and "H_over_d" in cell:
        out["gap"] = float(cell["H_over_d"])
    if "U_top" not in raw and "U_bottom" not in raw:
        out["U_top"] = 0.5 * out["gammadot"] * out["gap"]
        out["U_bottom"] = -out["U_top"]
    check_stresses(path, out)
    return out[list(CONTRACT_COLUMNS)]


def reversal_rows(data: pd.DataFrame, reversals, where) -> list:
    r"""The row at which each reversal starts: the first row of its leg where the strain reaches its strain.

    Leg :math:`k` (before reversal :math:`k`) shears in direction :math:`d_k`
    (+1 for the pre-shear, alternating after); reversal :math:`k` starts at the
    first row :math:`i` after reversal :math:`k-1` with
    :math:`d_k(\gamma_i - \gamma_k) \ge -\tfrac12 \Delta\gamma`, where
    :math:`\Delta\gamma` is the median strain step of the run. The row must lie
    within one strain step of the stated strain.
    """
    s, t = data["strain"].to_numpy(float), data["t"].to_numpy(float)
    step = float(np.median(np.abs(np.diff(s))))
    rows, lo, direction = [], 0, 1.0
    for k, rev in enumerate(reversals):
        target = float(rev["strain"])
        if "t" in rev:      # the reversal's row named by its time (a data release: exact, docs/data-release.md)
            i = int(np.argmin(np.abs(t - float(rev["t"]))))
            if i < lo or abs(t[i] - float(rev["t"])) > 1e-9 * max(1.0, abs(t[i])) or i + 1 >= len(t):
                _fail(where, f"reversal {k + 1} at t {float(rev['t']):.17g}: no data row at that time after data "
                             f"row {lo + 1} with a row after it")
            rows.append(i)
            lo, direction = i + 1, -direction
            continue
        hit = np.nonzero(direction * (s[lo:] - target) >= -0.5 * step)[0]
        if hit.size == 0:
            _fail(where, f"reversal {k + 1} at strain {target:g}: the run's strain never reaches it after "
                         f"data row {lo + 1} (strain {s[lo]:.6g} to {s[-1]:.6g})")
        i = lo + int(hit[0])
        if abs(s[i] - target) > 1.5 * step + 1e-12:
            _fail(where, f"reversal {k + 1} at strain {target:g}: the nearest row (data row {i + 1}) is at strain "
                         f"{s[i]:.6g}, more than a strain step ({step:.3g}) away")
        if i + 1 >= len(s):
            _fail(where, f"reversal {k + 1} at strain {target:g}: no data row after it")
        rows.append(i)
        lo, direction = i + 1, -direction
    return rows


def import_cases(meta_path, out) -> list:
    """Write every case of the metadata YAML into ``out`` in the contract's layout, and read it back.

    Parameters
    ----------
    meta_path : str or Path
        The metadata YAML (docs/own-dem-data.md); run files are relative to its folder.
    out : str or Path
        The DEM folder to write, e.g. ``results/dem`` (one ``<label>/`` per case).

    Returns
    -------
    list of Path
        The case folders written (each replaces a folder of the same label in ``out``).

    Raises
    ------
    DEMInputError
        Bad metadata (naming the key), a bad run file (naming the file, and the
        column, run and rows it breaks), or written files the contract's reader
        refuses. Nothing is written under ``out`` then: the cases are written
        beside it (``folders.staged``) and moved in once every one is read back.
    """
    meta = load_metadata(meta_path)
    out = Path(out)
    labels = []
    with staged(out) as tmp:
        for case in meta["cases"]:
            label = case_label(meta["pressure"], meta["inertial_number"], case["seed"])
            case_dir = tmp / label
            case_dir.mkdir()
            _write_case(meta, case, case_dir)
            _validate(case_dir, [r["protocol"] for r in case["runs"]])
            labels.append(label)
    return [out / label for label in labels]


def _write_case(meta, case, case_dir):
    cell = meta.get("cell") or {}
    common = {"seed": case["seed"], "imported": True, "source": meta.get("simulator", "unknown"),
              "inertial_number": meta["inertial_number"], "pressure_Pa": meta["pressure"]}
    if "N" in case or "N" in meta:
        common["N"] = int(case.get("N", meta.get("N")))
    costs = case.get("costs") or {}
    pre_end = None
    for j, run in enumerate(case["runs"]):
        src = meta["_dir"] / run["file"]
        data = read_minimal(src, cell)
        rate = float(np.median(data["gammadot"].to_numpy()[: max(10, len(data) // 10)]))
        mirrored = rate < 0
        if mirrored:    # the contract's pre-shear shears towards +x
            data = mirror_reversal(data)
        revs = run["reversals"]
        targets = [{**r, "strain": -float(r["strain"]) if mirrored else float(r["strain"])} for r in revs]
        rows = reversal_rows(data, targets, src)
        check_steady_signs(data.iloc[: rows[0] + 1], f"{src}: run {run['protocol']} of seed {case['seed']}")
        start = rows[0]     # the run's file holds its rows after this one
        if j == 0:
            pre = data.iloc[: rows[0] + 1]
            pre_end = (float(pre["t"].iloc[-1]), float(pre["strain"].iloc[-1]))
            pre.to_csv(case_dir / "preshear.csv", index=False)
            _sidecar(case_dir / "preshear.json", {**common, "stage": "preshear", "source_file": str(run["file"]),
                                                  "mirrored": mirrored, **costs.get("preshear", {})})
        else:           # one pre-shear per case: a later run starts where the first run's pre-shear ends
            held = np.flatnonzero((data["t"].to_numpy(float) == pre_end[0])
                                  & (data["strain"].to_numpy(float) == pre_end[1]))
            if held.size:   # the run holds the pre-shear's last row (a data release): it starts there, unshifted,
                start = int(held[-1])   # and may first go on shearing the pre-shear's way before it reverses
            else:
                t0, s0 = float(data["t"].iloc[start]), float(data["strain"].iloc[start])
                data = data.assign(t=data["t"] - t0 + pre_end[0], strain=data["strain"] - s0 + pre_end[1])
        t, s = data["t"].to_numpy(float), data["strain"].to_numpy(float)
        reversals = []
        for k, (i, r) in enumerate(zip(rows, revs)):
            transition = r.get("transition", "half_cosine" if run["protocol"] == "sinusoidal" else "heaviside")
            entry = {"t": float(t[i]), "strain": float(s[i]), "direction": -1 if k % 2 == 0 else 1,
                     "transition": transition}
            if transition == "half_cosine":
                entry["transition_strain"] = float(r["transition_strain"])
            reversals.append(entry)
        data.iloc[start + 1:].to_csv(case_dir / f"{run['protocol']}.csv", index=False)
        side = {**common, "stage": run["protocol"], "source_file": str(run["file"]), "mirrored": mirrored,
                "reversal_t": reversals[0]["t"], "reversal_strain": reversals[0]["strain"], "reversals": reversals,
                **costs.get(run["protocol"], {})}
        _sidecar(case_dir / f"{run['protocol']}.json", side)
    if "pack" in costs:
        _sidecar(case_dir / "pack.json", {**common, "stage": "pack", **costs["pack"]})
    scene = {"imported": True, "simulator": meta.get("simulator", "unknown"), "seed": case["seed"],
             "loading": {"pressure": meta["pressure"], "inertial_number": meta["inertial_number"]}}
    if cell:
        scene["geometry"] = {k: float(v) for k, v in cell.items()}
    _sidecar(case_dir / "scene.json", scene)


def _sidecar(path, content):
    path.write_text(json.dumps(content, indent=1, default=float))


def _validate(case_dir, protocols):
    """Read the case back as the analysis stages do: the checked reader, the transients and their kinds."""
    pre = read_series(case_dir / "preshear.csv", finite=("t", *MINIMAL_COLUMNS[1:], "mu"), min_samples=10,
                      what="the imported pre-shear")
    for protocol in protocols:
        path = case_dir / f"{protocol}.csv"
        run = read_series(path, finite=("t", *MINIMAL_COLUMNS[1:], "mu"), min_samples=10, what="the imported run")
        side = json.loads(path.with_suffix(".json").read_text())
        split_transients(pre, run, side, what=str(path))
        reversal_kinds(side, protocol, what=str(path))


def summary(case_dirs) -> str:
    """One line per case: its folder and its runs."""
    lines = []
    for d in case_dirs:
        runs = sorted(p.stem for p in Path(d).glob("*.csv") if p.stem != "preshear")
        lines.append(f"{d}: preshear + {', '.join(runs)}")
    return "\n".join(lines)


__all__ = ["MINIMAL_COLUMNS", "OPTIONAL_COLUMNS", "load_metadata", "read_minimal", "reversal_rows",
           "import_cases", "summary"]
