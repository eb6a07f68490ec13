"""Read and check one DEM time series (and its sidecar) of the DEM contract (docs/data-contract.md)."""
from __future__ import annotations

import csv
import gzip
import io
import json
import lzma
from pathlib import Path

import numpy as np
import pandas as pd

#: The columns every run must carry (docs/data-contract.md), in order.
CONTRACT_COLUMNS = (
    "t", "strain", "gammadot", "U_top", "U_bottom", "gap", "A_xx", "A_xy", "n_contacts",
    "sigma_xy", "p", "mu", "sigma_xy_bulk", "p_bulk", "phi", "Z", "inertial_number",
)
#: The stages that reverse the pre-shear (docs/scene.md).
REVERSAL_PROTOCOLS = ("heaviside", "sinusoidal")


class DEMInputError(ValueError):
    """A DEM file is missing, malformed, breaks the contract or cannot be used; the message names the file and the problem."""


#: Physical bounds every finite value of a column must respect, as (low, high, low_open):
#: A = -I/2 + <n (x) n> has eigenvalues in [-1/2, 1/2], so |A_xx|, |A_xy| <= 1/2; the wall
#: pressure p is positive (compression); mu = |sigma_xy|/p is not negative and, for a
#: granular layer, far below MU_MAX (DEM runs stay below 1 even in a reversal's transient).
MU_MAX = 2.0
BOUNDS = {"A_xx": (-0.5, 0.5, False), "A_xy": (-0.5, 0.5, False), "p": (0.0, np.inf, True),
          "mu": (0.0, MU_MAX, False)}

#: Strain and time must agree with the rate: between two rows, the strain increment and the
#: trapezoid integral of gammadot over the time step may differ by at most STRAIN_REL_TOL of
#: the larger of the two plus the strain the run's median |gammadot| advances in that time
#: step (the second term covers rows near a zero crossing of the rate, where both are
#: tiny). Measured on real YADE series (tiny cell of tests/test_dem_stages.py: pre-shear,
#: Heaviside and sinusoidal runs) the deviation is at most 4.4e-4 of this allowance (0.019
#: of the increment itself, at the sinusoid's zero crossing); on model-made series with the
#: contract's noise (dem_contract.synthetic) 4e-4. A strain jump, or a time jump without
#: strain, exceeds it by orders of magnitude.
STRAIN_REL_TOL = 0.1


