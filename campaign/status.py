"""A running or stopped campaign's progress: cases done, running and waiting, core-hours spent and left, its ETA.

Read only, from what the DEM stages write (nothing is locked, nothing written):

- ``<results_dir>/dem/<case>/<stage>.json``, the sidecar of a finished stage: its ``cpu_time_s``
  and ``wall_time_s``;
- ``<case_dir>/.partial/<stage>.log``, the stage's own copy of its log (yade_scripts/stagelog.py:
  a second name of the log file, kept however the stage was started), else
  ``<results_dir>/logs/dem/<case>/<stage>.log``, the log Snakemake names: the last progress line
  ``[stage] strain ... | NN.N% | t ... | ... particle-steps/s | ETA N s`` gives a running stage's
  progress and ETA;
- ``<case_dir>/.partial/<stage>.lock``, the stage lock (yade_scripts/stagelock.py): the stage runs
  while the process it names lives (on this host) and renews it (within ``STALE_S``);
- ``<case_dir>/.partial/<stage>/resume.json``, the checkpoint (yade_scripts/checkpoint.py): a
  stopped stage resumes from it, at step ``iter`` minus the steps of the stages before it, if it
  was made from the case's ``scene.json`` and the config still makes that scene (else the stage
  discards it and starts over).

A stage is done (sidecar), restored (its case taken from a data release), running, stopped (a log
or a checkpoint, no live owner: killed, or a guard fired) or waiting. Core-hours spent are the
finished stages' CPU; core-hours left are the cost model's (``campaign.cost``, the documented
throughput of the scene's engine) for what is not done, times the measured / projected ratio of
the finished stages, packs and shear stages apart (a pack's time to converge varies with kappa
more than the model says; a shear stage's steps are exact). The campaign's ETA schedules what is
left on the cores in use (``campaign.schedule.chain_makespan``: the running stages first, each at
its log's ETA), at the wall / CPU ratio the finished stages ran at.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import socket
import time
from dataclasses import dataclass, field
from pathlib import Path

from .cost import BASE_STAGES, PACK_TIME, scene_stages, scene_value, stage_seconds, stage_steps
from .price import ROOT, campaign_scenes, duration, plural, restored_cases
from .scene_spec import yade_scripts_module
from .scenes import result_key
from .schedule import chain_makespan

PROGRESS = re.compile(r"^\[(?P<stage>[^\]]+)\] (?P<what>[^|]*)\|\s*(?P<pct>[0-9.]+)% \|.*\| ETA (?P<eta>\S+) s")
#: Bytes read from the end of a log: its last progress line is there.
LOG_TAIL = 65536


def read_json(path) -> dict | None:
    try:
        value = json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None
    return value if isinstance(value, dict) else None


def log_tail(path) -> list[str]:
    """The last lines of a log file (empty when there is none)."""
    try:
        with open(path, "rb") as f:
            f.seek(max(0, os.fstat(f.fileno()).st_size - LOG_TAIL))
            return f.read().decode("utf-8", "replace").splitlines()
    except OSError:
        return []


def last_progress(lines) -> dict | None:
    """The last progress line's stage progress (fraction 0-1), ETA (s) and position (``strain 0.33``)."""
    for line in reversed(lines):
        m = PROGRESS.match(line)
        if m:
            try:
                eta = float(m["eta"])
            except ValueError:
                eta = float("nan")
            return dict(fraction=float(m["pct"]) / 100, eta_s=eta, at=m["what"].strip())
    return None


def live_owner(case_dir, stage) -> dict | None:
    """The record of the process that runs ``stage`` now (its lock, ``.partial/<stage>.lock``), or None.

    Alive: the lock was renewed within the stage lock's STALE_S and, on this host, its PID exists.
    """
    path = Path(case_dir) / ".partial" / f"{stage}.lock"
    rec = read_json(path)
    if rec is None:
        return None
    try:
        if time.time() - path.stat().st_mtime > yade_scripts_module("stagelock").STALE_S:
            return None
    except OSError:
        return None
    if rec.get("host") in (None, socket.gethostname()):
        try:
            os.kill(int(rec["pid"]), 0)   # signal 0: is it there? (nothing is sent)
        except ProcessLookupError:
            return None
        except (PermissionError, KeyError, ValueError, TypeError):
            pass
    return rec


