"""One results folder, one writer: a second Snakemake on it is refused before any job.

The lock (campaign/results_lock.py) is taken in the Snakefile's ``onstart``.
The Snakemake tests start a first run from one working directory, freeze it
(SIGSTOP) once it holds the lock, and start a second one from another (``-d``:
each has its own ``.snakemake``, so Snakemake's own lock does not see the other,
as with two clones) on the same results folder. The first one's target is a case's pack
(a YADE stage of a few seconds, so that the lock is held long enough to be seen and
frozen: a scene file alone is written in milliseconds, profiles/default), the second's
the other case's scene file (no YADE).
"""
import copy
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from campaign.results_lock import EXIT_BUSY, LOCK_NAME, STALE_S, ResultsBusy, ResultsLock
from tests.helpers import TINY

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
CONFIG = {key: value for key, value in TINY.items() if key != "calibration"}


def dead_pid():
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


# --- the lock itself -------------------------------------------------------------------

def test_second_lock_on_one_folder_is_refused_naming_the_owner(tmp_path):
    first = ResultsLock(tmp_path)
    first.acquire()
    with pytest.raises(ResultsBusy, match=rf"PID {os.getpid()} on host {socket.gethostname()}"):
        ResultsLock(tmp_path).acquire()
    first.release()
    assert not (tmp_path / LOCK_NAME).exists()
    second = ResultsLock(tmp_path)
    assert second.acquire() is None  # free again, nothing stale
    second.release()


def test_lock_of_a_dead_process_is_taken_over_with_a_message(tmp_path):
    stale = dict(pid=dead_pid(), host=socket.gethostname(), started="earlier", cwd="/elsewhere")
    (tmp_path / LOCK_NAME).write_text(json.dumps(stale))
    lines = []
    lock = ResultsLock(tmp_path, log=lines.append)
    assert lock.acquire() == stale
    assert len(lines) == 1 and f"PID {stale['pid']}" in lines[0] and "taken over" in lines[0]
    assert json.loads((tmp_path / LOCK_NAME).read_text())["pid"] == os.getpid()
    lock.release()


def test_lock_of_another_host_is_trusted_until_it_goes_stale(tmp_path):
    path = tmp_path / LOCK_NAME
    path.write_text(json.dumps(dict(pid=1, host="another-node", started="earlier")))
    with pytest.raises(ResultsBusy, match="another-node.*renewed less than"):
        ResultsLock(tmp_path).acquire()
    old = time.time() - STALE_S - 10
    os.utime(path, (old, old))
    lock = ResultsLock(tmp_path, log=lambda line: None)
    assert lock.acquire()["host"] == "another-node"
    lock.release()


# --- two Snakemakes --------------------------------------------------------------------

@pytest.fixture
def campaign(tmp_path):
    config = copy.deepcopy(CONFIG)
    config["results_dir"] = str(tmp_path / "results")
    config["allow_outside_tree"] = True  # a results folder under pytest's tmp_path
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    cases = [tmp_path / "results" / "dem" / f"p100000_I0.01_s{seed}" for seed in (1, 2)]
    return path, tmp_path / "results", (cases[0] / "pack.csv", cases[1] / "scene.json")


def snakemake(config, target, *args, workdir=None):
    where = ["-s", str(ROOT / "Snakefile"), "-d", str(workdir)] if workdir else []
    return [*SNAKEMAKE, "-j1", str(target), *where, "--configfile", str(config), *args]


def first_clone(tmp_path):
    """The first run's working directory: a clone's stage scripts, which its DEM rule runs by relative path."""
    folder = tmp_path / "first_clone"
    folder.mkdir()
    (folder / "yade_scripts").symlink_to(ROOT / "yade_scripts")
    return folder


def start_and_freeze(cmd, lock_path, workdir):
    """Start ``cmd`` in ``workdir``, wait until it holds the lock, then stop it (SIGSTOP)."""
    proc = subprocess.Popen(cmd, cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    deadline = time.time() + 300
    while not lock_path.exists():
        assert proc.poll() is None, proc.stdout.read()[-3000:]
        assert time.time() < deadline, "the first Snakemake never took the results-folder lock"
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGSTOP)
    return proc


@pytest.mark.slow
def test_second_snakemake_from_another_directory_is_refused_before_any_job(campaign, tmp_path):
    config, results, (pack1, scene2) = campaign
    lock_path = results / LOCK_NAME
    first_dir = first_clone(tmp_path)
    first = start_and_freeze(snakemake(config, pack1, workdir=first_dir), lock_path, first_dir)
    try:
        owner = json.loads(lock_path.read_text())
        assert owner["pid"] == first.pid
        other = tmp_path / "other_clone"
        other.mkdir()
        second = subprocess.run(snakemake(config, scene2, workdir=other), cwd=other, capture_output=True,
                                text=True, timeout=300)
        assert second.returncode == EXIT_BUSY, second.stdout[-2000:] + second.stderr[-2000:]
        assert f"Snakemake PID {first.pid}" in second.stderr and str(results) in second.stderr
        assert not scene2.exists()  # no job ran
        # a dry run and a summary need no lock, and leave the owner's alone
        for extra in (["-n"], ["--summary"]):
            look = subprocess.run(snakemake(config, scene2, *extra, workdir=other), cwd=other,
                                  capture_output=True, text=True, timeout=300)
            assert look.returncode == 0, look.stderr[-2000:]
        assert json.loads(lock_path.read_text()) == owner
    finally:
        os.killpg(first.pid, signal.SIGCONT)
    assert first.wait(timeout=300) == 0, first.stdout.read()[-3000:]
    assert pack1.exists() and not lock_path.exists()  # released on exit
    # the refused directory is not left locked: the same run now goes through
    again = subprocess.run(snakemake(config, scene2, workdir=other), cwd=other, capture_output=True, text=True,
                           timeout=300)
    assert again.returncode == 0, again.stderr[-3000:]
    assert scene2.exists() and not lock_path.exists()


@pytest.mark.slow
def test_lock_left_by_a_killed_snakemake_is_taken_over(campaign, tmp_path):
    config, results, (pack1, scene2) = campaign
    lock_path = results / LOCK_NAME
    first_dir = first_clone(tmp_path)
    first = start_and_freeze(snakemake(config, pack1, workdir=first_dir), lock_path, first_dir)
    os.killpg(first.pid, signal.SIGKILL)
    first.wait(timeout=60)
    assert lock_path.exists()  # SIGKILL: no onerror, the file stays (its flock is gone)
    other = tmp_path / "other_clone"
    other.mkdir()
    second = subprocess.run(snakemake(config, scene2, workdir=other), cwd=other, capture_output=True, text=True,
                            timeout=300)
    assert second.returncode == 0, second.stdout[-2000:] + second.stderr[-2000:]
    assert f"stale results-folder lock of Snakemake PID {first.pid}" in second.stdout + second.stderr
    assert scene2.exists() and not lock_path.exists()