def read_series(path, columns=CONTRACT_COLUMNS, min_samples: int = 2, what: str | None = None,
                finite=None) -> pd.DataFrame:
    """Read one contract CSV and check it.

    Parameters
    ----------
    path : str or Path
    columns : sequence of str
        The columns read: each must be present (column names are stripped of
        white space); the result holds them in this order, and nothing else.
    min_samples : int
        Fewest rows accepted.
    what : str, optional
        What the file should be (e.g. ``"the heaviside run of the case"``),
        added to the message when it is missing.
    finite : sequence of str, optional
        The columns that must be numeric and finite in every row (returned as
        float); default all of ``columns``. It must include ``t``.

    Returns
    -------
    pandas.DataFrame

    Raises
    ------
    DEMInputError
        In the order checked: the file is missing; a ragged row (a line with
        fewer or more fields than the header, or a last line without its
        newline: a row cut off while being written); not a readable CSV; a
        column is missing; a NaN, infinite or non-numeric value in a
        ``finite`` column (named with its first data row); fewer than
        ``min_samples`` rows; ``t`` not strictly increasing; a value outside
        its physical range (``BOUNDS``: |A_xx|, |A_xy| <= 1/2, p > 0,
        0 <= mu <= ``MU_MAX``); a stress not of order p or mu not
        |sigma_xy|/p (``check_stresses``); strain and t inconsistent with the integral of
        gammadot (a jump; when ``strain`` and ``gammadot`` are read); a gap
        in the sampling grid (``_check_sampling_grid``: rows missing). Every
        message names the file and the data row (counted from 1 after the header).
    """
    columns = list(columns)
    finite = columns if finite is None else list(finite)
    if "t" not in finite or not set(finite) <= set(columns):
        raise ValueError("read_series: 'finite' must include 't' and be a subset of 'columns'")
    path = Path(path)
    if not path.is_file():
        raise DEMInputError(f"{path}: file not found" + (f" (expected {what})" if what else ""))
    text = _read_complete_text(path)
    try:
        raw = pd.read_csv(io.StringIO(text))
    except Exception as exc:  # pandas raises several types for unreadable files
        raise DEMInputError(f"{path}: not a readable CSV ({exc})") from None
    raw.columns = [str(c).strip() for c in raw.columns]
    missing = [c for c in columns if c not in raw.columns]
    if missing:
        raise DEMInputError(f"{path}: missing column(s) {missing}; the DEM contract requires {list(CONTRACT_COLUMNS)}")
    data = raw[columns].copy()
    for c in finite:
        col = pd.to_numeric(data[c], errors="coerce")
        bad = ~np.isfinite(col.to_numpy(dtype=float))
        if bad.any():
            raise DEMInputError(f"{path}: column '{c}' has {bad.sum()} NaN/infinite/non-numeric value(s), "
                                f"first at data row {np.nonzero(bad)[0][0] + 1}")
        data[c] = col.astype(float)
    if len(data) < min_samples:
        raise DEMInputError(f"{path}: only {len(data)} samples, at least {min_samples} are needed")
    dt = np.diff(data["t"].to_numpy())
    if np.any(dt <= 0):
        raise DEMInputError(f"{path}: column 't' does not increase strictly (data row {int(np.argmax(dt <= 0)) + 2})")
    _check_bounds(path, data)
    check_stresses(path, data)
    if {"strain", "gammadot"} <= set(columns):
        _check_strain_integral(path, data)
    _check_sampling_grid(path, data)
    return data


def _read_complete_text(path: Path) -> str:
    """A series file's text, gzip- (``.gz``) or xz-compressed (``.xz``) or not, after ``check_complete_rows``
    (an empty file is left to pandas to report); ``read_series`` parses this text, so the file is read and
    decompressed once."""
    opener = {".gz": gzip.open, ".xz": lzma.open}.get(path.suffix)
    try:
        text = opener(path, "rt").read() if opener else path.read_text()
    except (OSError, UnicodeDecodeError, EOFError, lzma.LZMAError) as exc:
        raise DEMInputError(f"{path}: not a readable CSV ({exc})") from None
    if text.strip():
        check_complete_rows(path, text)
    return text


def check_complete_rows(path, text: str | None = None) -> int:
    """Every record of a CSV holds as many fields as its header, and the file ends with a newline.

    Records are parsed by the ``csv`` module (quoted fields may hold commas and
    line breaks), so a line is named as the reader counts it.

    Parameters
    ----------
    path : str or Path
    text : str, optional
        The file's text, if already read.

    Returns
    -------
    int
        The number of data records (after the header).

    Raises
    ------
    DEMInputError
        Naming the file and the line (and data row) with too few or too many
        fields, or the last line when it lacks its newline (a row cut off while
        being written).
    """
    path = Path(path)
    if text is None:
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            raise DEMInputError(f"{path}: not a readable CSV ({exc})") from None
    if not text.strip():
        raise DEMInputError(f"{path}: empty file (no header)")
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next(reader)
        n_rows = 0
        for record in reader:
            if not record:  # a blank line: pandas skips it too
                continue
            n_rows += 1
            if len(record) != len(header):
                raise DEMInputError(f"{path}: line {reader.line_num} (data row {n_rows}) has {len(record)} "
                                    f"field(s), the header {len(header)}: a ragged row (cut off while being "
                                    "written?)")
    except csv.Error as exc:
        raise DEMInputError(f"{path}: line {reader.line_num}: not a readable CSV ({exc})") from None
    if not text.endswith("\n"):
        raise DEMInputError(f"{path}: the last line (line {reader.line_num}, data row {n_rows}) does not end with "
                            "a newline: the row was cut off while being written")
    return n_rows


