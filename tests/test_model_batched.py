"""The batched integrator gives simulate's tables for many simple-shear runs at once, each guarded alone.

Agreement is checked against ``simulate``'s default (LSODA, rtol 1e-10) to 1e-6 in
|A|, theta_A (deg) and mu, on the work-precision cases and on the simple-shear hard
cases of tests/test_model_hard_cases.py; failures must be simulate's own.
"""
import numpy as np
import pandas as pd
import pytest

from model import (
    COLUMNS, FabricDivergence, PoleError, default_params, heaviside, params_from_dict, pure_shear, rest, simulate,
    sinusoidal, steady_shear, steady_state, tabulated,
)
from model.batched import simulate_batch
from model.histories import concatenate
from model.work_precision import CASES

TOL = 1e-6
QUANTITIES = ("A_norm", "theta_A", "mu")
DRIVEN_TO_POLE = dict(a1=0.5, b1=0.0, a2=-3.0, b2=0.0, c1=-2.0, c2=10.0)    # settles at 0.996 X_c (repelling)
ATTRACTING_POLE = dict(a1=0.5, a2=-3.0, b1=0.0, b2=0.0, c1=200.0, c2=-1000.0)  # c1 + c2 X_c > 0


def with_model1(**changes):
    d = default_params().to_dict()
    d["model1"].update(changes)
    return params_from_dict(d)


def diverging_model2():
    d = default_params().to_dict()
    d["model2"] = {"c1": -0.3, "c2": 8.0, "c3": 0.0}   # alpha2 > 0: Eq. 4 grows without bound
    return params_from_dict(d)


def mirrored_at(fraction):
    """Default Model 1 with X_c placed so that a reversal from steady state starts at X = fraction * X_c."""
    return with_model1(X_c=-steady_state(default_params())[2] / fraction)


def assert_agrees(table, ref, tol=TOL):
    """Same rows (t, strain, gammadot exactly), |A|, theta_A and mu within ``tol``."""
    assert list(table.columns) == COLUMNS and len(table) == len(ref)
    np.testing.assert_array_equal(table[["t", "strain", "gammadot"]].to_numpy(),
                                  ref[["t", "strain", "gammadot"]].to_numpy())
    for q in QUANTITIES:
        dev = np.max(np.abs(table[q].to_numpy() - ref[q].to_numpy()))
        assert dev < tol, f"{q} deviates by {dev:.3g}"
    np.testing.assert_array_equal(table.sigma_xy_over_p.to_numpy() == 0.0, ref.sigma_xy_over_p.to_numpy() == 0.0)


