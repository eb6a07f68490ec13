"""A running or stopped campaign's progress (campaign.status, ``python -m campaign status``).

First on a results folder built here in the formats the DEM writes (sidecars with their cost keys,
stage logs with progress lines as yade_scripts/sampling.py prints them, the checkpoint's
resume.json, the stage lock's record), with known numbers; then on a tiny real campaign run by
YADE and killed half-way, which must resume where the status says.
"""
import hashlib
import json
import os
import subprocess

import pytest
import yaml

from campaign import cost, status
from campaign.cases import cases
from campaign.scenes import scene_from_config, write_scene
from campaign.schema_defaults import with_defaults
from tests.helpers import ROOT, RUN, kill_preshear_after_first_checkpoint, run_main, yade

QUICK = yaml.safe_load((ROOT / "config" / "quick.yaml").read_text())
CI = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
#: The narrow cell at kappa 1e4, I 1e-3, dt 0.3 t_c (a stiffness campaign's physics), three seeds.
STIFF = {**QUICK, "campaign": "stiff", "loading": {"pressures": [1.0e5], "inertial_numbers": [1.0e-3]},
         "seeds": [1, 2, 3], "material": {**QUICK["material"], "kappa": 1.0e4}, "timestep": {"dt_over_tc": 0.3},
         "preshear": {"strain": 1.2}, "protocols": {"heaviside": {"strain": 0.4}}, "calibration": {"freeform": False}}
#: The measured CPU of every finished shear stage is this times the cost model's projection; a pack's PACK.
SHEAR, PACK = 1.5, 0.5
PACK_STEPS = 29140          # a real pack of this cell (seed 1 at kappa 1e4)


def config_for(tmp_path, base=STIFF):
    config = with_defaults(json.loads(json.dumps({**base, "results_dir": str(tmp_path / "results"),
                                                  "allow_outside_tree": True})))
    path = tmp_path / "campaign.yaml"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    return config, path


def finish(results, label, scene, stage, log_lines):
    """A finished stage: its sidecar (cost keys, CPU = ratio x projection, wall = 2 x CPU) and its log."""
    projected = cost.stage_seconds(scene, stage)
    cpu = (PACK if stage == "pack" else SHEAR) * projected
    steps = PACK_STEPS if stage == "pack" else cost.stage_steps(scene, stage)
    side = dict(N=cost.scene_disks(scene), steps=steps, cpu_time_s=cpu, wall_time_s=2 * cpu, stage=stage, resumed=0)
    (results / "dem" / label).mkdir(parents=True, exist_ok=True)
    (results / "dem" / label / f"{stage}.json").write_text(json.dumps(side))
    write_log(results, label, stage, [*log_lines, f"[{stage}] done: 513 samples, {steps} steps, {2 * cpu:.1f} s, "
                                                   "1.73e+06 particle-steps/s"])
    return cpu


def write_log(results, label, stage, lines):
    path = results / "logs" / "dem" / label / f"{stage}.log"
    path.parent.mkdir(parents=True, exist_ok=True)
    head = [f"=== stage {stage}: PID 6686 on host vm, started 2026-11-27T03:55:29+0000",
            "Using python version: 3.11.2 (main, Apr 28 2025, 14:11:48) [GCC 12.2.0]"]
    path.write_text("\n".join([*head, *lines]) + "\n")


def lock(results, label, stage, pid):
    """The stage lock's record (yade_scripts/stagelock.py) of process ``pid`` on this host."""
    import socket

    path = results / "dem" / label / ".partial" / f"{stage}.lock"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(dict(pid=pid, host=socket.gethostname(), stage=stage,
                                    started="2026-11-27T04:04:08+0000")) + "\n")


def dead_pid():
    """The PID of a process that has ended."""
    proc = subprocess.Popen(["true"])
    proc.wait()
    return proc.pid


@pytest.fixture
def half_done(tmp_path):
    """Seed 1 finished; seed 2 packed, its pre-shear killed after a checkpoint at 210,000 steps; seed 3 packing now."""
    config, path = config_for(tmp_path)
    results = tmp_path / "results"
    scenes = {label: scene_from_config(config, case, label) for label, case in cases(config).items()}
    s1, s2, s3 = scenes
    spent = sum(finish(results, s1, scenes[s1], stage, []) for stage in ("pack", "preshear", "heaviside"))
    spent += finish(results, s2, scenes[s2], "pack", ["[pack] jammed at the compaction load, t = 73.0: ramping to p"])
    write_log(results, s2, "preshear", [
        "[preshear] strain 0.4542 |  37.5% | t 450.51 | 4.39e+05 particle-steps/s | ETA 402 s",
        "[preshear] strain 0.5501 |  45.5% | t 545.53 | 4.24e+05 particle-steps/s | ETA 364 s",
        "[preshear] checkpoint at iteration 239140 (382 rows, written in 0.06 s)",
        "[preshear] strain 0.5870 |  48.5% | t 582.10 | 4.21e+05 particle-steps/s | ETA 340 s"])
    scene_file = results / "dem" / s2 / "scene.json"
    write_scene(scenes[s2], scene_file)
    partial = results / "dem" / s2 / ".partial" / "preshear"
    partial.mkdir(parents=True)
    (partial / "resume.json").write_text(json.dumps(dict(
        checkpoint="ckpt_a.yade.gz", iter=PACK_STEPS + 210000, rows=382,
        scene_sha256=hashlib.sha256(scene_file.read_text().encode()).hexdigest())))
    lock(results, s2, "preshear", dead_pid())          # SIGKILL leaves the lock file behind
    write_log(results, s3, "pack", ["[pack] phase compress |   2.5% | t 50.00 | 8.1e+05 particle-steps/s | "
                                    "ETA 300 s (at most)"])
    lock(results, s3, "pack", os.getpid())             # a live owner on this host
    return dict(config=config, path=path, scenes=scenes, labels=(s1, s2, s3), spent=spent, results=results)


