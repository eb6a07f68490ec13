"""fit_quality.csv holds finite scores or NaN with a reason, and warns when intervals rest on fewer than 3 seeds."""
import numpy as np
import pandas as pd
import pytest

from calibrate import pipeline, problem, route_choice, synthetic
from calibrate.profiles import ProfileSettings
from model import default_params


def held(scores, failure="PoleError: X = 0.1 >= X_c = 0.09"):
    """A held-out table of one (model, route) as bootstrap.run writes it: inf where a replicate failed."""
    s = np.array(scores, dtype=float)
    return pd.DataFrame({"replicate": range(len(s)), "score": s, "rms_A_norm": s / 50, "rms_theta_A": s * 20,
                         "rms_mu": s / 25, "failure": np.where(np.isfinite(s), "", failure)})


def test_heldout_means_leave_out_failed_replicates_and_count_them():
    h = held([1.0, np.inf, 3.0, np.inf])
    m = route_choice.heldout_means(h)
    assert m["heldout_score"] == 2.0 and m["heldout_rms_theta_A"] == 40.0
    assert m["heldout_replicates"] == 4 and m["heldout_failed"] == 2
    note = route_choice.score_note({"score": 1.1}, h)
    assert "2 of 4 replicates" in note and "PoleError" in note


def test_scores_are_nan_with_a_reason_when_nothing_could_be_integrated():
    h = held([np.inf, np.inf])
    m = route_choice.heldout_means(h)
    assert all(np.isnan(m[f"heldout_{k}"]) for k in route_choice.SCORES) and m["heldout_failed"] == 2
    note = route_choice.score_note({"score": np.inf, "failure": "FabricDivergence: the fabric diverged"}, h)
    assert "in-sample scores NaN" in note and "FabricDivergence" in note and "held-out scores NaN" in note


@pytest.mark.parametrize("seeds, warned", [((1,), True), ((1, 2), True), ((1, 2, 3), False)])
def test_seed_warning_below_three_seeds(seeds, warned):
    class Case:
        def __init__(self, s):
            self.group, self.name = "p1_I0.001", f"p1_I0.001_s{s}"
    text = problem.seed_warning([Case(s) for s in seeds])
    assert bool(text) == warned
    if warned:
        assert f"p1_I0.001 ({len(seeds)} seed" in text and "fewer than 3 seeds" in text


def test_one_seed_calibration_warns_in_log_and_table_and_writes_no_inf(tmp_path):
    dirs = synthetic.write_ensemble(tmp_path / "dem", default_params(), seeds=(1,))
    log = []
    pipeline.run(dirs, tmp_path / "cal", pipeline.Settings(n_boot=2, boot_evals=10, figures=False,
                                                           profile=ProfileSettings(n_points=4, evals=10)),
                 log=log.append)
    assert any(m.startswith("warning: bootstrap intervals rest on fewer than 3 seeds") for m in log)
    q = pd.read_csv(tmp_path / "cal" / "fit_quality.csv")
    assert q["warning"].str.contains("p1_I0.001 \\(1 seed\\)").all()
    numbers = q.select_dtypes("number").to_numpy()
    assert not np.isinf(numbers).any() and np.nanmax(np.abs(q.filter(regex="_score$").to_numpy())) < 1e6
    models = q[q["model"].isin(["model1", "model2"])]
    assert models["heldout_score"].isna().all()        # one seed: no replicate holds a seed out ...
    assert models["score_note"].str.contains("no bootstrap replicate held a seed out").all()   # ... and it says so


def test_a_dem_steady_angle_above_135_degrees_is_flagged_with_a_note():
    from calibrate.route_choice import steady_angle_flag
    assert steady_angle_flag(124.7) == {"steady_theta_above_135": False, "steady_note": ""}
    flag = steady_angle_flag(141.0)
    assert flag["steady_theta_above_135"] is True
    assert "141.0 deg is above 135 deg" in flag["steady_note"]