def _check_bounds(path: Path, data: pd.DataFrame) -> None:
    """Finite values of the ``BOUNDS`` columns lie within their physical range."""
    for col, (low, high, low_open) in BOUNDS.items():
        if col not in data.columns:
            continue
        v = pd.to_numeric(data[col], errors="coerce").to_numpy(dtype=float)
        with np.errstate(invalid="ignore"):
            bad = np.isfinite(v) & ((v <= low if low_open else v < low) | (v > high))
        allowed = f"{'(' if low_open else '['}{low:g}, {high:g}]"
        _refuse_rows(path, col, v, bad, lambda k: f"is outside its physical range {allowed}")


def _refuse_rows(path, col: str, values: np.ndarray, bad: np.ndarray, says, hint: str = "") -> None:
    """Raise ``DEMInputError`` at the first row where ``bad`` holds: the file, the column, its value there,
    the data row (from 1), ``says(row index)``, the number of such rows, then ``hint``."""
    if bad.any():
        k = int(np.argmax(bad))
        raise DEMInputError(f"{path}: column '{col}' = {values[k]:.6g} at data row {k + 1} {says(k)} "
                            f"({int(bad.sum())} row(s) in all){hint}")


#: Stresses are in units of the imposed pressure p: every released run stays within 0.14-2.6 (p, p_bulk)
#: and 0.72 (|sigma_xy|, |sigma_xy_bulk|), reversal transients included. A stress above STRESS_MAX p is
#: taken for a unit slip: a granular layer's pressure in Pa is 1e3 or more (the campaigns' 1e5).
STRESS_MAX = 100.0
STRESS_COLUMNS = ("sigma_xy", "p", "sigma_xy_bulk", "p_bulk")
#: mu = |sigma_xy|/p row by row (the DEM computes it so: equal to the bit in every released run).
#: MU_TOL, a quarter of one sample's scatter in mu (0.04, docs/data-contract.md), leaves room for
#: a simulator's rounding and catches any scale slip (a factor 2 on a steady mu of 0.27 is 0.27).
MU_TOL = 0.01


def check_stresses(path, data: pd.DataFrame) -> None:
    r"""The stresses are of order p, and mu is :math:`|\sigma_{xy}|/p` where both are given.

    Over the finite values of the columns ``data`` holds: :math:`|v| \le` ``STRESS_MAX``
    for each of ``STRESS_COLUMNS``; :math:`|\mu - |\sigma_{xy}|/p| \le` ``MU_TOL`` in every
    row with a non-zero rate (where the walls stand still the direction of shear is
    undefined, and a model-made series gives the friction of its fabric there:
    ``dem_contract.synthetic``).

    Parameters
    ----------
    path : str or Path
        The file the rows come from (named in the message).
    data : pandas.DataFrame

    Raises
    ------
    DEMInputError
        Naming the file, the column, the first offending data row (counted from 1)
        and how many rows offend; for a stress too large, with the hint that it
        looks like SI units.
    """
    for col in (c for c in STRESS_COLUMNS if c in data.columns):
        v = pd.to_numeric(data[col], errors="coerce").to_numpy(dtype=float)
        with np.errstate(invalid="ignore"):
            bad = np.abs(v) > STRESS_MAX
        _refuse_rows(path, col, v, bad, lambda k: "is not of order 1",
                     f": stresses are in units of the imposed pressure p (docs/data-contract.md), at most "
                     f"{STRESS_MAX:g}; a value like this looks like SI (Pa): divide the stresses by the imposed pressure")
    if not {"mu", "sigma_xy", "p"} <= set(data.columns):
        return
    mu, sxy, p = (pd.to_numeric(data[c], errors="coerce").to_numpy(dtype=float) for c in ("mu", "sigma_xy", "p"))
    moving = np.ones(len(mu), dtype=bool) if "gammadot" not in data.columns else \
        pd.to_numeric(data["gammadot"], errors="coerce").to_numpy(dtype=float) != 0.0
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.abs(sxy) / p
        bad = moving & np.isfinite(mu) & np.isfinite(ratio) & (np.abs(mu - ratio) > MU_TOL)
    _refuse_rows(path, "mu", mu, bad, lambda k: f"but |sigma_xy|/p = {ratio[k]:.6g} there",
                 f": mu is |sigma_xy|/p of its row within {MU_TOL:g} (docs/data-contract.md); leave mu out to have "
                 f"it derived")


