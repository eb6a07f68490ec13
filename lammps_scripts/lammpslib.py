"""LAMMPS imported as a library by the interpreter its Python module was installed for.

Debian's `python3-lammps` lives in `/usr/lib/python3/dist-packages` (the system
interpreter's) and loads `liblammps.so`, while Debian's `liblammps0` ships only the
versioned `liblammps.so.0` (the unversioned name comes with a -dev package). So:

- `run_under_lammps_interpreter` re-executes the script under the interpreter that
  imports `lammps` (`LAMMPS_PYTHON`, default `/usr/bin/python3`), as yadelib does for
  YADE's;
- `open_lammps` loads the library under its unversioned name if the system has it
  (`make setup` links it), else under the versioned one: it opens the instance
  through the versioned library itself and hands the Python module a pointer to it
  (the module's own `ptr` path, which finds the symbols in the loaded library).

Pure Python; LAMMPS is loaded only by `open_lammps`.
"""
import ctypes
import os
import sys

PYTHON = os.environ.get("LAMMPS_PYTHON", "/usr/bin/python3")
SONAMES = ("liblammps.so", "liblammps.so.0")
_REEXEC = "LAMMPS_SCRIPTS_REEXEC"  # set once the interpreter was switched: never loop


class LammpsNotFound(RuntimeError):
    """No `lammps` Python module or no LAMMPS shared library (exit code 2)."""


def importable():
    """True when this interpreter imports Debian's `lammps` module."""
    try:
        import lammps  # noqa: F401
    except ImportError:
        return False
    return True


def run_under_lammps_interpreter():
    """Re-execute this script under `LAMMPS_PYTHON` if this interpreter cannot import `lammps`."""
    if importable() or os.environ.get(_REEXEC):
        return
    if not os.path.isfile(PYTHON):
        raise LammpsNotFound(f"no `lammps` Python module here and no interpreter {PYTHON} "
                             f"(Debian: apt-get install lammps python3-lammps; or set LAMMPS_PYTHON)")
    sys.stdout.flush()
    sys.stderr.flush()
    os.environ[_REEXEC] = "1"
    os.execv(PYTHON, [PYTHON, *sys.argv])


def shared_library():
    """The first of SONAMES the dynamic loader finds, loaded with its symbols global."""
    errors = []
    for name in SONAMES:
        try:
            return name, ctypes.CDLL(name, mode=ctypes.RTLD_GLOBAL)
        except OSError as e:
            errors.append(str(e))
    raise LammpsNotFound("no LAMMPS shared library (" + "; ".join(errors) + "): apt-get install lammps")


def open_lammps(args=("-log", "none", "-screen", "none", "-nocite")):
    """A `lammps.lammps` instance (serial, no MPI) started with command-line ``args``."""
    try:
        import lammps
    except ImportError as e:
        raise LammpsNotFound(f"no `lammps` Python module in {sys.executable}: {e} "
                             f"(Debian: apt-get install python3-lammps)")
    name, lib = shared_library()
    if name == SONAMES[0]:
        return lammps.lammps(cmdargs=list(args))
    argv = [b"lammps", *(a.encode() for a in args)]
    lib.lammps_open_no_mpi.restype = ctypes.c_void_p
    lib.lammps_open_no_mpi.argtypes = [ctypes.c_int, ctypes.c_char_p * len(argv), ctypes.c_void_p]
    handle = lib.lammps_open_no_mpi(len(argv), (ctypes.c_char_p * len(argv))(*argv), None)
    new_capsule = ctypes.pythonapi.PyCapsule_New
    new_capsule.restype = ctypes.py_object
    new_capsule.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p]
    lmp = lammps.lammps(ptr=new_capsule(handle, None, None))
    lmp.owned_handle = handle  # closed by close_lammps (the module does not close what it did not open)
    return lmp


def close_lammps(lmp):
    """Free the instance (also one opened through the versioned library)."""
    handle = getattr(lmp, "owned_handle", None)
    if handle is None:
        lmp.close()
        return
    lmp.lib.lammps_close.argtypes = [ctypes.c_void_p]
    lmp.lib.lammps_close(handle)
    lmp.lmp = None
