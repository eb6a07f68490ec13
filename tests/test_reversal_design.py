"""The reversal-design table (claims/design.py) on curves whose errors are known in closed form.

DEM |A| is a constant; Model 1 and Model 2 are offsets of it, so each run's
claim-4 difference of squared model errors (issue 32: MSE, not RMSE) is exactly
offset 1^2 - offset 2^2.
"""
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from claims import design

S = np.linspace(0.0, 0.3, 61)


def curves(d1: float, d2: float, a0: float = 0.1) -> dict:
    frame = lambda off: pd.DataFrame({"s_rev": S, "A_norm": a0 + off + 0 * S, "kind": "heaviside"})
    return {"dem": frame(0.0), "model1": frame(d1), "model2": frame(d2)}


def case_dir(tmp_path, seed: int, cpu: dict):
    d = tmp_path / f"p100000_I0.001_s{seed}"
    d.mkdir()
    for stage, seconds in cpu.items():
        (d / f"{stage}.json").write_text(json.dumps({"N": 626, "cpu_time_s": seconds}))
    return d


@pytest.fixture
def campaign(tmp_path):
    """Four seeds: a single reversal each, and a train of two identical reversals (fully correlated)."""
    single = {1: 0.001, 2: 0.003, 3: 0.002, 4: 0.006}     # seed -> Model 1's offset (its RMSE; Model 2's is 0)
    train = {1: 0.002, 2: 0.002, 3: 0.004, 4: 0.000}
    runs, dirs = {}, []
    for seed in single:
        case = f"p100000_I0.001_s{seed}"
        dirs.append(case_dir(tmp_path, seed, {"pack": 600.0, "preshear": 1800.0, "single": 1200.0, "train": 2400.0}))
        runs[("odd", case, "p100000_I0.001", "single", False)] = curves(single[seed], 0.0)
        for k in (1, 2):
            runs[("odd", case, "p100000_I0.001", f"train_r{k}", False)] = curves(train[seed], 0.0)
        runs[("all", case, "p100000_I0.001", "single", True)] = curves(9.0, 0.0)   # in sample: never scored
    return runs, dirs, single, train


def test_each_protocol_gets_its_seed_to_seed_sd_cost_and_information(campaign):
    runs, dirs, single, train = campaign
    out = design.design_table(runs, dirs, ["single", "train"]).set_index("protocol")
    for name, values, hours in (("single", single, (600 + 1800 + 1200) / 3600), ("train", train, 1.3333333)):
        d = np.array(list(values.values())) ** 2        # MSE_1 - MSE_2 of constant offsets
        sd = np.std(d, ddof=1)
        assert out.loc[name, "seeds"] == 4
        assert out.loc[name, "mean_difference"] == pytest.approx(d.mean(), abs=1e-15)
        assert out.loc[name, "sd_per_seed"] == pytest.approx(sd, rel=1e-9)
        assert out.loc[name, "cpu_hours_per_seed"] == pytest.approx(hours, rel=1e-6)
        assert out.loc[name, "information_per_core_hour"] == pytest.approx(1 / (sd ** 2 * hours), rel=1e-6)
    assert out.loc["train", "reversals_per_seed"] == 2
    assert out["relative_information"].max() == 1.0


def test_a_train_whose_reversals_repeat_each_other_has_design_effect_k(campaign):
    runs, dirs, _, _ = campaign
    out = design.design_table(runs, dirs, ["single", "train"]).set_index("protocol")
    # two identical reversals per seed: the seed mean varies as one reversal does, not half as much;
    # with the unbiased variances of 4 seed means (SS/3) and 8 reversals (2 SS/7): (SS/3) / (2 SS/7 / 2) = 7/3
    assert out.loc["train", "design_effect"] == pytest.approx(7 / 3, rel=1e-9)
    assert out.loc["single", "design_effect"] == pytest.approx(1.0)


RELEASE = Path(__file__).resolve().parents[1] / "data" / "bulk-validation-paper"


@pytest.mark.skipif(not RELEASE.is_dir(), reason="the released validation cells are not in data/")
def test_recovery_of_a_reversal_from_the_steady_pre_shear_is_about_one(tmp_path):
    """Real DEM (a released narrow cell at the paper's physics): a Heaviside reversal from the end of a steady
    pre-shear starts from the steady fabric, |A0| / |A|_ss within the fabric's noise of 1; a protocol the
    case did not run gives NaN."""
    from claims.inputs import read_dem_case
    from dem_contract import release
    case = release.restore_case(RELEASE, "narrow-H37-W18_s1", tmp_path / "narrow-H37-W18_s1")
    dem = [read_dem_case(case, ["heaviside", "train03"])]
    r = design.recovery(dem, "heaviside")
    assert 0.9 < r < 1.1
    assert math.isnan(design.recovery(dem, "train03"))


def test_sd_interval_is_the_chi_square_one():
    lo, hi = design.sd_interval(2.0, 10)        # the table's 90 % level
    assert lo == pytest.approx(2.0 * math.sqrt(9 / stats.chi2.ppf(0.95, 9)))
    assert hi == pytest.approx(2.0 * math.sqrt(9 / stats.chi2.ppf(0.05, 9)))
    assert lo < 2.0 < hi
    assert all(math.isnan(x) for x in design.sd_interval(1.0, 1))


@pytest.mark.parametrize("key, base", [("train03_r2", "train03"), ("heaviside", "heaviside"), ("a_r1_r12", "a_r1")])
def test_a_schedules_reversal_key_maps_to_its_protocol(key, base):
    assert design.base_protocol(key) == base
