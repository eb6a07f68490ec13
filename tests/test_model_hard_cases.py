"""Hard cases: the pole X_c, reversals through zero rate, rests, long runs, big steps.

Every run must stay finite (no NaN anywhere) and never cross X_c silently:
either X stays below X_c or a PoleError names t, X and X_c. ``simulate`` itself
refuses to return a non-finite table or one with X >= X_c (tested below on the
table builder); the runs here are checked against facts it does not check itself.
"""
import numpy as np
import pytest

from model import (
    PoleError, default_params, heaviside, laws, params_from_dict, rest, simulate, sinusoidal,
    steady_shear, steady_state, tabulated,
)
from model.histories import concatenate

ADAPTIVE = ["RK45", "DOP853", "RK23", "Radau", "BDF", "LSODA"]


def with_model1(**changes):
    d = default_params().to_dict()
    d["model1"].update(changes)
    return params_from_dict(d)


def assert_consistent(tab, params):
    """Facts of a simple-shear table that ``simulate`` does not enforce itself.

    Where the layer moves, X is A:D'/|D'| = sqrt2 A_xy sign(gammadot) and mu is Eq. 2
    at that X (``laws.friction_eq2``, not the signed ratio the table is built from);
    the fabric stays within |A| <= 1/sqrt2, the bound of any contact network.
    """
    moving = tab[tab.gammadot != 0.0]
    assert len(moving) > 0
    X_of_A = np.sqrt(2.0) * moving.A_xy * np.sign(moving.gammadot)
    assert np.max(np.abs(moving.X - X_of_A)) < 1e-12, "X does not match A and the shear direction"
    f = params.friction_eq2
    assert np.max(np.abs(tab.mu - laws.friction_eq2(tab.X, f.X0, f.k1, f.k3, f.k5))) < 1e-12, "mu is not Eq. 2 at X"
    assert tab.A_norm.max() <= 1.0 / np.sqrt(2.0), "the fabric left the physical range"


def test_consistency_check_rejects_a_table_whose_X_or_mu_is_off():
    p = default_params()
    tab = simulate(p, heaviside(0.5, 0.5))
    assert_consistent(tab, p)
    for column, shift in (("X", 1e-9), ("mu", 1e-9), ("A_norm", 1.0)):
        bad = tab.copy()
        bad[column] += shift
        with pytest.raises(AssertionError):
            assert_consistent(bad, p)


def test_the_table_refuses_nan_and_X_beyond_the_pole():
    """The last guard of ``simulate``: the table builder raises instead of returning such rows."""
    from model.integrate import _table

    p = default_params()
    history = steady_shear(1.0)
    t = np.array([0.0, 0.5, 1.0])
    seg, direction = np.zeros(3, dtype=int), [(0.0, 1.0 / np.sqrt(2.0))]
    build = lambda Y: _table(history, p, "model1", "eq2", t, np.array(Y), seg, direction, p.model1.X_c)  # noqa: E731
    assert len(build([[0.01, -0.05]] * 3)) == 3
    with pytest.raises(FloatingPointError, match=r"non-finite values in columns .*A_xx"):
        build([[0.01, -0.05], [np.nan, -0.05], [0.01, -0.05]])
    b_pole = 1.001 * p.model1.X_c / np.sqrt(2.0)           # X = sqrt2 A_xy = 1.001 X_c
    with pytest.raises(PoleError, match=r"X = 0\.0827.* >= X_c = 0\.0827 at t = 0\.5"):
        build([[0.01, -0.05], [0.01, b_pole], [0.01, -0.05]])


# linear part alone would settle at X = -a1 a2/(2 + a2^2) = 0.136 > X_c: the pole must stop it
DRIVEN_TO_POLE = dict(a1=0.5, b1=0.0, a2=-3.0, b2=0.0, c1=-2.0, c2=10.0)  # settles at 0.996 X_c


