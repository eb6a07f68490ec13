"""RK4 near Model 1's pole: the step follows the stiffness, so it agrees with LSODA, or it refuses clearly.

Two calibrated-looking Model 1 sets (the pole term large where a reversal starts):
``NEAR`` as fitted on DEM data (X_c = 0.242), and ``AT_POLE`` with X_c = 0.094, just above
the mirrored steady X = 0.0929 a reversal starts from. With the paper's fixed step of
0.01 strain they erred by 2e-4 and 0.054 in |A|.
"""
import numpy as np
import pytest

from model import PoleError, default_params, heaviside, params_from_dict, simulate, sinusoidal, steady_state
from model import rk4

NEAR = dict(a1=-1.69, b1=32.0, c1=-628.0, a2=-56.9, b2=-72.7, c2=8.5e4, X_c=0.242)
AT_POLE = dict(NEAR, c2=1e3, X_c=0.094)
HISTORIES = {"heaviside": heaviside(2.0, 3.0), "sinusoidal": sinusoidal(2.0, 0.5, 3.0)}


def with_model1(m1):
    d = default_params().to_dict()
    d["model1"] = dict(m1)
    return params_from_dict(d)


def test_at_pole_set_starts_its_reversal_just_below_the_pole():
    X = steady_state(with_model1(AT_POLE))[2]
    assert 0 < AT_POLE["X_c"] - (-X) < 0.002


@pytest.mark.parametrize("history", HISTORIES)
@pytest.mark.parametrize("m1", [NEAR, AT_POLE], ids=["near", "at_pole"])
def test_rk4_at_its_default_step_is_within_a_ten_thousandth_of_lsoda_near_the_pole(m1, history):
    p, h = with_model1(m1), HISTORIES[history]
    ref = simulate(p, h, method="LSODA")
    tab = simulate(p, h, method="RK4")
    assert np.max(np.abs(tab.A_norm - ref.A_norm)) < 1e-4
    assert np.max(np.abs(tab.A_xy - ref.A_xy)) < 1e-4 and np.max(np.abs(tab.A_xx - ref.A_xx)) < 1e-4


def test_the_fixed_step_alone_errs_at_the_pole(monkeypatch):
    """Without the stiffness and pole bounds, the paper's fixed step is far off: the bounds do the work."""
    p, h = with_model1(AT_POLE), HISTORIES["heaviside"]
    ref = simulate(p, h, method="LSODA")
    monkeypatch.setattr(rk4, "STIFF_LIMIT", np.inf)
    monkeypatch.setattr(rk4, "POLE_FRACTION", np.inf)
    tab = simulate(p, h, method="RK4")
    assert np.max(np.abs(tab.A_norm - ref.A_norm)) > 1e-2


def test_rk4_refuses_with_the_step_it_needs_when_the_budget_runs_out(monkeypatch):
    """With a budget of 600 steps (the reversal needs about 900), the message names the step at the reversal."""
    monkeypatch.setattr(rk4, "MAX_SUBSTEPS", 600)
    with pytest.raises(PoleError, match=r"needs more than 600 steps: at t = 2 the step must be at most "
                                        r"1\.\d+e-05 \(stiffness max\|lambda\| = 2\.\d+e\+04\); use an adaptive method"):
        simulate(with_model1(AT_POLE), HISTORIES["heaviside"], method="RK4")


def test_the_stiffness_bound_leaves_the_papers_step_alone_away_from_the_pole():
    """Default parameters: every step of 0.01 strain is one RK4 step (h max|lambda| <= 0.22 < STIFF_LIMIT)."""
    p = default_params()
    from model.rhs import coefficient_law, make_rate
    alphas, X_c = coefficient_law(p, "model1")
    seg = heaviside(2.0, 3.0).segments[1]
    a, b, _ = steady_state(p)
    h, why = rk4.stable_step(make_rate(seg.kin, alphas, X_c), seg.t0, a, b, X_c)
    assert h > 0.01 and "stiffness" in why


def test_a_set_no_method_can_integrate_stops_rk4_with_a_message():
    p = with_model1(dict(NEAR, X_c=0.1))   # alpha2 > 0 past the reversal: the fabric runs away
    for method in ("LSODA", "RK4"):
        with pytest.raises(ValueError, match=r"diverged|X_c"):
            simulate(p, HISTORIES["heaviside"], method=method)
