"""The cost model of the DEM, in one place: a stage's steps, its disks and its one-thread seconds.

A stage of a scene (docs/scene.md) runs on ``N`` disks for ``steps`` time steps and costs

    seconds = N steps / throughput_engine(N),   throughput_engine(N) = factor x DOCUMENTED[engine](N)

of one thread (the engine's throughput: below), where

    steps = strain / (gammadot dt) = strain sqrt(4 kappa / pi) / (I dt_over_tc)     (pre-shear, a reversal run)
    steps = PACK_TIME sqrt(4 kappa / pi) / dt_over_tc                               (the pack)

(dt = dt_over_tc sqrt(m_d / kn) = dt_over_tc sqrt(pi / (4 kappa)) d sqrt(rho / p), gammadot = I sqrt(p / rho) / d;
``strain``: the stage's strain at full rate, a schedule's the sum of its segments'), and

    N = round(guess W H_grains / (pi <D^2> / 4)),   <D^2> = d^2 (a^2 + a b + b^2) / 3,

the count yade_scripts/scene.py ``derived`` makes: diameters uniform in [a, b] d (a = b: <D^2> = d^2 a^2),
``guess`` = pack.solid_fraction_guess, W = W_over_H H, H_grains = H - d between the walls, H in a periodic cell.

The throughput, particle-steps per CPU second of the scene's engine on one thread (its ``engine``
key: YADE when absent, or LAMMPS), is that engine's documented figure (``DOCUMENTED[engine]``,
interpolated log-log in N; LAMMPS's is LAMMPS_OVER_YADE = 3.5 times YADE's) times a factor: 1 for
the documented figure itself, or the one measured on this machine from the sidecars of that
engine's earlier runs (``measured_throughput``). A ``Throughput`` says which engine and which
factor; a scene is never priced at the other engine's (``scene_throughput``).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from dem_contract import sidecar_engine

from .scene_spec import protocol_strain, scene_default, scene_module

#: The DEM engines a scene may name (yade_scripts/scene.py ``ENGINES``), as a price names them.
ENGINE_NAMES = {"yade": "YADE", "lammps": "LAMMPS"}
# Throughput of YADE 2023.02a on one thread, particle-steps/s, at 500 and 5,000 disks;
# interpolated log-log in N, held constant outside. 500 disks: the `particle_steps_per_s` of the
# quick campaign's sidecars (496 disks, kappa 1e3, 2 cores with two YADE jobs side by side) read
# 2.2-2.5 M; we take 2.3 M. 5,000 disks: 0.8 M (python3 tools/benchmark.py, docs/findings.md
# "YADE's throughput").
YADE_DOCUMENTED = ((500, 2.3e6), (5000, 0.8e6))
# LAMMPS's (the project's stage, lammps_scripts/run_stage.py, one rank): YADE's curve times
# LAMMPS_OVER_YADE. docs/findings.md "LAMMPS's stage against YADE's": at 626 disks the paired
# stages gave 4.6-5.1 (4.6-6.2 with an earlier pair), LAMMPS's stage 7.99-8.09 M particle-steps
# per CPU second on a loaded machine. A ratio, because only the ratio was measured paired: the
# absolute figures move with the machine's load (YADE's stage 1.2-1.75 M there, 3.6 M in issue
# 36's trial). 3.5, below every paired ratio, so that a price errs long (a Slurm limit too short
# stops the job): 3.5 x 2.07 M = 7.3 M at 626 disks, under the stage's measured 7.99 M too. At
# 5,000 disks the stage was not measured: YADE's fall in N is kept, 2.8 M, far under bare LAMMPS's
# 19 M at 5,296 disks in issue 36's trial (LAMMPS's cost per particle-step hardly grows with N).
LAMMPS_OVER_YADE = 3.5
DOCUMENTED = {"yade": YADE_DOCUMENTED,
              "lammps": tuple((n, LAMMPS_OVER_YADE * rate) for n, rate in YADE_DOCUMENTED)}
DOCUMENTED_SOURCE = {
    "yade": "the documented figure (YADE 2023.02a: 2.3 M particle-steps/s at 500 disks, 0.8 M at 5,000)",
    "lammps": "the documented figure (LAMMPS, 3.5 x YADE's: 8.05 M particle-steps/s at 500 disks, 2.8 M at 5,000)",
}
# Pack: simulated time to converge, in d sqrt(rho/p), with the damped, quenched packing
# (docs/scene.md "Packing"), measured 2026-11-23 at kappa = 1e3, dt = 0.1 t_c, ke_max 1e-4: 44-61
# for 2,000 disks (wall and periodic cells), 89-99 for the 5,010-disk paper cell. The largest is
# assumed for every setting; the narrow cell at dt = 0.3 t_c packed in 91-141 at kappa 1e3, 49-77 at
# 1e4 and 43-51 at 1e5 (docs/findings.md, "The cost model against measured runs").
PACK_TIME = 100.0
#: Stages every case runs before its reversal runs.
BASE_STAGES = ("pack", "preshear")
#: Reversal protocols with a scene section of their own; every other one is in the scene's ``schedules``.
FIXED_PROTOCOLS = ("heaviside", "sinusoidal")
#: What a sidecar must record to count as a measurement of the throughput.
SIDECAR_KEYS = ("N", "steps", "cpu_time_s")


def engine_of(spec: dict) -> str:
    """The DEM engine of a scene or of a campaign config: its ``engine`` key, yade when absent
    (yade_scripts/scene.py ``engine``; campaign.scenes copies the config's into each scene)."""
    return scene_module().engine(spec)


def documented_throughput(n: float, engine: str = "yade") -> float:
    """Particle-steps per second of ``engine`` at ``n`` disks from ``DOCUMENTED``: log-log between its two points,
    constant outside.

    log T(n) = log T0 + f log(T1 / T0),   f = clip(log(n / n0) / log(n1 / n0), 0, 1).
    """
    (n0, r0), (n1, r1) = DOCUMENTED[engine]
    f = min(max(math.log(n / n0) / math.log(n1 / n0), 0.0), 1.0)
    return math.exp(math.log(r0) + f * math.log(r1 / r0))


@dataclass(frozen=True)
class Throughput:
    """One engine's one-thread throughput: ``factor`` times its documented figure, and where that factor comes from.

    ``factor`` is 1 for the documented figure; a measured one is the CPU time the documented figure
    projects for the sidecars read over their measured CPU time (``measured_throughput``).
    """

    factor: float = 1.0
    source: str = DOCUMENTED_SOURCE["yade"]
    sidecars: tuple = field(default=(), repr=False)
    engine: str = "yade"

    @property
    def measured(self) -> bool:
        return bool(self.sidecars)

    def __call__(self, n: float) -> float:
        """Particle-steps per CPU second at ``n`` disks: factor x documented_throughput(n, engine)."""
        return self.factor * documented_throughput(n, self.engine)


#: engine -> its documented throughput (factor 1).
DOCUMENTED_THROUGHPUTS = {engine: Throughput(source=DOCUMENTED_SOURCE[engine], engine=engine) for engine in DOCUMENTED}
DOCUMENTED_THROUGHPUT = DOCUMENTED_THROUGHPUTS["yade"]


def documented(engine: str = "yade") -> Throughput:
    """The documented throughput of ``engine`` (``DOCUMENTED_THROUGHPUTS``)."""
    return DOCUMENTED_THROUGHPUTS[engine]


def scene_throughput(scene: dict, throughput: Throughput | None = None) -> Throughput:
    """The throughput a scene is priced at: ``throughput``, or its engine's documented one when None.

    Raises
    ------
    ValueError
        When ``throughput`` is another engine's than the scene's.
    """
    engine = engine_of(scene)
    if throughput is None:
        return documented(engine)
    if throughput.engine != engine:
        raise ValueError(f"a {ENGINE_NAMES[engine]} scene priced at {ENGINE_NAMES[throughput.engine]}'s throughput")
    return throughput


def read_cost_sidecars(paths) -> list[tuple[Path, dict]]:
    """The sidecars among ``paths`` that record a stage's cost: (path, its dict) for each JSON file
    holding positive ``N``, ``steps`` and ``cpu_time_s`` (other JSON files of a case folder, a contact
    census for instance, are skipped)."""
    out = []
    for path in sorted(map(Path, paths)):
        try:
            side = json.loads(path.read_text())
        except (OSError, ValueError):
            continue
        if isinstance(side, dict) and all(isinstance(side.get(k), (int, float)) and side[k] > 0
                                          for k in SIDECAR_KEYS):
            out.append((path, side))
    return out


def measured_throughput(results_dir, folder: str = "dem", exclude=(), engine: str = "yade") -> Throughput:
    """The throughput of ``engine`` measured by the earlier runs of ``<results_dir>/<folder>/*/*.json``, else its
    documented one.

    ``exclude``: case folders not to read (cases restored from a data release: their CPU time was
    measured where the release was made). Only the sidecars of ``engine``'s stages count
    (``dem_contract.sidecar_engine``: their ``engine`` key; one without it was written by YADE).

    factor = sum_i (N_i steps_i / documented_throughput(N_i, engine)) / sum_i cpu_time_s_i

    over the stage sidecars found (``read_cost_sidecars``): the documented curve's shape in N,
    scaled to this machine (at a single N, factor x documented(N) = sum N steps / sum cpu_time_s).
    Only the shear stages' when there are any: they are most of a campaign's cost, and a pack
    runs faster per particle-step (4.1 M against 2.9 M at kappa 1e5 on the narrow cell).
    """
    where = Path(results_dir) / folder
    read = read_cost_sidecars(p for p in where.glob("*/*.json") if p.parent.name not in set(exclude))
    found = [(p, s) for p, s in read if sidecar_engine(s) == engine]
    shear = [(p, s) for p, s in found if s.get("stage", p.stem) != "pack"]
    found, packs = (shear, "") if shear else (found, " (packs only)")
    if not found:
        return documented(engine)
    projected = sum(s["N"] * s["steps"] / documented_throughput(s["N"], engine) for _, s in found)
    cpu = sum(s["cpu_time_s"] for _, s in found)
    disks = sorted({int(s["N"]) for _, s in found})
    rate = sum(s["N"] * s["steps"] for _, s in found) / cpu
    at = f"{disks[0]}" if len(disks) == 1 else f"{disks[0]}-{disks[-1]}"
    cases = len({p.parent for p, _ in found})
    source = (f"measured on this machine: {len(found)} stage sidecars{packs} of {cases} case{'s' * (cases != 1)} "
              f"in {where}, {rate / 1e6:.2g} M particle-steps per CPU second of {ENGINE_NAMES[engine]} at {at} disks")
    return Throughput(projected / cpu, source, tuple(str(p) for p, _ in found), engine)


# --- a stage's steps and disks -------------------------------------------------------

def mean_d2(size_min: float, size_max: float) -> float:
    """<D^2> / d^2 of diameters uniform in [size_min, size_max] d: (a^2 + a b + b^2) / 3 (a^2 when a = b)."""
    return (size_min**2 + size_min * size_max + size_max**2) / 3


def n_disks(H_over_d: float, W_over_H: float, guess: float = 0.8, size_min: float = 0.5, size_max: float = 1.5,
            kind: str = "walls") -> int:
    """Disks of a cell, as yade_scripts/scene.py counts them (module docstring):
    N = round(guess W H_grains / (pi <D^2> / 4)), H_grains = H - d (walls) or H (periodic), in d."""
    H_grains = H_over_d if kind == "periodic" else H_over_d - 1
    return round(guess * W_over_H * H_over_d * H_grains / (math.pi * mean_d2(size_min, size_max) / 4))


def steps_per_strain(kappa: float, inertial_number: float, dt_over_tc: float) -> float:
    """1 / (gammadot dt) = sqrt(4 kappa / pi) / (I dt_over_tc): time steps per unit of strain."""
    return math.sqrt(4 * kappa / math.pi) / (inertial_number * dt_over_tc)


def pack_steps(kappa: float, dt_over_tc: float, pack_time: float = PACK_TIME) -> float:
    """PACK_TIME sqrt(4 kappa / pi) / dt_over_tc: the pack's projected steps (T0 / dt per time unit)."""
    return pack_time * math.sqrt(4 * kappa / math.pi) / dt_over_tc


def scene_value(scene: dict, section: str, key: str):
    """A scene value, or the default the DEM takes when the scene leaves it out (yade_scripts/scene.py SPEC)."""
    value = (scene.get(section) or {}).get(key)
    return scene_default(section, key) if value is None else value


def scene_disks(scene: dict) -> int:
    """N of a scene (``n_disks`` of its geometry, material, pack and cell kind)."""
    mat, geo = scene["material"], scene["geometry"]
    return n_disks(geo["H_over_d"], geo["W_over_H"], scene_value(scene, "pack", "solid_fraction_guess"),
                   mat["size_ratio_min"], mat["size_ratio_max"], (scene.get("cell") or {}).get("kind", scene_default("cell", "kind")))


def reversal_stages(scene: dict) -> list[str]:
    """The reversal runs of a scene after its pre-shear: heaviside, sinusoidal, then its schedules, in order."""
    return [k for k in scene if k in FIXED_PROTOCOLS] + list(scene.get("schedules") or {})


def scene_stages(scene: dict) -> list[str]:
    """Every DEM stage of a scene, in the order they run: pack, pre-shear, the reversal runs."""
    return [*BASE_STAGES, *reversal_stages(scene)]


def stage_strain(scene: dict, stage: str) -> float:
    """Strain at full rate a shear stage runs: the pre-shear's, heaviside's or sinusoidal's ``strain``,
    a schedule's the sum of its segments' (campaign.scene_spec.protocol_strain)."""
    if stage in ("preshear", *FIXED_PROTOCOLS):
        return float(scene[stage]["strain"])
    return protocol_strain(stage, scene["schedules"][stage])


def stage_steps(scene: dict, stage: str) -> float:
    """Projected time steps of one stage of ``scene`` (module docstring; the pack at most its ``max_time``)."""
    kappa, dt_over_tc = scene["material"]["kappa"], scene_value(scene, "timestep", "dt_over_tc")
    if stage == "pack":
        return pack_steps(kappa, dt_over_tc, min(PACK_TIME, scene_value(scene, "pack", "max_time")))
    return math.ceil(stage_strain(scene, stage) * steps_per_strain(kappa, scene["loading"]["inertial_number"],
                                                                    dt_over_tc))


def stage_seconds(scene: dict, stage: str, throughput: Throughput | None = None) -> float:
    """Projected one-thread seconds of one stage of ``scene``: N steps / throughput(N), at ``throughput`` or,
    when None, the documented one of the scene's engine (``scene_throughput``)."""
    return core_seconds(scene_disks(scene), stage_steps(scene, stage), scene_throughput(scene, throughput))


def core_seconds(n: float, steps: float, throughput: Throughput = DOCUMENTED_THROUGHPUT) -> float:
    """N steps / throughput(N): one-thread seconds of ``steps`` time steps on ``n`` disks."""
    return n * steps / throughput(n)
