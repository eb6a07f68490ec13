"""The DEM resolution grid: one factor at a time around a base setting.

Each axis (kappa, inertial number, cell height, time step, sampling interval)
is varied with every other setting held at the base; a few seeds at the base
give the seed-to-seed spread. A grid point is one DEM case (pack -> preshear ->
heaviside) under ``<results>/accuracy/dem/<point>/``; its scene is the
campaign's (``campaign.scenes.scene_from_config``) with one key changed.

The grids and the base live in the ``accuracy:`` block of the config (see
``workflow/schemas/config.schema.yaml``).
"""
from __future__ import annotations

import copy
import math

import pandas as pd

from campaign import cost
from campaign.scenes import scene_from_config

# axis -> (config section, key, short label for point names)
AXES = {
    "kappa": ("material", "kappa", "kappa"),
    "inertial_number": ("loading", "inertial_number", "I"),
    "H_over_d": ("cell", "H_over_d", "H"),
    "dt_over_tc": ("timestep", "dt_over_tc", "dt"),
    "fine_interval": ("sampling", "fine_interval", "fine"),
    "coarse_interval": ("sampling", "coarse_interval", "coarse"),
}
# which end of an axis is the finest (the reference of that axis)
FINEST = {
    "kappa": max,             # stiffer: closer to rigid particles
    "inertial_number": min,   # slower: closer to quasi-static
    "H_over_d": max,          # taller cell: fewer wall effects
    "dt_over_tc": min,        # smaller step
    "fine_interval": min,     # denser sampling
    "coarse_interval": min,
}
BASE_LABEL = "base"
REPEAT_PREFIX = "repeat:"

def fmt(x: float) -> str:
    """A short, path-safe number: 1e4 -> '10000', 3e-3 -> '0.003'."""
    return f"{float(x):.6g}".replace("+", "")


def point_label(axis: str | None, value: float | None, seed: int) -> str:
    if axis is None:
        return f"{BASE_LABEL}_s{seed}"
    return f"{AXES[axis][2]}-{fmt(value)}_s{seed}"


def _same(a: float, b: float) -> bool:
    return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=0.0)


def active_grid(accuracy: dict) -> dict:
    """Axis -> sorted values to run: the full ``dem_grid`` or its ``default_subset``.

    Raises ValueError when a value of the default subset is not in dem_grid,
    naming the key.
    """
    grid = accuracy["dem_grid"]
    subset = accuracy.get("subset", "default")
    if subset == "full":
        chosen = grid
    elif subset == "default":
        chosen = accuracy.get("default_subset", grid)
        for axis, values in chosen.items():
            if axis not in grid:
                raise ValueError(f"accuracy.default_subset.{axis}: not an axis of accuracy.dem_grid")
            for v in values:
                if not any(_same(v, g) for g in grid[axis]):
                    raise ValueError(f"accuracy.default_subset.{axis}: {v:g} is not in accuracy.dem_grid.{axis}")
    else:
        raise ValueError(f"accuracy.subset = {subset!r}: must be 'default' or 'full'")
    out = {}
    for axis, values in chosen.items():
        if axis not in AXES:
            raise ValueError(f"accuracy grid axis {axis!r} unknown (allowed: {', '.join(AXES)})")
        out[axis] = sorted({float(v) for v in values})
    return out


def base_setting(accuracy: dict) -> dict:
    base = {k: float(v) for k, v in accuracy["base"].items()}
    missing = [a for a in AXES if a not in base]
    if missing:
        raise ValueError(f"accuracy.base misses {', '.join(missing)}")
    if base["coarse_interval"] < base["fine_interval"]:
        raise ValueError("accuracy.base: coarse_interval must be >= fine_interval")
    return base


def setting_of(base: dict, axis: str | None, value: float | None) -> dict:
    """The base with one axis changed; the sampling intervals stay ordered.

    A fine interval above the base's coarse one raises the coarse one to it, and
    a coarse interval below the base's fine one lowers the fine one to it.
    """
    s = dict(base)
    if axis is not None:
        s[axis] = float(value)
    if axis == "fine_interval" and s["coarse_interval"] < s["fine_interval"]:
        s["coarse_interval"] = s["fine_interval"]
    if axis == "coarse_interval" and s["fine_interval"] > s["coarse_interval"]:
        s["fine_interval"] = s["coarse_interval"]
    return s


