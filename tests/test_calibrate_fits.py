"""The law fits and the parameter table: exact on closed forms, honest about constraints."""
import numpy as np
import pandas as pd
import pytest

from calibrate import fits, tables
from calibrate.settings import Settings
from model.laws import friction_eq2, stress_ratio_eq2

TRUE_EQ2 = dict(X0=0.035, k1=2.4, k3=15.0, k5=2.0e4)


def test_signed_eq2_is_minus_sign_of_y_times_mu_and_falls_through_zero_at_X0():
    X = np.linspace(-0.12, 0.12, 241)
    tau = stress_ratio_eq2(X, **TRUE_EQ2)
    np.testing.assert_allclose(np.abs(tau), friction_eq2(X, **TRUE_EQ2), rtol=0, atol=1e-15)
    assert np.all(np.diff(tau) < 0)                       # one decreasing curve ...
    assert stress_ratio_eq2(TRUE_EQ2["X0"], **TRUE_EQ2) == 0.0   # ... through zero at X0
    assert np.all(tau[X > TRUE_EQ2["X0"]] < 0)


def test_eq2_fit_recovers_its_parameters_from_signed_samples_on_both_sides_of_X0():
    X = np.linspace(-0.12, 0.11, 400)                     # y from -0.155 to +0.075: both branches
    tau = stress_ratio_eq2(X, **TRUE_EQ2)
    steady = {"X": -0.08, "mu": stress_ratio_eq2(-0.08, **TRUE_EQ2), "se_mu": 0.01}
    fit = fits.fit_eq2(X, tau, 0.01, steady, Settings.steady_weight)
    for k, v in TRUE_EQ2.items():
        assert fit.values[k] == pytest.approx(v, rel=1e-4), k
    assert fit.rms < 1e-8


def test_X_c_lower_bound_lies_beyond_every_state_a_reversal_starts_from():
    steady = {"X": -0.080, "X_reversal_max": 0.090, "X_reversal_bound": 0.095}
    assert fits.xc_lower_bound(steady, 0.002) == pytest.approx(0.097)      # a new seed's bound, not the mean
    bins = pd.DataFrame({"X_mean": [-0.05, 0.1]})
    assert fits.xc_lower_bound(steady, 0.002, bins) == pytest.approx(0.102)
    assert fits.xc_lower_bound({"X": -0.080}, 0.002) == pytest.approx(0.082)


def test_parameter_table_notes_values_held_by_a_constraint_or_outside_their_interval():
    iv = pd.DataFrame({"route": ["curves"] * 3, "block": ["model1"] * 3, "parameter": ["X_c", "c1", "a1"],
                       "low": [0.097, -10.0, -1.0], "high": [0.12, -1.0, -0.5]})
    fitted = {("curves", "model1"): {"X_c": 0.097, "c1": -20.0, "a1": -0.8}}
    tab = tables.params_table(fitted, iv, {"model1": "curves"},
                              {("curves", "model1", "X_c"): (0.097, np.inf), ("curves", "model1", "c1"): (-np.inf, 0.0)})
    note = dict(zip(tab["parameter"], tab["note"]))
    assert "lower bound 0.097" in note["X_c"]
    assert "outside its interval" in note["c1"] and "bound" not in note["c1"]
    assert note["a1"] == ""


def test_reversal_start_bound_is_the_student_t_prediction_bound_for_a_new_seed():
    from calibrate.io import reversal_start_bound
    assert reversal_start_bound([0.08, 0.09, 0.10]) == pytest.approx(0.09 + 4.302653 * 0.01 * np.sqrt(4 / 3), rel=1e-6)
    assert reversal_start_bound([0.07]) == 0.07
    assert reversal_start_bound([0.09, 0.09]) == 0.09      # no spread: the largest seen


def test_default_route_is_route_2_unless_route_1_predicts_held_out_seeds_clearly_better():
    from calibrate.route_choice import choose_route

    def held(back, curves):
        return pd.DataFrame([{"replicate": k, "route": r, "score": v} for k, (b, c) in enumerate(zip(back, curves))
                             for r, v in (("backsolve", b), ("curves", c))])
    ins = {"backsolve": 1.0, "curves": 2.0}
    assert choose_route(held([1.00, 1.02, 0.99, 1.01], [1.01, 1.00, 1.02, 1.00]), ins) == "curves"   # a tie
    assert choose_route(held([0.90, 0.91, 0.89, 0.90], [1.00, 1.01, 1.00, 1.02]), ins) == "backsolve"
    assert choose_route(held([1.5, 1.5, 1.5, 1.5], [1.0, np.inf, 1.0, 1.0]), ins) == "backsolve"   # fewer failures
    assert choose_route(pd.DataFrame(), ins) == "backsolve"                                        # in-sample


def test_fabric_fits_keep_the_steady_state_stable_even_when_the_dem_fabric_leans_past_135_degrees():
    """A DEM steady fabric with A_xx > 0 is matched exactly only by alpha2 > 0 (unstable); the fit must not go there."""
    from model.laws import steady_state_constant
    X = np.linspace(-0.1, 0.05, 12)
    bins = pd.DataFrame({"X_mean": X, "alpha1": np.full_like(X, 0.3), "alpha2": 2.7 + 0 * X, "se_alpha1": 5.0,
                         "se_alpha2": 50.0, "cov12": 0.0, "used": True})   # weak bins pulling to the flipped side
    a, b, Xs = steady_state_constant(0.3, 2.7)                               # a > 0: theta_A above 135 deg
    steady = {"A_xx": a, "A_xy": b, "X": Xs, "se_A_xx": 1e-4, "se_A_xy": 1e-4}
    fit = fits.fit_model2(bins, steady, Settings.steady_weight)
    assert fit.values["c2"] + fit.values["c3"] * Xs < 0      # alpha2 at the steady X: a stable steady state
    assert fits.steady_fabric_residuals(-1.0, -12.0, steady, 1.0)[2] == 0.0
