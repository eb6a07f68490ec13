r"""Import DEM data the project did not make: minimal CSVs plus a YAML of case metadata -> the contract's layout.

A user with shear-reversal runs from another simulator (or another cell)
brings them in the minimal columns ``MINIMAL_COLUMNS`` (optional ones
``OPTIONAL_COLUMNS``) in one of two forms, per case, and one YAML file naming
the cases, their runs and the strains at which each run reverses
(docs/own-dem-data.md):

- *one file per run* (``whole_history``): each CSV holds the run's whole
  history, from the start of the pre-shear through its reversals;
- *branched* (``branched_history``, a case with a ``preshear:`` file): the
  pre-shear in its own CSV, and each run a branch from its saved state, its
  CSV starting at the first reversal, its first row the state there (the
  pre-shear's last row, ``on_pre_shear_clock``), its ``t`` and ``strain``
  going on from the pre-shear's or restarting at 0 at the branch.

This module writes them as the DEM stage would (docs/data-contract.md), the
same files from either form for the same history:
``<out>/<label>/preshear.csv`` (the pre-shear's rows up to the first reversal,
the state just before it included), ``<out>/<label>/<protocol>.csv`` (each
run's rows after its first reversal), their sidecars (``reversal_t``,
``reversal_strain``, ``reversals``; the costs when the YAML gives them) and a
``scene.json`` with the cell's geometry, and reads every file back through
``read_series`` and ``split_transients``: what the import writes, the
calibration, the comparison and the claims read.

Conventions of the minimal CSV (the contract's units, dimensionless):

- ``t`` in :math:`d\sqrt{\rho/p}`, ``strain`` accumulated since the start of the
  pre-shear (signed; a branch's may restart at 0 at the branch), ``gammadot``
  in :math:`\sqrt{p/\rho}/d` (signed, the wall speed difference over the
  gap), ``A_xx``, ``A_xy`` the deviatoric fabric
  (paper Eq. 1), ``sigma_xy`` and ``p`` in the imposed pressure (``p > 0`` in
  compression, ``sigma_xy`` with the sign of the rate in steady shear).
- A pre-shear towards -x (a negative rate) is mirrored (x -> -x,
  ``derived.mirror_reversal``) into the contract's frame, where the pre-shear
  shears towards +x (a branched case's branches with it).
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

from .derived import MIRRORED_COLUMNS, mirror_reversal, reversal_kinds, split_transients
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
        if "preshear" in case and not (isinstance(case["preshear"], str) and case["preshear"].strip()):
            _fail(where, f"preshear = {case['preshear']!r}: expected the pre-shear's file, relative to the YAML "
                         "(its runs then start at their reversal)")
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


def reversal_rows(data: pd.DataFrame, reversals, where, step=None) -> list:
    r"""The row at which each reversal starts: the first row of its leg where the strain reaches its strain.

    Leg :math:`k` (before reversal :math:`k`) shears in direction :math:`d_k`
    (+1 for the pre-shear, alternating after); reversal :math:`k` starts at the
    first row :math:`i` after reversal :math:`k-1` with
    :math:`d_k(\gamma_i - \gamma_k) \ge -\tfrac12 \Delta\gamma`, where
    :math:`\Delta\gamma` is the median strain step of the run. The row must lie
    within one strain step of the stated strain. A reversal that gives ``t``
    starts at the row at that time, exactly.

    Parameters
    ----------
    data : pandas.DataFrame
        The run (``t``, ``strain``), in the contract's frame.
    reversals : list of dict
        ``strain`` (and ``t``) of each reversal, in that frame.
    where : str or Path
        The run's file, for the message (rows are named as in ``data``).
    step : float, optional
        :math:`\Delta\gamma`; by default the median strain step of ``data`` (a
        branch passes that of the whole history: the same rows as its one file).
    """
    s, t = data["strain"].to_numpy(float), data["t"].to_numpy(float)
    step = float(np.median(np.abs(np.diff(s)))) if step is None else float(step)
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
    pre, pre_source, runs = (branched_history if "preshear" in case else whole_history)(meta, case, cell)
    pre.to_csv(case_dir / "preshear.csv", index=False)
    _sidecar(case_dir / "preshear.json", {**common, "stage": "preshear", **pre_source, **costs.get("preshear", {})})
    for run in runs:
        protocol, data = run["run"]["protocol"], run["data"]
        t, s = data["t"].to_numpy(float), data["strain"].to_numpy(float)
        reversals = []
        for k, (i, r) in enumerate(zip(run["rows"], run["run"]["reversals"])):
            transition = r.get("transition", "half_cosine" if protocol == "sinusoidal" else "heaviside")
            entry = {"t": float(t[i]), "strain": float(s[i]), "direction": -1 if k % 2 == 0 else 1,
                     "transition": transition}
            if transition == "half_cosine":
                entry["transition_strain"] = float(r["transition_strain"])
            reversals.append(entry)
        data.iloc[run["start"] + 1:].to_csv(case_dir / f"{protocol}.csv", index=False)
        side = {**common, "stage": protocol, "source_file": str(run["run"]["file"]), "mirrored": run["mirrored"],
                "reversal_t": reversals[0]["t"], "reversal_strain": reversals[0]["strain"], "reversals": reversals,
                **costs.get(protocol, {})}
        _sidecar(case_dir / f"{protocol}.json", side)
    if "pack" in costs:
        _sidecar(case_dir / "pack.json", {**common, "stage": "pack", **costs["pack"]})
    scene = {"imported": True, "simulator": meta.get("simulator", "unknown"), "seed": case["seed"],
             "loading": {"pressure": meta["pressure"], "inertial_number": meta["inertial_number"]}}
    if cell:
        scene["geometry"] = {k: float(v) for k, v in cell.items()}
    _sidecar(case_dir / "scene.json", scene)


def read_in_frame(meta, file, cell, mirror=None):
    """A run file as a contract table in the contract's frame (its pre-shear towards +x).

    Parameters
    ----------
    meta : dict
        ``load_metadata``'s answer (``_dir``: the folder run files are relative to).
    file : str
        The file as the YAML names it.
    cell : dict
        The YAML's ``cell`` (``read_minimal``).
    mirror : bool, optional
        Whether to mirror (x -> -x); by default when the rate of the file's first
        rows (``max(10, n/10)``) is negative, a pre-shear towards -x.

    Returns
    -------
    tuple
        The table, whether it was mirrored, and the file's path.
    """
    src = meta["_dir"] / file
    data = read_minimal(src, cell)
    if mirror is None:
        mirror = float(np.median(data["gammadot"].to_numpy()[: max(10, len(data) // 10)])) < 0
    return (mirror_reversal(data) if mirror else data), bool(mirror), src


def in_frame(reversals, mirrored, t_shift=0.0, strain_shift=0.0) -> list:
    """The YAML's reversals of a run in the frame of its table: mirrored with it, then shifted in strain (and t)."""
    sign = -1.0 if mirrored else 1.0
    return [{**r, "strain": sign * float(r["strain"]) + strain_shift}
            | ({"t": float(r["t"]) + t_shift} if "t" in r else {}) for r in reversals]


