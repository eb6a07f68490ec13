"""A calibration option edit reruns every calibration set it changes, and only those.

A finished calibration of two sets ("all" and "heaviside_only") is made once by
Snakemake's own calibrate rule (real ``python -m calibrate``, light options)
on model-made DEM series (``dem_contract.synthetic``, three seeds) written where
the campaign keeps its DEM results; ``--allowed-rules calibrate`` takes them as
given, so no YADE runs. Each test edits a copy of the config and asks Snakemake
(dry run, default rerun triggers) which sets it would recalibrate, and
``--summary`` whether a declared output is missing while nothing is planned for it.
"""
import copy
import re
from pathlib import Path

import pytest
import yaml

from dem_contract import synthetic
from model import default_params
from tests.helpers import TINY, snakemake, workflow_copy

GROUP = "p100000_I0.01"

CONFIG = {
    **TINY,
    "seeds": [1, 2, 3],
    "protocols": {"heaviside": {"strain": 0.5}, "sinusoidal": {"strain": 0.5, "transition_strain": 0.1}},
    "calibration": {
        "sets": {"heaviside_only": {"protocols": ["heaviside"]}},
        "options": "--bootstrap 2 --bootstrap-evals 20 --route2-evals 40 --profile-points 3 --profile-evals 10",
        "freeform": False,
    },
}

pytestmark = pytest.mark.slow  # about a minute of calibration, then a dry run and a summary per edit


def write(config, path):
    path.write_text(yaml.safe_dump(config))
    return path


def targets(config):
    """params.yaml of every set of ``config`` (what the comparison asks for)."""
    sets = ["all", *config["calibration"].get("sets", {})]
    return [f"{config['results_dir']}/calibration/{name}/params.yaml" for name in sets]


def calibrate_sets(config, path, *args):
    """Snakemake asked for every set's params.yaml with only the calibrate rule allowed, in a private
    working copy of the workflow next to ``path`` (its own .snakemake/, where the rerun triggers live)."""
    return snakemake(*targets(config), "--allowed-rules", "calibrate", "--configfile", write(config, path), *args,
                     cwd=workflow_copy(path.parent / "workflow"), timeout=600)


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """Two calibration sets, calibrated to the end; returns (config, its folder)."""
    tmp = tmp_path_factory.mktemp("calreruns")
    config = copy.deepcopy(CONFIG)
    config["results_dir"] = str(tmp / "results")
    config["allow_outside_tree"] = True  # a results folder under pytest's tmp_path
    synthetic.write_ensemble(tmp / "results" / "dem", default_params(), seeds=(1, 2, 3), group=GROUP, I=0.01,
                             fabric_noise=synthetic.FABRIC_NOISE, mu_noise=synthetic.MU_NOISE)
    result = calibrate_sets(config, tmp / "config.yaml", "-j1")
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-3000:]
    return config, tmp


def planned_sets(finished, edit, name):
    """The sets a dry run recalibrates after ``edit(config)``; asserts no declared output is
    missing while Snakemake plans nothing for it (``--summary``: status missing, plan no update)."""
    config, tmp = finished
    changed = copy.deepcopy(config)
    edit(changed)
    dry = calibrate_sets(changed, tmp / f"{name}.yaml", "-n")
    assert dry.returncode == 0, dry.stdout[-2000:] + dry.stderr[-2000:]
    summary = calibrate_sets(changed, tmp / f"{name}.yaml", "--summary")
    assert summary.returncode == 0, summary.stderr[-2000:]
    stale = [line.split("\t")[0] for line in summary.stdout.splitlines()
             if line.split("\t")[-2:] == ["missing", "no update"]]
    assert not stale, f"declared but missing, and not planned: {stale}"
    return set(re.findall(r"wildcards: calset=(\S+)", dry.stdout))


def test_unchanged_config_recalibrates_nothing(finished):
    assert planned_sets(finished, lambda c: None, "same") == set()


@pytest.mark.parametrize("name, edit", [
    ("freeform_on", lambda c: c["calibration"].update(freeform=True)),
    ("options", lambda c: c["calibration"].update(options=c["calibration"]["options"].replace(
        "--bootstrap 2", "--bootstrap 3"))),
])
def test_calibration_option_edit_recalibrates_every_set(finished, name, edit):
    assert planned_sets(finished, edit, name) == {"all", "heaviside_only"}


def test_set_protocol_edit_recalibrates_that_set_only(finished):
    edit = lambda c: c["calibration"]["sets"]["heaviside_only"].update(protocols=["heaviside", "sinusoidal"])  # noqa: E731
    assert planned_sets(finished, edit, "protocols") == {"heaviside_only"}


def test_new_set_calibrates_that_set_only(finished):
    edit = lambda c: c["calibration"]["sets"].update(sinusoidal_only={"protocols": ["sinusoidal"]})  # noqa: E731
    assert planned_sets(finished, edit, "new_set") == {"sinusoidal_only"}


def test_a_set_without_its_free_form_fit_says_so_in_freeform_csv(finished):
    config, _ = finished
    lines = Path(config["results_dir"], "calibration", "heaviside_only", "freeform.csv").read_text().splitlines()
    assert lines == ["section,key,value,low,high,n,detail", "note,not requested,,,,,calibration.freeform is false"]
