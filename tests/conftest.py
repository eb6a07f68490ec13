"""Fixtures shared by the test modules (plain helpers: tests/helpers.py).

The suite runs on both cores (``pytest -n 2``, pytest-xdist) and also without xdist
(``pytest -p no:xdist``). Tests that only make sense serially (a Slurm daemon, the timing
of signals between processes) carry the marker ``serial``: ``make test`` runs them after
the parallel part, alone (``-m serial -p no:xdist``).
"""
import fcntl
import hashlib
import json
import os
import subprocess

import pytest

from tests.helpers import dry_run, workflow_copy


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "serial: timing- or daemon-dependent; run alone, not beside other workers "
                   "(make test: pytest -p no:xdist -m serial)")


@pytest.fixture
def workflow_dir(tmp_path):
    """A private working copy of the workflow for one test's Snakemake runs (own .snakemake/, own results/)."""
    return workflow_copy(tmp_path / "workflow")


@pytest.fixture(scope="module")
def module_workflow_dir(tmp_path_factory):
    """A working copy of the workflow shared by one module's tests (for module-scoped runs)."""
    return workflow_copy(tmp_path_factory.mktemp("workflow"))


@pytest.fixture(scope="session")
def shared_dry_run(tmp_path_factory):
    """``helpers.dry_run(*args, quiet=...)`` in a fresh working copy, run once per session for each
    distinct argument list and shared by every module and pytest-xdist worker that asks for it.

    For dry runs that depend on their arguments alone (the repository's presets and profiles, no
    results): several modules plan the very same preset, at about 2.7 s of CPU a dry run. The
    result is kept as a JSON file per argument list under the session's temporary folder (the one
    the xdist workers share), made under an exclusive lock, so a worker waits for the other's run
    rather than repeating it. Returns a CompletedProcess."""
    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent  # the session's folder, above each worker's own
    folder = shared / "shared_dry_runs"
    folder.mkdir(exist_ok=True)

    def run(*args, quiet=True):
        key = hashlib.sha256(json.dumps([list(map(str, args)), quiet]).encode()).hexdigest()[:16]
        path = folder / f"{key}.json"
        with open(folder / f"{key}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not path.exists():
                r = dry_run(*args, quiet=quiet, cwd=workflow_copy(folder / f"{key}-workflow"))
                path.write_text(json.dumps({"args": r.args, "returncode": r.returncode, "stdout": r.stdout,
                                            "stderr": r.stderr}))
            done = json.loads(path.read_text())
        return subprocess.CompletedProcess(done["args"], done["returncode"], done["stdout"], done["stderr"])
    return run
