"""The stage's log file, written only by the process that holds the stage lock.

A workflow manager may remove a job's log before it runs the job (Snakemake unlinks
every `log:` file of a job it starts) and a shell redirection truncates it. When a
second run of a stage is refused (exit 5: another process holds the stage lock), both
would erase the log of the stage that is running. So the runner is given the log's
path (`--log`) instead of a redirection, opens it only once it holds the lock, and
keeps a second name for the same file, `<case_dir>/.partial/<stage>.log` (a hard
link): if the log's path is removed or replaced while the stage runs, the stage puts
its own file back under that path (`keep`, after every run chunk). A refusal writes
to stderr only.

A stage killed (SIGKILL) and run again appends to the same file: the log of a resumed
stage holds the interrupted run, then the resumed one, each from a header line.
"""
import os
import socket
import sys
import time


class StageLog:
    """Redirect this process's stdout and stderr (file descriptors 1 and 2, so YADE's
    own messages too) into the stage's log file at ``path``.

    Parameters
    ----------
    path : str
        The log file (for instance Snakemake's `log:` of the stage's rule).
    case_dir, stage : str
        The second name is `<case_dir>/.partial/<stage>.log`, inside the folder the
        stage lock protects.
    """

    def __init__(self, path, case_dir, stage):
        self.path = os.path.abspath(path)
        self.keep_path = os.path.join(case_dir, ".partial", f"{stage}.log")
        self.stage = stage
        self.fd = None

    def open(self):
        """Open (append) the stage's own file, publish it at ``path``, redirect fds 1 and 2."""
        os.makedirs(os.path.dirname(self.path), exist_ok=True)
        resumed = os.path.exists(self.keep_path)  # left by a run that was killed
        flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_CLOEXEC
        self.fd = os.open(self.keep_path, flags, 0o644)
        try:
            self.keep()
        except OSError as e:  # no hard link across file systems: write the log's path directly
            os.close(self.fd)
            os.unlink(self.keep_path)
            self.keep_path, resumed = None, False
            self.fd = os.open(self.path, flags, 0o644)
            print(f"[{self.stage}] no second name for the log ({e}): a refused run may remove it",
                  file=sys.stderr)
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(self.fd, 1)
        os.dup2(self.fd, 2)
        print(f"=== stage {self.stage}: PID {os.getpid()} on host {socket.gethostname()}, "
              f"started {time.strftime('%Y-%m-%dT%H:%M:%S%z')}"
              + (" (appended to the log of an interrupted run)" if resumed else ""), flush=True)

    def keep(self):
        """Put the stage's file back at ``path`` if something removed or replaced it."""
        if self.fd is None or self.keep_path is None:
            return
        try:
            if os.stat(self.path).st_ino == os.fstat(self.fd).st_ino:
                return
        except FileNotFoundError:
            pass
        tmp = f"{self.path}.tmp{os.getpid()}"
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        os.link(self.keep_path, tmp)
        os.replace(tmp, self.path)

    def close(self):
        """Publish a last time and drop the second name (before the stage lock is released)."""
        if self.fd is None:
            return
        sys.stdout.flush()
        sys.stderr.flush()
        self.keep()
        if self.keep_path is not None:
            try:
                os.unlink(self.keep_path)
            except FileNotFoundError:
                pass
