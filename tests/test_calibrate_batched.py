"""The curves route with the batched integrator (``CurvesOptions.integrator``) against the per-run loop.

Model-made cases (``calibrate.synthetic``, known parameters, DEM-magnitude noise):
the residuals of the two paths agree to 1e-6 (in units of the sample noise) at
tight tolerances (measured: 9e-8 at rtol 1e-10); at the curves route's default
rtol 1e-6 they differ by about 3e-4 noise units, the error of the batched
Dormand-Prince at that tolerance (LSODA's is 1e-5 against Radau at rtol 1e-12).
"""
from dataclasses import replace

import numpy as np
import pytest

import model.batched
from calibrate import curves_fit, curves_integration, dem_replays, synthetic
from calibrate.curves_integration import CurvesOptions, curves
from calibrate.integration_batcher import IntegrationBatcher
from calibrate.backsolve import BacksolveSettings
from calibrate.io import read_cases, steady_values
from calibrate.settings import Settings
from calibrate.smoothing import smooth_cases
from model import PoleError, params_from_dict
from tests.helpers import TRUTH_M1, truth_params

SIGMA_MU = 0.04
TIGHT = dict(rtol=1e-10, atol=1e-12)
DEFAULT = Settings().curves   # the curves route's settings in a calibration's defaults


@pytest.fixture(scope="module")
def replays(tmp_path_factory):
    dirs = synthetic.write_ensemble(tmp_path_factory.mktemp("cb") / "dem", truth_params(), seeds=(1, 2))
    cases = read_cases(dirs)
    return dem_replays.prepare(cases, smooth_cases(cases), BacksolveSettings()), steady_values(cases)


def with_model1(**changes):
    d = truth_params().to_dict()
    d["model1"] = {**TRUTH_M1, **changes}
    return params_from_dict(d)


def test_batched_and_loop_residuals_agree_to_1e6(replays):
    reps, _ = replays
    loop = replace(DEFAULT, integrator="loop", **TIGHT)
    for prm, model, friction in ((truth_params(), "model1", "eq2"), (truth_params(), "model2", "quadratic"),
                                 (with_model1(a1=-1.0, c2=2500.0), "model1", "eq2")):
        r_loop = curves_fit.residuals(prm, reps, model, friction, SIGMA_MU, loop)
        r_batch = curves_fit.residuals(prm, reps, model, friction, SIGMA_MU, replace(loop, integrator="batched"))
        assert np.max(np.abs(r_batch - r_loop)) < 1e-6, model


def test_a_failing_parameter_set_in_a_batch_fails_alone(replays):
    reps, _ = replays
    s = DEFAULT
    good, other = truth_params(), with_model1(a1=-1.0)
    pole = with_model1(X_c=0.05)   # every reversal starts at X of about 0.075 > X_c
    got = curves([(good, "model1", "eq2"), (pole, "model1", "eq2"), (other, "model1", "eq2")], reps, s)
    assert isinstance(got[1], PoleError)
    assert isinstance(curves([(pole, "model1", "eq2")], reps, replace(s, integrator="loop"))[0],
                      PoleError)   # as the loop scores it
    for k, prm in ((0, good), (2, other)):
        (alone,) = curves([(prm, "model1", "eq2")], reps, s)
        for m_batch, m_alone in zip(got[k], alone):
            np.testing.assert_array_equal(m_batch, m_alone)
    scores = curves_fit.score_many([(good, "model1"), (pole, "model1")], reps, s, SIGMA_MU)
    assert np.isfinite(scores[0]["score"]) and scores[1]["score"] == np.inf
    assert scores[1]["failure"].startswith("PoleError")


def count_calls(monkeypatch, module, name):
    calls = []
    real = getattr(module, name)

    def counted(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(module, name, counted)
    return calls


def test_the_integrator_option_selects_the_path(replays, monkeypatch):
    reps, _ = replays
    batch_calls = count_calls(monkeypatch, curves_integration, "simulate_batch")
    loop_calls = count_calls(monkeypatch, curves_integration, "simulate")
    curves_fit.residuals(truth_params(), reps, "model1", "eq2", SIGMA_MU, replace(DEFAULT, integrator="loop"))
    assert (len(batch_calls), len(loop_calls)) == (0, len(reps))
    curves_fit.residuals(truth_params(), reps, "model1", "eq2", SIGMA_MU, DEFAULT)
    assert (len(batch_calls), len(loop_calls)) == (1, len(reps))
    with pytest.raises(ValueError, match="integrator"):
        CurvesOptions(integrator="rk4")


def test_a_fit_batches_its_jacobian_and_matches_the_loop(replays, monkeypatch):
    reps, steady = replays
    doc = truth_params().to_dict()
    start = {**TRUTH_M1, "a1": -0.8, "a2": -4.5}
    loop = replace(DEFAULT, integrator="loop", max_evals=40, **TIGHT)
    f_loop = curves_fit.fit(reps, doc, "model1", start, steady, SIGMA_MU, loop)
    calls = count_calls(monkeypatch, model.batched, "simulate_batch")
    monkeypatch.setattr(curves_integration, "simulate_batch", model.batched.simulate_batch)
    f_batch = curves_fit.fit(reps, doc, "model1", start, steady, SIGMA_MU, replace(loop, integrator="batched"))
    n = f_batch.extra["evaluations"]
    assert n == f_loop.extra["evaluations"]
    assert len(calls) <= n / 4    # 7 parameters: the 7 Jacobian points of a step in one call
    for k, v in f_loop.values.items():
        assert f_batch.values[k] == pytest.approx(v, rel=1e-5, abs=1e-8), k


def test_jobs_under_one_batcher_get_what_they_get_alone_in_fewer_batches(replays, monkeypatch):
    reps, _ = replays
    s = DEFAULT
    sets = [with_model1(a1=a1) for a1 in (-0.8, -0.85, -0.9)] + [with_model1(X_c=0.05)]
    alone = [curves([(p, "model1", "eq2")], reps[: 1 + k % 3], s)[0] for k, p in enumerate(sets)]
    calls = count_calls(monkeypatch, curves_integration, "simulate_batch")
    jobs = [lambda batcher, k=k, p=p: curves([(p, "model1", "eq2")], reps[: 1 + k % 3], s, batcher)[0]
            for k, p in enumerate(sets)]
    together = IntegrationBatcher().run(jobs)
    assert len(calls) == 1
    assert isinstance(together[3], PoleError) and isinstance(alone[3], PoleError)
    for a, b in zip(alone[:3], together[:3]):
        for x, y in zip(a, b):
            np.testing.assert_array_equal(x, y)
