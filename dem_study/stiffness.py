"""The stiffness axis of the campaign's own cell: what kappa = kn / (p d) changes and what it costs.

Reads finished DEM cases (pre-shear and Heaviside reversal, each case a folder of the data
contract with its ``scene.json``), groups them by kappa, and builds:

- the stiffness table: per kappa the seeds, the steady mu, |A|, X, theta_A, phi and Z
  (mean and standard error over seeds), the Heaviside transient's early |A| (its minimum
  within ``early_strain`` of the reversal and where it lies) and early mu (mean over the first
  ``early_strain / 2``), the mean overlap in d (from ``preshear.census.json`` where
  ``yade_scripts/contact_census.py`` wrote it), the CPU cost per seed, and each steady value's
  difference from the stiffest kappa in combined standard errors;
- the fabric readings table: per kappa and reading of "the contacts" (``contact_census``),
  the steady-state snapshot's X, and its difference from the data contract's reading paired
  by seed (mean and standard error): which contacts the paper's fabric counted moves X by
  this much.

X = A:D'/|D'| = sqrt(2) A_xy s (docs/model.md; s the sign of the pre-shear's rate), so X < 0
in steady shear. Every derived quantity is ``dem_contract``'s (``steady_values``) or the
bulk study's (``bulk.load_case``: the binned transient of the reversal).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import read_series, steady_values
from dem_contract.release import read_manifest, require_intact, restore_case

from .analysis import StudyInputError, mean_and_se, strain_edges
from .bulk import load_case

STEADY = ("mu", "A_norm", "X", "theta_A_deg", "phi", "Z")
#: What makes a setting: the stiffness axis varies kappa; the checks at a fixed kappa vary the rest.
SETTING = ("kappa", "inertial_number", "dt_over_tc", "contact_law", "restitution")
AXIAL = {"theta_A_deg"}
CENSUS = "preshear.census.json"


def run_summary(case_dir, steady_window: float, early_strain: float, bin_width: float = 0.005) -> dict:
    """One case: its kappa, seed, steady values, early transient, overlap and CPU hours."""
    case_dir = Path(case_dir)
    try:
        scene = json.loads((case_dir / "scene.json").read_text())
    except (OSError, ValueError) as exc:
        raise StudyInputError(f"{case_dir}: no readable scene.json ({exc})") from None
    edges = strain_edges(3 * early_strain, bin_width)
    res = load_case(case_dir, case_dir.name, steady_window, edges, stage="heaviside")
    pre = read_series(case_dir / "preshear.csv", ("t", "strain", "gammadot", "A_xx", "A_xy", "mu"),
                      what=f"the pre-shear of {case_dir.name}")
    st = steady_values(pre, last_strain=steady_window)
    sign = float(np.sign(np.median(pre["gammadot"])))
    c = res.curves
    early = c[c["strain_since_reversal"] < early_strain]
    k = int(early["A_norm"].to_numpy().argmin())
    side = json.loads((case_dir / "preshear.json").read_text())
    mat = side["scene"]["material"]   # the scene as the stage read it, defaults filled
    row = dict(case=case_dir.name, kappa=float(mat["kappa"]), seed=int(scene["seed"]),
               inertial_number=float(scene["loading"]["inertial_number"]),
               dt_over_tc=float(scene["timestep"]["dt_over_tc"]), contact_law=str(mat["contact_law"]),
               restitution=float(mat["restitution"]), N=int(res.cost["N"]),
               **res.steady, X=math.sqrt(2.0) * st["A_xy"] * sign,
               A_min_early=float(early["A_norm"].iloc[k]),
               strain_at_A_min=float(early["strain_since_reversal"].iloc[k]),
               mu_early=float(c.loc[c["strain_since_reversal"] < early_strain / 2, "mu"].mean()),
               core_hours=float(res.cost["core_hours"]),
               core_hours_preshear=float(res.cost["cpu_time_preshear_s"]) / 3600)
    census = case_dir / CENSUS
    cs = json.loads(census.read_text()) if census.is_file() else None
    overlap = side.get("overlap_end_d") or (cs or {}).get("overlap_d")   # sidecars before 2026-11-27: the census
    if overlap:
        row["overlap_mean_d"], row["overlap_p90_d"] = overlap["mean"], overlap["p90"]
    if cs:
        row["rattler_fraction"] = cs["rattler_fraction"]
        for name, f in cs["fabric"].items():
            if "X" in f:
                row[f"X_{name}"] = f["X"]
    return row


def restore_releases(releases, into) -> list:
    """Every case of the data releases ``releases``, restored as finished cases under ``into``.

    Each release is checked against its manifest first (``require_intact``: an edited file
    stops here, named); its cases go to ``<into>/<release name>/<label>/`` (labels repeat
    across releases of one study: one release per setting).
    """
    out = []
    for release in map(Path, releases):
        require_intact(release)
        for label in read_manifest(release)["cases"]:
            out.append(restore_case(release, label, Path(into) / release.name / label))
    return out


def runs_table(case_dirs, steady_window: float, early_strain: float) -> pd.DataFrame:
    """One row per case (``run_summary``), sorted by setting and seed."""
    rows = [run_summary(d, steady_window, early_strain) for d in case_dirs]
    if not rows:
        raise StudyInputError("no case given")
    return pd.DataFrame(rows).sort_values([*SETTING, "seed"], ignore_index=True)


def base_setting(runs: pd.DataFrame) -> dict:
    """The stiffness axis's settings other than kappa: those most runs share."""
    return {q: runs[q].mode().iloc[0] for q in SETTING if q != "kappa"}