@dataclass
class StageStatus:
    """One stage of one case: its state and what it has cost or will cost (module docstring)."""

    case: str
    stage: str
    state: str                      # done, restored, running, stopped, waiting
    projected_s: float              # the cost model's one-thread seconds, the engine's documented throughput
    cpu_s: float = 0.0              # a finished stage's CPU (sidecar)
    wall_s: float = 0.0
    fraction: float = 0.0           # of the stage done (running: its log; stopped: at its checkpoint)
    eta_s: float | None = None      # a running stage's log
    at: str = ""                    # a running stage's position (``strain 0.45``)
    checkpoint: dict | None = None  # resume.json of a stopped or running stage
    owner: dict | None = None
    last_line: str = ""             # a stopped stage's log, last line
    stale: str = ""                 # why a rerun would discard the checkpoint (``stale_checkpoint``)

    @property
    def kind(self) -> str:
        return "pack" if self.stage == "pack" else "shear"


def stage_status(results_dir, label: str, scene: dict, stage: str, restored: bool) -> StageStatus:
    """The state of one stage of one case (module docstring)."""
    case_dir = Path(results_dir) / "dem" / label
    projected = stage_seconds(scene, stage)
    side = read_json(case_dir / f"{stage}.json")
    if side is not None and "cpu_time_s" in side:
        return StageStatus(label, stage, "restored" if restored else "done", projected,
                           float(side["cpu_time_s"]), float(side.get("wall_time_s", side["cpu_time_s"])), 1.0)
    if restored:
        return StageStatus(label, stage, "restored", projected, fraction=0.0)
    lines = (log_tail(case_dir / ".partial" / f"{stage}.log")            # however the stage was started
             or log_tail(Path(results_dir) / "logs" / "dem" / label / f"{stage}.log"))
    checkpoint = read_json(case_dir / ".partial" / stage / "resume.json")
    owner = live_owner(case_dir, stage)
    progress = last_progress(lines) or {}
    if owner is not None:
        fraction = _stage_fraction(scene, stage, progress.get("fraction", 0.0))
        return StageStatus(label, stage, "running", projected, fraction=fraction, eta_s=progress.get("eta_s"),
                           at=progress.get("at", ""), checkpoint=checkpoint, owner=owner)
    if lines or checkpoint:
        stale = stale_checkpoint(case_dir, scene, checkpoint) if checkpoint else ""
        fraction = _checkpoint_fraction(case_dir, scene, stage, checkpoint) if checkpoint and not stale else 0.0
        last = next((line for line in reversed(lines) if line.strip()), "")
        return StageStatus(label, stage, "stopped", projected, fraction=fraction, checkpoint=checkpoint,
                           last_line=last.strip()[:160], stale=stale)
    return StageStatus(label, stage, "waiting", projected)


def _stage_fraction(scene, stage, log_fraction) -> float:
    """Fraction of the projected steps a running stage has done, from its log's fraction of its planned steps:
    a shear stage's are the projected ones; the pack plans max_time and is projected to need
    min(PACK_TIME, max_time) (so at most 0.95 while it runs)."""
    if stage != "pack":
        return min(log_fraction, 1.0)
    max_time = scene_value(scene, "pack", "max_time")
    return min(log_fraction * max_time / min(PACK_TIME, max_time), 0.95)


def stale_checkpoint(case_dir, scene: dict, checkpoint: dict) -> str:
    """Why a rerun would discard ``checkpoint`` rather than resume from it; empty when it resumes.

    The stage resumes only from a checkpoint of the scene file it reads (yade_scripts/checkpoint.py
    compares their sha256), and Snakemake writes the case a new scene file when the config's scene
    differs from it in anything that enters the result (``campaign.scenes.result_key``).
    """
    try:
        text = (Path(case_dir) / "scene.json").read_text()
    except OSError:
        return "the case has no scene file"
    if hashlib.sha256(text.encode()).hexdigest() != checkpoint.get("scene_sha256"):
        return "its checkpoint is of another scene file"
    if result_key(json.loads(text)) != result_key(scene):
        return "the config has changed the scene since: the case is rerun from its pack"
    return ""


