r"""Bulk against walls: each cell's steady state, Heaviside transients and information per core-hour.

Reads every case of the study (``bulk_cells.cases``: ``<cell>_s<seed>``
folders with ``preshear.csv``, ``heaviside.csv`` and the three sidecars) and
builds, per cell, the seed mean and its standard error of

- the steady ``mu``, ``A_norm``, ``theta_A_deg``, ``phi``, ``Z`` over the last
  ``steady_window`` of pre-shear strain (``dem_contract.steady_values``; a
  wall cell's fabric, phi and Z are its bulk band's, mu its walls', as the
  campaign reports them; a periodic cell's are the whole cell's);
- the Heaviside transients ``mu``, ``A_norm``, ``theta_A_deg`` against strain
  since the reversal on a common grid (``analysis.transient_curves``);

and sets every cell against each reference cell (the W = 4H wall cells).

A cell with a reversal train (``bulk_cells.reversal_stage`` = ``train``) yields
several transients per seed (``dem_contract.split_transients``); each is put in
the frame of a reversal against the pre-shear (``analysis.transient_curves``
with its direction: a reversal back along the pre-shear is mirrored, x -> -x),
and a seed's curve is the mean of its transients. The seed stays the unit of
every standard error (its transients share one packing); ``early_se_pooled_<q>``
treats all transients of a cell as independent, and ``design_effect_<q>`` =
(early_se / early_se_pooled)^2 says how far they are not (1: independent).

Notes
-----
Standard error of a seed mean, n seeds: :math:`SE = s/\sqrt n` (theta_A on the
circle of axial angles, ``analysis.mean_and_se``). A steady quantity matches a
reference when

.. math:: |x_c - x_r| \le k \sqrt{SE_c^2 + SE_r^2}

(``match_se`` = k, 2 by default). A transient matches when its RMS difference
over the bins, :math:`\sqrt{\langle (\bar x_c - \bar x_r)^2 \rangle}`, is at
most k times the RMS difference seed noise alone gives,
:math:`\sqrt{\langle SE_c^2 + SE_r^2 \rangle}` (``transient_<q>_noise``).

Information per core-hour, per quantity q in (A_norm, theta_A_deg): with
:math:`SE_q` the RMS over the bins of the first ``early_strain`` after the
reversal of the per-bin standard error of the seed-mean curve, and C the
core-hours of all the cell's seeds (CPU time of pack, pre-shear and reversal),

.. math:: \mathcal I_q = \frac{1}{SE_q^2\, C} = \frac{1}{s_q^2\, c}

(c the core-hours of one seed, :math:`s_q` the seed-to-seed spread: independent
of the number of seeds). ``info_ratio_q`` is :math:`\mathcal I_q` over the tall
reference's; the core-hours a cell needs to reach the tall reference's
:math:`SE_q` are :math:`1/(\mathcal I_q SE_{q,\mathrm{tall}}^2)`.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import DEMInputError, angle_difference, read_series, read_sidecar, split_transients, steady_values

from .analysis import StudyInputError, mean_and_se, transient_curves
from .bulk_cost import STAGES, case_cost, reversal_stages

STEADY = ("mu", "A_norm", "theta_A_deg", "phi", "Z")
TRANSIENT = ("mu", "A_norm", "theta_A_deg")
INFORMATION = ("A_norm", "theta_A_deg")
AXIAL = {"theta_A_deg"}
COLUMNS = {"preshear": ("t", "strain", "gammadot", "A_xx", "A_xy", "mu", "phi", "Z"),
           "reversal": ("t", "strain", "gammadot", "A_xx", "A_xy", "mu")}


@dataclass
class CaseResult:
    case: str
    steady: dict
    curves: pd.DataFrame
    cost: dict
    transients: list = None     # each transient's curves (one for a single reversal)


def load_case(case_dir, case: str, steady_window: float | None, edges: np.ndarray,
              stage: str = "heaviside") -> CaseResult:
    """One case: steady values, binned transient (the mean of a train's transients) and CPU cost.

    ``steady_window``: the last pre-shear strain of the steady values, or None for the last half
    of its strain path (``dem_contract.steady_values``' default, the campaign's).
    ``stage``: the case's reversal run: ``heaviside`` or ``train`` (``bulk_cells.reversal_stage``),
    or any other reversal run with a sidecar (``sinusoidal``, a schedule: ``split_transients``).
    """
    case_dir = Path(case_dir)
    try:
        cost = case_cost(case_dir, (*STAGES[:2], stage))
        rev_side = read_sidecar(case_dir / f"{stage}.csv")
        pre = read_series(case_dir / "preshear.csv", COLUMNS["preshear"], what=f"the pre-shear of {case}")
        rev = read_series(case_dir / f"{stage}.csv", COLUMNS["reversal"], what=f"the {stage} run of {case}")
        transients = split_transients(pre, rev, rev_side, what=str(case_dir / f"{stage}.csv"))
    except (DEMInputError, StudyInputError) as e:
        raise StudyInputError(f"{case}: missing or bad output: {e}") from None
    st = steady_values(pre, last_strain=steady_window)
    if st["n_samples"] < 2:
        window = "half" if steady_window is None else f"{steady_window:g}"
        raise StudyInputError(f"{case}: fewer than 2 samples in the last {window} of pre-shear strain")
    steady = {"mu": st["mu"], "A_norm": st["A_norm"], "theta_A_deg": st["theta_A"], "phi": st["phi"], "Z": st["Z"]}
    pre_sign = float(np.sign(np.median(pre["gammadot"])))
    each = [transient_curves(tr.data, tr.strain0, edges, direction=tr.sign * pre_sign) for tr in transients]
    curve = each[0] if len(each) == 1 else mean_curves(each)[["strain_since_reversal", *TRANSIENT]]
    return CaseResult(case, steady, curve, cost, each)


def mean_curves(curves: list) -> pd.DataFrame:
    """Bin-wise mean of transient curves with the standard error per bin: ``<q>``, ``<q>_se``
    (theta_A on the circle of axial angles): a cell's seed mean, or a seed's train mean."""
    out = {"strain_since_reversal": curves[0]["strain_since_reversal"].to_numpy()}
    for q in TRANSIENT:
        stack = np.stack([c[q].to_numpy() for c in curves])
        ms = [mean_and_se(stack[:, j], q in AXIAL) for j in range(stack.shape[1])]
        out[q] = np.array([m for m, _ in ms])
        out[f"{q}_se"] = np.array([s for _, s in ms])
    return pd.DataFrame(out)


def cell_table(cases: pd.DataFrame, results: dict[str, CaseResult], early_strain: float):
    """Per cell: geometry, N, seeds, cost, steady mean +- SE, early SE and information per core-hour.

    Returns the table and the seed-mean curves of every cell (``mean_curves``).
    """
    rows, curves = [], {}
    for cell, group in cases.groupby("cell", sort=False):
        res = [results[c] for c in group["case"]]
        first = group.iloc[0]
        row = dict(cell=cell, kind=first["kind"], H_over_d=first["H_over_d"], W_over_d=first["W_over_d"],
                   N=int(res[0].cost["N"]), seeds=len(res))
        hours = np.array([r.cost["core_hours"] for r in res])
        row["core_hours_per_seed"] = float(hours.mean())
        row["core_hours"] = float(hours.sum())
        for stage in STAGES[:2]:   # the pack and pre-shear are what a reversal train shares
            row[f"core_hours_{stage}_per_seed"] = float(np.mean([r.cost[f"cpu_time_{stage}_s"] for r in res]) / 3600)
        row["core_hours_reversal_per_seed"] = (row["core_hours_per_seed"] - row["core_hours_pack_per_seed"]
                                               - row["core_hours_preshear_per_seed"])
        row["transients"] = sum(len(r.transients) for r in res)
        for q in STEADY:
            row[q], row[f"{q}_se"] = mean_and_se(np.array([r.steady[q] for r in res]), q in AXIAL)
        curves[cell] = c = mean_curves([r.curves for r in res])
        pooled = mean_curves([t for r in res for t in r.transients])   # every transient as if independent
        early = c["strain_since_reversal"] < early_strain
        for q in INFORMATION:
            se = float(np.sqrt(np.mean(np.square(c.loc[early, f"{q}_se"])))) if early.any() else np.nan
            row[f"early_se_{q}"] = se
            row[f"info_{q}"] = 1.0 / (se**2 * row["core_hours"]) if se > 0 else np.nan
            se_p = float(np.sqrt(np.mean(np.square(pooled.loc[early, f"{q}_se"])))) if early.any() else np.nan
            row[f"early_se_pooled_{q}"] = se_p
            row[f"design_effect_{q}"] = (se / se_p) ** 2 if se_p > 0 else np.nan
        rows.append(row)
    return pd.DataFrame(rows), curves


def _difference(q, a, b):
    return angle_difference(a, b) if q in AXIAL else np.asarray(a, float) - np.asarray(b, float)


def comparison(cells: pd.DataFrame, curves: dict, references, tall: str | None, match_se: float = 2.0):
    """One row per (cell, reference other than the cell); a cell compared with none gets one row
    with an empty reference. Adds the information-per-core-hour ratio to ``tall``.

    Columns (module docstring): the cell's row of ``cell_table``; ``d_<q>``, ``z_<q>`` (difference
    over the combined SE) per steady quantity; ``transient_<q>_rms``, ``transient_<q>_noise``;
    ``match`` (every quantity within ``match_se`` combined SE) and ``failing`` (the others, by name;
    a quantity without a standard error, one seed, fails as ``<q> (no SE)``); ``info_ratio_<q>``,
    ``core_hours_to_tall_se_<q>``.
    """
    by_cell = cells.set_index("cell")
    missing = [r for r in [*references, *([tall] if tall else [])] if r not in by_cell.index]
    if missing:
        raise StudyInputError(f"reference cell {missing[0]!r} has no runs (cells: {', '.join(by_cell.index)})")
    out = []
    for cell, row in by_cell.iterrows():
        base = {"cell": cell, **row.to_dict()}
        if tall:
            t = by_cell.loc[tall]
            for q in INFORMATION:
                base[f"info_ratio_{q}"] = row[f"info_{q}"] / t[f"info_{q}"]
                base[f"core_hours_to_tall_se_{q}"] = 1.0 / (row[f"info_{q}"] * t[f"early_se_{q}"] ** 2)
        refs = [r for r in references if r != cell]
        if not refs:
            out.append({**base, "reference": ""})
            continue
        for ref in refs:
            r = by_cell.loc[ref]
            pair, failing = {**base, "reference": ref}, []
            for q in STEADY:
                d = float(_difference(q, row[q], r[q]))
                se = float(np.hypot(row[f"{q}_se"], r[f"{q}_se"]))
                pair[f"d_{q}"], pair[f"z_{q}"] = d, d / se if se > 0 else np.nan
                if not np.isfinite(se):
                    failing.append(f"{q} (no SE)")
                elif abs(d) > match_se * se:
                    failing.append(q)
            c, cr = curves[cell], curves[ref]
            for q in TRANSIENT:
                d = _difference(q, c[q], cr[q])
                rms = float(np.sqrt(np.mean(np.square(d))))
                noise = float(np.sqrt(np.mean(np.square(c[f"{q}_se"]) + np.square(cr[f"{q}_se"]))))
                pair[f"transient_{q}_rms"], pair[f"transient_{q}_noise"] = rms, noise
                if not np.isfinite(noise):
                    failing.append(f"transient_{q} (no SE)")
                elif rms > match_se * noise:
                    failing.append(f"transient_{q}")
            pair["match"] = not failing
            pair["failing"] = ", ".join(failing)
            out.append(pair)
    table = pd.DataFrame(out)
    first = ["cell", "reference", "match", "failing"]
    return table[first + [c for c in table.columns if c not in first]]


def analyse(cases: pd.DataFrame, bulk_dir, steady_window: float, edges: np.ndarray, early_strain: float,
            references, tall: str | None, match_se: float = 2.0):
    """Load every case of ``cases`` under ``bulk_dir``; returns (comparison table, cell table, curves)."""
    results = {c: load_case(Path(bulk_dir) / c, c, steady_window, edges, st)
               for c, st in zip(cases["case"], reversal_stages(cases))}
    cells, curves = cell_table(cases, results, early_strain)
    return comparison(cells, curves, references, tall, match_se), cells, curves


def verdict(table: pd.DataFrame, references, tall: str | None, match_se: float = 2.0,
            target_ratio: float = 10.0) -> dict:
    """Which cells match every reference, and the best of them by information per core-hour.

    ``best``: among the cells that are not references and match every reference, the one
    whose smaller ``info_ratio`` (|A| or theta_A) is largest; ``best_reaches_target``: that
    ratio is at least ``target_ratio`` (the issue's tenth of the tall cell's cost).
    """
    cells = {}
    for cell, rows in table.groupby("cell", sort=False):
        first = rows.iloc[0]
        compared = rows[rows["reference"].fillna("") != ""]
        cells[cell] = {
            "kind": first["kind"], "N": int(first["N"]), "core_hours_per_seed": float(first["core_hours_per_seed"]),
            "matches": {r["reference"]: bool(r["match"]) for _, r in compared.iterrows()},
            "failing": {r["reference"]: r["failing"] for _, r in compared.iterrows() if not r["match"]},
            **{f"info_ratio_{q}": float(first.get(f"info_ratio_{q}", np.nan)) for q in INFORMATION},
        }
    matching = [c for c, v in cells.items() if c not in references and v["matches"] and all(v["matches"].values())]
    worst = {c: min(cells[c][f"info_ratio_{q}"] for q in INFORMATION) for c in matching}
    best = max(worst, key=worst.get) if worst and tall else None
    return {"match_se": match_se, "references": list(references), "tall_reference": tall,
            "matching_every_reference": matching, "best": best,
            "best_info_ratio": worst.get(best) if best else None,
            "best_reaches_target": bool(best is not None and worst[best] >= target_ratio),
            "target_ratio": target_ratio, "cells": cells}
