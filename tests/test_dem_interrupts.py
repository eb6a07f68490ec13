"""Interrupted DEM stages with real YADE: SIGTERM/SIGINT checkpoint and resume, one owner per stage,
a log no refused run touches, no listening socket.

Each test starts a pre-shear on the tiny cell of test_dem_stages (pack made once
here), interrupts or doubles it, and checks that the final series lies exactly on
the stage's grid of sampling steps: no gap, no duplicated row, no foreign row.
"""
import json
import math
import os
import re
import shutil
import signal
import subprocess
import time

import numpy as np
import pytest

from tests.helpers import RUN, command, make_scene, read, yade

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


def start(scene, cdir, log=None, **kw):
    kw.setdefault("preexec_fn", _sigint_as_at_a_terminal)
    extra = ["--log", log] if log else []
    return subprocess.Popen(command(RUN, scene, "preshear", cdir, *extra),
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


@pytest.fixture(scope="module")
def uninterrupted(packed, tmp_path_factory):
    """The pre-shear to strain 2.0 of new_case, run without interruption: its CSV's bytes."""
    scene, cdir = new_case(packed, tmp_path_factory.mktemp("uninterrupted"), strain=2.0)
    r = yade(RUN, scene, "preshear", cdir)
    assert r.returncode == 0, r.stderr[-2000:]
    return (cdir / "preshear.csv").read_bytes()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_writes_a_checkpoint_exits_4_and_the_rerun_resumes_to_the_same_bit(packed, uninterrupted,
                                                                                    tmp_path, sig):
    """The signal rewinds to the last reload point (every 10,000 steps, past which 80 rows lie
    on this cell) and checkpoints there; the resumed series is the uninterrupted one's."""
    scene, cdir = new_case(packed, tmp_path, strain=2.0)
    proc = start(scene, cdir)
    try:
        wait_for_rows(cdir, 80, proc)
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
    assert (cdir / "preshear.csv").read_bytes() == uninterrupted


def test_second_process_on_a_stage_is_refused_and_leaves_the_first_ones_log_intact(packed, tmp_path):
    """The second run is started as Snakemake starts a job: its `log:` file removed first, then the
    runner given that same path. It exits 5 on stderr only; the first completes and its log, put
    back under its path, holds the whole run (header, progress before the removal, the end)."""
    scene, cdir = new_case(packed, tmp_path, strain=1.2)
    log = tmp_path / "logs" / "preshear.log"
    first = start(scene, cdir, log=log)
    try:
        wait_for_rows(cdir, 5, first)
        t0 = time.time()
        while "| t " not in (log.read_text() if log.exists() else ""):  # a progress line (every 1 s)
            assert first.poll() is None and time.time() - t0 < 60
            time.sleep(0.1)
        before = log.read_text()
        log.unlink()  # what Snakemake does to a job's log before it runs the job
        second = yade(RUN, scene, "preshear", cdir, "--log", log, timeout=60)
        assert first.poll() is None, "the first run ended before the second was refused"
        out, err = first.communicate(timeout=120)
    finally:
        if first.poll() is None:
            first.kill()
    assert second.returncode == 5, second.stdout[-1000:] + second.stderr[-1000:]
    assert f"being run by PID {first.pid} on host" in second.stderr
    assert "Traceback" not in second.stderr
    assert first.returncode == 0, log.read_text()[-2000:]
    text = log.read_text()
    assert text.startswith(before) and f"=== stage preshear: PID {first.pid} on host" in text
    assert "[preshear] done:" in text and "busy" not in text
    assert out == "" and err == ""  # everything went to the log
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
    """Snakemake killed with SIGKILL leaves its job running: here the parent is a bash.

    The orphan is stopped (SIGSTOP: it keeps its lock, as any live owner does) while the
    rerun decides, so that on a loaded machine it cannot finish before the rerun asks for
    the lock (a rerun that finds the stage free rightly runs it: that is not a refusal)."""
    scene, cdir = new_case(packed, tmp_path, strain=1.5)
    cmd = " ".join(command(RUN, scene, "preshear", cdir)) + f" > {tmp_path / 'orphan.log'} 2>&1; echo finished"
    parent = subprocess.Popen(["bash", "-c", cmd], env=ENV, start_new_session=True)
    lock = cdir / ".partial" / "preshear.lock"
    orphan = None
    try:
        wait_for_rows(cdir, 5, parent)
        orphan = json.loads(lock.read_text())["pid"]
        assert orphan != parent.pid  # the stage is a child of bash, not bash itself
        parent.kill()
        parent.wait()
        os.kill(orphan, signal.SIGSTOP)
        rerun = yade(RUN, scene, "preshear", cdir, timeout=60)
        assert running(orphan), "the orphan ended before the rerun asked for the lock"
        os.kill(orphan, signal.SIGCONT)
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
        if orphan is not None and running(orphan):
            os.kill(orphan, signal.SIGCONT)
        if lock.exists():
            os.kill(json.loads(lock.read_text())["pid"], signal.SIGKILL)
    assert "done:" in (tmp_path / "orphan.log").read_text()
    side = assert_complete_on_grid(cdir, 1.5)
    assert side["resumed"] == 0


def listening_tcp_ports(pid):
    """TCP ports process ``pid`` listens on: the inodes of its sockets (/proc/<pid>/fd) among the
    LISTEN rows (state 0A) of /proc/<pid>/net/tcp and tcp6."""
    inodes = set()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        try:
            m = re.fullmatch(r"socket:\[(\d+)\]", os.readlink(f"/proc/{pid}/fd/{fd}"))
        except OSError:
            continue
        if m:
            inodes.add(m.group(1))
    ports = []
    for table in ("tcp", "tcp6"):
        try:
            rows = open(f"/proc/{pid}/net/{table}").read().splitlines()[1:]
        except FileNotFoundError:
            continue
        ports += [int(f[1].rsplit(":", 1)[1], 16) for f in map(str.split, rows) if f[3] == "0A" and f[9] in inodes]
    return sorted(ports)


SERVER_LINES = re.compile(r"auth cookie|TCP python prompt|XMLRPC", re.I)


def test_the_yade_launcher_listens_and_prints_its_cookie(tmp_path):
    """The check below can fail: a script run by `yade -n -x` listens (the Python prompt on
    9000 and up, XMLRPC on 21000 and up) and its output holds the prompt's auth cookie."""
    script = tmp_path / "wait.py"
    script.write_text("import time\ntime.sleep(120)\n")
    out = tmp_path / "launcher.log"
    with open(out, "w") as fh:
        proc = subprocess.Popen(["yade", "-n", "-x", str(script)], stdout=fh, stderr=subprocess.STDOUT, env=ENV)
    try:
        t0 = time.time()
        while len(listening_tcp_ports(proc.pid)) < 2:
            assert proc.poll() is None and time.time() - t0 < 60
            time.sleep(0.2)
        ports = listening_tcp_ports(proc.pid)
    finally:
        proc.kill()
        proc.wait()
    assert any(9000 <= p < 9100 for p in ports) and any(21000 <= p < 21100 for p in ports), ports
    assert SERVER_LINES.search(out.read_text())


def test_a_running_stage_listens_on_no_port_and_logs_no_cookie(packed, tmp_path):
    scene, cdir = new_case(packed, tmp_path, strain=1.2)
    log = tmp_path / "preshear.log"
    proc = start(scene, cdir, log=log)
    try:
        wait_for_rows(cdir, 20, proc)
        ports = listening_tcp_ports(proc.pid)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert ports == []
    assert proc.returncode == 0, log.read_text()[-2000:]
    text = log.read_text()
    assert "[preshear] done:" in text
    assert not SERVER_LINES.search(text + out + err)
