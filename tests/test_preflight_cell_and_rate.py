"""The pre-flight check names a wall cell's key given to a periodic cell, and a loading with no rate.

Each case runs the pre-flight command the Snakefile's gate runs (``python -m preflight
check``, in-process: ``helpers.preflight_check``; its wiring into Snakemake is
tests/test_campaign_preflight.py) on a copy of the CI preset with one thing wrong:
it must exit with code 2 and name the key and what is allowed; the unchanged preset
(and its periodic variant without the wall cell's key) must pass.
"""
import copy
from pathlib import Path

import pytest
import yaml

import preflight
from tests.helpers import preflight_check

ROOT = Path(__file__).resolve().parents[1]
CI = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
CI["calibration"]["options"] = ""  # checking them imports calibrate (seconds)


def periodic(config):
    config["cell"].update(kind="periodic", W_over_H=1)


def check(config, tmp_path):
    config = copy.deepcopy(config)
    config["results_dir"] = str(tmp_path / "results")
    config["allow_outside_tree"] = True  # a results folder under pytest's tmp_path
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    return preflight_check(path)


def test_periodic_cell_given_the_wall_cells_bulk_band_is_refused(tmp_path):
    config = copy.deepcopy(CI)
    periodic(config)
    result = check(config, tmp_path)
    assert result.returncode == 2, result.stderr[-2000:]
    assert ("config error: sampling.bulk_exclusion_d = 2: applies to a wall cell only" in result.stderr
            and "(allowed: leave it out, or set cell.kind: walls)" in result.stderr), result.stderr[-2000:]


def test_periodic_cell_without_wall_keys_and_the_wall_cell_pass_the_check():
    config = copy.deepcopy(CI)
    assert preflight.check(config) == []
    periodic(config)
    del config["sampling"]["bulk_exclusion_d"]
    assert preflight.check(config) == []


@pytest.mark.parametrize("loading", [{"pressures": [1.0e5]}, {"pressures": [1.0e5], "allow_inertial": False}])
def test_loading_without_a_rate_names_the_two_keys_it_accepts(tmp_path, loading):
    config = copy.deepcopy(CI)
    config["loading"] = loading
    result = check(config, tmp_path)
    assert result.returncode == 2, result.stderr[-2000:]
    assert "loading.inertial_numbers" in result.stderr and "loading.wall_velocities" in result.stderr
    assert "not valid under any of the given schemas" not in result.stderr, result.stderr[-2000:]


def test_loading_with_both_rates_still_says_not_both():
    config = copy.deepcopy(CI)
    config["loading"]["wall_velocities"] = [0.1]
    assert preflight.check(config) == ["config error: loading: give inertial_numbers or wall_velocities, not both"]
