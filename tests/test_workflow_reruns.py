"""A config edit reruns the DEM exactly when it changes a DEM result.

A real tiny campaign (two ~40-disk cases, a short pre-shear and Heaviside
reversal: about 40 s of YADE on one core) is run once through Snakemake; each
test then edits a copy of its config and asks Snakemake (dry run) what it would
rerun.
"""
import copy
import shutil

import pytest
import yaml

from tests.helpers import counts as job_counts
from tests.helpers import TINY, dry_run, snakemake, workflow_copy

DEM_RULES = {"scene", "dem_pack", "dem_preshear", "dem_reversal"}

CASES = ["p100000_I0.01_s1", "p100000_I0.01_s2"]


def write(config, path):
    path.write_text(yaml.safe_dump(config))
    return path




@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """The tiny campaign's DEM, run to the end in a working copy of its own (whose .snakemake/ keeps
    the metadata the reruns are decided on); returns (config, its folder, DEM targets)."""
    if shutil.which("yade") is None:
        pytest.skip("needs YADE (Debian package yade)")
    tmp = tmp_path_factory.mktemp("reruns")
    config = copy.deepcopy(TINY)
    config["results_dir"] = str(tmp / "results")
    config["allow_outside_tree"] = True  # a results folder under pytest's tmp_path
    targets = [f"{config['results_dir']}/dem/{case}/heaviside.csv" for case in CASES]
    result = snakemake("-j1", *targets, "--configfile", write(config, tmp / "config.yaml"),
                       cwd=workflow_copy(tmp / "workflow"), timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    return config, tmp, targets


def planned(finished, edit, name, all_targets=False):
    """Jobs a dry run plans after ``edit(config)``: rule -> count."""
    config, tmp, targets = finished
    changed = copy.deepcopy(config)
    edit(changed)
    path = write(changed, tmp / f"{name}.yaml")
    result = dry_run(*([] if all_targets else targets), "--configfile", path, cwd=tmp / "workflow")
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    return job_counts(result.stdout)


pytestmark = [pytest.mark.yade, pytest.mark.slow]


def test_unchanged_config_reruns_nothing(finished):
    assert planned(finished, lambda c: None, "same") == {}


@pytest.mark.parametrize("name, edit", [
    ("friction", lambda c: c["material"].update(friction=0.2)),
    ("kappa", lambda c: c["material"].update(kappa=2.0e3)),
    ("preshear_strain", lambda c: c["preshear"].update(strain=0.25)),
    ("heaviside_strain", lambda c: c["protocols"]["heaviside"].update(strain=0.06)),
    ("bulk_exclusion", lambda c: c["sampling"].update(bulk_exclusion_d=1.5)),
])
def test_dem_setting_edit_reruns_every_case(finished, name, edit):
    counts = planned(finished, edit, name)
    assert {rule: counts.get(rule) for rule in DEM_RULES} == {rule: len(CASES) for rule in DEM_RULES}, counts


@pytest.mark.parametrize("name, edit", [
    ("calibration_options", lambda c: c["calibration"].update(options="--bootstrap 9")),
    ("compare_options", lambda c: c.update(compare={"options": "--zoom 0.05"})),
    ("run_intervals", lambda c: c["run"].update(progress_every_s=5)),
])
def test_edit_outside_the_dem_reruns_no_dem_job(finished, name, edit):
    counts = planned(finished, edit, name, all_targets=True)
    assert "calibrate" in counts  # the dry run does plan the stages after the DEM
    assert not DEM_RULES & set(counts), counts


# --------------------------------------------------------------------------- more seeds reuse the finished ones

@pytest.mark.yade
@pytest.mark.slow
def test_extending_seeds_plans_only_the_new_seeds_dem(finished):
    if shutil.which("yade") is None:
        pytest.skip("needs YADE (Debian package yade)")
    counts = planned(finished, lambda c: c.update(seeds=[*c["seeds"], 3]), "one_more_seed", all_targets=True)
    assert {rule: counts.get(rule) for rule in DEM_RULES} == {rule: 1 for rule in DEM_RULES}, counts
    assert counts.get("claims_plan") == 1 and counts.get("claims") == 1