def _check_strain_integral(path: Path, data: pd.DataFrame) -> None:
    r"""Strain and time agree with the rate between consecutive rows.

    .. math:: |\Delta\gamma_i - T_i| \le r\,\big(\max(|\Delta\gamma_i|, |T_i|)
              + \mathrm{median}|\dot\gamma|\,\Delta t_i\big),\qquad
              T_i = \tfrac12(\dot\gamma_{i-1} + \dot\gamma_i)\,\Delta t_i

    with :math:`r` = ``STRAIN_REL_TOL``, over the rows where t, strain and
    gammadot are all finite. Between two rows of opposite rates (a sharp
    reversal inside a run, whose jump lies somewhere in the step) only
    :math:`|\Delta\gamma_i| \le (1 + r) \max(|\dot\gamma_{i-1}|, |\dot\gamma_i|)\,\Delta t_i`
    is required; the same holds for the step of a start from rest (the rows
    at rest at the start of the run, then the first moving one: ``_steps_from_rest``).

    Raises
    ------
    DEMInputError
        Naming the first row where the strain (or the time) jumps.
    """
    t, s, g = (pd.to_numeric(data[c], errors="coerce").to_numpy(dtype=float) for c in ("t", "strain", "gammadot"))
    rows = np.nonzero(np.isfinite(t) & np.isfinite(s) & np.isfinite(g))[0]
    if len(rows) < 2:
        return
    t, s, g = t[rows], s[rows], g[rows]
    ds, dt = np.diff(s), np.diff(t)
    trap = 0.5 * (g[1:] + g[:-1]) * dt
    tol = STRAIN_REL_TOL * (np.maximum(np.abs(ds), np.abs(trap)) + np.median(np.abs(g)) * dt)
    bad = np.abs(ds - trap) > tol
    # a sharp reversal between two rows (a reversal schedule's heaviside segment), or a start from rest
    # (the wall speed steps from 0 between the row at rest and the next one): the rate jumps somewhere
    # in the step, so only the bound |ds| <= (1 + r) max(|g_i-1|, |g_i|) dt holds there
    sharp = (np.sign(g[1:]) * np.sign(g[:-1]) < 0) | _steps_from_rest(g)
    bad[sharp] = np.abs(ds[sharp]) > (1 + STRAIN_REL_TOL) * np.maximum(np.abs(g[1:]), np.abs(g[:-1]))[sharp] * dt[sharp]
    if bad.any():
        k = int(np.argmax(bad))
        raise DEMInputError(
            f"{path}: strain jumps by {ds[k]:+.6g} between data rows {rows[k] + 1} and {rows[k + 1] + 1} where "
            f"the rate integrates to {trap[k]:+.6g} over the time step: strain, t and gammadot disagree "
            f"(tolerance {tol[k]:.3g})")


#: A gap in the sampling grid (rows missing from a series whose t, strain and gammadot still agree
#: across it). With the sidecar's ``sampling_steps`` and ``dt`` (YADE runs) no time step may exceed
#: the largest sampling interval by more than GRID_REL_TOL (rounding; one missing row doubles it);
#: without them (model-made or imported series) no step may exceed GAP_FACTOR times the larger of
#: its two neighbours (the grid changes from fine to coarse, but never in one step by this much
#: on its own; the presets' coarse/fine ratios are 2.5 to 10, and a coarse stretch has several steps).
GRID_REL_TOL = 0.01
GAP_FACTOR = 3.0