def test_each_stage_is_done_stopped_running_or_waiting(half_done):
    s = status.campaign_status(half_done["config"], cores=2)
    s1, s2, s3 = half_done["labels"]
    states = {(st.case, st.stage): st.state for st in s.stages}
    assert states == {(s1, "pack"): "done", (s1, "preshear"): "done", (s1, "heaviside"): "done",
                      (s2, "pack"): "done", (s2, "preshear"): "stopped", (s2, "heaviside"): "waiting",
                      (s3, "pack"): "running", (s3, "preshear"): "waiting", (s3, "heaviside"): "waiting"}
    assert [s.case_state(stages) for stages in s.cases().values()] == ["done", "stopped", "running"]


def test_a_stage_started_outside_the_workflow_shows_the_progress_of_its_own_log(half_done):
    """A stage run by hand with its own --log keeps a copy in .partial/<stage>.log: the status reads it there."""
    results, s3 = half_done["results"], half_done["labels"][2]
    (results / "logs" / "dem" / s3 / "pack.log").unlink()          # the workflow's log path: not written
    own = results / "dem" / s3 / ".partial" / "pack.log"
    own.write_text("[pack] phase compress |  10.0% | t 200.00 | 8.1e+05 particle-steps/s | ETA 250 s (at most)\n")
    pack = next(st for st in status.campaign_status(half_done["config"], cores=2).stages
                if (st.case, st.stage) == (s3, "pack"))
    assert pack.state == "running" and pack.fraction > 0.0 and pack.eta_s == 250


def test_a_killed_stage_resumes_from_its_checkpoint_not_from_its_last_progress_line(half_done):
    s = status.campaign_status(half_done["config"])
    stopped = next(st for st in s.stages if st.state == "stopped")
    planned = cost.stage_steps(half_done["scenes"][stopped.case], "preshear")
    assert stopped.fraction == pytest.approx(210000 / planned)           # 46.5 %, not the log's 48.5 %
    assert status.resume_text(stopped).startswith(
        f"{stopped.case} preshear resumes from its checkpoint at 47 % (iteration 239140, 382 rows, "
        ".partial/preshear/ckpt_a.yade.gz); its log ends: [preshear] strain 0.5870")


def test_a_checkpoint_of_another_scene_is_not_resumed_from(half_done):
    config = half_done["config"]
    changed = {**config, "material": {**config["material"], "friction": 0.3}}
    stopped = next(st for st in status.campaign_status(changed).stages if st.state == "stopped")
    assert stopped.fraction == 0 and status.resume_text(stopped).startswith(
        f"{stopped.case} preshear starts over (the config has changed the scene since: the case is rerun")
    resume = half_done["results"] / "dem" / stopped.case / ".partial" / "preshear" / "resume.json"
    resume.write_text(json.dumps({**json.loads(resume.read_text()), "scene_sha256": "0" * 64}))
    stopped = next(st for st in status.campaign_status(config).stages if st.state == "stopped")
    assert "starts over (its checkpoint is of another scene file)" in status.resume_text(stopped)


def test_core_hours_spent_are_the_sidecars_and_left_the_model_scaled_by_what_is_done(half_done):
    s = status.campaign_status(half_done["config"])
    assert s.spent_s == pytest.approx(half_done["spent"])
    assert s.ratio("shear") == pytest.approx(SHEAR) and s.ratio("pack") == pytest.approx(PACK)
    assert s.wall_per_cpu == pytest.approx(2.0)
    s1, s2, s3 = half_done["labels"]
    scenes = half_done["scenes"]
    stopped = next(st for st in s.stages if st.state == "stopped")
    running = next(st for st in s.stages if st.state == "running")
    # the running pack: 2.5 % of its max_time's steps done, of its projected PACK_TIME's
    max_time = cost.scene_value(scenes[s3], "pack", "max_time")
    assert running.fraction == pytest.approx(0.025 * max_time / cost.PACK_TIME)
    left = (SHEAR * cost.stage_seconds(scenes[s2], "preshear") * (1 - stopped.fraction)
            + SHEAR * cost.stage_seconds(scenes[s2], "heaviside")
            + PACK * cost.stage_seconds(scenes[s3], "pack") * (1 - running.fraction)
            + SHEAR * (cost.stage_seconds(scenes[s3], "preshear") + cost.stage_seconds(scenes[s3], "heaviside")))
    assert s.left_s == pytest.approx(left)


