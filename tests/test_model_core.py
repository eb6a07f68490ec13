"""Behaviour of the continuum model on cases with known answers."""
import math

import numpy as np
import pytest

from model import (
    default_params, heaviside, laws, params_from_dict, pure_shear, rest, rigid_rotation,
    simulate, steady_shear, steady_state, superpose_rotation, sinusoidal,
)
from model.histories import concatenate


def constant_coefficient_params(alpha1=-0.3, alpha2=-3.75):
    """Model 2 with c3 = 0 has constant alphas: the closed form of docs/model.md applies."""
    d = default_params().to_dict()
    d["model2"] = {"c1": alpha1, "c2": alpha2, "c3": 0.0}
    return params_from_dict(d)


@pytest.mark.parametrize("model", ["model1", "model2"])
@pytest.mark.parametrize("gammadot", [1.0, -1.0])
def test_steady_state_is_where_a_long_shear_from_isotropy_ends(model, gammadot):
    """The root finder against the ODE itself: 50 strain of steady shear from A = 0 (X-dependent alphas)."""
    p = default_params()
    a, b, X = steady_state(p, model, sign=int(gammadot))
    history = steady_shear(50.0, gammadot)
    end = simulate(p, history, model=model, A0=(0.0, 0.0), method="LSODA", t_eval=[history.t_end]).iloc[-1]
    assert end.A_norm == pytest.approx(laws.fabric_norm(a, b), abs=1e-6)
    assert end.theta_A == pytest.approx(laws.fabric_angle_deg(a, b), abs=1e-6)
    assert end.X == pytest.approx(X, abs=1e-6)


def test_integration_from_isotropic_reaches_closed_form_steady_state():
    p = constant_coefficient_params()
    tab = simulate(p, steady_shear(60.0), model="model2", A0=(0.0, 0.0), rtol=1e-11, atol=1e-13)
    a_ref, b_ref, X_ref = laws.steady_state_constant(-0.3, -3.75)
    end = tab.iloc[-1]
    assert abs(end.A_xx - a_ref) < 1e-8 and abs(end.A_xy - b_ref) < 1e-8 and abs(end.X - X_ref) < 1e-8


def test_default_model1_steady_state_is_the_documented_one():
    a, b, X = steady_state(default_params())
    assert X == pytest.approx(-0.0700, abs=5e-4)
    assert laws.fabric_norm(a, b) == pytest.approx(0.075, abs=1e-3)
    assert 120.0 < laws.fabric_angle_deg(a, b) < 130.0


@pytest.mark.parametrize("model", ["model1", "model2"])
def test_superposed_rigid_rotation_rotates_the_fabric(model):
    p = default_params()
    omega = 0.7
    base = heaviside(1.0, 1.5)
    t = np.linspace(0.0, base.t_end, 41)
    ref = simulate(p, base, model=model, t_eval=t, rtol=1e-11, atol=1e-13)
    rot = simulate(p, superpose_rotation(base, omega), model=model, A0=ref[["A_xx", "A_xy"]].iloc[0],
                   t_eval=t, rtol=1e-11, atol=1e-13)
    phi = omega * ref.t.to_numpy()
    c, s = np.cos(2 * phi), np.sin(2 * phi)
    a, b = ref.A_xx.to_numpy(), ref.A_xy.to_numpy()
    assert np.max(np.abs(rot.A_xx - (a * c - b * s))) < 1e-8
    assert np.max(np.abs(rot.A_xy - (a * s + b * c))) < 1e-8
    assert np.max(np.abs(rot.X - ref.X)) < 1e-8          # X is objective
    assert np.max(np.abs(rot.A_norm - ref.A_norm)) < 1e-8


def test_rigid_rotation_turns_the_fabric_without_changing_it():
    p = default_params()
    tab = simulate(p, rigid_rotation(0.5, 1.0), A0=(0.05, 0.0), rtol=1e-11, atol=1e-13)
    end = tab.iloc[-1]
    assert end.A_norm == pytest.approx(laws.fabric_norm(0.05, 0.0), abs=1e-10)
    assert end.theta_A == pytest.approx(math.degrees(0.5), abs=1e-7)


def test_pure_shear_aligns_the_fabric_with_compression():
    """Pure shear stretching x compresses y: contacts gather along y (theta_A = 90) for alpha1 < 0."""
    tab = simulate(default_params(), pure_shear(1.0, 20.0), model="model2", A0=(0.0, 0.0))
    assert tab.theta_A.iloc[-1] == pytest.approx(90.0, abs=1e-6)
    assert tab.X.iloc[-1] < 0


@pytest.mark.parametrize("method", ["DOP853", "RK45", "Radau", "LSODA"])
def test_fabric_against_strain_is_rate_independent(method):
    p = default_params()
    strains = np.concatenate([np.linspace(0, 0.65, 14), np.linspace(0.65, 0.0, 14)[1:]])  # peak 0.5 + 0.5/pi
    tabs = [simulate(p, sinusoidal(0.5, 0.5, 0.5, gammadot=g), method=method, strain_eval=strains,
                     rtol=1e-10, atol=1e-12) for g in (1e-6, 1e3)]
    for col in ("A_xx", "A_xy", "mu"):
        assert np.max(np.abs(tabs[0][col].to_numpy() - tabs[1][col].to_numpy())) < 1e-7


