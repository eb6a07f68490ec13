"""Wall time of a campaign's DEM jobs on a number of cores, scheduled as Snakemake schedules them.

- ``makespan(costs, cores)``: independent jobs, longest first, each to the core free first.
- ``chain_makespan(cases, cores)``: each case a chain pack -> pre-shear -> its reversal runs (the
  reversal runs of a case side by side once its pre-shear is done). Whenever a core is free the
  ready job of highest priority starts, the priority being its own seconds plus the longest chain
  of its case after it (``workflow/rules/resources.smk``, ``dem_priority``); jobs already running
  hold their cores from the start.
- ``longest_chain(cases)``: the wall time with one core per job (a cluster): the longest case's
  pack + pre-shear + longest reversal run.
"""
from __future__ import annotations

import heapq

from .cost import BASE_STAGES


def makespan(costs, cores: int = 2) -> float:
    """Longest-first list scheduling of independent jobs on ``cores``: an estimate of the wall time."""
    loads = [0.0] * cores
    for c in sorted(costs, reverse=True):
        loads[loads.index(min(loads))] += c
    return max(loads)


def after_seconds(stages: dict) -> dict:
    """Seconds of the longest chain that follows each stage of one case (dict stage -> seconds, in run order)."""
    longest_reversal = max((s for k, s in stages.items() if k not in BASE_STAGES), default=0.0)
    return {k: (stages.get("preshear", 0.0) + longest_reversal if k == "pack" else
                longest_reversal if k == "preshear" else 0.0) for k in stages}


def longest_chain(cases: dict) -> float:
    """Wall time with one core per job: max over cases of pack + pre-shear + the longest reversal run.

    ``cases``: case -> {stage: seconds}.
    """
    return max((stages.get("pack", 0.0) + after_seconds(stages).get("pack", 0.0) for stages in cases.values()),
               default=0.0)


def chain_makespan(cases: dict, cores: int = 2, running=()) -> float:
    """Wall time of the cases' stages on ``cores`` (module docstring).

    Parameters
    ----------
    cases : dict
        case -> {stage: seconds}, stages in run order (pack, preshear, reversal runs); a stage
        already done is left out or given 0 seconds.
    cores : int
        Jobs run at once.
    running : iterable of (case, stage)
        Stages that run now: they start first, whatever their priority.
    """
    running = set(running)
    prio, waiting = {}, {}
    for case, stages in cases.items():
        after = after_seconds(stages)
        for stage, seconds in stages.items():
            key = (case, stage)
            prio[key] = float("inf") if key in running else seconds + after[stage]
            waiting[key] = None if stage == "pack" else (case, "pack") if stage == "preshear" else (case, "preshear")
    done = {(c, s) for c in cases for s in BASE_STAGES if s not in cases[c]}   # no such stage: nothing to wait for
    ready, busy, now = [], [], 0.0
    order = {key: i for i, key in enumerate(prio)}

    def release():
        for key in [k for k, before in waiting.items() if before is None or before in done]:
            del waiting[key]
            heapq.heappush(ready, (-prio[key], order[key], key))

    release()
    while ready or busy:
        while ready and len(busy) < max(1, cores):
            _, _, key = heapq.heappop(ready)
            heapq.heappush(busy, (now + cases[key[0]][key[1]], order[key], key))
        now, _, key = heapq.heappop(busy)
        done.add(key)
        release()
    return now
