"""The bulk-vs-walls study's DEM cases: which cells, their scenes and their cost.

Config block ``accuracy.bulk_vs_walls`` (``workflow/schemas/config.schema.yaml``):
named cells (``kind``, ``H_over_d``, ``W_over_H``), each run with every seed
(or the cell's own ``seeds``) through pack -> preshear -> heaviside under
``<results>/accuracy/bulk/<cell>_s<seed>/``; a cell with ``train: {every,
reversals}`` runs, in place of the one Heaviside reversal, a reversal train
(stage ``train``: a Heaviside reversal every ``every`` strain, ``reversals``
times, docs/scene.md) whose transients the analysis averages per seed. A case's scene is the campaign's
(``campaign.scenes.scene_from_config``) with the cell, kappa, the inertial
number and the study's strains changed; pressure, the rest of the material,
the time step and the sampling stay the campaign's.

Disks in a cell (``yade_scripts/scene.py``), with <D^2> of diameters uniform in
[min, max] d,

    N = round(guess W H_grains / (pi <D^2> / 4)),
    H_grains = H - d (wall cell: between the walls' centre lines, less d), H (periodic cell),

so N = 0.86 H W / d^2 for the wall cell at H = 12 d and N = 0.94 H W / d^2 for a
periodic cell (guess 0.8, sizes 0.5-1.5 d).
"""
from __future__ import annotations

import copy
import re

import pandas as pd

from campaign import cost
from campaign.schema_defaults import block_defaults
from campaign.scenes import scene_from_config

NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9-]*$")
SEP = "_s"
CELL_KEYS = ("kind", "H_over_d", "W_over_H", "mass", "contact_law", "train", "seeds")
TRAIN_STAGE = "train"
PERIODIC_MAX_W_OVER_H = 1.1


def settings(config: dict) -> dict:
    """The study's block with the schema's defaults filled in (``campaign.schema_defaults``)."""
    return {**block_defaults("accuracy", "bulk_vs_walls"), **(config.get("accuracy") or {}).get("bulk_vs_walls", {})}


def enabled(config: dict) -> bool:
    return bool(settings(config)["run"])


def reversal_stage(spec: dict) -> str:
    """The reversal stage a cell runs after its pre-shear: ``heaviside``, or ``train`` for a cell with a train."""
    return TRAIN_STAGE if spec.get("train") else "heaviside"


def reversal_strain(spec: dict, settings_: dict) -> float:
    """Strain sheared after the pre-shear: the study's ``heaviside_strain``, or ``every`` x ``reversals``."""
    train = spec.get("train")
    return float(train["every"]) * int(train["reversals"]) if train else float(settings_["heaviside_strain"])


def case_label(cell: str, seed: int) -> str:
    return f"{cell}{SEP}{int(seed)}"


def split_label(label: str) -> tuple[str, int]:
    """``'W4H-H37_s2'`` -> ``('W4H-H37', 2)``."""
    cell, sep, seed = label.rpartition(SEP)
    if not sep or not seed.isdigit():
        raise ValueError(f"{label!r} is not a bulk-study case label (<cell>{SEP}<seed>)")
    return cell, int(seed)


def n_disks(kind: str, H_over_d: float, W_over_H: float, guess: float = 0.8,
            size_min: float = 0.5, size_max: float = 1.5) -> int:
    """Disks of a cell (module docstring): ``campaign.cost.n_disks`` of the cell's kind."""
    return cost.n_disks(H_over_d, W_over_H, guess, size_min, size_max, kind)


def _disk_kwargs(config: dict) -> dict:
    mat = config["material"]
    return dict(guess=config.get("pack", {}).get("solid_fraction_guess", 0.8),
                size_min=mat["size_ratio_min"], size_max=mat["size_ratio_max"])


def cases(config: dict) -> pd.DataFrame:
    """One row per DEM case: ``case``, ``cell``, ``seed``, the cell's keys, ``N``, ``reference``, ``tall``,
    ``stage`` (``reversal_stage``) and ``reversals`` (transients the case yields).

    ``reference``: the cell is one of ``references`` (the W = 4H wall cells the
    others are compared with); ``tall``: the cell is ``tall_reference`` (the
    paper's cell, the denominator of the information-per-core-hour ratio).
    """
    s = settings(config)
    refs = set(s.get("references", []))
    rows = []
    for cell, spec in s["cells"].items():
        n = n_disks(spec.get("kind", "walls"), spec["H_over_d"], spec["W_over_H"], **_disk_kwargs(config))
        for seed in spec.get("seeds", s["seeds"]):
            rows.append(dict(case=case_label(cell, seed), cell=cell, seed=int(seed),
                             kind=spec.get("kind", "walls"), H_over_d=float(spec["H_over_d"]),
                             W_over_H=float(spec["W_over_H"]), W_over_d=float(spec["W_over_H"] * spec["H_over_d"]),
                             N=n, reference=cell in refs, tall=cell == s.get("tall_reference"),
                             stage=reversal_stage(spec), reversals=int((spec.get("train") or {}).get("reversals", 1))))
    return pd.DataFrame(rows)