@pytest.mark.parametrize("method", ADAPTIVE)
def test_approach_to_the_pole_is_resolved_below_X_c(method):
    p = with_model1(**DRIVEN_TO_POLE)
    tab = simulate(p, steady_shear(20.0), A0=(0.0, 0.0), method=method, rtol=1e-6, atol=1e-9)
    assert_consistent(tab, p)
    assert tab.X.max() > 0.99 * p.model1.X_c            # it did get close
    a, b, X = steady_state(p)                             # and settles on the barrier's fixed point
    assert tab.X.iloc[-1] == pytest.approx(X, abs=1e-5)


def test_approach_to_the_pole_with_a_fine_rk4_step_stays_below():
    p = with_model1(**DRIVEN_TO_POLE)
    tab = simulate(p, steady_shear(20.0), A0=(0.0, 0.0), method="RK4", step=1e-3)
    assert_consistent(tab, p)


def test_an_attracting_pole_stops_with_an_error_naming_t_X_and_X_c():
    p = with_model1(a1=0.5, a2=-3.0, b1=0.0, b2=0.0, c1=200.0, c2=-1000.0)  # c1 + c2 X_c > 0: the pole attracts
    with pytest.raises(PoleError, match=r"t = .*X = .*X_c = 0\.0827") as info:
        simulate(p, steady_shear(20.0), A0=(0.0, 0.0))
    assert np.isfinite(info.value.t) and info.value.X <= p.model1.X_c * 1.01


@pytest.mark.parametrize("method", ADAPTIVE + ["RK4"])
def test_heaviside_reversal_with_mirrored_X_at_099_X_c_stays_stable(method):
    X_ss = steady_state(default_params())[2]
    p = with_model1(X_c=-X_ss / 0.99)
    tab = simulate(p, heaviside(1.0, 3.0), method=method, step=1e-3)
    assert_consistent(tab, p)
    after = tab[tab.gammadot < 0]
    assert after.X.iloc[0] == pytest.approx(0.99 * p.model1.X_c, rel=1e-9)
    assert after.X.iloc[-1] == pytest.approx(X_ss, abs=1e-3)


def test_reversal_that_mirrors_X_beyond_X_c_is_bad_input():
    X_ss = steady_state(default_params())[2]
    p = with_model1(X_c=-X_ss * 0.999)  # steady state exists, its mirror lies beyond the pole
    with pytest.raises(PoleError, match=r"X starts at .* >= X_c"):
        simulate(p, heaviside(1.0, 1.0), A0=steady_state(default_params())[:2])


@pytest.mark.parametrize("method", ["DOP853", "LSODA", "Radau", "RK4"])
@pytest.mark.parametrize("model", ["model1", "model2"])
def test_sinusoidal_reversal_through_zero_rate_is_clean(method, model):
    tab = simulate(default_params(), sinusoidal(1.0, 0.3, 2.0), model=model, method=method, step=1e-3)
    assert_consistent(tab, default_params())
    zero = tab[tab.gammadot == 0.0]
    assert len(zero) == 1 and zero.sigma_xy_over_p.iloc[0] == 0.0
    assert np.all(np.abs(np.diff(tab.A_xy)) < 5e-3)        # the fabric is continuous through zero rate
    assert tab.theta_A.iloc[-1] == pytest.approx(55.3, abs=0.5)


@pytest.mark.parametrize("method", ["DOP853", "BDF", "RK4"])
def test_rests_freeze_the_fabric_and_never_make_nan(method):
    h = concatenate(rest(2.0), steady_shear(1.0), rest(3.0), steady_shear(1.0, -1.0), rest(1.0))
    tab = simulate(default_params(), h, method=method, step=1e-2)
    assert_consistent(tab, default_params())
    at_rest = tab[tab.gammadot == 0.0]
    assert len(at_rest) > 10 and np.all(at_rest.sigma_xy_over_p == 0.0)
    first = tab[tab.t <= 2.0]
    assert np.ptp(first.A_xx) == 0.0 and np.ptp(first.A_xy) == 0.0