def test_rk4_converges_at_fourth_order_on_a_smooth_case():
    """Steady forward shear from isotropy: X < 0 throughout, so Eq. 6 and Eq. 4 are smooth."""
    p = default_params()
    h = steady_shear(2.0)
    ref = simulate(p, h, A0=(0.0, 0.0), method="DOP853", rtol=1e-13, atol=1e-15, t_eval=[2.0])
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    err = []
    for s in steps:
        tab = simulate(p, h, A0=(0.0, 0.0), method="RK4", step=s, t_eval=[2.0])
        assert tab.X.max() < 0
        err.append(abs(tab.A_xy.iloc[-1] - ref.A_xy.iloc[-1]) + abs(tab.A_xx.iloc[-1] - ref.A_xx.iloc[-1]))
    slope = np.polyfit(np.log(steps), np.log(err), 1)[0]
    assert 3.8 < slope < 4.2, (slope, err)


@pytest.mark.parametrize("model", ["model1", "model2"])
def test_heaviside_reversal_turns_theta_through_vertical(model):
    """The paper's claim for Model 1 (and, with our defaults, Model 2): 125 -> 55 deg via 90, not via 0/180."""
    tab = simulate(default_params(), heaviside(2.0, 3.0), model=model)
    after = tab[tab.t >= 2.0]
    assert after.theta_A.iloc[0] == pytest.approx(124.7, abs=0.5)
    assert after.theta_A.iloc[-1] == pytest.approx(55.3, abs=0.5)
    assert np.all((after.theta_A > 40.0) & (after.theta_A < 140.0))   # never near 0/180
    assert np.any(np.abs(np.diff(np.sign(after.theta_A - 90.0))) > 0)  # crosses 90
    assert after.A_norm.min() < 0.5 * after.A_norm.iloc[0]          # |A| falls first


def test_output_columns_and_sign_conventions():
    tab = simulate(default_params(), heaviside(1.0, 1.0))
    assert list(tab.columns) == ["t", "strain", "gammadot", "A_xx", "A_xy", "A_norm", "theta_A", "X", "mu",
                                 "sigma_xy_over_p"]
    fwd, back = tab[tab.gammadot > 0], tab[tab.gammadot < 0]
    assert np.all(fwd.sigma_xy_over_p > 0)
    # after the reversal the stress keeps its old sign while X > X0, then follows gammadot
    X0 = default_params().friction_eq2.X0
    assert back.X.iloc[0] > X0 and back.sigma_xy_over_p.iloc[0] > 0 and back.sigma_xy_over_p.iloc[-1] < 0
    moving = tab[(tab.gammadot != 0) & (tab.X != X0)]
    assert np.all(np.sign(moving.sigma_xy_over_p) == -np.sign(moving.gammadot * (moving.X - X0)))
    assert np.allclose(np.abs(tab.sigma_xy_over_p), tab.mu)
    assert tab.strain.max() == pytest.approx(1.0) and tab.strain.iloc[-1] == pytest.approx(0.0, abs=1e-12)
    assert np.all((tab.theta_A >= 0) & (tab.theta_A < 180))


def test_quadratic_friction_is_used_when_asked():
    p = default_params()
    tab = simulate(p, steady_shear(1.0), friction="quadratic")
    q = p.friction_quadratic
    assert np.allclose(tab.mu, q.m0 + q.m1 * tab.X + q.m2 * tab.X**2)


@pytest.mark.parametrize("kwargs, message", [
    ({"model": "model3"}, r"model = 'model3' is not one of"), ({"method": "Euler"}, r"method = 'Euler' is not one of"),
    ({"friction": "linear"}, r"friction = 'linear' is not one of"), ({"rtol": -1.0}, r"rtol = -1.0 .*\(0, 1\)"),
    ({"method": "RK4", "step": 0.0}, r"step = 0.0 .*\(0, inf\)"), ({"A0": (np.nan, 0.0)}, r"A0 = \(nan, 0.0\)"),
])
def test_bad_options_are_rejected_by_name_and_value(kwargs, message):
    with pytest.raises(ValueError, match=message):
        simulate(default_params(), steady_shear(1.0), **kwargs)


def test_bad_parameter_names_key_and_range():
    d = default_params().to_dict()
    d["model1"]["X_c"] = 2.0
    with pytest.raises(ValueError, match=r"model1\.X_c.*\(0, 1\)"):
        simulate(d, steady_shear(1.0))


def test_strain_eval_follows_the_path_through_a_reversal():
    strains = [0.0, 0.5, 1.0, 1.0, 0.5, 0.0]
    tab = simulate(default_params(), heaviside(1.0, 1.0), strain_eval=strains)
    assert np.allclose(tab.strain, strains, atol=1e-12)
    assert list(np.sign(tab.gammadot)) == [1, 1, 1, -1, -1, -1]
    assert tab.X.iloc[3] == pytest.approx(-tab.X.iloc[2])  # X flips at the reversal


def test_concatenated_rest_keeps_the_fabric():
    h = concatenate(steady_shear(1.0), rest(5.0), steady_shear(1.0))
    tab = simulate(default_params(), h, A0=(0.0, 0.0))
    during = tab[(tab.t >= 1.0) & (tab.t <= 6.0)]
    assert np.ptp(during.A_xx) == 0.0 and np.ptp(during.A_xy) == 0.0
    assert np.all(during.sigma_xy_over_p[(during.t > 1.0) & (during.t < 6.0)] == 0.0)
