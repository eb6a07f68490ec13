"""dem_contract.stage_costs: the one reader of a DEM case's per-stage costs from its sidecars."""
import json
import math

import pytest

from dem_contract import DEMInputError, stage_costs

STAGES = ("pack", "preshear", "heaviside")
SIDECARS = {
    "pack": dict(N=500, cpu_time_s=2.0, wall_time_s=2.5, steps=1000, stage="pack"),
    "preshear": dict(N=500, cpu_time_s=30.0, wall_time_s=33.0, steps=20000, stage="preshear"),
    "heaviside": dict(N=500, cpu_time_s=8.0, wall_time_s=9.5, steps=6000, stage="heaviside"),
}


def write_case(d, sidecars=SIDECARS):
    d.mkdir(parents=True, exist_ok=True)
    for stage, side in sidecars.items():
        (d / f"{stage}.json").write_text(json.dumps(side))
    return d


def test_per_stage_costs_and_their_sums_over_the_stages(tmp_path):
    c = stage_costs(write_case(tmp_path / "case"), STAGES)
    assert list(c) == ["N",
                       "cpu_time_pack_s", "wall_time_pack_s", "steps_pack",
                       "cpu_time_preshear_s", "wall_time_preshear_s", "steps_preshear",
                       "cpu_time_heaviside_s", "wall_time_heaviside_s", "steps_heaviside",
                       "cpu_time_s", "wall_time_s", "steps"]
    assert c["N"] == 500
    assert c["cpu_time_preshear_s"] == 30.0 and c["wall_time_heaviside_s"] == 9.5 and c["steps_pack"] == 1000
    assert c["cpu_time_s"] == 40.0 and c["wall_time_s"] == 45.0 and c["steps"] == 27000
    assert isinstance(c["steps"], int) and isinstance(c["N"], int)


def test_the_stages_asked_are_summed_and_only_the_keys_asked_are_read(tmp_path):
    c = stage_costs(write_case(tmp_path / "case"), ("preshear", "heaviside"), keys=("wall_time_s",))
    assert list(c) == ["N", "wall_time_preshear_s", "wall_time_heaviside_s", "wall_time_s"]
    assert c["wall_time_s"] == 42.5


def test_a_missing_key_raises_naming_the_file_and_the_key(tmp_path):
    side = {**SIDECARS, "preshear": {k: v for k, v in SIDECARS["preshear"].items() if k != "cpu_time_s"}}
    case = write_case(tmp_path / "case", side)
    with pytest.raises(DEMInputError, match=r"preshear\.json: sidecar without cpu_time_s") as err:
        stage_costs(case, STAGES)
    assert str(case / "preshear.json") in str(err.value)
    # a key not asked for is not required
    assert stage_costs(case, STAGES, keys=("wall_time_s", "steps"))["steps"] == 27000


def test_a_missing_key_gives_nan_for_that_stage_and_its_sum_when_asked(tmp_path):
    side = {**SIDECARS, "preshear": {k: v for k, v in SIDECARS["preshear"].items() if k != "cpu_time_s"}}
    c = stage_costs(write_case(tmp_path / "case", side), STAGES, missing="nan")
    assert math.isnan(c["cpu_time_preshear_s"]) and math.isnan(c["cpu_time_s"])
    assert c["cpu_time_pack_s"] == 2.0 and c["wall_time_s"] == 45.0 and c["steps"] == 27000


def test_a_missing_sidecar_raises_naming_the_file_or_gives_nan(tmp_path):
    case = write_case(tmp_path / "case", {s: SIDECARS[s] for s in ("pack", "preshear")})
    with pytest.raises(DEMInputError, match=r"heaviside\.json: file not found"):
        stage_costs(case, STAGES)
    c = stage_costs(case, STAGES, missing="nan")
    assert math.isnan(c["wall_time_heaviside_s"]) and math.isnan(c["steps"]) and c["N"] == 500
    empty = stage_costs(tmp_path / "model-made", STAGES, missing="nan")     # no sidecars at all
    assert all(math.isnan(v) for v in empty.values())


def test_a_sidecar_without_the_number_of_disks_raises(tmp_path):
    side = {**SIDECARS, "pack": {k: v for k, v in SIDECARS["pack"].items() if k != "N"}}
    with pytest.raises(DEMInputError, match=r"pack\.json: sidecar without N"):
        stage_costs(write_case(tmp_path / "case", side), STAGES)


def test_stages_that_disagree_on_the_number_of_disks_are_named(tmp_path):
    side = {**SIDECARS, "heaviside": {**SIDECARS["heaviside"], "N": 499}}
    with pytest.raises(DEMInputError, match=r"disagree on N.*'heaviside': 499"):
        stage_costs(write_case(tmp_path / "case", side), STAGES, missing="nan")


def test_an_unknown_rule_or_key_is_a_programming_error(tmp_path):
    case = write_case(tmp_path / "case")
    with pytest.raises(ValueError, match="missing='zero'"):
        stage_costs(case, STAGES, missing="zero")
    with pytest.raises(ValueError, match="cpu_s"):
        stage_costs(case, STAGES, keys=("cpu_s",))