def test_tabulated_history_with_ramps_through_zero_and_a_rest():
    t = [0.0, 1.0, 1.2, 1.5, 2.0, 2.3, 4.0]
    g = [1.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0]
    t2 = [0.0, 1.0, 1.3, 3.0]
    g2 = [1.0, 1.0, -1.0, -1.0]   # crosses zero inside a linear piece, at t = 1.15
    for tt, gg in ((t, g), (t2, g2)):
        tab = simulate(default_params(), tabulated(tt, gg))
        assert_consistent(tab, default_params())
        expected_end = np.trapezoid(gg, tt)
        assert tab.strain.iloc[-1] == pytest.approx(expected_end, abs=1e-12)


@pytest.mark.parametrize("method", ["DOP853", "LSODA", "RK4"])
def test_100_units_of_steady_shear_do_not_drift(method):
    p = default_params()
    a, b, X = steady_state(p)
    tab = simulate(p, steady_shear(100.0), method=method)
    # within tolerance everywhere, and no accumulation: the end is as close as the start
    assert np.max(np.abs(tab.A_xx - a)) < 1e-7 and np.max(np.abs(tab.A_xy - b)) < 1e-7
    assert abs(tab.A_xx.iloc[-1] - a) < 1e-9 and abs(tab.A_xy.iloc[-1] - b) < 1e-9


@pytest.mark.parametrize("step", [0.05, 0.1, 0.2, 0.5])
def test_rk4_step_too_large_for_the_pole_errors_clearly_or_stays_bounded(step):
    X_ss = steady_state(default_params())[2]
    p = with_model1(X_c=-X_ss / 0.99)
    try:
        tab = simulate(p, heaviside(1.0, 3.0), method="RK4", step=step)
    except PoleError as err:
        assert "X_c" in str(err) and "step" in str(err)
        assert err.X >= err.X_c and np.isfinite(err.t)
    else:
        assert_consistent(tab, p)
        assert tab.A_norm.max() < 1.0


def test_step_budget_stops_a_crawling_solver_with_a_clear_error():
    from model import default_params, heaviside, simulate

    with pytest.raises(RuntimeError, match=r"RK45 needed more than 5 steps .*stiff"):
        simulate(default_params(), heaviside(1.0, 1.0), method="RK45", rtol=1e-10, max_steps=5)
    table = simulate(default_params(), heaviside(1.0, 1.0), method="RK45", rtol=1e-6, max_steps=20000)
    reference = simulate(default_params(), heaviside(1.0, 1.0))        # LSODA at rtol 1e-10
    assert np.max(np.abs(table.A_norm - reference.A_norm)) < 1e-5       # a budget that suffices changes nothing


def test_parameters_that_blow_the_fabric_up_stop_with_a_clear_error_not_nan():
    from model import FabricDivergence, default_params, heaviside, params_from_dict, simulate

    doc = default_params().to_dict()
    doc["model2"] = {"c1": -0.3, "c2": 8.0, "c3": 0.0}  # alpha2 > 0: Eq. 4 grows without bound
    with pytest.raises(FabricDivergence, match=r"diverged at t = .*exceeds 1/sqrt\(2\)"):
        simulate(params_from_dict(doc), heaviside(1.0, 5.0), model="model2", A0=(-0.02, -0.05))


def test_steady_state_ignores_a_stable_root_with_an_unphysical_fabric():
    """A fit can leave a stable root at |A| > 1/sqrt(2) (alpha2 ~ 0 near X = 0): it is not a steady state."""
    from model import params_from_dict, steady_state
    d = default_params().to_dict()
    # a Model 1 fit of the quick campaign (2026-11-22) before the stability hinge of calibrate.fits:
    # its root near the DEM's X = -0.088 is unstable (alpha2 = +2.7), the only stable one has |A| = 1.22
    d["model1"] = dict(a1=-1.6052157, b1=-21.110877, c1=-3.8e-08, a2=0.17912873, b2=-28.638976, c2=83072.673,
                       X_c=0.38416035)
    with pytest.raises(ValueError, match="no stable steady state .*1/sqrt"):
        steady_state(params_from_dict(d))