def expand(accuracy: dict) -> pd.DataFrame:
    """The study's rows: one per (axis, value), plus one per base seed.

    Columns: ``axis`` (an axis name, or ``seed`` for the base seeds), ``value``,
    ``point`` (the case directory name), ``seed``, ``is_base``, ``finest``
    (this row is its axis's reference) and the full setting (one column per axis).
    The base value of every axis is always on that axis (it is the base point);
    axis points run with the first seed. An axis value listed in
    ``accuracy.repeat`` also runs with every other seed, in rows whose axis is
    ``repeat:<axis>`` (``analysis.repeat_table`` sets their mean against the
    base seeds').
    """
    base = base_setting(accuracy)
    if accuracy.get("steady_window", 0.5) >= accuracy.get("preshear_strain", 1.5):
        raise ValueError("accuracy.steady_window must be below accuracy.preshear_strain")
    seeds = [int(s) for s in accuracy["seeds"]]
    seed0 = seeds[0]
    rows = []
    for axis, values in active_grid(accuracy).items():
        values = sorted({*values, base[axis]})
        finest = FINEST[axis](values)
        for v in values:
            is_base = _same(v, base[axis])
            rows.append(dict(
                axis=axis, value=v, seed=seed0, is_base=is_base, finest=_same(v, finest),
                point=point_label(None if is_base else axis, v, seed0),
                **setting_of(base, None if is_base else axis, v),
            ))
    for seed in seeds:
        rows.append(dict(axis="seed", value=float(seed), seed=seed, is_base=True, finest=False,
                         point=point_label(None, None, seed), **base))
    grid = active_grid(accuracy)
    for axis, values in (accuracy.get("repeat") or {}).items():
        for v in values:
            if axis not in grid or not any(_same(v, g) for g in grid[axis]) or _same(v, base[axis]):
                raise ValueError(f"accuracy.repeat.{axis}: {v:g} is not a non-base value of the active grid "
                                 f"(accuracy.subset = {accuracy.get('subset', 'default')!r})")
            for seed in seeds[1:]:
                rows.append(dict(axis=f"{REPEAT_PREFIX}{axis}", value=float(v), seed=seed, is_base=False,
                                 finest=False, point=point_label(axis, v, seed), **setting_of(base, axis, v)))
    return pd.DataFrame(rows)


def unique_points(table: pd.DataFrame) -> pd.DataFrame:
    """One row per DEM case (the base point appears on every axis)."""
    cols = ["point", "seed", *AXES]
    return table[cols].drop_duplicates("point").reset_index(drop=True)


# --- cost estimate ----------------------------------------------------------

def estimate(config: dict) -> pd.DataFrame:
    """Per DEM case of the study: disks, shear steps and estimated one-thread seconds of pack + shear.

    est_core_s = N (pack_steps + steps) / throughput(N), steps = steps_per_strain (preshear + heaviside strain),
    the cost model of ``campaign.cost`` at the documented throughput of the config's engine.
    """
    acc = config["accuracy"]
    strain = acc["preshear_strain"] + acc["heaviside_strain"]
    mat, pack = config["material"], config.get("pack", {})
    kw = dict(guess=pack.get("solid_fraction_guess", 0.8),
              size_min=mat["size_ratio_min"], size_max=mat["size_ratio_max"])
    pts = unique_points(expand(acc))
    W = config["cell"]["W_over_H"]
    pts["N"] = [cost.n_disks(h, W, **kw) for h in pts["H_over_d"]]
    pts["steps"] = [cost.steps_per_strain(k, i, f) * strain
                    for k, i, f in zip(pts["kappa"], pts["inertial_number"], pts["dt_over_tc"])]
    rate = cost.documented(cost.engine_of(config))
    pts["est_core_s"] = [cost.core_seconds(n, steps + cost.pack_steps(k, f), rate)
                         for n, steps, k, f in zip(pts["N"], pts["steps"], pts["kappa"], pts["dt_over_tc"])]
    return pts


# --- scenes -------------------------------------------------------------------

def point_config(config: dict, setting: dict) -> dict:
    """A copy of the campaign config with the point's setting and the study's protocol."""
    acc = config["accuracy"]
    cfg = copy.deepcopy(config)
    for axis, (section, key, _) in AXES.items():
        if section != "loading":
            cfg.setdefault(section, {})[key] = float(setting[axis])
    cfg["preshear"] = {**cfg.get("preshear", {}), "strain": float(acc["preshear_strain"])}
    cfg["protocols"] = {"heaviside": {"strain": float(acc["heaviside_strain"])}}
    return cfg


def point_scene(config: dict, point: str) -> dict:
    """The scene file of one study point (by its name)."""
    pts = unique_points(expand(config["accuracy"]))
    row = pts[pts["point"] == point]
    if row.empty:
        raise ValueError(f"no study point named {point!r}")
    row = row.iloc[0].to_dict()
    cfg = point_config(config, row)
    case = dict(pressure=float(config["loading"]["pressures"][0]),
                inertial_number=float(row["inertial_number"]), seed=int(row["seed"]))
    scene = scene_from_config(cfg, case, point)
    scene["meta"]["study"] = "accuracy"
    return scene
