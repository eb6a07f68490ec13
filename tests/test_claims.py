"""The claims stage (claims/): its statistics in closed form, the decision rule, and verdicts on model-made data.

The end-to-end checks run the comparison (compare.comparison.run, no calibration:
the parameters are known) on cases written by dem_contract.synthetic with serially
correlated noise of the DEM's size added, and build the claims table from its curves.
"""
import math

import numpy as np
import pandas as pd
import pytest

from claims import measures, stats
from claims.cli import main
from claims.inputs import read_dem_case
from claims.table import claims_table
from compare import comparison
from dem_contract import fabric_angle_deg
from tests.helpers import comparison_for_truth, table_of


@pytest.fixture(scope="module")
def model1_case(tmp_path_factory):
    root = tmp_path_factory.mktemp("m1")
    return (root, *comparison_for_truth(root, "model1"))


@pytest.fixture(scope="module")
def model1_truth(model1_case):
    return table_of(*model1_case[1:])


@pytest.fixture(scope="module")
def model2_truth(tmp_path_factory):
    return table_of(*comparison_for_truth(tmp_path_factory.mktemp("m2"), "model2"))


# --------------------------------------------------------------------------- verdicts on model-made data


def test_model1_truth_with_a_strong_pole_reproduces_model1_captures_the_fall_better(model1_truth):
    # issue 32: one row per figure (step reversals, Fig. 4; the sinusoidal reversal, Fig. 5), a pooled one
    for cid in ("4-sin", "4-pooled"):
        row = model1_truth.loc[cid]
        assert row["verdict"] == "reproduced"
        assert row["high"] < 0 and row["n"] == 4
    assert model1_truth.loc["4-step", "estimate"] < 0
    assert model1_truth.loc["4-pooled", "adequacy"].startswith("Model 1 within")   # the truth: inside the DEM's band


def test_model2_truth_does_not_reproduce_model1_captures_the_fall_better(model2_truth):
    for cid in ("4-step", "4-sin", "4-pooled"):
        row = model2_truth.loc[cid]
        assert row["verdict"] in ("negligible", "contradicted", "contradicted, negligible")
        assert row["estimate"] > 0           # the generating model has the smaller error


def test_model_truth_decides_the_friction_claim_both_ways(model1_truth, model2_truth):
    # the paper's claim 7 is the zoom of Fig. 4c: a step reversal
    assert model1_truth.loc["7-step", "verdict"] == "reproduced"
    assert model2_truth.loc["7-step", "verdict"] in ("inconclusive", "contradicted")


def test_the_table_has_every_claim_with_an_interval_a_named_test_and_a_verdict(model1_truth):
    assert list(model1_truth.index) == ["1a", "1b", "2a", "2b", "3", "4-step", "4-sin", "4-pooled", "5", "6",
                                        "7-step", "7-sin", "7-pooled", "8"]
    assert {p.strip() for v in model1_truth["verdict"] for p in v.split(",")} <= set(stats.VERDICTS)
    computed = model1_truth.drop(index="2b")    # 2b needs a calibration's Eq. 2, not given here
    assert np.isfinite(computed[["estimate", "low", "high"]].to_numpy(float)).all()
    assert (computed["low"] <= computed["estimate"]).all() and (computed["estimate"] <= computed["high"]).all()
    assert "bootstrap over seeds, 1000 resamples" in model1_truth.loc["3", "test"]
    assert "bootstrap over seeds, 1000 resamples" in model1_truth.loc["4-step", "test"]
    assert model1_truth.loc["2b", "verdict"] == "inconclusive"


def test_a_model_made_fall_is_reproduced_and_its_steady_angle_is_reachable(model1_truth):
    assert model1_truth.loc["1a", "verdict"] == "reproduced"
    assert model1_truth.loc["8", "verdict"] == "reproduced"       # default parameters: 124.7 degrees
    assert model1_truth.loc["8", "estimate"] == pytest.approx(124.7, abs=3.0)


