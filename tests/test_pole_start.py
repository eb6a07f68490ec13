"""Model 1 with its pole a fitted offset above each run's start (model/calibrate/compare ``pole_start``).

Model-made data (``calibrate.synthetic``) with a known truth: a Model 1 whose
pole sits ``DELTA_TRUE`` above the mirrored X every run reverses from.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from calibrate import pipeline, route2, synthetic
from calibrate import pole_start as cps
from compare import pole_start as mps
from compare.dem import load_reversals
from dem_contract.synthetic import FABRIC_NOISE, MU_NOISE
from model import default_params, load_params, save_params, steady_state
from model.pole_start import DELTA_MIN, mirrored_x, pole_position

DELTA_TRUE = 0.02
NOISE = 0.05   # of one 500-disk run's noise: small, so each run's start X is known to ~1e-4


@pytest.fixture(scope="module")
def truth_fit(tmp_path_factory):
    """A pole-at-start truth (the pre-shear ends in the steady state: X_rev = -X_ss for every run), fitted."""
    root = tmp_path_factory.mktemp("pole")
    p = default_params()
    _, _, x_ss = steady_state(p, "model1")
    truth = dataclasses.replace(p, model1=dataclasses.replace(p.model1, c2=3000.0, X_c=-x_ss + DELTA_TRUE))
    save_params(default_params(), root / "start.yaml")   # the fit starts from the defaults, not the truth
    dirs = synthetic.write_ensemble(root, truth, seeds=(1, 2, 3), A_start=None, fabric_noise=NOISE * FABRIC_NOISE,
                                    mu_noise=NOISE * MU_NOISE)
    out = cps.run(dirs, root / "start.yaml", ["heaviside", "sinusoidal"], root / "pole_start.yaml", max_evals=100,
                  profile_points=10, log=lambda *a: None)
    return root, dirs, out


def test_fitted_delta_recovers_a_pole_placed_above_each_runs_start(truth_fit):
    _, _, out = truth_fit
    low, high = out["delta_interval"]
    assert low <= DELTA_TRUE <= high
    assert low > 0.0 and high < 2 * DELTA_TRUE   # an interval that says something, not the whole range
    assert out["fit"]["success"]


def test_delta_profiled_down_to_the_start_stays_finite(truth_fit):
    root, _, _ = truth_fit
    prof = pd.read_csv(root / "pole_start_profile.csv")
    assert prof["value"].min() == pytest.approx(DELTA_MIN)
    assert np.all(np.isfinite(prof[["value", "objective", "delta", "threshold"]].to_numpy()))
    # the pole at the start is worse than the truth by far more than the threshold: the lower end is measured
    assert prof.loc[prof["value"].idxmin(), "delta"] > prof["threshold"].iloc[0]


def test_a_pole_offset_of_zero_is_clipped_to_the_smallest_offset():
    assert pole_position(0.07, 0.0) == pytest.approx(0.07 + DELTA_MIN)
    assert pole_position(0.07, -1.0) == pytest.approx(0.07 + DELTA_MIN)
    assert pole_position(-0.01, 0.0) == pytest.approx(DELTA_MIN)   # a start on the steady side: pole just above 0
    with pytest.raises(ValueError, match="finite"):
        pole_position(float("nan"), 0.01)


def test_model_curves_at_zero_offset_are_finite_or_a_named_failure(truth_fit):
    _, dirs, out = truth_fit
    settings = pipeline.Settings(protocols=("heaviside", "sinusoidal"))
    cases = pipeline.read_inputs(dirs, settings)
    samples, _ = pipeline.smooth(cases, settings)
    replays = route2.prepare(cases, samples, settings.backsolve)
    doc = load_params(truth_fit[0] / "start.yaml").to_dict()
    doc.pop("provenance", None)
    doc.pop("intervals", None)
    prm = cps._block_params(doc, out["model1"])
    for c in cps.curves([(prm, 0.0), (prm, DELTA_MIN)], replays, settings.route2):
        if isinstance(c, Exception):
            assert "starts at or beyond" not in str(c)   # never a start past the pole
        else:
            assert all(np.all(np.isfinite(m)) for m in c)


def test_a_run_that_shears_forward_first_is_given_its_pole_above_the_state_it_reverses_from(tmp_path):
    # a short pre-shear from isotropy: the fabric still grows during the half cosine's forward part,
    # so the X it reverses from lies above the mirrored X of the start fabric
    p = default_params()
    (case,) = synthetic.write_ensemble(tmp_path, p, seeds=(1,), preshear_strain=0.3, fabric_noise=0.0, mu_noise=0.0)
    rev = load_reversals(case, "sinusoidal")[0]
    naive = mirrored_x(rev.A0[1], -np.sign(rev.rate_before))
    x_rev = mps.reversal_x(rev, p)
    assert x_rev > naive + DELTA_MIN
    pred = mps.predict_start(rev, p, DELTA_MIN)
    assert "starts at or beyond" not in pred.status


def test_calibration_and_comparison_put_the_pole_at_the_same_place(truth_fit):
    root, dirs, out = truth_fit
    params, _ = cps.load(root / "pole_start.yaml")
    for d in dirs:
        for proto in ("heaviside", "sinusoidal"):
            rev = load_reversals(d, proto)[0]
            assert mps.reversal_x(rev, params) == pytest.approx(out["x_rev"][f"{rev.label}/{proto}"], abs=1e-6)