def test_the_campaigns_eta_schedules_what_is_left_on_the_cores_in_use(half_done):
    one, two = (status.campaign_status(half_done["config"], cores=c) for c in (1, 2))
    # one core: every stage left, one after the other, at the finished stages' wall per CPU second
    assert one.eta_s == pytest.approx(sum(one.left_wall_s(st) for st in one.stages))
    assert one.eta_s == pytest.approx(2.0 * one.left_s)
    assert two.eta_s < one.eta_s


def test_the_command_prints_cases_core_hours_eta_and_what_resumes_where(half_done):
    r = run_main("campaign.__main__", ["status", "--configfile", half_done["path"], "--cores", "2"])
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    s1, s2, s3 = half_done["labels"]
    assert lines[0].endswith("/results/dem): 3 DEM cases: 1 done, 1 running, 1 stopped, 0 waiting")
    assert lines[1].split()[0] == s1 and lines[1].count("done (") == 3
    assert f"{s2}  pack done" in lines[2] and "preshear stopped (checkpoint at 47 %); heaviside waiting" in lines[2]
    assert f"{s3}  pack running 50.0 % at phase compress, ETA at most 5 min (PID {os.getpid()})" in lines[3]
    assert lines[4].startswith("core-hours: ") and "the cost model x 1.5 for shear stages (2 finished), " \
                                                     "x 0.5 for pack stages (2 finished)" in lines[4]
    assert lines[5].startswith("ETA of the campaign's DEM: about ") and "on 2 cores" in lines[5]
    assert lines[6] == "run the same command again: finished stages are kept, and"
    assert lines[7].startswith(f"  {s2} preshear resumes from its checkpoint at 47 %")


def test_a_campaign_not_started_is_all_waiting_at_the_documented_throughput(tmp_path):
    config, _ = config_for(tmp_path)
    s = status.campaign_status(config)
    assert {st.state for st in s.stages} == {"waiting"} and s.spent_s == 0
    assert s.left_s == pytest.approx(sum(st.projected_s for st in s.stages))
    lines = status.status_lines(s)
    assert lines[0].endswith("3 DEM cases: 0 done, 3 waiting")
    assert "none finished: the documented throughput" in lines[-2]


@pytest.mark.yade
def test_a_real_campaign_killed_half_way_resumes_where_the_status_says(tmp_path):
    """Two CI cases: seed 1 run to its end, seed 2's pre-shear killed (SIGKILL) after a checkpoint, as
    the workflow runs the stages (run_stage.py with --log); then the pre-shear run again."""
    ci = {**CI, "seeds": [1, 2], "preshear": {"strain": 0.6}, "protocols": {"heaviside": {"strain": 0.1}},
          "run": {"checkpoint_every_s": 1, "progress_every_s": 1}, "calibration": {"freeform": False}}
    config, path = config_for(tmp_path, ci)
    results = tmp_path / "results"
    labels = list(cases(config))
    for label in labels:
        write_scene(scene_from_config(config, cases(config)[label], label), results / "dem" / label / "scene.json")

    def run(label, stage):
        r = yade(RUN, results / "dem" / label / "scene.json", stage, results / "dem" / label,
                 "--log", results / "logs" / "dem" / label / f"{stage}.log")
        assert r.returncode == 0, r.stderr[-2000:]

    for stage in ("pack", "preshear", "heaviside"):
        run(labels[0], stage)
    run(labels[1], "pack")
    kill_preshear_after_first_checkpoint(results / "dem" / labels[1] / "scene.json", results / "dem" / labels[1],
                                         log=results / "logs" / "dem" / labels[1] / "preshear.log")
    s = status.campaign_status(config)
    states = {(st.case, st.stage): st.state for st in s.stages}
    assert states[(labels[1], "preshear")] == "stopped" and states[(labels[1], "heaviside")] == "waiting"
    assert all(states[(labels[0], stage)] == "done" for stage in ("pack", "preshear", "heaviside"))
    stopped = next(st for st in s.stages if st.state == "stopped")
    resume = json.loads((results / "dem" / labels[1] / ".partial" / "preshear" / "resume.json").read_text())
    assert stopped.checkpoint == resume and 0 < stopped.fraction < 1
    pack_steps = json.loads((results / "dem" / labels[1] / "pack.json").read_text())["steps"]
    r = run_main("campaign.__main__", ["status", "--configfile", path])
    assert f"{labels[1]} preshear resumes from its checkpoint at {100 * stopped.fraction:.0f} % (iteration " \
           f"{resume['iter']}" in r.stdout
    assert (resume["iter"] - pack_steps) % 10000 == 0       # a checkpoint at a reload point of the stage
    run(labels[1], "preshear")
    log = (results / "logs" / "dem" / labels[1] / "preshear.log").read_text()
    assert f"resumed from {resume['checkpoint']} at iteration {resume['iter']}" in log
    after = status.campaign_status(config)
    assert {(st.case, st.stage): st.state for st in after.stages}[(labels[1], "preshear")] == "done"
    assert after.spent_s > s.spent_s and after.left_s < s.left_s