def problems(config: dict) -> list[str]:
    """What the schema cannot see, one line each naming the key; empty when the study may run."""
    s = settings(config)
    key = "accuracy.bulk_vs_walls"
    out = []
    cells = s.get("cells") or {}
    for name, spec in cells.items():
        if not NAME.match(name):
            out.append(f"config error: {key}.cells.{name}: a cell name must be letters, digits and '-' "
                       "(it names the case folders <cell>_s<seed>)")
        if spec.get("kind", "walls") == "periodic" and spec["W_over_H"] > PERIODIC_MAX_W_OVER_H:
            out.append(f"config error: {key}.cells.{name}.W_over_H = {spec['W_over_H']:g}: too wide for a "
                       f"periodic cell (allowed: at most {PERIODIC_MAX_W_OVER_H})")
        train = spec.get("train")
        if train and float(train["every"]) < s["heaviside_strain"]:
            out.append(f"config error: {key}.cells.{name}.train.every = {train['every']:g}: must be at least "
                       f"{key}.heaviside_strain = {s['heaviside_strain']:g} (each transient is compared over it)")
        if train and name in s.get("references", []):
            out.append(f"config error: {key}.cells.{name}.train: a reference cell runs the one Heaviside reversal")
        if spec.get("kind", "walls") == "walls" and "mass" in spec:
            out.append(f"config error: {key}.cells.{name}.mass: a wall cell has no cell mass (periodic cells only)")
    for ref in s.get("references", []):
        if ref not in cells:
            out.append(f"config error: {key}.references: {ref!r} is not a cell of {key}.cells "
                       f"(allowed: {', '.join(cells)})")
    tall = s.get("tall_reference")
    if tall is not None and tall not in s.get("references", []):
        out.append(f"config error: {key}.tall_reference = {tall!r}: not one of {key}.references")
    if s["steady_window"] >= s["preshear_strain"]:
        out.append(f"config error: {key}.steady_window = {s['steady_window']:g}: must be below "
                   f"{key}.preshear_strain = {s['preshear_strain']:g}")
    if s["early_strain"] > s["heaviside_strain"]:
        out.append(f"config error: {key}.early_strain = {s['early_strain']:g}: must be at most "
                   f"{key}.heaviside_strain = {s['heaviside_strain']:g}")
    if not out:
        out += scene_problems(config)
    return out


def scene_problems(config: dict) -> list[str]:
    """Each cell's scene (first seed) through the DEM's own validator (yade_scripts/scene.py), naming the cell."""
    from campaign.scene_spec import scene_module

    module = scene_module()
    s = settings(config)
    out = []
    for cell in s["cells"]:
        try:
            module.validate(case_scene(config, case_label(cell, s["seeds"][0])))
        except module.SceneError as exc:
            out.append(f"config error: accuracy.bulk_vs_walls.cells.{cell}: the scene: "
                       f"{str(exc).removeprefix('scene error: ')}")
    return out


def case_config(config: dict, cell: str) -> dict:
    """A copy of the campaign config with the cell, kappa, pack overrides and the study's protocol."""
    s = settings(config)
    spec = s["cells"][cell]
    cfg = copy.deepcopy(config)
    cfg["cell"] = {k: spec[k] for k in ("kind", "H_over_d", "W_over_H", "mass") if k in spec}
    cfg["material"] = {**cfg["material"], "kappa": float(s["kappa"])}
    if "contact_law" in spec:
        cfg["material"]["contact_law"] = spec["contact_law"]
    elif spec.get("kind", "walls") == "periodic":
        cfg["material"].pop("contact_law", None)   # the periodic cell's own (and only) law
    cfg["pack"] = {**cfg.get("pack", {}), **s.get("pack", {})}
    cfg["preshear"] = {**cfg.get("preshear", {}), "strain": float(s["preshear_strain"])}
    train = spec.get("train")
    if train:
        cfg["protocols"] = {TRAIN_STAGE: {"train": {"every": float(train["every"]), "reversals": int(train["reversals"]),
                                                    "transition": "heaviside"}}}
    else:
        cfg["protocols"] = {"heaviside": {"strain": float(s["heaviside_strain"])}}
    return cfg


def case_scene(config: dict, label: str) -> dict:
    """The scene file of one case of the study (by its label ``<cell>_s<seed>``)."""
    cell, seed = split_label(label)
    s = settings(config)
    if cell not in s["cells"]:
        raise ValueError(f"no cell named {cell!r} in accuracy.bulk_vs_walls.cells")
    case = dict(pressure=float(config["loading"]["pressures"][0]),
                inertial_number=float(s["inertial_number"]), seed=seed)
    scene = scene_from_config(case_config(config, cell), case, label)
    scene["meta"]["study"] = "bulk_vs_walls"
    return scene


def estimate(config: dict) -> pd.DataFrame:
    """Per case: disks, steps and estimated one-thread seconds (``campaign.cost``, the documented throughput
    of the config's engine).

    seconds = N (pack_steps + steps_per_strain (preshear + reversal strain)) / throughput(N)

    (the reversal strain: ``reversal_strain``, the train's for a cell with one).
    """
    s = settings(config)
    table = cases(config)
    dt = config["timestep"]["dt_over_tc"]
    strain = s["preshear_strain"] + table["cell"].map(lambda c: reversal_strain(s["cells"][c], s))
    table["steps"] = cost.steps_per_strain(s["kappa"], s["inertial_number"], dt) * strain + cost.pack_steps(s["kappa"], dt)
    rate = cost.documented(cost.engine_of(config))
    table["est_core_s"] = [cost.core_seconds(n, steps, rate) for n, steps in zip(table["N"], table["steps"])]
    return table