@pytest.mark.parametrize("model", ["model1", "model2"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_agrees_with_lsoda_on_every_work_precision_case(case, model):
    p = default_params()
    history = CASES[case]()
    A0 = steady_state(p, model)[:2]
    t_eval = np.linspace(0.0, history.t_end, 601)
    result = simulate_batch(p, history, model=model, A0=A0, t_eval=t_eval)
    assert result.status.solver[0] == "batched"
    assert_agrees(result.trajectory(0), simulate(p, history, model=model, A0=A0, t_eval=t_eval))


def test_reversal_with_mirrored_X_at_099_X_c_agrees_without_leaving_the_batch():
    p = mirrored_at(0.99)
    result = simulate_batch(p, heaviside(1.0, 3.0))           # A0: the steady state, as simulate
    assert result.status.solver[0] == "batched"
    table = result.trajectory(0)
    assert_agrees(table, simulate(p, heaviside(1.0, 3.0)))
    assert table[table.gammadot < 0].X.iloc[0] == pytest.approx(0.99 * p.model1.X_c, rel=1e-9)


@pytest.mark.parametrize("model", ["model1", "model2"])
def test_sinusoidal_reversal_through_zero_rate_agrees(model):
    history = sinusoidal(1.0, 0.3, 2.0)
    table = simulate_batch(default_params(), history, model=model).trajectory(0)
    assert_agrees(table, simulate(default_params(), history, model=model))
    zero = table[table.gammadot == 0.0]
    assert len(zero) == 1 and zero.sigma_xy_over_p.iloc[0] == 0.0


def test_100_units_of_steady_shear_agree_and_do_not_drift():
    p = default_params()
    a, b, _ = steady_state(p)
    table = simulate_batch(p, steady_shear(100.0)).trajectory(0)
    assert_agrees(table, simulate(p, steady_shear(100.0)))
    assert np.max(np.abs(table.A_xx - a)) < 1e-9 and np.max(np.abs(table.A_xy - b)) < 1e-9


def test_approach_to_a_repelling_pole_falls_back_to_simulate_and_agrees():
    p = with_model1(**DRIVEN_TO_POLE)
    result = simulate_batch(p, steady_shear(20.0), A0=(0.0, 0.0))
    st = result.status.iloc[0]
    assert st.status == "ok" and st.solver == "simulate" and "stiff" in st.fallback_reason
    table = result.trajectory(0)
    assert_agrees(table, simulate(p, steady_shear(20.0), A0=(0.0, 0.0)), tol=1e-12)
    assert table.X.max() > 0.99 * p.model1.X_c


@pytest.mark.parametrize("case", ["attracting pole", "reversal mirrored beyond X_c"])
def test_a_pole_gives_the_same_PoleError_as_simulate(case):
    if case == "attracting pole":
        p, history, A0 = with_model1(**ATTRACTING_POLE), steady_shear(20.0), (0.0, 0.0)
    else:
        p, history, A0 = mirrored_at(1.0 / 0.999), heaviside(1.0, 1.0), steady_state(default_params())[:2]
    with pytest.raises(PoleError) as expected:
        simulate(p, history, A0=A0)
    result = simulate_batch(p, history, A0=A0)
    assert result.status.status[0] == "pole" and len(result.table) == 0
    with pytest.raises(PoleError) as got:
        result.trajectory(0)
    assert str(got.value) == str(expected.value)
    assert (got.value.t, got.value.X, got.value.X_c) == (expected.value.t, expected.value.X, expected.value.X_c)


def test_a_fabric_that_blows_up_is_flagged_diverged_like_simulate():
    p, history, A0 = diverging_model2(), heaviside(1.0, 5.0), (-0.02, -0.05)
    with pytest.raises(FabricDivergence):
        simulate(p, history, model="model2", A0=A0)
    result = simulate_batch(p, history, model="model2", A0=A0)
    assert result.status.status[0] == "diverged"
    with pytest.raises(FabricDivergence, match=r"diverged at t = .*exceeds 1/sqrt\(2\)"):
        result.trajectory(0)


def test_a_trajectory_that_meets_the_pole_is_flagged_alone_and_the_others_go_on():
    normal1 = (default_params(), heaviside(1.0, 2.0), "model1", None)
    attracting = (with_model1(**ATTRACTING_POLE), steady_shear(20.0), "model1", (0.0, 0.0))
    normal2 = (default_params(), sinusoidal(1.0, 0.5, 1.5), "model2", None)
    diverging = (diverging_model2(), heaviside(1.0, 5.0), "model2", (-0.02, -0.05))
    runs = [normal1, attracting, normal2, diverging]
    P, H, M, A0 = (list(x) for x in zip(*runs))
    result = simulate_batch(P, H, model=M, A0=A0)
    assert list(result.status.status) == ["ok", "pole", "ok", "diverged"]
    assert list(result.ok) == [True, False, True, False]
    assert set(result.table.trajectory) == {0, 2}
    for i in (0, 2):
        p, h, m, a0 = runs[i]
        alone = simulate_batch(p, h, model=m, A0=a0).trajectory(i - i)
        pd.testing.assert_frame_equal(result.trajectory(i), alone)
        assert_agrees(result.trajectory(i), simulate(p, h, model=m, A0=a0))


def test_a_batch_of_identical_trajectories_gives_identical_results():
    p = mirrored_at(0.99)
    one = simulate_batch(p, heaviside(1.0, 2.0)).trajectory(0)
    many = simulate_batch([p] * 7, heaviside(1.0, 2.0))
    assert len(many) == 7 and many.ok.all()
    for i in range(7):
        pd.testing.assert_frame_equal(many.trajectory(i), one, check_exact=True)


@pytest.mark.parametrize("size", [2, 9, 40])
def test_the_result_does_not_depend_on_the_batch_composition(size):
    p = mirrored_at(0.99)
    history = heaviside(1.0, 2.0)
    alone = simulate_batch(p, history, model="model1").trajectory(0)
    rng = np.random.default_rng(size)
    others = [(default_params(), sinusoidal(0.5, 0.4, 1.0), "model2"), (default_params(), heaviside(0.3, 0.8), "model1"),
              (with_model1(**DRIVEN_TO_POLE), steady_shear(3.0), "model1")]
    runs = [others[k] for k in rng.integers(len(others), size=size)]
    where = int(rng.integers(size))
    runs[where] = (p, history, "model1")
    P, H, M = (list(x) for x in zip(*runs))
    mixed = simulate_batch(P, H, model=M)
    pd.testing.assert_frame_equal(mixed.trajectory(where), alone, check_exact=True)


def test_per_trajectory_report_grids_with_left_and_right_limits_at_a_reversal():
    """Route 2's use: unit-rate histories in path strain, read at given path strains (a boundary twice)."""
    histories = [steady_shear(0.7, -1.0) + steady_shear(1.2, 1.0), steady_shear(2.0, -1.0)]
    t_evals = [np.array([0.0, 0.35, 0.7, 0.7, 1.0, 1.9]), np.linspace(0.0, 2.0, 9)]
    A0 = [(-0.005, 0.05), (-0.005, 0.05)]
    result = simulate_batch(default_params(), histories, A0=A0, t_eval=t_evals)
    for i in range(2):
        assert_agrees(result.trajectory(i), simulate(default_params(), histories[i], A0=A0[i], t_eval=t_evals[i]))
    rows = result.trajectory(0)
    assert rows.X.iloc[2] == pytest.approx(-rows.X.iloc[3], abs=1e-15)     # X flips sign at the reversal


def test_strain_eval_tabulated_rates_and_rests_agree():
    t = [0.0, 1.0, 1.2, 1.5, 2.0, 2.3, 4.0]
    g = [1.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0]
    histories = [tabulated(t, g), concatenate(rest(1.0), steady_shear(1.0), rest(0.5), steady_shear(1.0, -1.0)),
                 heaviside(1.0, 2.0)]
    strain_eval = [None, None, np.concatenate([np.linspace(0, 1, 11), np.linspace(1, -1, 21)])]
    friction = ["eq2", "quadratic", "eq2"]
    result = simulate_batch(default_params(), histories, friction=friction, strain_eval=strain_eval)
    for i, h in enumerate(histories):
        ref = simulate(default_params(), h, friction=friction[i], strain_eval=strain_eval[i])
        assert_agrees(result.trajectory(i), ref)


def test_a_step_budget_hands_the_trajectory_to_simulate_unchanged():
    result = simulate_batch(default_params(), heaviside(1.0, 2.0), max_steps=5)
    assert result.status.solver[0] == "simulate" and "budget" in result.status.fallback_reason[0]
    pd.testing.assert_frame_equal(result.trajectory(0), simulate(default_params(), heaviside(1.0, 2.0)),
                                  check_exact=True)


def test_bad_input_is_rejected_by_name():
    with pytest.raises(ValueError, match="simple shear only"):
        simulate_batch(default_params(), pure_shear(1.0, 1.0))
    with pytest.raises(ValueError, match=r"different lengths: \{'params': 2, 'histories': 3\}"):
        simulate_batch([default_params()] * 2, [heaviside(1.0, 1.0)] * 3)
    with pytest.raises(ValueError, match=r"trajectory 1: model = 'model3'"):
        simulate_batch(default_params(), heaviside(1.0, 1.0), model=["model1", "model3"])
    with pytest.raises(ValueError, match=r"rtol = 0.0 is outside the allowed range"):
        simulate_batch(default_params(), heaviside(1.0, 1.0), rtol=0.0)


def test_benchmark_writes_the_cost_table_with_batched_and_looped_times(tmp_path, capsys):
    from model.batched_benchmark import main

    assert main(["--out", str(tmp_path), "--sizes", "1", "4", "--reference", "1"]) == 0
    table = pd.read_csv(tmp_path / "batched_cost.csv")
    assert list(table.N) == [1, 4]
    assert (table.batched_s > 0).all() and (table.loop_s > 0).all()
    assert np.allclose(table.speedup, table.loop_s / table.batched_s)
    assert table.status_agrees.all() and (table.max_dev_A_norm < TOL).all() and (table.max_dev_mu < TOL).all()
    assert "speedup" in capsys.readouterr().out
