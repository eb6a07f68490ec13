"""The stage lock (yade_scripts/stagelock.py) without YADE: one owner, stale locks, foreign hosts."""
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "yade_scripts"))
import stagelock  # noqa: E402


def dead_pid():
    p = subprocess.Popen(["true"])
    p.wait()
    return p.pid


def test_second_owner_is_refused_with_the_first_named(tmp_path):
    first = stagelock.StageLock(tmp_path, "preshear")
    first.acquire()
    with pytest.raises(stagelock.Busy, match=f"PID {os.getpid()} on host"):
        stagelock.StageLock(tmp_path, "preshear").acquire()
    stagelock.StageLock(tmp_path, "heaviside").acquire()  # another stage of the same case is free
    first.release()
    stagelock.StageLock(tmp_path, "preshear").acquire()  # free again once released


def test_lock_of_a_dead_process_is_taken_over_with_a_log_line(tmp_path):
    lock_file = tmp_path / ".partial" / "preshear.lock"
    lock_file.parent.mkdir()
    pid = dead_pid()
    lock_file.write_text(json.dumps(dict(pid=pid, host=os.uname().nodename, started="yesterday")))
    lines = []
    old = stagelock.StageLock(tmp_path, "preshear", log=lines.append).acquire()
    assert old["pid"] == pid
    assert len(lines) == 1 and f"stale lock of PID {pid}" in lines[0]
    assert json.loads(lock_file.read_text())["pid"] == os.getpid()


def test_lock_of_another_host_is_trusted_until_it_goes_stale(tmp_path):
    lock_file = tmp_path / ".partial" / "preshear.lock"
    lock_file.parent.mkdir()
    lock_file.write_text(json.dumps(dict(pid=1, host="elsewhere", started="now")))
    with pytest.raises(stagelock.Busy, match="PID 1 on host elsewhere"):
        stagelock.StageLock(tmp_path, "preshear").acquire()
    old = time.time() - stagelock.STALE_S - 5
    os.utime(lock_file, (old, old))
    assert stagelock.StageLock(tmp_path, "preshear", log=lambda line: None).acquire()["host"] == "elsewhere"


def test_release_removes_the_lock_and_an_empty_partial_folder_only(tmp_path):
    lk = stagelock.StageLock(tmp_path, "preshear")
    lk.acquire()
    lk.release()
    assert not (tmp_path / ".partial").exists()
    lk = stagelock.StageLock(tmp_path, "preshear")
    lk.acquire()
    (tmp_path / ".partial" / "preshear").mkdir()  # an interrupted stage's checkpoints stay
    lk.release()
    assert not (tmp_path / ".partial" / "preshear.lock").exists()
    assert (tmp_path / ".partial" / "preshear").is_dir()


def test_lock_naming_a_live_process_that_holds_no_flock_is_taken_over(tmp_path):
    """Liveness is the flock, not the PID in the file: after a crash the PID may name an
    unrelated live process (reused), and the stage must still start."""
    lock_file = tmp_path / ".partial" / "preshear.lock"
    lock_file.parent.mkdir()
    other = subprocess.Popen(["sleep", "30"])
    try:
        lock_file.write_text(json.dumps(dict(pid=other.pid, host=os.uname().nodename, started="before")))
        lines = []
        old = stagelock.StageLock(tmp_path, "preshear", log=lines.append).acquire()
        assert other.poll() is None  # still alive, and its PID did not keep the stage
    finally:
        other.kill()
        other.wait()
    assert old["pid"] == other.pid and f"stale lock of PID {other.pid}" in lines[0]