def _sidecar_max_step(path: Path) -> float | None:
    """The largest sampling interval of a YADE series, in its time unit (from the sidecar), or None."""
    side = path.with_suffix(".json")
    try:
        meta = json.loads(side.read_text()) if side.is_file() else {}
        steps = [int(v) for v in (meta.get("sampling_steps") or {}).values() if v]
        return max(steps) * float(meta["dt"]) / float(meta["time_unit_s"]) if steps else None
    except (OSError, ValueError, TypeError, KeyError, AttributeError, ZeroDivisionError):
        return None  # no usable sidecar: read_sidecar names a malformed one


def _check_sampling_grid(path: Path, data: pd.DataFrame) -> None:
    """No row is missing from the series' sampling grid (``GRID_REL_TOL``, ``GAP_FACTOR``).

    Raises
    ------
    DEMInputError
        Naming the two data rows around the gap, its length in t, and the
        interval the grid allows there.
    """
    t = data["t"].to_numpy(dtype=float)
    if len(t) < 3:
        return
    dt = np.diff(t)
    max_step = _sidecar_max_step(path)
    if max_step is not None:
        allowed = np.full_like(dt, (1 + GRID_REL_TOL) * max_step)
        rule = "the largest sampling interval of the sidecar's sampling_steps"
    else:
        neighbours = np.maximum(np.concatenate([[0.0], dt[:-1]]), np.concatenate([dt[1:], [0.0]]))
        allowed = GAP_FACTOR * neighbours
        rule = f"{GAP_FACTOR:g} times the larger neighbouring step"
    bad = dt > allowed
    if bad.any():
        k = int(np.argmax(bad))
        raise DEMInputError(
            f"{path}: a gap in the sampling grid between data rows {k + 1} and {k + 2} (t {t[k]:.6g} to "
            f"{t[k + 1]:.6g}: a step of {dt[k]:.6g}, at most {allowed[k]:.6g} allowed, {rule}): rows are "
            f"missing ({int(bad.sum())} gap(s) in all)")

#: A row is at rest when its |gammadot| is below this fraction of the run's median |gammadot|.
REST_FRACTION = 0.1


def _steps_from_rest(g: np.ndarray) -> np.ndarray:
    r"""Steps of the rate from rest at the start of a run, between consecutive rows.

    True for the step from row :math:`i-1` to row :math:`i` when every row up to
    :math:`i-1` is at rest (:math:`|\dot\gamma| \le` ``REST_FRACTION`` times the
    median :math:`|\dot\gamma|`) and row :math:`i` is not: a start from rest, where
    the wall speed steps from 0 somewhere in the time step, as in every external
    run that starts its pre-shear at t = 0 with the walls still.
    """
    rest = np.abs(g) <= REST_FRACTION * np.median(np.abs(g))
    leading = np.logical_and.accumulate(rest)       # the rows at rest before the first move
    return leading[:-1] & ~rest[1:]


def read_sidecar(path) -> dict:
    """The JSON sidecar ``<stage>.json`` of a CSV ``<stage>.csv`` (``{}`` if there is none).

    Raises
    ------
    DEMInputError
        The sidecar is not valid JSON, or not a JSON object.
    """
    side = Path(path).with_suffix(".json")
    if not side.is_file():
        return {}
    try:
        meta = json.loads(side.read_text())
    except json.JSONDecodeError as exc:
        raise DEMInputError(f"{side}: invalid JSON sidecar ({exc})") from None
    if not isinstance(meta, dict):
        raise DEMInputError(f"{side}: expected a JSON object")
    return meta


def sidecar_engine(sidecar: dict) -> str:
    """The DEM engine that wrote a stage's sidecar: its ``engine`` key, else ``lammps`` when it names
    ``lammps_version``, else ``yade`` (YADE's sidecars from before the key existed)."""
    return sidecar.get("engine") or ("lammps" if "lammps_version" in sidecar else "yade")

