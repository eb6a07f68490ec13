"""One writer per results folder: an exclusive lock on ``<results_dir>/.snakemake-writer.lock``.

Snakemake's own lock lives in the working directory (``.snakemake/locks``), so
two Snakemakes started from two clones, or with two ``--directory`` values,
would otherwise both write one results folder: the DEM stages have their own
lock, the calibration, comparison and claims jobs none. The Snakefile takes
this lock in ``onstart`` (only a run that executes jobs: a dry run, ``--summary``,
``--report`` or "Nothing to be done" never takes it) and releases it in
``onsuccess`` / ``onerror``; a second run is refused before its first job.

As ``yade_scripts/stagelock.py`` does for one stage: an advisory ``flock`` held
for the life of the process (the kernel drops it when the process dies, even on
SIGKILL) on a file that names its owner (PID, host, start time, working
directory). A lock file left by a dead process on this host is taken over with
one line saying so. On a shared file system a record of another host is
trusted until it has not been renewed for ``STALE_S`` seconds (the owner renews
the file's mtime every ``TOUCH_S`` seconds from a daemon thread).
"""
from __future__ import annotations

import errno
import fcntl
import json
import os
import socket
import sys
import threading
import time

LOCK_NAME = ".snakemake-writer.lock"
STALE_S = 300.0  # a lock of another host not renewed for this long is stale
TOUCH_S = 10.0  # the owner renews its lock this often
EXIT_BUSY = 5  # exit code of a refused run (as a refused DEM stage)


class ResultsBusy(RuntimeError):
    """Another live Snakemake writes the results folder."""


def _read(fd) -> dict | None:
    os.lseek(fd, 0, os.SEEK_SET)
    raw = os.read(fd, 65536).decode("utf-8", "replace").strip()
    if not raw:
        return None
    try:
        rec = json.loads(raw)
    except ValueError:
        return {"raw": raw}
    return rec if isinstance(rec, dict) else {"raw": raw}


def describe(rec: dict | None) -> str:
    """One line naming the owner of a lock record."""
    if not rec or "pid" not in rec:
        return "an unknown process" + (f" (lock file holds {rec['raw'][:80]!r})" if rec and "raw" in rec else "")
    return (f"Snakemake PID {rec['pid']} on host {rec.get('host', '?')}, started {rec.get('started', '?')} "
            f"in {rec.get('cwd', '?')}")


class ResultsLock:
    """Exclusive ownership of one results folder by one Snakemake process.

    Parameters
    ----------
    results_dir : str or Path
        The lock file is ``<results_dir>/.snakemake-writer.lock`` (the folder is created).
    log : callable
        Receives one line when a stale lock is taken over.
    """

    def __init__(self, results_dir, log=print):
        self.dir = os.path.abspath(results_dir)
        self.path = os.path.join(self.dir, LOCK_NAME)
        self.log = log
        self.fd = None
        self._stop = threading.Event()

    def acquire(self) -> dict | None:
        """Take the lock or raise ``ResultsBusy`` naming its owner; returns the stale record taken over, or None."""
        os.makedirs(self.dir, exist_ok=True)
        for _ in range(50):
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                rec = _read(fd)
                os.close(fd)
                if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise ResultsBusy(self._busy_message(rec)) from None
                raise
            try:  # the previous owner may have removed the file between our open and flock
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if not same:
                os.close(fd)
                continue
            old = _read(fd)
            if old is not None and not self._may_take_over(old, fd):
                os.close(fd)
                raise ResultsBusy(self._busy_message(old, foreign=True))
            self.fd = fd
            self._write()
            threading.Thread(target=self._renew, name="results-lock", daemon=True).start()
            if old is not None:
                self.log(f"stale results-folder lock of {describe(old)} taken over (that process is gone): {self.path}")
            return old
        raise RuntimeError(f"could not create the lock file {self.path}")

    def _may_take_over(self, rec: dict, fd) -> bool:
        """flock succeeded, so no process on this host holds the lock; a record of
        another host (shared file system) is trusted only until it goes stale."""
        if rec.get("host") in (None, socket.gethostname()):
            return True
        return time.time() - os.fstat(fd).st_mtime > STALE_S

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
        """Remove the lock file (still holding the lock), then unlock."""
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