def _checkpoint_fraction(case_dir, scene, stage, checkpoint) -> float:
    """Fraction of the stage a resume from ``checkpoint`` starts at: (iter - the steps of the stages
    before it, from their sidecars) / the stage's projected steps; 0 when a sidecar is missing."""
    before = list(BASE_STAGES[:BASE_STAGES.index(stage)]) if stage in BASE_STAGES else list(BASE_STAGES)
    steps_before = 0
    for prior in before:
        side = read_json(Path(case_dir) / f"{prior}.json")
        if side is None or "steps" not in side:
            return 0.0
        steps_before += int(side["steps"])
    return min(max((int(checkpoint.get("iter", 0)) - steps_before) / stage_steps(scene, stage), 0.0), 1.0)


@dataclass
class CampaignStatus:
    """Every stage of a campaign's cases (``stage_status``) and what follows from them (module docstring)."""

    campaign: str
    results_dir: str
    stages: list = field(default_factory=list)
    cores: int = 2

    def cases(self) -> dict:
        """case -> its stages' StageStatus, in run order."""
        out = {}
        for st in self.stages:
            out.setdefault(st.case, []).append(st)
        return out

    @staticmethod
    def case_state(stages) -> str:
        """done (every stage done or restored), running (a stage runs), stopped (one was stopped), else waiting."""
        states = {st.state for st in stages}
        if states <= {"done", "restored"}:
            return "done"
        return next((s for s in ("running", "stopped") if s in states), "waiting")

    def finished(self, kind=None) -> list:
        """The stages that ran here to their end (not restored), of one kind (pack, shear) or all."""
        return [st for st in self.stages if st.state == "done" and kind in (None, st.kind)]

    def ratio(self, kind) -> float:
        """Measured / projected CPU of the finished stages of ``kind``; 1 (the documented throughput) with none."""
        done = self.finished(kind)
        projected = sum(st.projected_s for st in done)
        return sum(st.cpu_s for st in done) / projected if done and projected > 0 else 1.0

    @property
    def wall_per_cpu(self) -> float:
        """Wall seconds per CPU second of the finished stages (1 with none): how much of a core each one had."""
        done = self.finished()
        cpu = sum(st.cpu_s for st in done)
        return max(sum(st.wall_s for st in done) / cpu, 1.0) if done and cpu > 0 else 1.0

    def left_cpu_s(self, st: StageStatus) -> float:
        """CPU seconds a stage still needs: projected x ratio of its kind x (1 - fraction done); 0 if done."""
        if st.state in ("done", "restored"):
            return 0.0
        return st.projected_s * self.ratio(st.kind) * (1.0 - st.fraction)

    def left_wall_s(self, st: StageStatus) -> float:
        """Wall seconds a stage still needs: a running shear stage's log ETA, else left_cpu_s x wall_per_cpu."""
        if st.state == "running" and st.kind == "shear" and st.eta_s is not None and st.eta_s == st.eta_s:
            return st.eta_s
        return self.left_cpu_s(st) * self.wall_per_cpu

    @property
    def spent_s(self) -> float:
        return sum(st.cpu_s for st in self.finished())

    @property
    def left_s(self) -> float:
        return sum(self.left_cpu_s(st) for st in self.stages)

    @property
    def eta_s(self) -> float:
        """Wall time to the end of the DEM on ``cores``: what is left, scheduled (module docstring)."""
        cases = {case: {st.stage: self.left_wall_s(st) for st in stages} for case, stages in self.cases().items()}
        running = [(st.case, st.stage) for st in self.stages if st.state == "running"]
        return chain_makespan(cases, self.cores, running)