def whole_history(meta, case, cell):
    """The runs of a case whose files each hold the whole history, from the start of the pre-shear on.

    Returns
    -------
    tuple
        The pre-shear (the first run's rows up to its first reversal, that row
        included), its sidecar's ``source_file`` and ``mirrored``, and per run a
        dict: ``run`` (its YAML entry), ``data`` (its table in the contract's frame,
        on the pre-shear's clock and strain), ``rows`` (the row of each reversal),
        ``start`` (the run's file holds the rows after this one) and ``mirrored``.
    """
    pre, pre_source, out = None, None, []
    for run in case["runs"]:
        data, mirrored, src = read_in_frame(meta, run["file"], cell)
        rows = reversal_rows(data, in_frame(run["reversals"], mirrored), src)
        check_steady_signs(data.iloc[: rows[0] + 1], f"{src}: run {run['protocol']} of seed {case['seed']}")
        start = rows[0]
        if pre is None:
            pre, pre_source = data.iloc[: start + 1], {"source_file": str(run["file"]), "mirrored": mirrored}
        else:   # one pre-shear per case: a later run starts where the first run's pre-shear ends
            data, start = after_pre_shear(data, start, pre)
        out.append({"run": run, "data": data, "rows": rows, "start": start, "mirrored": mirrored})
    return pre, pre_source, out


