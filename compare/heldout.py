r"""In-sample against out-of-sample errors over calibration sets.

Each ``compare predict`` run writes ``errors.csv`` for one calibration set with
an ``in_sample`` flag per row (the run's case and protocol were among those the
set was calibrated on). This module pools the seed-level rows per (set, model)
into one in-sample and one out-of-sample figure of merit per quantity:

- ``rmse_<q>_in`` / ``_out``: pooled RMSE, sqrt(sum n_i rmse_i^2 / sum n_i)
  over the runs that integrated (n_i samples each);
- ``max_<q>_in`` / ``_out``: largest error over those runs;
- ``n_in``, ``n_out``: runs; ``failed_in``, ``failed_out``: runs where the model
  could not be integrated (e.g. Model 1's PoleError), which count as failures,
  not as small errors;
- ``held_out``: what the set did not see; ``note``: why a column is empty.

A configuration with a single calibration set (or sets that all see every
case) has no held-out rows: the table then still lists every set with its
in-sample errors and says so in ``note``.
"""
from __future__ import annotations


import numpy as np
import pandas as pd

from dem_contract.tables import read_table

from .dem import DEMInputError
from .metrics import QUANTITIES

NEEDED = ("set", "level", "case", "group", "protocol", "in_sample", "model", "status", "n_samples")


def read_errors(paths) -> pd.DataFrame:
    """Concatenate ``errors.csv`` files, checking their columns (a cut or ragged file is refused by line)."""
    frames = []
    for path in paths:
        frames.append(read_table(path, NEEDED, "an errors.csv of 'compare predict'"))
    if not frames:
        raise DEMInputError("no errors.csv given")
    return pd.concat(frames, ignore_index=True)


def _pooled(rows, q):
    ok = rows[rows["status"] == "ok"]
    if ok.empty:
        return np.nan, np.nan
    n = ok["n_samples"].to_numpy(float)
    rmse = float(np.sqrt(np.sum(n * ok[f"rmse_{q}"].to_numpy(float) ** 2) / np.sum(n)))
    return rmse, float(ok[f"max_{q}"].max())


def _describe(rows):
    parts = []
    for protocol, sub in rows.groupby("protocol", sort=False):
        groups = ", ".join(f"{g} ({n} seeds)" for g, n in sub.groupby("group", sort=False)["case"].nunique().items())
        parts.append(f"{protocol}: {groups}")
    return "; ".join(parts)


def heldout_table(paths) -> pd.DataFrame:
    """The in-sample against out-of-sample table (see the module docstring)."""
    err = read_errors(paths)
    err = err[err["level"] == "seed"].copy()
    err["in_sample"] = err["in_sample"].astype(str).str.lower().isin(("true", "1"))
    rows = []
    n_sets = err["set"].nunique()
    for (calset, model), sub in err.groupby(["set", "model"], sort=False):
        row = dict(set=calset, model=model)
        ins, outs = sub[sub["in_sample"]], sub[~sub["in_sample"]]
        for q in QUANTITIES:
            row[f"rmse_{q}_in"], row[f"max_{q}_in"] = _pooled(ins, q)
            row[f"rmse_{q}_out"], row[f"max_{q}_out"] = _pooled(outs, q)
        row.update(n_in=len(ins), n_out=len(outs), failed_in=int((ins["status"] != "ok").sum()),
                   failed_out=int((outs["status"] != "ok").sum()), held_out=_describe(outs) if len(outs) else "")
        notes = []
        if outs.empty:
            notes.append("no held-out runs: this set is calibrated on every case and protocol compared"
                         + ("; the configuration defines no other calibration set (a single pressure, "
                            "inertial number and protocol split is impossible or not configured)"
                            if n_sets == 1 else ""))
        if ins.empty:
            notes.append("no in-sample runs compared")
        for label, part in (("in-sample", ins), ("out-of-sample", outs)):
            bad = part[part["status"] != "ok"]
            if len(bad):
                kinds = sorted({s.split(":")[0] for s in bad["status"]})
                notes.append(f"{len(bad)} {label} run(s) not integrated ({', '.join(kinds)}); errors pooled over the rest")
        row["note"] = "; ".join(notes)
        rows.append(row)
    return pd.DataFrame(rows)