# --------------------------------------------------------------------------- statistics in closed form


def test_clopper_pearson_of_3_out_of_3_is_the_closed_form():
    # the table's one level (issue 32): a 90 % interval, 5 % on each side
    est, lo, hi, n = stats.clopper_pearson(3, 3)
    assert (est, hi, n) == (1.0, 1.0, 3)
    assert lo == pytest.approx(0.05 ** (1 / 3), rel=1e-9)        # Beta(0.05; 3, 1) = 0.05^(1/3) = 0.368
    assert stats.clopper_pearson(3, 3, level=0.95)[1] == pytest.approx(0.025 ** (1 / 3), rel=1e-9)


def test_clopper_pearson_of_0_out_of_n_is_the_closed_form():
    est, lo, hi, _ = stats.clopper_pearson(0, 6)
    assert (est, lo) == (0.0, 0.0)
    assert hi == pytest.approx(1 - 0.05 ** (1 / 6), rel=1e-9)


def test_bootstrap_interval_of_a_mean_approaches_the_normal_interval():
    x = np.random.default_rng(3).normal(2.0, 1.0, 400)
    est, lo, hi, n = stats.mean_interval(x, n_resamples=2000)
    half = 1.6449 * x.std(ddof=1) / np.sqrt(n)          # the table's 90 % interval
    assert est == pytest.approx(x.mean())
    assert lo == pytest.approx(est - half, abs=0.15 * half) and hi == pytest.approx(est + half, abs=0.15 * half)


def test_bootstrap_interval_needs_two_seeds_and_is_reproducible():
    assert all(math.isnan(v) for v in stats.mean_interval([0.3])[1:3])
    assert stats.mean_interval([1.0, 1.0, 1.0])[1:3] == (1.0, 1.0)
    assert stats.mean_interval([0.1, 0.5, 0.2], seed=4) == stats.mean_interval([0.1, 0.5, 0.2], seed=4)


@pytest.mark.parametrize("low, high, null, side, expected", [
    (-0.3, -0.1, 0.0, "<", "reproduced"),
    (0.1, 0.3, 0.0, "<", "contradicted"),
    (-0.1, 0.3, 0.0, "<", "inconclusive"),
    (0.6, 0.9, 0.5, ">", "reproduced"),
    (0.1, 0.4, 0.5, ">", "contradicted"),
    (0.0, 0.2, 0.0, ">", "inconclusive"),        # touching the null is not excluding it
    (float("nan"), float("nan"), 0.0, ">", "inconclusive"),
])
def test_decision_rule(low, high, null, side, expected):
    assert stats.verdict(low, high, null, side) == expected


# --------------------------------------------------------------------------- per-run measures


def fabric(theta_deg, norm=0.1):
    """A_xx, A_xy of a fabric of |A| = norm along theta (A_xx = |A| cos 2theta / sqrt2)."""
    t = np.radians(2.0 * np.asarray(theta_deg, float))
    return norm * np.cos(t) / np.sqrt(2.0), norm * np.sin(t) / np.sqrt(2.0)


@pytest.mark.parametrize("stop, axis", [(55.0, "90"), (235.0, "0/180")])
def test_crossing_names_the_axis_by_the_sign_of_A_xx_where_A_xy_changes_sign(stop, axis):
    s = np.linspace(0.0, 0.5, 201)
    a, b = fabric(np.linspace(125.0, stop, s.size))
    c = measures.crossing(s, a, b, noisy=False)
    assert c["axis"] == axis
    assert fabric_angle_deg(c["A_xx_cross"], 0.0) == (90.0 if axis == "90" else 0.0)


def test_a_crossing_within_the_noise_is_unclear():
    s = np.linspace(0.0, 0.5, 501)
    a, b = fabric(np.linspace(125.0, 55.0, s.size), norm=0.001)   # tiny fabric: A_xx at the crossing ~ 0.0007
    rng = np.random.default_rng(0)
    a = a + rng.normal(0.0, 0.01, s.size)
    assert measures.crossing(s, a, b, noisy=True)["axis"] == "unclear"


