# Runtime (minutes) and memory (MB) of every rule, for a cluster (profiles/slurm)
# and anywhere else resources are enforced. Each rule sets its own, so a
# `--default-resources ...` on the command line (which replaces the profile's
# whole default-resources block) cannot strip them.
#
# DEM stages: the projected one-thread seconds of the stage (campaign/cost.py, the one cost
# model: N * steps / throughput(N) from the scene's kappa, I, dt_over_tc, strain and pack time),
# at the documented throughput of the scene's engine (its `engine`, the config's: YADE's, or
# LAMMPS's, 3.5 times it), not this machine's: a cluster node is not this machine, and
# DEM_SAFETY was measured against the documented figure,
#     runtime = ceil(attempt * (DEM_SAFETY * seconds / 60 + DEM_OVERHEAD_MIN)).
# Measured on the quick preset (496 disks, two YADE jobs on 2 shared cores): the
# stages took 0.7-2.1 times this estimate; DEM_SAFETY = 3 covers that and a
# slower node. A LAMMPS stage is one job like a YADE stage, and LAMMPS's documented
# figure is below what its stage measured (campaign/cost.py), so DEM_SAFETY holds for
# it too. A stage stopped at its limit checkpoints and exits (docs/scene.md);
# Snakemake's retry (profile `retries`) resubmits it with `attempt` + 1, so a
# longer limit, and it resumes from the checkpoint.
# Memory: 253 MB peak RSS measured at 496 disks (YADE + Python); taken as
# 250 MB + 50 kB per disk, times DEM_MEM_SAFETY, at least 1000 MB.
import math
from collections import namedtuple

from campaign.cost import scene_disks, scene_stages
from campaign.cost import stage_seconds as dem_seconds
from campaign.schedule import after_seconds, longest_chain

DEM_SAFETY = 3.0
DEM_OVERHEAD_MIN = 2.0  # the engine's start, loading a state, writing outputs
DEM_MEM_SAFETY = 2.0


def _scene_of(wc):
    """The scene dict of a DEM job: a campaign case, a DEM-study point or a bulk-study case."""
    if "case" in wc.keys():
        return case_scene(wc.case)
    if "bulkcase" in wc.keys():
        return bulk_scene(wc.bulkcase)
    return point_scene(wc.point)


def dem_runtime(stage=None):
    """A resources function: minutes for the stage, growing with ``attempt``."""

    def runtime(wc, attempt):
        name = stage or wc.protocol
        minutes = DEM_SAFETY * dem_seconds(_scene_of(wc), name) / 60 + DEM_OVERHEAD_MIN
        return math.ceil(attempt * minutes)

    return runtime


# Scheduling on few cores (`make quick` runs -j2): of the ready jobs Snakemake starts those of
# highest priority first (rules without one: 0). Every DEM stage outranks the rest, because every
# calibration set but the per-I ones waits for the whole DEM; among them the longest remaining
# chain of its case goes first (longest processing time first, the projected seconds of the stage
# and of the stages after it), so no lone I = 2e-3 pre-shear ends the DEM. The calibration sets
# then go largest first (set_priority): "all" with its pole-at-start fit is the longest chain
# after the DEM, and started first it leaves the second core to the other sets.
DEM_PRIORITY = 1000


def dem_priority(stage=None):
    """A priority function: DEM_PRIORITY + projected seconds of the stage and of the case's stages after it.

    The scene (written in no time) gets its case's whole chain: at the start only scenes are ready, and
    a scene left at priority 0 would wait behind the first case's pack, pre-shear and reversals.
    """

    def priority(wc):
        name = stage or wc.protocol
        scene = _scene_of(wc)
        seconds = {s: dem_seconds(scene, s) for s in scene_stages(scene)}
        if name == "scene":
            return DEM_PRIORITY + round(longest_chain({"case": seconds}))
        return DEM_PRIORITY + round(seconds[name] + after_seconds(seconds)[name])

    return priority


def set_priority(wc):
    """A calibration set's priority: its series (cases x (pre-shear + protocols)), the largest set first."""
    spec = CALIBRATION_SETS[wc.calset]
    return len(spec["cases"]) * (1 + len(spec["protocols"]))


def dem_mem_mb(wc):
    n = scene_disks(_scene_of(wc))
    return max(1000, math.ceil(DEM_MEM_SAFETY * (250 + 0.05 * n)))


# The other rules: measured wall time and peak RSS on the CI preset (3 cases x
# 3 series, 2 shared cores; benchmarks/*.tsv), times 4 in time and 2 in memory,
# per attempt, with a floor. Calibration and comparison grow with the number of
# series (cases x (pre-shear + protocols)), so their time is scaled by it; the
# CI preset also runs them with lighter options (fewer bootstrap fits), hence
# their larger floors.
Cost = namedtuple("Cost", "runtime mem_mb")


def measured(seconds, mem_mb, floor_min=10, per_series=False):
    """Cost(runtime function of attempt, mem_mb) from one measured run (see above)."""

    def runtime(wc, attempt):
        scale = max(1.0, len(CASES) * (1 + len(PROTOCOLS)) / 9) if per_series else 1.0
        return math.ceil(attempt * max(floor_min, 4 * seconds / 60 * scale))

    return Cost(runtime, max(1000, math.ceil(2 * mem_mb)))


#                          measured: s, peak MB (CI preset)
COST_SMALL = measured(3.5, 145)  # dem_summary, compare_heldout
COST_ODE_WORK_PRECISION = measured(30.4, 129)
COST_BATCHED_COST = measured(74.0, 266)  # quick preset
COST_STAGE_OVERHEAD = measured(2082.8, 269)  # make bench at nice 10 on 2 cores busy with 6-8 jobs (312 s of CPU)
COST_ENGINE_THROUGHPUT = measured(900.0, 500)  # not benchmarked here: a guess (the 5,000-disk packings dominate)
COST_CALIBRATE = measured(18.3, 229, floor_min=120, per_series=True)
COST_CALIBRATION_COST = measured(2 * 18.3, 229, floor_min=240, per_series=True)  # two calibrations per set
COST_COMPARE = measured(14.6, 203, floor_min=30, per_series=True)
COST_CLAIMS = measured(7.9, 197, per_series=True)  # quick preset (12 reversal runs)
COST_DEM_STUDY_ANALYSIS = measured(30.0, 500, floor_min=30)  # not benchmarked here: a guess, like SMALL x 10
