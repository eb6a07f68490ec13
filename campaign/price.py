"""A campaign's price before it runs: its DEM stages' projected core-seconds, wall times and what drives them.

Every DEM stage of every case is priced by the cost model (``campaign.cost``) at the throughput of
the campaign's engine (config ``engine``: YADE or LAMMPS) measured by the campaign's own earlier runs
of that engine (the sidecars in ``<results_dir>/dem/``) or, with none, at that engine's documented one.
A case the config restores from a data release (config ``release:``, docs/data-release.md) runs no DEM
and costs nothing. Then

    core-hours = sum of the stages' seconds / 3600,
    wall time on C cores = campaign.schedule.chain_makespan (the cases' chains on C cores),
    cluster wall time = campaign.schedule.longest_chain (one core per job),

and, against the quick preset (config/quick.yaml), the setting whose ratio to the preset's is
largest (``cost_drivers``): the slowest inertial number, kappa, the cell's disks, the time step,
the strain per case, or the number of cases. ``price_lines`` are what the pre-flight check prints
(``preflight``), ``python -m campaign estimate`` prints the table.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from dem_contract.release import CASES_DIR, released_cases

from .cases import cases
from .configfile import load_configfile
from .cost import (ENGINE_NAMES, Throughput, core_seconds, documented_throughput, engine_of, measured_throughput,
                   scene_disks, scene_stages, scene_throughput, scene_value, stage_steps, stage_strain)
from .scenes import result_key, scene_from_config
from .schedule import chain_makespan, longest_chain

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "config" / "quick.yaml"
#: Above this wall time on the cores given, the price says so and names what drives it.
THRESHOLD_H = 1.0


def campaign_scenes(config: dict) -> dict:
    """Case label -> the scene the campaign writes for it (``campaign.scenes.scene_from_config``)."""
    return {label: scene_from_config(config, case, label) for label, case in cases(config).items()}


def restored_cases(config: dict, scenes: dict, root=ROOT) -> dict:
    """Case label -> release folder, for the cases the workflow restores rather than runs
    (workflow/rules/release.smk: released with every protocol, from the scene this config makes)."""
    if not config.get("release"):
        return {}
    out = {}
    for label, folder in released_cases(config["release"], list(config["protocols"]), root).items():
        if label in scenes:
            released = json.loads((Path(folder) / CASES_DIR / label / "sidecars" / "scene.json").read_text())
            if result_key(released) == result_key(scenes[label]):
                out[label] = folder
    return out


def stage_table(scenes: dict, throughput: Throughput | None = None, restored=()) -> pd.DataFrame:
    """One row per DEM stage of every case: case, stage, N, steps, core_s (projected one-thread seconds at
    ``throughput``, or at the documented one of each scene's engine when None: ``campaign.cost.scene_throughput``),
    throughput (``measured``, ``documented``, or ``restored`` for a case restored from a release: 0 s)."""
    rows = []
    for label, scene in scenes.items():
        n, rate = scene_disks(scene), scene_throughput(scene, throughput)
        for stage in scene_stages(scene):
            steps = stage_steps(scene, stage)
            rows.append(dict(case=label, stage=stage, N=n, steps=int(round(steps)),
                             core_s=0.0 if label in restored else core_seconds(n, steps, rate),
                             throughput="restored" if label in restored else
                             "measured" if rate.measured else "documented"))
    return pd.DataFrame(rows, columns=["case", "stage", "N", "steps", "core_s", "throughput"])


def case_seconds(table: pd.DataFrame) -> dict:
    """case -> {stage: seconds} of the stages that run (``campaign.schedule``'s input)."""
    out = {}
    for row in table.itertuples():
        if row.throughput != "restored":
            out.setdefault(row.case, {})[row.stage] = row.core_s
    return out


@dataclass
class Price:
    """The price of a campaign's DEM (module docstring); seconds are one-thread (core) seconds."""

    campaign: str
    table: pd.DataFrame
    throughput: Throughput
    cores: int
    restored: dict = field(default_factory=dict)
    drivers: list = field(default_factory=list)

    @property
    def core_s(self) -> float:
        return float(self.table["core_s"].sum())

    @property
    def wall_s(self) -> float:
        return chain_makespan(case_seconds(self.table), self.cores)

    @property
    def cluster_s(self) -> float:
        return longest_chain(case_seconds(self.table))

    @property
    def n_run(self) -> int:
        return self.table.loc[self.table["throughput"] != "restored", "case"].nunique()


def price(config: dict, cores: int = 2, root=ROOT, reference=QUICK) -> Price:
    """The price of the campaign of ``config`` (its schema defaults filled in, as the Snakefile holds it after
    ``validate``) on ``cores``, against ``reference``."""
    scenes = campaign_scenes(config)
    restored = restored_cases(config, scenes, root)
    throughput = measured_throughput(config.get("results_dir", "results"), exclude=restored, engine=engine_of(config))
    ref = load_configfile(reference)
    return Price(str(config.get("campaign", "")), stage_table(scenes, throughput, restored), throughput, int(cores),
                 restored, cost_drivers(scenes, campaign_scenes(ref)))


# --- what drives the cost ---------------------------------------------------------------

def _num(x: float) -> str:
    """3 significant digits, a short exponent: 6.04e-05 -> '6.04e-5', 1e+05 -> '1e5'."""
    text = f"{x:.3g}"
    mantissa, _, exp = text.partition("e")
    return f"{mantissa}e{int(exp)}" if exp else text


def _times(r: float) -> str:
    return f"{r:.0f}" if r >= 10 else f"{r:.2g}"


def _settings(scenes: dict) -> pd.DataFrame:
    """Per scene, the settings the cost grows with: I, kappa, dt_over_tc, N, the cost of a step
    N / T(N) (T the documented throughput of the scene's engine) and the strain sheared (pre-shear and
    reversal runs)."""
    return pd.DataFrame([dict(I=s["loading"]["inertial_number"], kappa=s["material"]["kappa"],
                              dt=scene_value(s, "timestep", "dt_over_tc"), N=scene_disks(s),
                              per_step=scene_disks(s) / documented_throughput(scene_disks(s), engine_of(s)),
                              strain=sum(stage_strain(s, k) for k in scene_stages(s) if k != "pack"))
                         for s in scenes.values()])


def cost_drivers(scenes: dict, reference: dict) -> list[tuple[float, str]]:
    """(ratio, text) per setting, the largest first: how many times the campaign's costliest value of
    the setting costs the reference's (the quick preset's) cheapest.

    ratios: I_ref / I (steps per strain grow as 1/I), sqrt(kappa / kappa_ref), dt_ref / dt,
    (N / T(N)) / (N_ref / T(N_ref)) (the cost of a step, T the documented throughput of each one's engine),
    strain / strain_ref (per case), cases / cases_ref.
    """
    c, r = _settings(scenes), _settings(reference)
    cell, cell_ref = c.loc[c["per_step"].idxmax()], r.loc[r["per_step"].idxmin()]
    out = [
        (r["I"].max() / c["I"].min(), f"the inertial number {_num(c['I'].min())}, {{x}} times slower than "
                                      f"the quick preset's {_num(r['I'].max())}"),
        (math.sqrt(c["kappa"].max() / r["kappa"].min()),
         f"kappa {_num(c['kappa'].max())}, {{x}} times slower than the quick preset's {_num(r['kappa'].min())} "
         "(steps grow as sqrt(kappa))"),
        (r["dt"].max() / c["dt"].min(), f"the time step {_num(c['dt'].min())} t_c, {{x}} times slower than the "
                                        f"quick preset's {_num(r['dt'].max())} t_c"),
        (cell["per_step"] / cell_ref["per_step"], f"the cell of {int(cell['N'])} disks, {{x}} times slower per "
                                                  f"step than the quick preset's {int(cell_ref['N'])}"),
        (c["strain"].max() / r["strain"].min(), f"the strain per case {_num(c['strain'].max())}, {{x}} times the "
                                                f"quick preset's {_num(r['strain'].min())}"),
        (len(c) / len(r), f"{len(c)} DEM cases, {{x}} times the quick preset's {len(r)}"),
    ]
    return sorted(((float(ratio), text.format(x=_times(ratio))) for ratio, text in out), key=lambda t: -t[0])


# --- the lines the pre-flight check prints ---------------------------------------------------

def duration(seconds: float) -> str:
    """A wall time for people: '40 s', '25 min', '2.3 h'."""
    if seconds < 100:
        return f"{seconds:.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def price_lines(p: Price, threshold_h: float = THRESHOLD_H, root=ROOT) -> list[str]:
    """One line for the campaign; a second one above ``threshold_h`` on the cores given, naming what drives it."""
    name = f"campaign {p.campaign}" if p.campaign else "the campaign"
    releases = ", ".join(sorted({_shown(folder, root) for folder in p.restored.values()}))
    if p.n_run == 0:
        return [f"price: {name}: all {plural(len(p.restored), 'DEM case')} restored from the release {releases}: "
                "no DEM to run, no DEM cost"]
    restored = f" ({len(p.restored)} more restored from {releases}, at no cost)" if p.restored else ""
    lines = [f"price: {name}: {plural(p.n_run, 'DEM case')}{restored}, {p.core_s / 3600:.2g} core-hours, about "
             f"{duration(p.wall_s)} on {plural(p.cores, 'core')}, {duration(p.cluster_s)} on a cluster with one core "
             f"per job ({ENGINE_NAMES[p.throughput.engine]}'s throughput: "
             f"{'measured' if p.throughput.measured else 'documented'})"]
    if p.wall_s > threshold_h * 3600:
        lines.append(f"price: {name} takes more than {threshold_h:g} h on {plural(p.cores, 'core')}; what drives "
                     f"the cost: {p.drivers[0][1]} (each stage: python -m campaign estimate --configfile ...)")
    return lines


def _shown(folder, root) -> str:
    """A release folder as the config names it: relative to the repository when inside it."""
    path = Path(folder)
    return str(path.relative_to(root)) if path.is_relative_to(root) else str(path)