def on_axis(table: pd.DataFrame, base: dict) -> pd.Series:
    """Rows of ``table`` on the stiffness axis: every setting but kappa equals the base's."""
    return np.logical_and.reduce([table[q] == v for q, v in base.items()])


def stiffness_table(runs: pd.DataFrame) -> pd.DataFrame:
    """Per setting (``SETTING``): seeds, mean and SE of every steady and early quantity, overlap,
    core-hours per seed, and each steady value's distance in combined SEs (``z_<q>``) from the
    stiffest kappa on the stiffness axis (``base_setting``), with ``on_axis`` marking the axis's rows."""
    early = ("A_min_early", "strain_at_A_min", "mu_early")
    extra = [q for q in ("overlap_mean_d", "overlap_p90_d", "rattler_fraction") if q in runs]
    rows = []
    for setting, g in runs.groupby(list(SETTING), sort=True):
        row = dict(zip(SETTING, setting), seeds=len(g), N=int(g["N"].iloc[0]),
                   core_hours_per_seed=float(g["core_hours"].mean()),
                   core_hours_preshear_per_seed=float(g["core_hours_preshear"].mean()))
        for q in (*STEADY, *early, *extra):
            row[q], row[f"{q}_se"] = mean_and_se(g[q].to_numpy(dtype=float), q in AXIAL)
        rows.append(row)
    table = pd.DataFrame(rows)
    table["on_axis"] = on_axis(table, base_setting(runs))
    ref = table[table["on_axis"]].iloc[-1]
    for q in STEADY:
        se = np.hypot(table[f"{q}_se"], ref[f"{q}_se"])
        table[f"z_{q}"] = np.where(se > 0, (table[q] - ref[q]) / se, np.nan)
    return table


def readings_table(runs: pd.DataFrame) -> pd.DataFrame:
    """Per setting and reading: the snapshot X (mean, SE over seeds) and its seed-paired difference
    from the data contract's reading (mean, SE); empty without census files."""
    names = [c.removeprefix("X_") for c in runs if c.startswith("X_")]
    rows = []
    for setting, g in runs.groupby(list(SETTING), sort=True):
        if "X_contract" not in g or g["X_contract"].isna().all():
            continue
        for name in names:
            x = g[f"X_{name}"].to_numpy(dtype=float)
            diff = x - g["X_contract"].to_numpy(dtype=float)
            m, se = mean_and_se(x, False)
            dm, dse = mean_and_se(diff, False)
            rows.append(dict(zip(SETTING, setting), reading=name, seeds=len(g), X=m, X_se=se,
                             minus_contract=dm, minus_contract_se=dse))
    return pd.DataFrame(rows)


def figure(table: pd.DataFrame, out) -> None:
    """Steady |A|, -X and mu against kappa on the stiffness axis (seed mean +- SE), and the core-hours per seed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    table = table[table["on_axis"]]
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), constrained_layout=True)
    k = table["kappa"]
    for q, label in (("A_norm", "steady |A|"), ("X", "steady -X")):
        sign = -1 if q == "X" else 1
        axes[0].errorbar(k, sign * table[q], yerr=table[f"{q}_se"], marker="o", capsize=3, label=label)
    axes[0].errorbar(k, table["A_min_early"], yerr=table["A_min_early_se"], marker="s", capsize=3,
                     label="min |A| after a Heaviside reversal")
    axes[0].set(xscale="log", xlabel=r"$\kappa = k_n/(p\,d)$", ylabel="fabric (dimensionless)")
    axes[0].legend(fontsize=7)
    axes[1].errorbar(k, table["mu"], yerr=table["mu_se"], marker="o", capsize=3, label=r"steady $\mu$")
    axes[1].errorbar(k, table["mu_early"], yerr=table["mu_early_se"], marker="s", capsize=3,
                     label=r"early $\mu$ after the reversal")
    axes[1].set(xscale="log", xlabel=r"$\kappa$", ylabel=r"$\mu = |\sigma_{xy}|/p$")
    axes[1].legend(fontsize=7)
    axes[2].plot(k, table["core_hours_per_seed"], "o-", label="core-hours per seed")
    axes[2].set(xscale="log", yscale="log", xlabel=r"$\kappa$", ylabel="core-hours per seed (CPU)")
    if "overlap_mean_d" in table:
        ax = axes[2].twinx()
        ax.plot(k, table["overlap_mean_d"], "s--", color="C3", label=r"mean overlap $\delta/d$")
        ax.set(yscale="log", ylabel=r"mean overlap $\delta/d$")
        ax.legend(fontsize=7, loc="lower left")
    axes[2].legend(fontsize=7, loc="upper left")
    fig.suptitle(f"Stiffness axis: seeds per kappa {', '.join(str(int(s)) for s in table['seeds'])} "
                 "(error bars: standard error over seeds)", fontsize=9)
    fig.savefig(out, dpi=150)
    plt.close(fig)
