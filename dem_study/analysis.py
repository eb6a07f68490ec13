"""What each DEM setting buys in accuracy and costs in time.

Reads the study's points table (``grid.expand``) and each point's series and
sidecars (``preshear.csv``, ``heaviside.csv``, ``{pack,preshear,heaviside}.json``,
docs/data-contract.md) and builds:

- the cost table: per (axis, value) the wall time, particle-steps per second,
  the steady mu, |A|, theta_A and their deviation from the finest value of
  that axis, the RMS deviation of the Heaviside transients (mu, |A|, theta_A
  against strain since the reversal, on a common strain grid) from the finest,
  and the seed-to-seed spread of the same quantities at the base setting;
- mu(I): the steady friction against the achieved inertial number with the fit
  mu = mu_c + b I, and the quasi-static check of the campaign's I;
- the repeats: axis values run with every seed, their mean steady values
  against the base seeds' mean, in standard errors (``repeat_table``).

Notes
-----
The files are read through ``dem_contract``'s readers, and every derived
quantity is ``dem_contract``'s: steady values over the last ``steady_window``
of pre-shear strain (``steady_values``): mu as the mean of the sampled mu,
|A| and theta_A from the mean A (``fabric_norm``, ``fabric_angle_deg``);
angle differences modulo 180 deg (``angle_difference``); the mean of theta_A
over seeds on the circle of axial angles (``axial_mean``).

The seed spread is the root mean square of the differences between every pair
of base seeds: the typical difference of two single runs that differ only by
their seed, directly comparable with a deviation between two single runs.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from dem_contract import (DEMInputError, angle_difference, axial_mean, fabric_angle_deg, fabric_norm, read_series,
                          read_sidecar, stage_costs, steady_values)
from dem_contract.derived import mirror_reversal

from .grid import AXES, REPEAT_PREFIX

QUANTITIES = ("mu", "A_norm", "theta_A_deg")
STAGES = ("pack", "preshear", "heaviside")
#: The columns read from each stage's series.
COLUMNS = {"preshear": ("t", "strain", "A_xx", "A_xy", "mu", "inertial_number"),
           "heaviside": ("t", "strain", "A_xx", "A_xy", "mu")}

DEFAULT_TOLERANCE = {
    "mu": 0.02, "A_norm": 0.01, "theta_A_deg": 2.0,
    "transient_mu": 0.03, "transient_A_norm": 0.015, "transient_theta_A_deg": 5.0,
}


class StudyInputError(ValueError):
    pass


def steady_state(preshear: pd.DataFrame, window: float) -> dict:
    """Steady mu, |A|, theta_A and achieved I over the last ``window`` of pre-shear strain (``dem_contract.steady_values``)."""
    st = steady_values(preshear, last_strain=window)
    if st["n_samples"] < 2:
        raise StudyInputError(f"fewer than 2 samples in the last {window:g} of pre-shear strain")
    return {"mu": st["mu"], "A_norm": st["A_norm"], "theta_A_deg": st["theta_A"],
            "inertial_number": st["inertial_number"]}


def transient_curves(reversal: pd.DataFrame, reversal_strain: float, edges: np.ndarray,
                     sub: int = 10, direction: float = -1.0) -> pd.DataFrame:
    """mu, |A|, theta_A against strain since the reversal, on the bins ``edges``.

    ``direction``: the sign of the shear after the reversal relative to the pre-shear's
    (-1: against it, the Heaviside run; +1: a train's reversal back along it). The
    +1 reversal is mirrored (``dem_contract.derived.mirror_reversal``, x -> -x:
    strain and ``A_xy`` change sign, theta_A -> 180 deg - theta_A) into the frame of a
    -1 one, so every transient starts from the same steady fabric.

    Each column (mu, A_xx, A_xy) is linearly interpolated between its samples
    onto ``sub`` points per bin and averaged over each bin; |A| and theta_A come
    from the bin-mean A. For a densely sampled run this is the bin mean; for a
    coarsely sampled one it is the mean of the piecewise-linear reconstruction,
    so every sampling interval lands on the same grid without a half-interval
    shift. Before the first sample the first value is held.
    """
    if direction > 0:   # into the frame of a reversal against the pre-shear
        reversal, reversal_strain = mirror_reversal(reversal), -reversal_strain
    x = reversal_strain - reversal["strain"].to_numpy()   # strain falls after the reversal
    order = np.argsort(x)
    x = x[order]
    if len(x) < 2:
        raise StudyInputError("fewer than 2 samples after the reversal")
    centres = 0.5 * (edges[1:] + edges[:-1])
    widths = np.diff(edges)
    fine = (edges[:-1, None] + (np.arange(sub)[None, :] + 0.5) / sub * widths[:, None]).ravel()
    out = {}
    for col in ("mu", "A_xx", "A_xy"):
        v = reversal[col].to_numpy()[order]
        out[col] = np.interp(fine, x, v).reshape(len(centres), sub).mean(axis=1)
    return pd.DataFrame({"strain_since_reversal": centres, "mu": out["mu"],
                         "A_norm": fabric_norm(out["A_xx"], out["A_xy"]),
                         "theta_A_deg": fabric_angle_deg(out["A_xx"], out["A_xy"])})


def curve_rms(c: pd.DataFrame, ref: pd.DataFrame) -> dict:
    """RMS difference of two transient tables on the same grid (angles modulo 180 deg)."""
    d = {"mu": c["mu"] - ref["mu"], "A_norm": c["A_norm"] - ref["A_norm"],
         "theta_A_deg": angle_difference(c["theta_A_deg"], ref["theta_A_deg"])}
    return {f"transient_{q}": float(np.sqrt(np.mean(np.square(v)))) for q, v in d.items()}


def steady_difference(s: dict, ref: dict) -> dict:
    return {"mu": s["mu"] - ref["mu"], "A_norm": s["A_norm"] - ref["A_norm"],
            "theta_A_deg": float(angle_difference(s["theta_A_deg"], ref["theta_A_deg"]))}


@dataclass
class PointResult:
    point: str
    steady: dict
    curves: pd.DataFrame
    cost: dict = field(default_factory=dict)


def load_point(case_dir: Path, point: str, steady_window: float, edges: np.ndarray) -> PointResult:
    case_dir = Path(case_dir)
    try:
        # wall time and steps per stage: every sidecar must exist and record them
        costs = stage_costs(case_dir, STAGES, keys=("wall_time_s", "steps"), missing="raise")
        sidecars = {s: read_sidecar(case_dir / f"{s}.csv") for s in STAGES}
        pre = read_series(case_dir / "preshear.csv", COLUMNS["preshear"], what="the pre-shear of the point")
        rev = read_series(case_dir / "heaviside.csv", COLUMNS["heaviside"], what="the heaviside run of the point")
    except DEMInputError as e:
        raise StudyInputError(f"{point}: missing or bad output: {e}") from None
    # CPU time (immune to other jobs on the machine) and the share of it spent sampling,
    # where the sidecars record them (yade_scripts since the sampler-CPU change); NaN otherwise
    cpu = stage_costs(case_dir, STAGES, keys=("cpu_time_s",), missing="nan")
    shear = ("preshear", "heaviside")
    shear_wall = sum(costs[f"wall_time_{s}_s"] for s in shear)
    shear_psteps = sum(sidecars[s]["particle_steps_per_s"] * costs[f"wall_time_{s}_s"] for s in shear)
    strain = sum(abs(sidecars[s]["strain_end"] - sidecars[s]["strain_start"]) for s in shear)
    sampler = {s: sidecars[s].get("sampler_cpu_s", np.nan) for s in shear}
    cost = {
        "N": costs["N"],
        "steps_shear": sum(costs[f"steps_{s}"] for s in shear),
        "wall_time_s": costs["wall_time_s"],
        "wall_time_pack_s": costs["wall_time_pack_s"],
        "wall_time_shear_s": float(shear_wall),
        "wall_time_per_strain_s": float(shear_wall / strain),
        "particle_steps_per_s": float(shear_psteps / shear_wall),
        "kappa_achieved": float(sidecars["preshear"]["kappa_achieved"]),
        "cpu_time_s": cpu["cpu_time_s"],
        "sampling_cost": float(sum(sampler.values()) / sum(cpu[f"cpu_time_{s}_s"] - sampler[s] for s in shear)),
    }
    rev_strain = sidecars["heaviside"].get("reversal_strain", sidecars["heaviside"]["strain_start"])
    return PointResult(point, steady_state(pre, steady_window),
                       transient_curves(rev, rev_strain, edges), cost)


def strain_edges(heaviside_strain: float, bin_width: float) -> np.ndarray:
    n = max(int(np.floor(heaviside_strain / bin_width + 1e-9)), 2)
    return np.linspace(0.0, n * bin_width, n + 1)


def seed_spread(results: list[PointResult]) -> dict:
    """RMS over pairs of seeds of the steady and transient differences (NaN with one seed)."""
    keys = [*QUANTITIES, *(f"transient_{q}" for q in QUANTITIES)]
    pairs = list(itertools.combinations(results, 2))
    if not pairs:
        return {k: float("nan") for k in keys}
    acc = {k: [] for k in keys}
    for a, b in pairs:
        for q, v in steady_difference(a.steady, b.steady).items():
            acc[q].append(v)
        for q, v in curve_rms(a.curves, b.curves).items():
            acc[q].append(v)
    return {k: float(np.sqrt(np.mean(np.square(v)))) for k, v in acc.items()}


def cost_table(points: pd.DataFrame, results: dict[str, PointResult], tolerance: dict | None = None) -> pd.DataFrame:
    """One row per (axis, value) of ``points`` (and per base seed), see the module docstring.

    ``within_tolerance``: every deviation from the finest value of the axis is at
    most max(tolerance, seed spread) (a single run per setting cannot resolve a
    difference below the seed spread).
    """
    tol = {**DEFAULT_TOLERANCE, **(tolerance or {})}
    base_seeds = points[points["axis"] == "seed"]["point"].tolist()
    spread = seed_spread([results[p] for p in base_seeds])
    rows = []
    for axis, group in points[~points["axis"].str.startswith(REPEAT_PREFIX)].groupby("axis", sort=False):
        if axis == "seed":
            ref = results[group["point"].iloc[0]]
        else:
            finest = group[group["finest"]]
            if len(finest) != 1:
                raise StudyInputError(f"axis {axis}: {len(finest)} finest rows, expected 1")
            ref = results[finest["point"].iloc[0]]
        for row in group.to_dict("records"):
            r = results[row["point"]]
            out = {"axis": axis, "value": row["value"], "point": row["point"], "seed": row["seed"],
                   "is_base": row["is_base"], "finest": row["finest"],
                   **{a: row[a] for a in AXES}, **r.cost}
            out["inertial_number_achieved"] = r.steady["inertial_number"]
            for q in QUANTITIES:
                out[f"{q}_steady"] = r.steady[q]
            for q, v in steady_difference(r.steady, ref.steady).items():
                out[f"d_{q}"] = v
            out.update({f"d_{k}": v for k, v in curve_rms(r.curves, ref.curves).items()})
            for k, v in spread.items():
                out[f"seed_spread_{k}"] = v
            ok = True
            for k in [*QUANTITIES, *(f"transient_{q}" for q in QUANTITIES)]:
                limit = np.nanmax([tol[k], spread[k]])
                ok &= bool(abs(out[f"d_{k}"]) <= limit)
            out["within_tolerance"] = ok if axis != "seed" else np.nan
            rows.append(out)
    return pd.DataFrame(rows)


def repeat_table(points: pd.DataFrame, results: dict[str, PointResult]) -> pd.DataFrame:
    r"""Repeated axis values (``accuracy.repeat``): their mean over seeds against the base seeds' mean.

    One row per (axis, value, quantity) of the steady mu, |A| and theta_A:
    ``mean``, ``se`` (standard error over the point's seeds), ``base_mean``,
    ``base_se``, ``difference`` and ``z`` = difference / sqrt(se^2 + base_se^2),
    the number of standard errors that separate the setting from the base; a
    single-run deviation in ``dem_cost.csv`` is only trusted where this is large.
    """
    cols = ["axis", "value", "quantity", "n_seeds", "mean", "se", "n_base_seeds", "base_mean", "base_se",
            "difference", "z"]
    rep = points[points["axis"].str.startswith(REPEAT_PREFIX)]
    if rep.empty:
        return pd.DataFrame(columns=cols)
    base = [results[p] for p in points.loc[points["axis"] == "seed", "point"]]
    rows = []
    for (axis_tag, value), group in rep.groupby(["axis", "value"], sort=False):
        axis = axis_tag.removeprefix(REPEAT_PREFIX)
        first = points[(points["axis"] == axis) & np.isclose(points["value"], value)]["point"].tolist()
        runs = [results[p] for p in first + group["point"].tolist()]
        for q in QUANTITIES:
            x = np.array([r.steady[q] for r in runs])
            y = np.array([r.steady[q] for r in base])
            (mean_x, se_x), (mean_y, se_y) = (mean_and_se(v, axial=q == "theta_A_deg") for v in (x, y))
            diff = angle_difference(mean_x, mean_y) if q == "theta_A_deg" else mean_x - mean_y
            with np.errstate(divide="ignore", invalid="ignore"):   # identical seeds: z is +-inf or NaN
                z = float(np.divide(diff, np.hypot(se_x, se_y)))
            rows.append({"axis": axis, "value": float(value), "quantity": q, "n_seeds": len(x), "mean": mean_x,
                         "se": se_x, "n_base_seeds": len(y), "base_mean": mean_y, "base_se": se_y,
                         "difference": float(diff), "z": z})
    return pd.DataFrame(rows, columns=cols)


def mean_and_se(x, axial: bool):
    r"""Mean over seeds and its standard error :math:`s/\sqrt n` (NaN for one seed).

    Axial angles (``axial``) are averaged on the circle (``dem_contract.axial_mean``),
    and :math:`s` is taken from their differences to that mean modulo 180 deg
    (``angle_difference``), so seeds on either side of 0/180 are close.
    """
    n = len(x)
    if not axial:
        return float(x.mean()), (float(x.std(ddof=1) / np.sqrt(n)) if n > 1 else np.nan)
    mean = float(axial_mean(x))
    dev = angle_difference(x, mean)
    return mean, (float(np.sqrt(np.sum(dev**2) / (n - 1) / n)) if n > 1 else np.nan)


def cheapest_within_tolerance(table: pd.DataFrame) -> dict:
    """Per axis: the value with the smallest shear wall time per unit strain that is within tolerance."""
    out = {}
    for axis, group in table[table["axis"] != "seed"].groupby("axis", sort=False):
        ok = group[group["within_tolerance"].astype(bool)]
        if ok.empty:
            continue
        best = ok.loc[ok["wall_time_per_strain_s"].idxmin()]
        out[axis] = {"value": float(best["value"]), "point": best["point"],
                     "wall_time_per_strain_s": float(best["wall_time_per_strain_s"])}
    return out


def recommended_setting(points: pd.DataFrame, cheapest: dict) -> dict:
    """The base setting with each studied axis at its cheapest value within tolerance.

    Assumes the axes act independently (the grid varies one at a time).
    """
    base = points[points["axis"] == "seed"].iloc[0]
    return {a: float(cheapest[a]["value"]) if a in cheapest else float(base[a]) for a in AXES}


@dataclass
class MuOfIFit:
    mu_c: float
    b: float
    mu_c_stderr: float
    b_stderr: float
    r2: float
    n: int


def fit_mu_of_I(I, mu) -> MuOfIFit:
    """Least-squares line mu = mu_c + b I (scipy.stats.linregress)."""
    I, mu = np.asarray(I, float), np.asarray(mu, float)
    if len(np.unique(I)) < 2:
        raise StudyInputError("mu(I) needs at least two distinct inertial numbers")
    res = stats.linregress(I, mu)
    return MuOfIFit(float(res.intercept), float(res.slope), float(res.intercept_stderr),
                    float(res.stderr), float(res.rvalue**2), len(I))


def quasi_static_check(fit: MuOfIFit, campaign_I, tolerance: float) -> pd.DataFrame:
    """(mu(I) - mu_c)/mu_c = b I/mu_c for each campaign I, and whether it is below ``tolerance``."""
    I = np.asarray(campaign_I, float)
    excess = fit.b * I / fit.mu_c
    return pd.DataFrame({"inertial_number": I, "mu_fit": fit.mu_c + fit.b * I,
                         "rel_excess": excess, "within_quasi_static": excess <= tolerance})


def mu_of_I_table(points: pd.DataFrame, results: dict[str, PointResult], campaign_I, tolerance: float):
    """The I axis and the base seeds: steady mu against achieved I, the fit and the campaign check."""
    sel = points[(points["axis"] == "inertial_number") | (points["axis"] == "seed")]
    sel = sel.drop_duplicates("point")
    data = pd.DataFrame({
        "kind": "data", "point": sel["point"].to_numpy(), "seed": sel["seed"].to_numpy(),
        "inertial_number": sel["inertial_number"].to_numpy(),
        "inertial_number_achieved": [results[p].steady["inertial_number"] for p in sel["point"]],
        "mu_steady": [results[p].steady["mu"] for p in sel["point"]],
    })
    fit = fit_mu_of_I(data["inertial_number_achieved"], data["mu_steady"])
    data["mu_fit"] = fit.mu_c + fit.b * data["inertial_number_achieved"]
    data["rel_excess"] = fit.b * data["inertial_number_achieved"] / fit.mu_c
    camp = quasi_static_check(fit, campaign_I, tolerance).assign(kind="campaign")
    table = pd.concat([data, camp], ignore_index=True)
    for k in ("mu_c", "mu_c_stderr", "b", "b_stderr", "r2"):
        table[k] = getattr(fit, k)
    table["quasi_static_tolerance"] = tolerance
    return table, fit
