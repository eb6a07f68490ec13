"""Interrupted DEM stages with real YADE: SIGTERM/SIGINT checkpoint and resume, one owner per stage.

Each test starts a pre-shear on the tiny cell of test_dem_stages (pack made once
here), interrupts or doubles it, and checks that the final series lies exactly on
the stage's grid of sampling steps: no gap, no duplicated row, no foreign row.
"""
import json
import math
import os
import shutil
import signal
import subprocess
import time

import numpy as np
import pytest

from tests.helpers import RUN, make_scene, read, yade

pytestmark = [pytest.mark.yade, pytest.mark.serial]  # timing of signals between processes: run alone
ENV = dict(os.environ, OMP_NUM_THREADS="1")


@pytest.fixture(scope="module")
def packed(tmp_path_factory):
    root = tmp_path_factory.mktemp("packed")
    scene = root / "scene.json"
    scene.write_text(json.dumps(make_scene()))
    r = yade(RUN, scene, "pack", root / "case")
    assert r.returncode == 0, r.stderr[-2000:]
    return root / "case"


def new_case(packed, tmp_path, strain):
    cdir = tmp_path / "case"
    cdir.mkdir()
    for f in ("pack.final.yade.gz", "pack.json"):
        shutil.copy(packed / f, cdir / f)
    sc = make_scene()
    sc["preshear"]["strain"] = strain
    sc["run"]["progress_every_s"] = 1
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(sc))
    return scene, cdir


def _sigint_as_at_a_terminal():
    """A stage started from a terminal gets Ctrl-C; pytest run as a background job of a
    non-interactive shell passes SIGINT on ignored, which the stage rightly keeps ignoring."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start(scene, cdir, **kw):
    kw.setdefault("preexec_fn", _sigint_as_at_a_terminal)
    return subprocess.Popen(["yade", "-n", "-x", str(RUN), str(scene), "preshear", str(cdir)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV, **kw)


def wait_for_rows(cdir, rows, proc=None, timeout=60):
    """Until the running stage's partial CSV holds `rows` rows."""
    csv = cdir / ".partial" / "preshear" / "preshear.csv"
    t0 = time.time()
    while not (csv.exists() and len(csv.read_text().splitlines()) > rows):
        assert proc is None or proc.poll() is None, "the stage ended before it could be interrupted"
        assert time.time() - t0 < timeout
        time.sleep(0.05)


def expected_steps(side, fine_window):
    """Step indices (since the start of the stage) of every row: fine up to the first
    sample at or past the fine window, coarse after it, and the final state."""
    fine, coarse = side["sampling_steps"]["fine"], side["sampling_steps"]["coarse"]
    fine_end = math.ceil(fine_window * (1.0 / (side["gammadot_nominal"] * side["dt"])))
    out, i, every = [], 0, fine
    while True:
        i += every
        if i >= side["steps"]:
            break
        out.append(i)
        if i >= fine_end:
            every = coarse
    return out + [side["steps"]]


def assert_complete_on_grid(cdir, strain):
    side = json.loads((cdir / "preshear.json").read_text())
    s = read(cdir / "preshear.csv")
    k = (s["t"] - side["t_start"]) * side["time_unit_s"] / side["dt"]
    assert np.abs(k - np.rint(k)).max() < 1e-6  # every row on a whole step
    assert np.rint(k).astype(int).tolist() == expected_steps(side, make_scene()["sampling"]["fine_window"])
    assert side["samples"] == len(s)
    assert s["strain"][-1] == pytest.approx(strain, rel=0.05)
    assert not (cdir / ".partial").exists()
    return side


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_writes_a_checkpoint_exits_4_and_the_rerun_resumes(packed, tmp_path, sig):
    scene, cdir = new_case(packed, tmp_path, strain=2.0)
    proc = start(scene, cdir)
    try:
        wait_for_rows(cdir, 60, proc)
        t0 = time.time()
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=30)
        delay = time.time() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
    print(f"{sig.name}: exit {proc.returncode} {delay:.2f} s after the signal")
    assert proc.returncode == 4, err[-2000:]
    assert f"{sig.name} received: checkpoint at iteration" in err
    assert delay < 5  # one run chunk (about 1 s) plus the checkpoint
    resume = json.loads((cdir / ".partial" / "preshear" / "resume.json").read_text())
    assert resume["rows"] >= 60
    assert not (cdir / "preshear.csv").exists() and not (cdir / ".partial" / "preshear.lock").exists()

    r = yade(RUN, scene, "preshear", cdir)
    assert r.returncode == 0, r.stderr[-2000:]
    assert f"{resume['rows']} rows kept" in r.stdout
    assert "stale lock" not in r.stdout  # the interrupted stage released its lock
    side = assert_complete_on_grid(cdir, 2.0)
    assert side["resumed"] == 1


def test_second_process_on_a_stage_is_refused_and_the_first_completes(packed, tmp_path):
    scene, cdir = new_case(packed, tmp_path, strain=1.2)
    first = start(scene, cdir)
    try:
        wait_for_rows(cdir, 5, first)
        second = yade(RUN, scene, "preshear", cdir, timeout=60)
        assert first.poll() is None, "the first run ended before the second started"
        out, err = first.communicate(timeout=120)
    finally:
        if first.poll() is None:
            first.kill()
    assert second.returncode == 5, second.stdout[-1000:] + second.stderr[-1000:]
    assert f"being run by PID {first.pid} on host" in second.stderr
    assert "Traceback" not in second.stderr
    assert first.returncode == 0, err[-2000:]
    side = assert_complete_on_grid(cdir, 1.2)
    assert side["resumed"] == 0


def running(pid: int) -> bool:
    """The process exists and is not a zombie (an orphan's zombie waits for whoever adopted it)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_rerun_while_an_orphan_runs_is_refused_and_the_orphan_completes(packed, tmp_path):
    """Snakemake killed with SIGKILL leaves its job running: here the parent is a bash."""
    scene, cdir = new_case(packed, tmp_path, strain=1.5)
    cmd = f"yade -n -x {RUN} {scene} preshear {cdir} > {tmp_path / 'orphan.log'} 2>&1; echo finished"
    parent = subprocess.Popen(["bash", "-c", cmd], env=ENV, start_new_session=True)
    lock = cdir / ".partial" / "preshear.lock"
    try:
        wait_for_rows(cdir, 5, parent)
        orphan = json.loads(lock.read_text())["pid"]
        assert orphan != parent.pid  # yade is a child of bash, not bash itself
        parent.kill()
        parent.wait()
        rerun = yade(RUN, scene, "preshear", cdir, timeout=60)
        assert rerun.returncode == 5, rerun.stdout[-1000:] + rerun.stderr[-1000:]
        assert f"being run by PID {orphan} on host" in rerun.stderr
        t0 = time.time()
        # the orphan is not our child: wait for it to exit (it unlinks the lock, then removes .partial/)
        while lock.exists() or running(orphan):
            assert time.time() - t0 < 120
            time.sleep(0.1)
    finally:
        if parent.poll() is None:
            parent.kill()
        if lock.exists():
            os.kill(json.loads(lock.read_text())["pid"], signal.SIGKILL)
    assert "done:" in (tmp_path / "orphan.log").read_text()
    side = assert_complete_on_grid(cdir, 1.5)
    assert side["resumed"] == 0