def test_transition_width_of_a_linear_turn_is_80_percent_of_its_span():
    s = np.linspace(0.0, 0.6, 601)
    theta = np.interp(s, [0.0, 0.1, 0.3, 0.6], [125.0, 125.0, 55.0, 55.0])
    a, b = fabric(theta)
    assert measures.transition_width(s, a, b) == pytest.approx(0.8 * 0.2, abs=2e-3)


def test_fall_depth_and_its_strain():
    s = np.linspace(0.0, 0.5, 501)
    x = 1.0 - 0.6 * np.exp(-((s - 0.05) / 0.02) ** 2)
    f = measures.fall(s, x, 1.0, noisy=False)
    assert f["depth"] == pytest.approx(0.6) and f["s_min"] == pytest.approx(0.05) and f["excess"] == f["depth"]


def test_binned_scatter_is_zero_for_a_single_valued_curve_and_the_noise_otherwise():
    x = np.random.default_rng(1).uniform(-0.1, 0.1, 4000)
    assert measures.binned_scatter(x, np.zeros_like(x)) == 0.0
    y = 0.3 + 2 * x + np.random.default_rng(2).normal(0.0, 0.05, x.size)
    assert measures.binned_scatter(x, y) == pytest.approx(0.05, rel=0.1)


def test_early_rmse_uses_only_the_window():
    s = np.linspace(0.0, 0.5, 501)
    dem = np.zeros_like(s)
    model = np.where(s <= 0.1, 0.02, 1.0)
    assert measures.early_rmse(s, dem, model, 0.1) == pytest.approx(0.02)


def test_a_steady_angle_above_135_degrees_contradicts_the_reachable_steady_row():
    from claims.table import Bootstrap, steady_angle_row
    row = steady_angle_row({f"p1_I0.001_s{k}": {"theta_A": t} for k, t in enumerate((139.0, 140.5, 138.2))},
                           Bootstrap(500))
    assert row["verdict"] == "contradicted" and row["low"] > 135.0
    assert "p1_I0.001_s0, p1_I0.001_s1, p1_I0.001_s2" in row["detail"]


# --------------------------------------------------------------------------- reversal schedules


def with_schedule_copies(dirs, root):
    """The cases with three one-reversal schedules that repeat their classic runs: ``again_h``, ``again_h2``
    (a step) and ``again_s`` (a half cosine), so each seed has three Heaviside reversals of equal values and
    two sinusoidal ones (a mean over runs that ignored the kinds would weigh the Heaviside ones 3:2)."""
    import json
    import shutil
    out = []
    for d in dirs:
        case = root / d.name
        shutil.copytree(d, case)
        for name, classic, transition in (("again_h", "heaviside", {"transition": "heaviside"}),
                                          ("again_h2", "heaviside", {"transition": "heaviside"}),
                                          ("again_s", "sinusoidal", {"transition": "half_cosine",
                                                                     "transition_strain": 0.1})):
            shutil.copy(case / f"{classic}.csv", case / f"{name}.csv")
            meta = json.loads((case / f"{classic}.json").read_text())
            meta["reversals"] = [dict(t=meta["reversal_t"], strain=meta["reversal_strain"], direction=-1, **transition)]
            (case / f"{name}.json").write_text(json.dumps(meta))
        out.append(case)
    return out


