"""A reversal starts from the state at the reversal (dem_contract.pre_reversal_state), not from a lagging mean.

Model-made double reversals (back after 0.15 strain, while the fabric still
moves fast) with the contract's per-sample noise: the start state of the second
reversal (a line fitted over the moving leg before it, taken at its end) is
compared with the noise-free model state at that reversal (the last sample
before it), over several noise seeds, against the window's mean; so is the
first reversal's, from a steady pre-shear, where the mean is kept.
"""
import json

import numpy as np
import pandas as pd
import pytest

from dem_contract import PRE_REVERSAL_WINDOW, fabric_norm, pre_reversal_state, split_transients, synthetic
from model import default_params

SCHEDULE = {"double": [(0.15, -1), (0.4, 1)]}
SEEDS = range(1, 13)


def legs(case):
    """The leg before each reversal of the double run: the pre-shear, then the first transient."""
    pre = pd.read_csv(case / "preshear.csv")
    run = pd.read_csv(case / "double.csv")
    tr = split_transients(pre, run, json.loads((case / "double.json").read_text()))
    return pre, tr[0].data, tr


def window_mean(leg):
    """The former start state: the mean over the last PRE_REVERSAL_WINDOW strain (at least 10 samples)."""
    back = np.abs(leg["strain"].to_numpy()[-1] - leg["strain"].to_numpy())
    win = back <= PRE_REVERSAL_WINDOW
    if win.sum() < 10:
        win[-10:] = True
    return leg["A_xx"].to_numpy()[win].mean(), leg["A_xy"].to_numpy()[win].mean()


@pytest.fixture(scope="module")
def errors(tmp_path_factory):
    root = tmp_path_factory.mktemp("double")
    kw = dict(preshear_strain=2.0, A_start=(0.0, 0.0), protocols=(), schedules=SCHEDULE, coarse=0.01, fine=0.001)
    truth = legs(synthetic.write_case(root / "truth", default_params(), seed=0, **kw))
    rows = []
    for seed in SEEDS:
        noisy = legs(synthetic.write_case(root / f"s{seed}", default_params(), seed=seed,
                                          fabric_noise=synthetic.FABRIC_NOISE, mu_noise=synthetic.MU_NOISE, **kw))
        for which, leg, true_leg in (("first", noisy[0], truth[0]), ("second", noisy[1], truth[1])):
            a0, b0 = true_leg["A_xx"].iloc[-1], true_leg["A_xy"].iloc[-1]
            st = pre_reversal_state(leg, estimate="line")
            am, bm = window_mean(leg)
            rows.append({"reversal": which, "seed": seed, "fit": fabric_norm(st["A_xx"], st["A_xy"]) - fabric_norm(a0, b0),
                         "mean": fabric_norm(am, bm) - fabric_norm(a0, b0)})
        first, second = noisy[2]
        assert first.initial == pre_reversal_state(noisy[0])                         # the steady pre-shear: its mean
        assert second.initial == pre_reversal_state(noisy[1], estimate="line")      # a moving leg: the line's end
    return pd.DataFrame(rows)


def test_the_start_of_a_later_reversal_is_unbiased_where_a_window_mean_lags(errors):
    second = errors[errors["reversal"] == "second"]
    assert abs(second["mean"].mean()) > 0.01                     # the mean over 0.1 strain lags the moving fabric
    assert abs(second["fit"].mean()) < 0.004                     # the line at the reversal does not
    assert np.sqrt((second["fit"] ** 2).mean()) < np.sqrt((second["mean"] ** 2).mean())


def test_from_a_steady_pre_shear_the_mean_is_the_better_estimate(errors):
    first = errors[errors["reversal"] == "first"]
    assert abs(first["mean"].mean()) < 0.004 and abs(first["fit"].mean()) < 0.005
    assert np.sqrt((first["mean"] ** 2).mean()) < np.sqrt((first["fit"] ** 2).mean())   # the line costs noise


def test_an_unknown_estimate_is_refused():
    pre = pd.DataFrame({"strain": np.linspace(0, 1, 20), "gammadot": 1.0, "A_xx": 0.0, "A_xy": 0.0, "mu": 0.3})
    with pytest.raises(ValueError, match="estimate = 'median' is not one of"):
        pre_reversal_state(pre, estimate="median")


def test_a_steady_leg_gives_its_level_and_a_ramp_its_end():
    s = np.linspace(0.0, 1.0, 101)
    pre = pd.DataFrame({"strain": s, "gammadot": np.ones_like(s), "A_xx": np.full_like(s, -0.1),
                        "A_xy": 0.05 + 0.2 * s, "mu": np.full_like(s, 0.3)})
    st = pre_reversal_state(pre, estimate="line")
    assert st["A_xx"] == pytest.approx(-0.1) and st["A_xy"] == pytest.approx(0.25) and st["mu"] == pytest.approx(0.3)
    assert pre_reversal_state(pre)["A_xy"] == pytest.approx(0.24)    # the mean over the last 0.1 strain lags
