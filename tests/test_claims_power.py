"""The power analysis of the model comparisons (claims/power.py): closed forms, a simulated t-test, presets."""
import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from claims import power
from claims.cli import main
from compare import comparison
from dem_contract.synthetic import FABRIC_NOISE, MU_NOISE, write_ensemble
from model import default_params, save_params
from tests.helpers import add_correlated_noise, strong_pole_params

Z = stats.norm.ppf(0.95) + stats.norm.ppf(0.8)      # 2.4865: the normal form's factor (one-sided 5 %, issue 32)


@pytest.mark.parametrize("sd, delta", [(1.0, 0.1), (0.0007, -0.00002), (3.0, 0.2)])
def test_seeds_needed_for_many_seeds_is_the_normal_closed_form(sd, delta):
    # n = ((z_0.95 + z_0.8) sd / delta)^2; the t test needs at most a few seeds more
    closed = (Z * sd / delta) ** 2
    n = power.seeds_needed(sd, delta)
    assert closed > 500
    assert math.ceil(closed) <= n <= math.ceil(closed) + 3


def test_seeds_needed_is_the_first_n_with_80_percent_power():
    n = int(power.seeds_needed(1.0, 0.5))
    assert power.power_t(n, 1.0, 0.5) >= 0.8 > power.power_t(n - 1, 1.0, 0.5)
    assert n == 27     # noncentral t, one-sided 5 % (the table's 90 % interval): 27 (the normal form: 24.7)


def test_simulated_t_tests_with_the_computed_seeds_reach_80_percent_power():
    # the verdict "reproduced" is the 90 % t interval below 0; simulate it on normal per-seed values
    sd, delta, reps = 0.0066, -0.0036, 4000
    n = int(power.seeds_needed(sd, delta))
    rng = np.random.default_rng(7)
    d = rng.normal(delta, sd, size=(reps, n))
    high = stats.ttest_1samp(d, 0.0, axis=1).confidence_interval(0.90).high
    hit = float(np.mean(high < 0))
    se = math.sqrt(0.8 * 0.2 / reps)
    assert hit == pytest.approx(power.power_t(n, sd, delta), abs=3 * se)
    assert 0.8 - 3 * se <= hit
    half = n // 2
    high = stats.ttest_1samp(d[:, :half], 0.0, axis=1).confidence_interval(0.90).high
    assert np.mean(high < 0) == pytest.approx(power.power_t(half, sd, delta), abs=3 * se)
    assert np.mean(high < 0) < 0.8 - 3 * se     # half the seeds: well short of 80 %


def test_no_effect_needs_infinitely_many_seeds_and_no_spread_is_not_a_number():
    assert power.seeds_needed(0.001, 0.0) == math.inf
    assert math.isnan(power.seeds_needed(math.nan, -0.001))


def test_the_dem_volume_is_constant_when_the_noise_falls_as_one_over_root_n():
    # 4x the disks halves the per-seed s.d.: a quarter of the seeds, the same seeds x disks (normal form)
    sd4 = power.scaled_sd(0.002, 500, 2, 2000, 2)
    assert sd4 == pytest.approx(0.001)
    assert power.scaled_sd(0.002, 500, 2, 500, 8) == pytest.approx(0.001)   # or 4x the transients
    assert power.normal_seeds(sd4, 0.0002) * 2000 == pytest.approx(power.normal_seeds(0.002, 0.0002) * 500)


@pytest.mark.parametrize("name, seeds, transients, area", [("config", 4, 1, 37 * 148), ("quick", 6, 2, 37 * 18.5)])
def test_presets_count_pooled_seeds_and_the_transients_scored_out_of_sample(name, seeds, transients, area):
    # paper preset: one ensemble, so only heaviside_only's unseen sinusoidal run is out of sample;
    # disks scale with the cell's area H x W from the measured campaign's (H = 12d, W = 4H: 496 disks)
    cost = {"disks": 496.0, "geometry": {"H_over_d": 12, "W_over_H": 4}}
    p = power.preset_from_config(name, f"config/{name}.yaml", cost)
    assert (p["seeds"], p["transients"]) == (seeds, transients)
    assert p["disks"] == pytest.approx(496.0 * area / (12 * 48))


def test_a_preset_is_reached_when_its_seeds_reach_the_seeds_needed_at_its_noise():
    row = {"sd_per_seed": 0.002, "disks_per_seed": 500, "transients_per_seed": 2, "effect": -0.001}
    at_500 = power.seeds_needed(0.002, -0.001)
    assert not power.reach(row, int(at_500) - 1, 500, 2)["reached"] and power.reach(row, int(at_500), 500, 2)["reached"]
    assert power.reach(row, 4, 5000, 2)["seeds_needed"] == power.seeds_needed(0.002 / math.sqrt(10), -0.001)


def test_a_bad_preset_file_is_named(tmp_path):
    (tmp_path / "p.yaml").write_text("seeds: [1]\n")
    with pytest.raises(ValueError, match="p.yaml: preset 'bulk' lacks"):
        power.preset_from_config("bulk", tmp_path / "p.yaml", {"disks": 1.0, "geometry": None})


