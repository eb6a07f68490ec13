"""One writer per results folder: an exclusive lock on ``<results_dir>/.snakemake-writer.lock``.

Snakemake's own lock lives in the working directory (``.snakemake/locks``), so
two Snakemakes started from two clones, or with two ``--directory`` values,
would otherwise both write one results folder: the DEM stages have their own
lock, the calibration, comparison and claims jobs none. The Snakefile takes
this lock in ``onstart`` (only a run that executes jobs: a dry run, ``--summary``,
``--report`` or "Nothing to be done" never takes it) and releases it in
``onsuccess`` / ``onerror``; a second run is refused before its first job.

The lock is ``yade_scripts/stagelock.py``'s, for a folder instead of a stage: an advisory ``flock`` held
for the life of the process (the kernel drops it when the process dies, even on
SIGKILL) on a file that names its owner (PID, host, start time, working
directory). A lock file left by a dead process on this host is taken over with
one line saying so. On a shared file system a record of another host is
trusted until it has not been renewed for ``STALE_S`` seconds (the owner renews
the file's mtime every ``TOUCH_S`` seconds from a daemon thread).
"""
from __future__ import annotations

import json
import os
import socket
import sys
import threading
import time

from .scene_spec import yade_scripts_module

_stagelock = yade_scripts_module("stagelock")

LOCK_NAME = ".snakemake-writer.lock"
STALE_S = _stagelock.STALE_S  # a lock of another host not renewed for this long is stale
TOUCH_S = _stagelock.TOUCH_S  # the owner renews its lock this often
EXIT_BUSY = 5  # exit code of a refused run (as a refused DEM stage)

#: Another live Snakemake writes the results folder (the stage lock's refusal).
ResultsBusy = _stagelock.Busy


def describe(rec: dict | None) -> str:
    """One line naming the owner of a lock record."""
    if not rec or "pid" not in rec:
        return "an unknown process" + (f" (lock file holds {rec['raw'][:80]!r})" if rec and "raw" in rec else "")
    return (f"Snakemake PID {rec['pid']} on host {rec.get('host', '?')}, started {rec.get('started', '?')} "
            f"in {rec.get('cwd', '?')}")


class ResultsLock(_stagelock.StageLock):
    """Exclusive ownership of one results folder by one Snakemake process.

    The stage lock's ``acquire`` (flock, the re-check that the path is still the
    locked file, stale-lock takeover); the record names the working directory and
    a daemon thread renews it, since Snakemake runs no loop of its own.

    Parameters
    ----------
    results_dir : str or Path
        The lock file is ``<results_dir>/.snakemake-writer.lock`` (the folder is created).
    log : callable
        Receives one line when a stale lock is taken over.
    """

    def __init__(self, results_dir, log=print):
        super().__init__(results_dir, "results", log)
        self.dir = os.path.abspath(results_dir)
        self.path = os.path.join(self.dir, LOCK_NAME)
        self._stop = threading.Event()

    def acquire(self) -> dict | None:
        """Take the lock or raise ``ResultsBusy`` naming its owner; returns the stale record taken over, or None."""
        old = super().acquire()
        threading.Thread(target=self._renew, name="results-lock", daemon=True).start()
        return old

    def _taken_over_line(self, old) -> str:
        return f"stale results-folder lock of {describe(old)} taken over (that process is gone): {self.path}"

    def _busy_message(self, rec, foreign=False) -> str:
        where = f"results folder {self.dir} is being written by {describe(rec)}"
        if foreign:
            return (f"{where}, whose lock {self.path} was renewed less than {STALE_S:.0f} s ago; no job started. "
                    f"If that process is gone, wait {STALE_S:.0f} s or delete the lock file.")
        return (f"{where}; no job started (exit {EXIT_BUSY}). Wait for it to finish, or stop it "
                f"(kill -INT {rec.get('pid', '<pid>') if rec else '<pid>'}), or use another results_dir. "
                "A dry run (-n), --summary and --report need no lock.")

    def _write(self) -> None:
        rec = dict(pid=os.getpid(), host=socket.gethostname(), cwd=os.getcwd(),
                   started=time.strftime("%Y-%m-%dT%H:%M:%S%z"))
        os.ftruncate(self.fd, 0)
        os.lseek(self.fd, 0, os.SEEK_SET)
        os.write(self.fd, (json.dumps(rec) + "\n").encode())
        os.fsync(self.fd)

    def _renew(self) -> None:
        while not self._stop.wait(TOUCH_S):
            fd = self.fd
            if fd is None:
                return
            try:
                os.utime(fd)
            except OSError:
                return

    def release(self) -> None:
        """Remove the lock file (still holding the lock), then unlock; the results folder stays."""
        if self.fd is None:
            return
        self._stop.set()
        try:
            os.unlink(self.path)
        except FileNotFoundError:
            pass
        fd, self.fd = self.fd, None
        os.close(fd)


_held: ResultsLock | None = None


def take_or_exit(results_dir) -> None:
    """The Snakefile's ``onstart``: take the results folder's lock, or print why not and exit with ``EXIT_BUSY``."""
    global _held
    lock = ResultsLock(results_dir, log=lambda line: print(line, flush=True))
    try:
        lock.acquire()
    except ResultsBusy as exc:
        print(f"refused: {exc}", file=sys.stderr, flush=True)
        raise SystemExit(EXIT_BUSY) from None
    _held = lock


def give_back() -> None:
    """The Snakefile's ``onsuccess`` and ``onerror``: release the lock this process holds (if any)."""
    global _held
    if _held is not None:
        _held.release()
        _held = None
