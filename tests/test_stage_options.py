"""An options string of the config as the words a stage gets, and what those words set (campaign/stage_options.py)."""
import pytest

from campaign import stage_options
from tests.helpers import workflow_rules


def test_an_options_string_is_split_into_words_as_a_shell_would_split_it():
    config = {"calibration": {"options": "--freeform-layouts 5:2  --route2-method=LSODA"}}
    assert stage_options.words(config, "calibration.options") == ["--freeform-layouts", "5:2", "--route2-method=LSODA"]
    assert stage_options.words({"calibration": {}}, "calibration.options") == []
    assert stage_options.words({}, "compare.options") == []


def test_given_takes_the_words_up_to_the_next_option_and_negative_numbers_as_values():
    argv = ["--route2-evals=80", "--freeform-penalties", "1e-4", "-1", "--no-figures", "--zoom", "-1e-3"]
    assert stage_options.given(argv) == {"--route2-evals": ["80"], "--freeform-penalties": ["1e-4", "-1"],
                                         "--no-figures": [], "--zoom": ["-1e-3"]}
    assert stage_options.given_int(argv, "--route2-evals", 300) == 80
    assert stage_options.given_int(argv, "--profile-points", 10) == 10


@pytest.mark.parametrize("options, evals, points", [
    ("--route2-evals=120", 120, 10),                       # '=' form, and the variant's own default of points
    ("--bootstrap 8 --profile-points 8 --route2-evals 80", 80, 8),
])
def test_the_pole_start_fit_takes_its_budget_from_calibrates_own_words(module_workflow_dir, options, evals, points):
    rules = {r.name: r for r in workflow_rules(module_workflow_dir, module_workflow_dir / "config" / "ci.yaml",
                                               config={"calibration": {"options": options}})}
    params = rules["pole_start_calibrate"].params
    assert (params.evals, params.points) == (evals, points)
