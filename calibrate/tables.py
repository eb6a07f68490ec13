"""Output tables: params.yaml (``model.params`` format), params_table.csv (with a note on
values held by a constraint or outside their interval), backsolve_alpha_vs_X.csv, fit_quality.csv."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from model import params_from_dict, save_params

ROUTE_NAMES = {"backsolve": "route 1: back-solve of Eq. 4, fit to alpha(X) bins",
               "curves": "route 2: integrated model fitted to the DEM curves",
               "mu_vs_X": "friction law fitted to mu(X) samples"}


def _note(value, lo, hi, bounds) -> str:
    """Warnings a reader of the table needs: a value on its constraint, or outside its own interval."""
    notes = []
    for side, b in zip(("lower", "upper"), bounds):
        if np.isfinite(b) and abs(value - b) <= 1e-6 * max(abs(b), 1.0):
            notes.append(f"at its {side} bound {b:.6g} (the constraint, not the data, sets it)")
    tol = 1e-6 * max(abs(lo), abs(hi)) if np.isfinite(lo) and np.isfinite(hi) else 0.0
    if np.isfinite(lo) and np.isfinite(hi) and not lo - tol <= value <= hi + tol:
        notes.append("outside its interval (replicates do not scatter about it: poorly identified)")
    return "; ".join(notes)


def params_table(fitted: dict, iv: pd.DataFrame, default_route: dict, bounds: dict | None = None) -> pd.DataFrame:
    """Rows (block, parameter, value, low, high, route, default, note[, boot_low, boot_high, interval]).

    ``fitted`` maps (route, block) -> values dict; ``iv`` is ``bootstrap.intervals`` (or, with the
    columns ``boot_low``, ``boot_high`` and ``interval`` carried over, ``pipeline.reported_intervals``:
    the reported interval is clipped to the fit's bounds);
    ``default_route`` maps block -> the route written to params.yaml; ``bounds``
    maps (route, block, parameter) -> (low, high), the fit's constraints, which
    ``note`` reports when a value sits on one.
    """
    bounds = bounds or {}
    rows = []
    for (route, block), vals in fitted.items():
        iv_route = "backsolve" if route == "mu_vs_X" else route
        for name, v in vals.items():
            m = iv[(iv["route"] == iv_route) & (iv["block"] == block) & (iv["parameter"] == name)]
            lo, hi = (float(m["low"].iloc[0]), float(m["high"].iloc[0])) if len(m) else (np.nan, np.nan)
            b = bounds.get((route, block, name), (-np.inf, np.inf))
            if len(m) and "boot_low" in m.columns:   # the widening stops at a bound (the percentile interval does not)
                lo = min(max(lo, b[0]), float(m["boot_low"].iloc[0]))
                hi = max(min(hi, b[1]), float(m["boot_high"].iloc[0]))
            extra = {c: (m[c].iloc[0] if len(m) else (np.nan if c != "interval" else ""))
                     for c in ("boot_low", "boot_high", "interval") if c in iv.columns}
            rows.append({"block": block, "parameter": name, "value": v, "low": lo, "high": hi, "route": route,
                         "default": default_route.get(block) == route, "note": _note(v, lo, hi, b), **extra})
    return pd.DataFrame(rows)


def bins_table(bins: pd.DataFrame, iv: pd.DataFrame) -> pd.DataFrame:
    """Back-solve bins with their bootstrap intervals (alpha*_low, alpha*_high)."""
    out = bins.copy()
    b = iv[iv["route"] == "bins"]
    for a in ("alpha1", "alpha2"):
        lo, hi = [], []
        for x in out["X_lo"]:
            m = b[(b["block"] == f"{x:.6g}") & (b["parameter"] == a)]
            lo.append(float(m["low"].iloc[0]) if len(m) else np.nan)
            hi.append(float(m["high"].iloc[0]) if len(m) else np.nan)
        out[f"{a}_low"], out[f"{a}_high"] = lo, hi
    return out


def write_params(doc: dict, path) -> None:
    """Validate through ``model.params`` and write the YAML ``model/`` reads."""
    save_params(params_from_dict(doc, source=str(path)), path)


def write_csv(df: pd.DataFrame, path) -> None:
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(path, index=False, float_format="%.8g")
