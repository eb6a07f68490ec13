"""The quantities derived from a DEM series (dem_contract.derived): closed forms, and one value per run for every stage."""
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from dem_contract import (angle_difference, axial_mean, fabric_angle_deg, fabric_norm, read_series, reversal_indices,
                          steady_values, steady_window, synthetic)
from model import default_params

ROOT = Path(__file__).resolve().parents[1]


# --- angles -------------------------------------------------------------------------------

def test_the_mean_of_179_and_1_degrees_is_the_horizontal_not_90():
    assert abs(angle_difference(axial_mean([179.0, 1.0]), 0.0)) < 1e-9
    assert axial_mean([89.0, 91.0]) == pytest.approx(90.0)
    assert axial_mean([170.0, 175.0, 183.0]) == pytest.approx(176.0, abs=0.01)   # 183 is the direction 3
    # one mean per column; the result lies in [0, 180)
    m = axial_mean(np.array([[178.0, 40.0], [4.0, 50.0]]), axis=0)
    assert m[0] == pytest.approx(1.0, abs=1e-6) and m[1] == pytest.approx(45.0)
    assert np.all((m >= 0) & (m < 180))


def test_angle_difference_wraps_into_minus_90_exclusive_to_90_inclusive():
    d = angle_difference([179.0, 1.0, 90.0, 0.0, 370.0, -100.0], [1.0, 179.0, 0.0, 90.0, 5.0, 0.0])
    assert d == pytest.approx([-2.0, 2.0, 90.0, 90.0, 5.0, 80.0])
    assert np.all((d > -90) & (d <= 90))


@pytest.mark.parametrize("theta", [0.0, 30.0, 90.0, 120.0, 135.0, 170.0])
def test_fabric_norm_and_angle_of_a_known_tensor(theta):
    # A = lam (n n - t t) with n at theta: eigenvalues +-lam, |A| = sqrt(A:A) = sqrt(2) lam, major direction n
    lam = 0.07
    n = np.array([np.cos(np.radians(theta)), np.sin(np.radians(theta))])
    t = np.array([-n[1], n[0]])
    A = lam * (np.outer(n, n) - np.outer(t, t))
    assert fabric_norm(A[0, 0], A[0, 1]) == pytest.approx(np.sqrt(np.sum(A * A)))
    assert fabric_norm(A[0, 0], A[0, 1]) == pytest.approx(np.sqrt(2) * lam)
    assert abs(angle_difference(fabric_angle_deg(A[0, 0], A[0, 1]), theta)) < 1e-9
    w, v = np.linalg.eigh(A)   # an independent major direction: the eigenvector of the largest eigenvalue
    major = np.degrees(np.arctan2(v[1, -1], v[0, -1]))
    assert abs(angle_difference(fabric_angle_deg(A[0, 0], A[0, 1]), major)) < 1e-9


# --- steady state -------------------------------------------------------------------------

@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_steady_window_is_the_last_half_of_the_strain_path(direction):
    strain = direction * np.linspace(0.0, 2.0, 201)
    win = steady_window(strain)
    assert win.sum() == 101 and np.all(np.abs(strain[win]) >= 1.0) and np.all(win[100:])
    # a series whose first half is a transient and whose last half is level: only the level counts
    level = np.where(np.abs(strain) >= 1.0, 0.05, 0.5)
    pre = pd.DataFrame({"strain": strain, "A_xx": 0.0, "A_xy": -level, "mu": 1.0 + level, "phi": 0.8, "Z": 3.5})
    st = steady_values(pre)
    assert st["A_xy"] == pytest.approx(-0.05) and st["mu"] == pytest.approx(1.05) and st["n_samples"] == 101
    assert st["A_norm"] == pytest.approx(0.05 * np.sqrt(2)) and st["theta_A"] == pytest.approx(135.0)
    assert st["phi"] == pytest.approx(0.8) and "inertial_number" not in st
    assert steady_window(strain, last_strain=0.5).sum() == 51   # strain 1.5 to 2.0, every 0.01


def test_steady_window_refuses_a_fraction_outside_0_1():
    with pytest.raises(ValueError, match="fraction"):
        steady_window(np.linspace(0, 1, 10), fraction=1.5)


# --- reversals ----------------------------------------------------------------------------

def test_two_reversals_are_found_through_noise_spikes_and_a_rest():
    rng = np.random.default_rng(3)
    g = np.concatenate([np.full(120, 1.0), np.full(80, -1.0), np.zeros(15), np.full(60, -1.0), np.full(100, 1.0)])
    g = g + rng.normal(0.0, 0.05, g.size)   # noise about zero in the rest has random signs
    g[[30, 31, 150, 300]] *= -1             # spikes of the other sign, one or two samples long
    assert reversal_indices(g).tolist() == [120, 275]
    assert reversal_indices(np.abs(g)).size == 0
    # a raw sign test would count every spike and every sign of the noise in the rest
    assert np.count_nonzero(np.diff(np.sign(g)) != 0) > 4


# --- one value per run, whichever stage asks ----------------------------------------------

def _summary_module():
    from campaign import summary

    return summary


def test_campaign_summary_calibration_and_comparison_report_the_same_steady_state_of_a_run(tmp_path):
    from calibrate import io
    from compare.dem import load_reversal
    # a noisy run from isotropy: its first half is a transient, so a different window gives different values
    case = synthetic.write_case(tmp_path / "p1_I0.001_s1", default_params(), seed=1, preshear_strain=2.0,
                                A_start=(0.0, 0.0), fabric_noise=0.0125, mu_noise=0.04)
    for stage in ("preshear", "heaviside", "sinusoidal"):   # the sidecar keys a DEM run has and the summary lists
        side = case / f"{stage}.json"
        meta = json.loads(side.read_text())
        meta.update(N=500, kappa_achieved=1e3, inertial_number_achieved=1e-3, dt_over_tc=0.1, steps=1000,
                    wall_time_s=1.0, particle_steps_per_s=5e5)
        side.write_text(json.dumps(meta))
    row = _summary_module().case_row("p1_I0.001_s1", {"pressure": 1.0, "inertial_number": 1e-3, "seed": 1}, case,
                                     ["preshear", "heaviside", "sinusoidal"])
    cal = io.read_case(case).preshear.meta["steady"]
    ens = io.steady_values([io.read_case(case)])
    rev = load_reversal(case, "heaviside")
    assert row["mu_steady"] == cal["mu"] == ens["mu"] == rev.steady_mu
    assert row["A_norm_steady"] == cal["A_norm"] == ens["A_norm"] == rev.steady_A
    assert row["theta_A_steady_deg"] == cal["theta_A"] == ens["theta_A"]
    # and the window matters on this run: the last third would give another |A|
    pre = read_series(case / "preshear.csv")
    assert abs(steady_values(pre, fraction=1 / 3)["A_norm"] - row["A_norm_steady"]) > 1e-4