def campaign_status(config: dict, cores: int = 2, root=ROOT) -> CampaignStatus:
    """The status of every DEM stage of the campaign of ``config`` (schema defaults filled in)."""
    scenes = campaign_scenes(config)
    restored = restored_cases(config, scenes, root)
    results = str(config.get("results_dir", "results"))
    stages = [stage_status(results, label, scene, stage, label in restored)
              for label, scene in scenes.items() for stage in scene_stages(scene)]
    return CampaignStatus(str(config.get("campaign", "")), results, stages, int(cores))


def _stage_text(st: StageStatus) -> str:
    if st.state == "done":
        return f"{st.stage} done ({duration(st.cpu_s)} CPU)"
    if st.state == "running":
        bound = " at most" if st.stage == "pack" else ""   # the pack's log counts to its max_time
        eta = f", ETA{bound} {duration(st.eta_s)}" if st.eta_s is not None and st.eta_s == st.eta_s else ""
        at = f" at {st.at}" if st.at else ""
        pid = f" (PID {st.owner.get('pid')})" if st.owner and "pid" in st.owner else ""
        return f"{st.stage} running {100 * st.fraction:.1f} %{at}{eta}{pid}"
    if st.state == "stopped":
        return f"{st.stage} stopped" + (f" (checkpoint at {100 * st.fraction:.0f} %)" if st.checkpoint and not st.stale
                                         else "")
    return f"{st.stage} {st.state}"


def resume_text(st: StageStatus) -> str:
    """Where a stopped stage goes on when the campaign is run again."""
    if st.checkpoint and st.stale:
        what = f"starts over ({st.stale})"
    elif st.checkpoint:
        where = f"resumes from its checkpoint at {100 * st.fraction:.0f} %" if st.fraction > 0 else \
            "resumes from its checkpoint"
        what = (f"{where} (iteration {st.checkpoint.get('iter')}, {st.checkpoint.get('rows')} rows, "
                f".partial/{st.stage}/{st.checkpoint.get('checkpoint')})")
    else:
        what = "starts over (no checkpoint)"
    return f"{st.case} {st.stage} {what}" + (f"; its log ends: {st.last_line}" if st.last_line else "")


def status_lines(s: CampaignStatus) -> list[str]:
    """What ``python -m campaign status`` prints (module docstring)."""
    cases = s.cases()
    counts = {state: sum(s.case_state(stages) == state for stages in cases.values())
              for state in ("done", "running", "stopped", "waiting")}
    name = f"campaign {s.campaign}" if s.campaign else "the campaign"
    lines = [f"{name} ({s.results_dir}/dem): {plural(len(cases), 'DEM case')}: "
             + ", ".join(f"{n} {state}" for state, n in counts.items() if n or state in ("done", "waiting"))]
    width = max(map(len, cases), default=0)
    for case, stages in cases.items():
        if all(st.state == "restored" for st in stages):
            lines.append(f"  {case:<{width}}  restored from its release")
            continue
        lines.append(f"  {case:<{width}}  " + "; ".join(_stage_text(st) for st in stages))
    pack, shear = s.finished("pack"), s.finished("shear")

    def scale(kind, done):
        return (f"x {s.ratio(kind):.2g} for {kind} stages ({len(done)} finished)" if done else
                f"x 1 for {kind} stages (none finished: the documented throughput)")

    lines.append(f"core-hours: {s.spent_s / 3600:.2g} spent (the CPU of {plural(len(pack) + len(shear), 'finished stage')}), "
                 f"{s.left_s / 3600:.2g} left (the cost model {scale('shear', shear)}, {scale('pack', pack)})")
    if s.left_s > 0:
        lines.append(f"ETA of the campaign's DEM: about {duration(s.eta_s)} on {plural(s.cores, 'core')} (the running "
                     f"stages at their logs' ETA, the rest at {s.wall_per_cpu:.2g} wall s per CPU s, as the finished "
                     "stages ran)")
    stopped = [st for st in s.stages if st.state == "stopped"]
    if stopped:
        lines.append("run the same command again: finished stages are kept, and")
        lines += [f"  {resume_text(st)}" for st in stopped]
    return lines
