r"""What the claims stage reads: the comparison's tables and the DEM series (through ``dem_contract``).

- ``read_comparison``: every calibration set's ``predictions.csv`` (per-seed DEM
  and model curves against ``s_rev``) under ``results/compare/<set>/``, with the
  ``in_sample`` flag of each (set, case, protocol) from that set's ``errors.csv``
  (a run is out of sample when the set was not calibrated on its case or on its
  protocol).
- ``read_dem_case``: one case's pre-shear steady state (``dem_contract.steady_values``;
  theta_A mirrored to positive shear) and the samples of every reversal of its
  protocol runs (a schedule's too, each tagged with its kind) for the collapse
  of mu on X (``X = sqrt2 A_xy sign(gammadot)``, docs/model.md).
- Every curve of ``predictions.csv`` carries its reversal's ``kind`` (heaviside:
  a step; sinusoidal: a half cosine); the claims group a seed's reversals by it.

Bad or missing input raises ``DEMInputError`` naming the file (exit status 2 at
the command line).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import (REVERSAL_PROTOCOLS, DEMInputError, fabric_norm, pre_reversal_state, read_series,
                          read_sidecar, split_case_label, split_transients, steady_values)
from dem_contract.derived import reversal_kinds
from dem_contract.tables import read_table

PREDICTION_COLUMNS = ("set", "case", "group", "seed", "protocol", "source", "s_rev", "A_xx", "A_xy", "A_norm",
                      "theta_A", "mu")
ERROR_COLUMNS = ("set", "level", "case", "protocol", "in_sample")
SERIES_COLUMNS = ("t", "strain", "gammadot", "A_xx", "A_xy", "sigma_xy", "p", "mu")
RATE_DEAD_BAND = 0.1   # samples with |gammadot| below this fraction of the run's median have no direction


def read_csv(path, columns, what):
    """A table of an earlier stage; a cut or ragged one is refused by file and line (``read_table``)."""
    return read_table(path, columns, what)


def comparison_sets(compare_dir) -> list:
    """Names of the calibration sets under ``compare_dir`` (sub-folders holding predictions.csv)."""
    compare_dir = Path(compare_dir)
    if not compare_dir.is_dir():
        raise DEMInputError(f"{compare_dir}: comparison folder not found")
    sets = sorted(p.parent.name for p in compare_dir.glob("*/predictions.csv"))
    if not sets:
        raise DEMInputError(f"{compare_dir}: no <set>/predictions.csv (run the comparison stage first)")
    return sets


def read_comparison(compare_dir, sets=None) -> pd.DataFrame:
    """Every set's predictions.csv with an ``in_sample`` column, one frame.

    Parameters
    ----------
    compare_dir : path
        ``results/compare``.
    sets : list of str, optional
        Calibration sets to read (default: every sub-folder with predictions.csv).
    """
    compare_dir = Path(compare_dir)
    frames = []
    for name in sets or comparison_sets(compare_dir):
        pred = read_csv(compare_dir / name / "predictions.csv", PREDICTION_COLUMNS, "the comparison's curves")
        err = read_csv(compare_dir / name / "errors.csv", ERROR_COLUMNS, "the comparison's errors")
        flags = (err[err["level"] == "seed"].drop_duplicates(["case", "protocol"])
                 .set_index(["case", "protocol"])["in_sample"].astype(bool))
        key = pd.MultiIndex.from_frame(pred[["case", "protocol"]])
        pred["in_sample"] = flags.reindex(key).fillna(True).to_numpy(bool)   # unknown: never scored out of sample
        if "kind" not in pred:   # a comparison from before kinds: only the classic runs, named after their kind
            kinds = {p: reversal_kinds({}, p, what=str(compare_dir / name / "predictions.csv"))[0]["kind"]
                     for p in pred["protocol"].unique()}
            pred["kind"] = pred["protocol"].map(kinds)
        pred["set"] = name
        frames.append(pred)
    return pd.concat(frames, ignore_index=True)


def runs(pred: pd.DataFrame):
    """(set, case, group, protocol, in_sample) -> {source: curve frame sorted by s_rev}, for each run."""
    out = {}
    for (st, case, group, proto, ins), g in pred.groupby(["set", "case", "group", "protocol", "in_sample"], sort=True):
        out[(st, case, group, proto, bool(ins))] = {src: d.sort_values("s_rev").reset_index(drop=True)
                                                  for src, d in g.groupby("source")}
    return out


def dem_curves(pred: pd.DataFrame) -> dict:
    """(case, group, protocol) -> the DEM curve (the same in every set: the first set's)."""
    dem = pred[pred["source"] == "dem"]
    out = {}
    for (case, group, proto, st), d in dem.groupby(["case", "group", "protocol", "set"], sort=True):
        out.setdefault((case, group, proto), d.sort_values("s_rev").reset_index(drop=True))
    return out


SAMPLE_COLUMNS = ["protocol", "kind", "reversal", "X", "mu", "A_xy", "stress_ratio"]


@dataclass
class DemCase:
    """One DEM case: its pre-shear steady state and its reversal samples."""

    label: str
    group: str
    steady: dict                 # dem_contract.steady_values of the pre-shear; theta_A for positive shear
    samples: pd.DataFrame = field(default_factory=pd.DataFrame)   # SAMPLE_COLUMNS
    initial_A: dict = field(default_factory=dict)   # protocol -> |A| just before each of its reversals


def read_dem_case(case_dir, protocols=REVERSAL_PROTOCOLS) -> DemCase:
    """Read ``<case_dir>/preshear.csv`` and every reversal of the protocol runs it holds.

    Each run (``dem_contract.read_series``) is split into its transients, one per
    reversal (``dem_contract.split_transients``; a heaviside or sinusoidal run is one),
    and each transient's moving samples (``|gammadot|`` above ``RATE_DEAD_BAND`` of the
    run's median) are tagged with the run's ``protocol``, the reversal's ``kind``
    (``dem_contract.derived.reversal_kinds``: heaviside or sinusoidal, from the sidecar
    for a schedule) and its number ``reversal``. ``X = sqrt2 A_xy sign(gammadot)`` and
    mu are the same in either frame, so a +1 reversal needs no mirroring here. The
    fabric just before each reversal (its transient's ``initial`` state) is kept as
    ``initial_A``: protocol -> |A| per reversal.

    Parameters
    ----------
    case_dir : path
        ``results/dem/<label>``.
    protocols : sequence of str
        Protocols to read (heaviside, sinusoidal, schedules); a run the case lacks is skipped.
    """
    case_dir = Path(case_dir)
    if not case_dir.is_dir():
        raise DEMInputError(f"{case_dir}: case directory not found")
    pre = read_series(case_dir / "preshear.csv", SERIES_COLUMNS, 10, what="the pre-shear of the case")
    steady = steady_values(pre)
    sign = pre_reversal_state(pre)["gammadot_sign"]
    if sign < 0:   # mirror to positive shear: the angle Eq. 4's bound refers to
        steady["theta_A"] = float(np.mod(180.0 - steady["theta_A"], 180.0))
    frames, initial_A = [], {}
    for proto in protocols:
        path = case_dir / f"{proto}.csv"
        if not path.exists():
            continue
        d = read_series(path, SERIES_COLUMNS, 10, what=f"the {proto} run of the case")
        meta = read_sidecar(path)
        transients = split_transients(pre, d, meta, what=str(path))
        kinds = reversal_kinds(meta, proto, what=str(path))
        if len(kinds) != len(transients):
            raise DEMInputError(f"{path}: the sidecar's schedule makes {len(kinds)} reversal(s), the run holds "
                                f"{len(transients)}")
        median = np.median(np.abs(d["gammadot"].to_numpy()))
        initial_A[proto] = [float(fabric_norm(tr.initial["A_xx"], tr.initial["A_xy"])) for tr in transients]
        for tr, kind in zip(transients, kinds):
            t = tr.data
            g = t["gammadot"].to_numpy()
            moving = np.abs(g) > RATE_DEAD_BAND * median
            frames.append(pd.DataFrame({
                "protocol": proto, "kind": kind["kind"], "reversal": tr.index,
                "X": np.sqrt(2.0) * t["A_xy"].to_numpy()[moving] * np.sign(g[moving]),
                "mu": t["mu"].to_numpy()[moving], "A_xy": t["A_xy"].to_numpy()[moving],
                "stress_ratio": (t["sigma_xy"] / t["p"]).to_numpy()[moving]}, columns=SAMPLE_COLUMNS))
    group, _ = split_case_label(case_dir.name)
    samples = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=SAMPLE_COLUMNS)
    return DemCase(label=case_dir.name, group=group, steady=steady, samples=samples, initial_A=initial_A)


FREEFORM_COLUMNS = ("section", "key", "value", "low", "high", "n", "detail")


def read_freeform(path) -> pd.DataFrame:
    """A calibration set's ``freeform.csv`` (``calibrate.freeform.table``); DEMInputError naming the file if bad."""
    return read_csv(Path(path), FREEFORM_COLUMNS, "free-form table of python -m calibrate --freeform")
