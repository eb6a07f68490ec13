"""Fixtures shared by the test modules (plain helpers: tests/helpers.py).

The suite runs on both cores (``pytest -n 2``, pytest-xdist) and also without xdist
(``pytest -p no:xdist``). Tests that only make sense serially (a Slurm daemon, the timing
of signals between processes) carry the marker ``serial``: ``make test`` runs them after
the parallel part, alone (``-m serial -p no:xdist``).
"""
import pytest

from tests.helpers import workflow_copy


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
