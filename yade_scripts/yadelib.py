"""YADE imported as a library by a plain Python interpreter, not run by the `yade` launcher.

The launcher (`yade -n -x script.py`) starts YADE's remote servers before it runs the
script: a TCP Python prompt on localhost:9000 and up, guarded by a six-letter cookie it
prints into the log, and an XMLRPC server on localhost:21000 and up without any
authentication. Any local user who can read the log, or try the cookies, gets a Python
prompt running as the job's owner for as long as the stage runs. YADE starts these
servers only in its launcher (`yade.remote.runServers()` under `__main__`); a Python
program that imports the `yade` package opens no socket. So the stages import it.

The launcher names the two things a library import needs: the interpreter YADE was
built for (its `#!` line; YADE's compiled modules match that interpreter's numpy) and
the folder of YADE's `yade` package (the `sys.path.insert(1, '...')` line of Debian's
launcher, or `<YADE_PREFIX>/lib/<arch>/yade<suffix>/py` as the launcher computes it).
Pure Python; YADE is imported only by `import_yade`.
"""
import os
import re
import shutil
import sys

LAUNCHER = os.environ.get("YADE_LAUNCHER", "yade")  # the launcher whose build is used
_REEXEC = "YADE_SCRIPTS_REEXEC"  # set once the interpreter was switched: never loop


class YadeNotFound(RuntimeError):
    """No YADE launcher on PATH or no `yade` package where it says (exit code 2)."""


def launcher_path():
    path = shutil.which(LAUNCHER)
    if path is None:
        raise YadeNotFound(f"YADE launcher {LAUNCHER!r} not found on PATH (Debian: apt-get install yade; "
                           f"or set YADE_LAUNCHER to the launcher of the build to use)")
    return os.path.realpath(path)


def launcher_facts(path):
    """(interpreter, package folder) read from the launcher script at ``path``."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        text = fh.read(65536)
    first = text.splitlines()[0] if text else ""
    interp = first[2:].strip().split()[0] if first.startswith("#!") and first[2:].strip() else None
    if interp is not None and os.path.basename(interp) == "env":  # `#!/usr/bin/env python3`: the PATH's
        interp = None
    m = re.search(r"sys\.path\.insert\(\s*1\s*,\s*['\"]([^'\"]+)['\"]\s*\)", text)
    folder = m.group(1) if m else None
    if folder is None or not os.path.isfile(os.path.join(folder, "yade", "__init__.py")):
        raise YadeNotFound(f"cannot find YADE's python package from the launcher {path} "
                           f"(no sys.path.insert(1, '<folder>') naming a folder with yade/__init__.py)")
    return interp, folder


def run_under_yade_interpreter():
    """Re-execute this script under the launcher's interpreter if another one runs it.

    YADE's compiled modules are built against that interpreter and its numpy; the
    project's virtual environment may have another of each. Returns only when the
    interpreter is the right one (or the launcher names none).
    """
    interp, _ = launcher_facts(launcher_path())
    if interp is None or os.environ.get(_REEXEC):
        return
    if os.path.realpath(sys.executable) != os.path.realpath(interp):
        sys.stdout.flush()
        sys.stderr.flush()
        os.environ[_REEXEC] = "1"
        os.execv(interp, [interp, *sys.argv])


def under_the_launcher():
    """True when the `yade` launcher runs this process (its remote servers are then open)."""
    return "yade.remote" in sys.modules


def import_yade():
    """Import the `yade` package (and its Omega) as a library; return the module."""
    if not any(os.path.isfile(os.path.join(p or ".", "yade", "__init__.py")) for p in sys.path):
        _, folder = launcher_facts(launcher_path())
        sys.path.insert(1, folder)
    import yade  # noqa: F401  (the C++ core boots here)
    import yade.config  # noqa: F401
    import yade.wrapper  # noqa: F401
    return yade