# --------------------------------------------------------------------------- the claims command line


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    """Three noisy model-made seeds, both models at the known parameters, as the comparison stage writes them."""
    root = tmp_path_factory.mktemp("power")
    params = default_params()
    dirs = write_ensemble(root / "dem", params, seeds=(1, 2, 3), preshear_strain=0.4, reversal_strain=0.3,
                          coarse=0.005, fabric_noise=FABRIC_NOISE, mu_noise=MU_NOISE)
    save_params(params, root / "params.yaml")
    c = comparison.run(dirs, root / "params.yaml", ["heaviside", "sinusoidal"], set_name="other", train_cases=[])
    out = root / "compare" / "other"
    out.mkdir(parents=True)
    c.predictions.to_csv(out / "predictions.csv", index=False)
    c.errors.to_csv(out / "errors.csv", index=False)
    return root, dirs


def test_command_line_writes_the_power_table_and_the_readme_paragraph(compared, tmp_path):
    root, dirs = compared
    assert main(["--compare", str(root / "compare"), "--dem", *map(str, dirs), "--calibration",
                 str(root / "params.yaml"), "--resamples", "200", "--preset", "paper=config/config.yaml",
                 "--out", str(tmp_path)]) == 0
    pw = pd.read_csv(tmp_path / "power.csv")
    assert list(pw.columns) == power.COLUMNS
    rows = [f"{c}-{f}" for c in ("4", "7") for f in ("step", "sin", "pooled")]    # one per figure (issue 32)
    assert list(zip(pw["claim_id"].astype(str), pw["effect_choice"])) == [
        (r, e) for r in rows for e in ("measured", "minimal")]
    assert (pw["seeds_measured"] == 3).all()
    assert pw.groupby(pw["claim_id"].str.rsplit("-", n=1).str[-1])["transients_per_seed"].first().to_dict() == {
        "step": 1, "sin": 1, "pooled": 2}
    table = pd.read_csv(tmp_path / "paper_claims.csv").set_index("claim_id")
    minimal = pw[pw["effect_choice"] == "minimal"].set_index("claim_id")
    assert (minimal["effect"] == -table.loc[minimal.index, "margin"]).all()     # the minimal effect: the margin
    assert (pw["sd_per_seed"] > 0).all() and (pw.loc[pw["effect_choice"] == "minimal", "effect"] < 0).all()
    minimal = pw[pw["effect_choice"] == "minimal"]
    assert (minimal["seeds_needed"] == [power.seeds_needed(s, e) for s, e in
                                        zip(minimal["sd_per_seed"], minimal["effect"])]).all()
    section = (tmp_path / "README_section.md").read_text()
    assert "### Power" in section and "the paper preset (4 seeds x" in section
    assert (pw["core_hours"] == power.UNKNOWN).all()   # model-made cases carry no DEM cost: "unknown", not NaN
    assert "unknown core-hours" in section and "nan core-hours" not in section


def test_command_line_names_a_bad_preset_and_exits_2(compared, tmp_path, capsys):
    root, dirs = compared
    assert main(["--compare", str(root / "compare"), "--dem", *map(str, dirs), "--resamples", "200",
                 "--preset", "paper", "--out", str(tmp_path)]) == 2
    assert "--preset 'paper': expected NAME=CONFIG.yaml" in capsys.readouterr().err


# --------------------------------------------------------------------------- with a pole acting (model-made)


def strong_pole_differences(root, scale, seeds=8):
    """Per-seed differences of claim 4 on model-made data, Model 1 with a strong pole the truth, at ``scale`` x
    one 500-disk run's serially correlated noise (the generator and noise of tests/test_claims.py)."""
    from claims import inputs, table
    params = strong_pole_params()
    dirs = write_ensemble(root / "dem", params, seeds=tuple(range(1, seeds + 1)), model="model1", friction="eq2",
                          preshear_strain=0.5, reversal_strain=0.6, coarse=0.005)
    for k, d in enumerate(dirs):
        add_correlated_noise(d, k, scale)
    save_params(params, root / "params.yaml")
    c = comparison.run(dirs, root / "params.yaml", ["heaviside", "sinusoidal"], set_name="other", train_cases=[])
    runs = inputs.runs(c.predictions.assign(in_sample=False))
    scores, _ = table.early_scores(runs, table.dem_of(runs), "A_norm", table.EARLY_A)
    return table._pooled(scores, lambda r: r["mse"]["model1"] - r["mse"]["model2"])[1]


def test_with_a_strong_pole_acting_500_disks_need_tens_of_seeds_and_16_times_more_disks_a_handful(tmp_path):
    # claim 4's paired difference of squared model errors (issue 32): with the pole acting the noisy
    # pre-reversal fabric moves Model 1 along its pole, and the difference spreads with the DEM's noise
    full = strong_pole_differences(tmp_path / "full", 1.0)
    quarter = strong_pole_differences(tmp_path / "quarter", 0.25)     # the noise of ~16 x 500 disks
    n_full = power.seeds_needed(full.std(ddof=1), full.mean())
    n_quarter = power.seeds_needed(quarter.std(ddof=1), quarter.mean())
    assert full.mean() < 0 and quarter.mean() < 0
    assert full.std(ddof=1) > 2 * quarter.std(ddof=1)
    assert n_full >= 20 and n_quarter <= 8
