"""The stage runners' shared command line: scene, stage lock, log, then the engine's run.

python3 <engine>_scripts/run_stage.py <scene.json> <stage> <case_dir> [--log <file>]

Pure Python (no YADE, no LAMMPS): yade_scripts/run_stage.py and lammps_scripts/run_stage.py
differ only in how they start their engine and run the stage (the ``run`` they hand to
``main``). The order is: the scene (its `engine` must be the runner's), the stage lock (a
refusal is cheap and immediate), the log (opened only once the lock is held, see stagelog),
the engine. Exit codes: 0 done, 1 unexpected error, 2 bad scene, missing input or engine not
found, 3 guard fired, 4 interrupted by SIGTERM or SIGINT, 5 another live process runs this
stage of this case (nothing touched, the log included).
"""
import os
import signal
import sys
import time
import traceback

import scene as scenemod
import stagelock
import stagelog
from stageerrors import GuardError, InputError, Interrupted

#: A stage's failure -> (exit code, the message's prefix on stderr).
EXITS = ((InputError, 2, "input error"), (GuardError, 3, "guard"), (Interrupted, 4, "interrupted"))

RUNNERS = {"yade": "yade_scripts/run_stage.py", "lammps": "lammps_scripts/run_stage.py"}
SIGNALS = []  # (signal number, time.time() when Python ran the handler) of each SIGTERM/SIGINT


def on_signal(signum, frame):
    SIGNALS.append((signum, time.time()))


def install_signal_handlers():
    """SIGTERM and SIGINT only record themselves (SIGNALS); the stage's run loop checkpoints and
    stops at the end of its current run chunk (exit code 4, `interrupted`).

    A SIGINT ignored by the parent (a background job of a non-interactive shell) stays ignored.
    """
    signal.signal(signal.SIGTERM, on_signal)
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, on_signal)


def interrupted(where, rows, partial):
    """The Interrupted error of the first signal received: checkpoint at ``where`` (its step),
    ``rows`` rows, in the work folder ``partial``."""
    name = signal.Signals(SIGNALS[0][0]).name
    return Interrupted(f"{name} received: checkpoint at {where} ({rows} rows) written in {partial}; "
                       f"run the same command again to resume")


def usage(engine):
    return (f"usage: python3 {RUNNERS[engine]} <scene.json> "
            "<pack|preshear|heaviside|sinusoidal|<schedule name>> <case_dir> [--log <file>]")


def parse(argv):
    """(scene path, stage, case_dir, log path or None), or None if the command line is wrong."""
    argv, log = list(argv), None
    if "--log" in argv:
        k = argv.index("--log")
        if k + 1 >= len(argv):
            return None
        log = argv[k + 1]
        del argv[k:k + 2]
    if len(argv) != 3:
        return None
    return (*argv, log)


class Renew:
    """Called by the run loop after every chunk: renew the lock, keep the log in place."""

    def __init__(self, lock, log):
        self.lock, self.log = lock, log

    def touch(self):
        self.lock.touch()
        if self.log is not None:
            self.log.keep()


def exit_code(work):
    """Call ``work()``; 0, or the exit code of the stage failure it raised (EXITS), named on stderr."""
    try:
        work()
    except tuple(cls for cls, _, _ in EXITS) as e:
        code, what = next((c, w) for cls, c, w in EXITS if isinstance(e, cls))
        print(f"{what}: {e}", file=sys.stderr)
        return code
    return 0


def run_stage(stage, renew):
    """Run the engine's ``stage`` (a stages.Stage): signals recorded (`install_signal_handlers`),
    prepare, run to the end (``renew`` after every run chunk), the engine closed whatever happens;
    the exit code (`exit_code`)."""
    install_signal_handlers()

    def work():
        try:
            stage.prepare()
            stage.run(renew)
        finally:
            stage.close()

    return exit_code(work)


def leave(main):
    """The runner's last act: ``main()``'s exit code (1 with the traceback on an unexpected error: in
    the log once it is open), the output flushed, then os._exit (YADE's threads are not joined)."""
    try:
        rc = main()
    except Exception:
        traceback.print_exc()
        rc = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(rc)


def main(argv, engine, run):
    """Check the command line and the scene, hold the stage lock, open the log, then
    ``run(scene, sha, stage, case_dir, renew)``; return the exit code."""
    args = parse(argv)
    if args is None or not (args[1] in scenemod.STAGES or scenemod.PROTOCOL_NAME.match(args[1])):
        print(usage(engine), file=sys.stderr)
        return 2
    path, stage, case_dir, log_path = args
    try:
        scene, sha = scenemod.load(path, stage)
    except scenemod.SceneError as e:
        print(e, file=sys.stderr)
        return 2
    if scenemod.engine(scene) != engine:
        other = scenemod.engine(scene)
        print(f"scene error: {scenemod.ENGINE} = {other!r}: this scene is for {RUNNERS[other]} "
              f"({RUNNERS[engine]} runs {scenemod.ENGINE} = {engine!r})", file=sys.stderr)
        return 2
    said = []  # the lock's lines (a stale lock taken over) go to the log, once it is open
    lock = stagelock.StageLock(case_dir, stage, log=said.append)
    try:
        lock.acquire()
    except stagelock.Busy as e:
        print(f"busy: {e}", file=sys.stderr)
        return 5
    log = stagelog.StageLog(log_path, case_dir, stage) if log_path else None
    try:
        if log is not None:
            log.open()
        for line in said:
            print(line, flush=True)
        return run(scene, sha, stage, case_dir, Renew(lock, log))
    finally:
        if log is not None:
            log.close()
        lock.release()
