"""Read and check one DEM time series (and its sidecar) of the DEM contract (docs/data-contract.md)."""
from __future__ import annotations

import json
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
        In the order checked: the file is missing or not a readable CSV; a
        column is missing; a NaN, infinite or non-numeric value in a
        ``finite`` column (named with its first data row); fewer than
        ``min_samples`` rows; ``t`` not strictly increasing.
    """
    columns = list(columns)
    finite = columns if finite is None else list(finite)
    if "t" not in finite or not set(finite) <= set(columns):
        raise ValueError("read_series: 'finite' must include 't' and be a subset of 'columns'")
    path = Path(path)
    if not path.is_file():
        raise DEMInputError(f"{path}: file not found" + (f" (expected {what})" if what else ""))
    try:
        raw = pd.read_csv(path)
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
    return data


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