def test_claims_over_cases_with_a_schedule_use_one_value_per_seed_and_count_every_reversal(model1_case, tmp_path):
    root, dirs, _ = model1_case
    protocols = ["heaviside", "sinusoidal", "again_h", "again_h2", "again_s"]
    cases = with_schedule_copies(dirs, tmp_path)
    c = comparison.run(cases, root / "params.yaml", protocols, set_name="other", train_cases=[])
    pred = c.predictions.assign(in_sample=False)
    kinds = [("again_h", "heaviside"), ("again_h2", "heaviside"), ("again_s", "sinusoidal"),
             ("heaviside", "heaviside"), ("sinusoidal", "sinusoidal")]
    assert sorted(pred.drop_duplicates("protocol")[["protocol", "kind"]].itertuples(index=False)) == kinds
    dem_cases = [read_dem_case(d, protocols) for d in cases]
    assert sorted(dem_cases[0].samples.groupby(["protocol", "kind"]).groups) == kinds
    with_copies = claims_table(pred, dem_cases, eq2=None, n_resamples=1000).set_index("claim_id")
    classic = claims_table(pred[pred["protocol"].isin(["heaviside", "sinusoidal"])],
                           [read_dem_case(d) for d in cases], eq2=None, n_resamples=1000).set_index("claim_id")
    # a seed's reversals of one kind are averaged first: repeating them leaves every seed's value, so every
    # interval over seeds, as it was (the collapse, 2a, pools the samples of a seed: more samples, same seeds)
    per_seed = ["1a", "1b", "3", "4-step", "4-sin", "4-pooled", "5", "6", "7-step", "7-sin", "7-pooled", "8"]
    assert classic.loc[per_seed, "n"].tolist() == [4] * len(per_seed)
    for col in ("estimate", "low", "high", "n"):
        assert with_copies.loc[per_seed, col].tolist() == pytest.approx(classic.loc[per_seed, col].tolist(),
                                                                        rel=1e-12, nan_ok=True), col
    assert with_copies.loc["2a", "n"] == classic.loc["2a", "n"] == 4
    # claim 3's detail still counts reversals: five per seed now
    assert "clear runs 8 of 8" in classic.loc["3", "detail"] and "clear runs 20 of 20" in with_copies.loc["3", "detail"]


# --------------------------------------------------------------------------- command line


def test_command_line_writes_the_table_the_figure_and_the_readme_section(model1_case, tmp_path):
    root, dirs, c = model1_case
    out = tmp_path / "compare" / "other"
    out.mkdir(parents=True)
    c.predictions.to_csv(out / "predictions.csv", index=False)
    c.errors.to_csv(out / "errors.csv", index=False)
    assert main(["--compare", str(tmp_path / "compare"), "--dem", *map(str, dirs), "--calibration",
                 str(root / "params.yaml"), "--resamples", "500", "--out", str(tmp_path / "claims")]) == 0
    table = pd.read_csv(tmp_path / "claims" / "paper_claims.csv")
    assert len(table) == 14 and table.loc[table["claim_id"] == "2b", "n"].item() == 4   # Eq. 2 read this time
    section = (tmp_path / "claims" / "README_section.md").read_text()
    claims_part = section.split("\n### ")[0]        # the power and reversal-design tables follow it
    assert claims_part.count("\n| ") == 1 + len(table) and "**reproduced**" in section
    assert "### The reversal design" in section
    assert (tmp_path / "claims" / "paper_claims.png").stat().st_size > 10_000



def test_command_line_names_a_missing_comparison_and_exits_2(tmp_path, capsys):
    assert main(["--compare", str(tmp_path / "absent"), "--dem", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    assert "absent: comparison folder not found" in capsys.readouterr().err


def test_interval_of_three_seeds_is_at_least_the_student_t_interval():
    # three seeds on one side: the percentile bootstrap spans only their range; the (90 %) t interval
    # mean +- t(0.95, 2) s / sqrt(3) = 3 +- 2.920 * sqrt(7) / sqrt(3) reaches below 0
    est, lo, hi, n = stats.mean_interval([1.0, 2.0, 6.0])
    half = 2.919985580355516 * np.sqrt(7.0) / np.sqrt(3.0)
    assert (est, n) == (3.0, 3)
    assert lo == pytest.approx(3.0 - half, rel=1e-9) and hi == pytest.approx(3.0 + half, rel=1e-9)
    assert stats.verdict(lo, hi, 0.0, ">") == "inconclusive"