def after_pre_shear(data, start, pre):
    """A later run of a whole-history case on the first run's pre-shear: its table and the row it starts after.

    A run holding the pre-shear's last row (same ``t`` and ``strain``, as a data
    release writes it) starts there, unshifted, and may first go on shearing the
    pre-shear's way before it reverses; any other is shifted in ``t`` and
    ``strain`` so that its first reversal's row lies at the pre-shear's end.
    """
    t_end, s_end = float(pre["t"].iloc[-1]), float(pre["strain"].iloc[-1])
    held = np.flatnonzero((data["t"].to_numpy(float) == t_end) & (data["strain"].to_numpy(float) == s_end))
    if held.size:
        return data, int(held[-1])
    t0, s0 = float(data["t"].iloc[start]), float(data["strain"].iloc[start])
    return data.assign(t=data["t"] - t0 + t_end, strain=data["strain"] - s0 + s_end), start


def branched_history(meta, case, cell):
    """The runs of a branched case: the pre-shear in its own file, each run a branch starting at its reversal.

    The pre-shear file's rate decides the mirror for every branch. Each branch's
    first row is the state at the reversal (``on_pre_shear_clock``), the state
    the pre-shear's last row holds; its first reversal is that row, and its
    later ones are found on the branch's rows (``reversal_rows``, rows named as
    in the branch's file).

    Returns
    -------
    tuple
        As ``whole_history``: the pre-shear, its sidecar's ``source_file`` and
        ``mirrored``, and per run its dict (``data``: the pre-shear's rows
        followed by the branch's after its first row).
    """
    pre, mirrored, pre_src = read_in_frame(meta, case["preshear"], cell)
    check_steady_signs(pre, f"{pre_src}: the pre-shear of seed {case['seed']}")
    out = []
    for run in case["runs"]:
        where = f"run {run['protocol']} of seed {case['seed']}"
        branch, _, src = read_in_frame(meta, run["file"], cell, mirror=mirrored)
        targets = in_frame(run["reversals"], mirrored)
        check_first_reversal(branch, targets[0], f"{src}: {where}", mirrored)
        branch, t_shift, s_shift = on_pre_shear_clock(pre, branch, f"{src}: {where}", pre_src, mirrored)
        targets = [{**targets[0], "t": float(branch["t"].iloc[0])},
                   *in_frame(run["reversals"][1:], mirrored, t_shift, s_shift)]
        data = pd.concat([pre, branch.iloc[1:]], ignore_index=True)
        rows = reversal_rows(branch, targets, src, step=float(np.median(np.abs(np.diff(data["strain"].to_numpy())))))
        out.append({"run": run, "data": data, "rows": [len(pre) - 1 + i for i in rows], "start": len(pre) - 1,
                    "mirrored": mirrored})
    return pre, {"source_file": str(case["preshear"]), "mirrored": mirrored}, out


def check_first_reversal(branch, target, where, mirrored):
    """A branch's first reversal is at its first row: the stated strain lies within one strain step of it."""
    s = branch["strain"].to_numpy(float)
    step = float(np.median(np.abs(np.diff(s))))
    if abs(s[0] - target["strain"]) > 1.5 * step + 1e-12:
        sign = -1.0 if mirrored else 1.0
        _fail(where, f"reversal 1 at strain {sign * target['strain']:g}: a branch starts at its first reversal, "
                     f"but its first data row is at strain {sign * s[0]:.6g}, more than a strain step "
                     f"({step:.3g}) away (give the strain of the branch's first row)")


