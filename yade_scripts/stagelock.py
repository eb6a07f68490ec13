"""One owner per stage: an exclusive lock on `<case_dir>/.partial/<stage>.lock`.

Only the process holding the lock reads or writes `<case_dir>/.partial/<stage>/`
and renames the stage's outputs into place, so an orphaned run (its Snakemake
killed) and a rerun of the same stage can never mix their files.

The lock is an advisory `flock` held for the life of the process (the kernel
drops it when the process dies, even on SIGKILL) on a file that names its owner
(PID, host, start time). The owner renews the file's mtime while it runs
(`touch`), so that a lock left by a process on another host, where the PID
cannot be checked, is taken as stale only once it has not been renewed for
`STALE_S` seconds. Pure Python: no YADE import.

Liveness is the flock itself, not the PID in the file: the kernel holds the lock
exactly as long as the owner's open file, so a successful flock on this host proves
that no process holds it, and a PID check could only refuse wrongly (the PID reused
by an unrelated process). The runner takes the lock before it imports YADE, so a
refusal comes within a fraction of a second of the start, while the owner runs.
"""
import errno
import fcntl
import json
import os
import socket
import time

STALE_S = 300.0  # a lock of another host not renewed for this long is stale
TOUCH_S = 10.0  # the owner renews its lock at most this often


class Busy(RuntimeError):
    """Another live process owns the stage (run_stage exits with code 5)."""


def _read(fd):
    os.lseek(fd, 0, os.SEEK_SET)
    raw = os.read(fd, 65536).decode("utf-8", "replace").strip()
    if not raw:
        return None
    try:
        rec = json.loads(raw)
    except ValueError:
        return {"raw": raw}
    return rec if isinstance(rec, dict) else {"raw": raw}


def describe(rec):
    """One line naming the owner of a lock record."""
    if not rec:
        return "an unknown process"
    if "pid" not in rec:
        return f"an unknown process (lock file holds {rec.get('raw', '')[:80]!r})"
    return f"PID {rec['pid']} on host {rec.get('host', '?')} (started {rec.get('started', '?')})"


class StageLock:
    """Exclusive ownership of one stage of one case.

    Parameters
    ----------
    case_dir, stage : str
        The lock file is `<case_dir>/.partial/<stage>.lock`.
    log : callable
        Receives one line when a stale lock is taken over.
    """

    def __init__(self, case_dir, stage, log=print):
        self.dir = os.path.join(case_dir, ".partial")
        self.path = os.path.join(self.dir, f"{stage}.lock")
        self.stage, self.case_dir, self.log = stage, case_dir, log
        self.fd = None
        self.last_touch = 0.0

    def acquire(self):
        """Take the lock or raise Busy naming its owner. Returns the stale record taken over, or None."""
        for _ in range(50):
            os.makedirs(self.dir, exist_ok=True)
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            except FileNotFoundError:  # a sibling stage removed the empty .partial/ just now
                continue
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as e:
                rec = _read(fd)
                os.close(fd)
                if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise Busy(self._busy_message(rec)) from None
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
                raise Busy(self._busy_message(old, foreign=True))
            self.fd = fd
            self._write()
            if old is not None:
                self.log(self._taken_over_line(old))
            return old
        raise RuntimeError(f"could not create the lock file {self.path}")

    def _taken_over_line(self, old):
        """The one line logged when a stale lock is taken over."""
        return f"[{self.stage}] stale lock of {describe(old)} taken over (that process is gone): {self.path}"

    def _may_take_over(self, rec, fd):
        """flock succeeded, so no process on this machine holds the lock; a record from
        another host (shared file system) is trusted only once it has gone stale."""
        if rec.get("host") in (None, socket.gethostname()):
            return True
        return time.time() - os.fstat(fd).st_mtime > STALE_S

    def _busy_message(self, rec, foreign=False):
        where = f"stage {self.stage} of {self.case_dir} is being run by {describe(rec)}"
        if foreign:
            return (f"{where}, whose lock {self.path} was renewed less than {STALE_S:.0f} s ago; "
                    f"not started. If that process is gone, wait {STALE_S:.0f} s or delete the lock file.")
        return (f"{where}; not started (exit 5). Wait for it to finish, or stop it "
                f"(kill -TERM {rec.get('pid', '<pid>') if rec else '<pid>'}: it writes a checkpoint) "
                f"and run the stage again.")

    def _write(self):
        rec = dict(pid=os.getpid(), host=socket.gethostname(), stage=self.stage,
                   started=time.strftime("%Y-%m-%dT%H:%M:%S%z"))
        os.ftruncate(self.fd, 0)
        os.lseek(self.fd, 0, os.SEEK_SET)
        os.write(self.fd, (json.dumps(rec) + "\n").encode())
        os.fsync(self.fd)
        self.last_touch = time.time()

    def touch(self):
        """Renew the lock's mtime (at most every TOUCH_S seconds)."""
        now = time.time()
        if self.fd is not None and now - self.last_touch >= TOUCH_S:
            os.utime(self.fd)
            self.last_touch = now

    def release(self):
        """Remove the lock file (still holding the lock), unlock, and remove .partial/ if empty."""
        if self.fd is None:
            return
        try:
            os.unlink(self.path)
        except FileNotFoundError:
            pass
        os.close(self.fd)
        self.fd = None
        try:
            os.rmdir(self.dir)
        except OSError:
            pass  # another stage's lock or folder is still there
