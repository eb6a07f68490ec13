"""campaign/: the case table and the scene files the workflow writes."""
import copy
import os
from pathlib import Path

import pytest
import yaml

from campaign.cases import cases
from campaign.scene_spec import scene_module
from campaign.scenes import result_key, scene_from_config, scene_of_result_key, write_scene
from dem_contract.labels import parse_case_label

ROOT = Path(__file__).resolve().parents[1]
QUICK = yaml.safe_load((ROOT / "config" / "quick.yaml").read_text())


def scene_validator():
    return scene_module().validate


def test_cases_cover_every_pressure_rate_and_seed_under_parseable_labels():
    table = cases(QUICK)
    assert len(table) == 2 * 3
    for label, case in table.items():
        assert parse_case_label(label) == dict(group=label.rsplit("_s", 1)[0], **case)


def test_wall_velocities_become_inertial_numbers_with_the_nominal_gap():
    # I = (2U/H) d / sqrt(p/rho): H = 12 mm, U = 0.06 m/s, sqrt(1e5/2500) = 6.3246 m/s -> I = 1.581e-3
    config = copy.deepcopy(QUICK)
    config["cell"]["H_over_d"] = 12
    config["loading"] = {"pressures": [1e5], "wall_velocities": [0.06]}
    (case, *_) = cases(config).values()
    assert case["inertial_number"] == pytest.approx(2 * 0.06 / 12e-3 * 1e-3 / 6.32455532, rel=1e-6)


def test_scene_passes_the_dem_validator_and_round_trips_through_its_result_key():
    label, case = next(iter(cases(QUICK).items()))
    scene = scene_from_config(QUICK, case, label)
    scene_validator()(scene, stage="sinusoidal")
    assert scene_of_result_key(result_key(scene), QUICK) == scene


def test_result_key_moves_with_the_physics_not_with_the_run_intervals():
    label, case = next(iter(cases(QUICK).items()))
    key = result_key(scene_from_config(QUICK, case, label))
    slower_progress = copy.deepcopy(QUICK)
    slower_progress["run"]["progress_every_s"] = 5
    assert result_key(scene_from_config(slower_progress, case, label)) == key
    softer = copy.deepcopy(QUICK)
    softer["material"]["friction"] = 0.2
    assert result_key(scene_from_config(softer, case, label)) != key


def test_scene_file_is_rewritten_only_when_its_content_changes(tmp_path):
    label, case = next(iter(cases(QUICK).items()))
    scene = scene_from_config(QUICK, case, label)
    path = tmp_path / "scene.json"
    assert write_scene(scene, path) is True
    os.utime(path, (1, 1))
    assert write_scene(scene, path) is False and path.stat().st_mtime == 1
    assert write_scene({**scene, "seed": 99}, path) is True and path.stat().st_mtime > 1


def test_periodic_cell_config_gives_a_periodic_scene_without_the_wall_band():
    config = copy.deepcopy(QUICK)
    config["cell"] = {"H_over_d": 12, "W_over_H": 1.0, "kind": "periodic", "mass": 0.5}
    config["sampling"]["bulk_exclusion_d"] = 3      # the schema's default, filled in for every config
    label, case = next(iter(cases(config).items()))
    scene = scene_from_config(config, case, label)
    assert scene["cell"] == {"kind": "periodic", "mass": 0.5}
    assert scene["geometry"] == {"H_over_d": 12, "W_over_H": 1.0}
    assert "bulk_exclusion_d" not in scene["sampling"]
    checked = scene_validator()(scene, stage="heaviside")
    assert checked["material"]["contact_law"] == "frictvisco"


def test_wall_cell_scene_is_unchanged_by_an_explicit_kind():
    label, case = next(iter(cases(QUICK).items()))
    explicit = copy.deepcopy(QUICK)
    explicit["cell"]["kind"] = "walls"
    assert result_key(scene_from_config(explicit, case, label)) == result_key(scene_from_config(QUICK, case, label))