#: Columns of a branch's first row that must hold the pre-shear's last row's state (``on_pre_shear_clock``).
BRANCH_STATE_COLUMNS = ("A_xx", "A_xy", "sigma_xy", "p")
#: How far they may differ, in their units (p for the stresses): a tenth of one sample's scatter in the
#: fabric (docs/data-contract.md), room for a simulator writing four decimals; one state is one value.
BRANCH_STATE_TOL = 1e-3
#: How far a branch's first ``t`` (``strain``) may lie from the pre-shear's last one, or from 0 for a
#: restarted clock, as a fraction of the branch's median time (strain) step: a row one sample away is a step.
BRANCH_CLOCK_TOL = 1e-2


def on_pre_shear_clock(pre, branch, where, pre_src, mirrored=False):
    """A branch in the pre-shear's ``t`` and ``strain``, checked to start in the pre-shear's last state.

    Each of ``t`` and ``strain`` either goes on from the pre-shear (the branch's
    first row holds the pre-shear's last value: kept as it is) or restarts at 0
    at the branch (shifted by the pre-shear's last value), within
    ``BRANCH_CLOCK_TOL`` of the branch's median step; the columns
    ``BRANCH_STATE_COLUMNS`` of the first row equal the pre-shear's last row's
    within ``BRANCH_STATE_TOL`` (the state the branch starts from).

    Parameters
    ----------
    pre, branch : pandas.DataFrame
        The pre-shear and the branch, in the contract's frame (``read_in_frame``).
    where, pre_src : str or Path
        The branch's file and run, and the pre-shear's file, for the message.
    mirrored : bool
        Whether both were mirrored: the message gives the values as in the files.

    Returns
    -------
    tuple
        The branch on the pre-shear's clock and strain, and the shifts added to
        its ``t`` and its ``strain``.

    Raises
    ------
    DEMInputError
        Naming the branch's file and run, the column, its first row's value and
        the values allowed (the pre-shear's last, from ``pre_src``, or 0).
    """
    end, first = pre.iloc[-1], branch.iloc[0]
    as_in_file = {c: -1.0 if mirrored and c in MIRRORED_COLUMNS else 1.0
                  for c in ("t", "strain", *BRANCH_STATE_COLUMNS)}
    shifts = []
    for col in ("t", "strain"):
        tol = BRANCH_CLOCK_TOL * float(np.median(np.abs(np.diff(branch[col].to_numpy(float)))))
        if abs(first[col] - end[col]) <= tol:
            shifts.append(0.0)
        elif abs(first[col]) <= tol:
            shifts.append(float(end[col]))
        else:
            _fail(where, f"column '{col}' = {as_in_file[col] * first[col]:.9g} in the first data row: a branch's "
                         f"first row is the state at the reversal, its {col} the pre-shear's last "
                         f"({as_in_file[col] * end[col]:.9g}, {pre_src}) or 0 "
                         f"(restarted at the branch), within {tol:.3g}")
    for col in BRANCH_STATE_COLUMNS:
        if not abs(first[col] - end[col]) <= BRANCH_STATE_TOL:
            _fail(where, f"column '{col}' = {as_in_file[col] * first[col]:.6g} in the first data row, the "
                         f"pre-shear's last row ({pre_src}) {as_in_file[col] * end[col]:.6g}: a branch's first row "
                         f"is the state at the reversal, the pre-shear's last, within {BRANCH_STATE_TOL:g} (is it "
                         "the branch of this pre-shear?)")
    t_shift, s_shift = shifts
    if t_shift or s_shift:
        branch = branch.assign(t=branch["t"] + t_shift, strain=branch["strain"] + s_shift)
    return branch, t_shift, s_shift


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


__all__ = ["MINIMAL_COLUMNS", "OPTIONAL_COLUMNS", "BRANCH_STATE_COLUMNS", "BRANCH_STATE_TOL", "BRANCH_CLOCK_TOL",
           "load_metadata", "read_minimal", "reversal_rows", "on_pre_shear_clock", "import_cases", "summary"]
