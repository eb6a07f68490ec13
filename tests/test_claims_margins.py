"""Margins and equivalence (two one-sided tests) in the claims table: the "negligible" verdict.

Closed forms for the one 90 % interval and the decision rule (issue 32: direction and equivalence at
5 % one-sided each, read off the same interval); model-made data with a known truth
(``dem_contract.synthetic``) for the verdict: a Model 1 whose pole barely acts differs from Model 2
by less than the margin, and the table must say so.
"""
import math

import numpy as np
import pytest

from claims import margins, report, stats
from claims.inputs import read_dem_case
from claims.table import claims_table
from compare import comparison
from dem_contract.synthetic import FABRIC_NOISE, MU_NOISE, write_ensemble
from model import default_params, params_from_dict, save_params

NAN = float("nan")


@pytest.mark.parametrize("low, high, margin, expected", [
    (-0.3, -0.1, 0.05, "reproduced"),                  # real and larger than the margin
    (-0.03, -0.01, 0.05, "reproduced, negligible"),    # real but too small to matter
    (0.01, 0.03, 0.05, "contradicted, negligible"),
    (-0.02, 0.02, 0.05, "negligible"),                 # whatever its sign, too small
    (-0.02, 0.06, 0.05, "inconclusive"),               # the interval reaches the margin
    (-0.02, 0.02, NAN, "inconclusive"),                # no margin: the sided rule alone
    (NAN, NAN, 0.05, "inconclusive"),
])
def test_decision_rule_with_a_margin(low, high, margin, expected):
    # issue 32: one interval (90 %) decides the direction and the equivalence, both at 5 % one-sided
    assert stats.verdict(low, high, 0.0, "<", margin) == expected


def test_an_interval_wholly_on_one_side_and_inside_the_margin_reads_reproduced_negligible():
    # the deciding campaign's claim 4 before issue 32: 90 % [-0.0038, -0.0005] inside +-0.0042 read "negligible"
    # (its 95 % interval reached 0); at one level the words match the interval
    assert stats.verdict(-0.0038, -0.0005, 0.0, "<", 0.0042) == "reproduced, negligible"


def test_a_margin_about_a_nonzero_null_is_centred_on_the_null():
    # claim 8: steady angle against 135 degrees, margin 1 degree
    assert stats.verdict(134.4, 135.4, 135.0, "<", 1.0) == "negligible"
    assert stats.verdict(133.9, 135.4, 135.0, "<", 1.0) == "inconclusive"


def test_the_interval_of_three_seeds_is_at_least_the_90_percent_t_interval():
    # mean +- t(0.95, 2) s / sqrt(3) = 2 +- 2.919986 * 1 / sqrt(3): the percentile bootstrap is narrower
    est, lo, hi, _ = stats.mean_interval([1.0, 2.0, 3.0])
    half = 2.919985580355516 / np.sqrt(3.0)
    assert lo == pytest.approx(2.0 - half, rel=1e-9) and hi == pytest.approx(2.0 + half, rel=1e-9)


def test_the_interval_of_many_seeds_approaches_the_normal_90_percent_interval():
    x = np.random.default_rng(5).normal(0.0, 1.0, 400)
    _, lo, hi, _ = stats.mean_interval(x, n_resamples=2000)
    half = 1.6449 * x.std(ddof=1) / np.sqrt(x.size)
    assert lo == pytest.approx(x.mean() - half, abs=0.15 * half) and hi == pytest.approx(x.mean() + half,
                                                                                          abs=0.15 * half)


def test_verdict_counts_count_a_double_verdict_for_both():
    counts = stats.verdict_counts(["reproduced", "reproduced, negligible", "negligible", "inconclusive",
                                   "both fail"])
    assert counts == {"reproduced": 2, "contradicted": 0, "negligible": 2, "inconclusive": 1, "both fail": 1}


def test_the_decisive_margin_is_where_negligible_starts():
    m = stats.decisive_margin(-0.0038, 0.0010, 0.0)
    assert m == 0.0038
    assert stats.verdict(-0.0038, 0.0010, 0.0, "<", 1.001 * m) == "negligible"
    assert stats.verdict(-0.0038, 0.0010, 0.0, "<", 0.999 * m) == "inconclusive"


# --------------------------------------------------------------------------- model-made data


def weak_pole_params():
    """Model 1 whose pole barely acts (c_i a hundredth of the defaults); Model 2 = Model 1's linear part."""
    d = default_params().to_dict()
    d.pop("provenance", None)
    d["model1"].update(c1=-2.0, c2=10.0)
    return params_from_dict(d)


@pytest.fixture(scope="module")
def weak_pole_table(tmp_path_factory):
    """Claims table of 4 seeds made by Model 1 with a weak pole, small white noise, both models at the truth."""
    root = tmp_path_factory.mktemp("weak")
    params = weak_pole_params()
    dirs = write_ensemble(root / "dem", params, seeds=(1, 2, 3, 4), model="model1", friction="eq2",
                          preshear_strain=0.5, reversal_strain=0.6, coarse=0.005,
                          fabric_noise=0.1 * FABRIC_NOISE, mu_noise=0.1 * MU_NOISE)
    save_params(params, root / "params.yaml")
    c = comparison.run(dirs, root / "params.yaml", ["heaviside", "sinusoidal"], set_name="other", train_cases=[])
    pred = c.predictions.assign(in_sample=False)
    return claims_table(pred, [read_dem_case(d) for d in dirs], eq2=None, n_resamples=1000).set_index("claim_id")


def test_an_effect_inside_the_margin_with_small_noise_is_negligible(weak_pole_table):
    for cid in ("4-step", "4-sin", "4-pooled"):
        row = weak_pole_table.loc[cid]
        assert "negligible" in row["verdict"]
        assert -row["margin"] < row["low"] <= row["estimate"] <= row["high"] < row["margin"]
        assert row["adequacy"].startswith("Model 1 within; Model 2 within")


def test_every_comparative_claim_has_a_positive_margin_and_the_others_none(weak_pole_table):
    t = weak_pole_table
    compared = ["4-step", "4-sin", "4-pooled", "5", "6", "7-step", "7-sin", "7-pooled", "8"]
    assert (t.loc[compared, "margin"] > 0).all()
    assert t.loc[["1a", "1b", "2a", "2b", "3"], "margin"].isna().all()
    assert t.loc["5", "margin"] == margins.TURN_FRACTION and t.loc["8", "margin"] == margins.STEADY_ANGLE_DEG
    # claim 4's margin: (f x the DEM's seed-to-seed s.d. of |A| over the window)^2, the scale of the data's noise
    band = np.sqrt(t.loc["4-step", "margin"]) / margins.BAND_FRACTION
    assert 0.5 * 0.1 * FABRIC_NOISE < band < 3 * 0.1 * FABRIC_NOISE


def test_the_readme_section_and_the_forest_plot_show_the_margin(weak_pole_table, tmp_path):
    tab = weak_pole_table.reset_index()
    section = report.markdown_section(tab)
    assert "| margin |" in section and "estimate [90 % interval]" in section and "**negligible**" in section
    row4 = next(line for line in section.splitlines() if line.startswith("| 4-step |"))
    assert f"+-{tab.loc[tab['claim_id'] == '4-step', 'margin'].item():.3g}" in row4 and "Model 1 within" in row4
    assert "| none |" in next(line for line in section.splitlines() if line.startswith("| 1a |"))
    report.forest_plot(tab, tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 10_000
    assert not math.isnan(tab["sd"].iloc[0])
