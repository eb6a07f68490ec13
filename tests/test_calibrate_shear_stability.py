"""Every fitted parameter set must shear steadily (calibrate/shear_stability.py, calibrate.pipeline's guard).

The unstable Model 2 set is the route-1 fit the CI preset's calibration set 'all' made on
its DEM data (c1, c2, c3 below): Eq. 5 with these alphas has no stable steady state of
simple shear, and forward shear from isotropy passes |A| = 1/sqrt 2 within a strain.
"""
import math
from functools import partial

import numpy as np
import pandas as pd
import pytest

from calibrate import profiles, route_choice, shear_stability
from model import default_params, params_from_dict, simulate, steady_shear
from model.laws import alpha_model2, spline_of_linear

UNSTABLE_MODEL2 = {"c1": -1.006897, "c2": -17.295029, "c3": -90.281996}


def doc_with(model2=None):
    d = default_params().to_dict()
    d.pop("provenance", None)
    if model2:
        d["model2"] = dict(model2)
    return d


def test_default_parameters_shear_steadily():
    for model in ("model1", "model2"):
        v = shear_stability.check_block(doc_with(), model)
        assert v["stable"] and v["note"] == "" and math.isnan(v["diverges_at"]) and v["steady_X"] < 0


def test_a_model2_set_without_a_stable_steady_state_is_refused_with_its_divergence_strain():
    v = shear_stability.check_block(doc_with(UNSTABLE_MODEL2), "model2")
    assert not v["stable"] and "no stable steady state of simple shear" in v["note"]
    assert 0.5 < v["diverges_at"] < 1.5 and "|A| > 1/sqrt 2 after" in v["note"]
    # the divergence strain is the model's own: model.simulate from isotropy leaves |A| <= 1/sqrt 2 there
    with pytest.raises(Exception):
        simulate(params_from_dict(doc_with(UNSTABLE_MODEL2)), steady_shear(v["diverges_at"] + 0.1), model="model2",
                 A0=(0.0, 0.0))
    tab = simulate(params_from_dict(doc_with(UNSTABLE_MODEL2)), steady_shear(0.98 * v["diverges_at"]),
                   model="model2", A0=(0.0, 0.0))
    assert 0.3 < tab["A_norm"].max() < 1 / np.sqrt(2)       # still physical just before, growing fast


def solve_ivp_forward_divergence(alphas, X_c=math.inf, strain=shear_stability.FORWARD_STRAIN):
    """The forward test as scipy's solve_ivp runs it (LSODA, two terminal events): the reference."""
    from scipy.integrate import solve_ivp

    def rate(_, y):
        al1, al2 = alphas(float(np.sqrt(2.0) * y[1]))
        return [al2 * y[0] / np.sqrt(2.0) + y[1], 0.5 * al1 + al2 * y[1] / np.sqrt(2.0) - y[0]]

    def norm(_, y):
        return shear_stability.AB2_MAX - (y[0] ** 2 + y[1] ** 2)

    def pole(_, y):
        return (X_c - np.sqrt(2.0) * y[1]) if math.isfinite(X_c) else 1.0

    norm.terminal = pole.terminal = True
    with np.errstate(all="ignore"):
        sol = solve_ivp(rate, (0.0, strain), [0.0, 0.0], method="LSODA", rtol=1e-6, atol=1e-9, events=(norm, pole))
    if sol.t_events[0].size:
        return float(sol.t_events[0][0]), "|A| > 1/sqrt 2"
    if sol.t_events[1].size:
        return float(sol.t_events[1][0]), "X reaches the pole X_c"
    assert sol.status == 0 and np.all(np.isfinite(sol.y))
    return None


def test_forward_shear_from_isotropy_ends_where_solve_ivp_with_its_events_ends_to_the_bit():
    p = default_params()
    laws = {
        "model1 default": shear_stability.law_of(p, "model1"),
        "model2 default": shear_stability.law_of(p, "model2"),
        "model2 unstable": shear_stability.law_of(doc_with(UNSTABLE_MODEL2), "model2"),
        "alpha1 = 1, alpha2 = -1 (steady X = 1/3), pole at 0.1": (partial(alpha_model2, c1=1.0, c2=-1.0, c3=0.0), 0.1),
        "spline": (spline_of_linear((-0.3, -0.1, 0.0, 0.1), -2.4, 1.0, -36.0, -120.0), math.inf),
        "spline, alpha2 > 0": (spline_of_linear((-0.3, 0.0, 0.3), 0.5, 0.0, 1.0, 5.0), math.inf),
    }
    outcomes = {}
    for name, (alphas, X_c) in laws.items():
        got = shear_stability.forward_divergence(alphas, X_c)
        assert got == solve_ivp_forward_divergence(alphas, X_c), name
        outcomes[name] = got[1] if got else "stays physical"
    assert set(outcomes.values()) == {"stays physical", "|A| > 1/sqrt 2", "X reaches the pole X_c"}, outcomes


def test_a_free_form_law_is_checked_like_the_models():
    br = np.linspace(-0.2, 0.2, 6)
    m2 = UNSTABLE_MODEL2
    assert not shear_stability.check(spline_of_linear(br, m2["c1"], 0.0, m2["c2"], m2["c3"]))["stable"]
    d = default_params().model2
    assert shear_stability.check(spline_of_linear(br, d.c1, 0.0, d.c2, d.c3))["stable"]


def quality_rows():
    return [{"model": m, "route": r} for m in ("model1", "model2") for r in ("backsolve", "curves")]


def test_the_pipeline_names_an_unstable_set_and_moves_the_default_to_the_stable_route():
    quality, log = quality_rows(), []
    routes = route_choice.guard_shear_stability(quality, {"model1": "curves", "model2": "backsolve"},
                                            doc_with(UNSTABLE_MODEL2), doc_with(), log.append)
    assert routes == {"model1": "curves", "model2": "curves"}
    q = pd.DataFrame(quality).set_index(["model", "route"])
    assert not q.loc[("model2", "backsolve"), "shear_stable"] and q.loc[("model2", "curves"), "shear_stable"]
    assert "no stable steady state" in q.loc[("model2", "backsolve"), "shear_note"]
    assert q.loc[("model2", "curves"), "default"] and not q.loc[("model2", "backsolve"), "default"]
    assert any(line.startswith("shear stability: model2 backsolve") and "refused" in line for line in log)


def test_the_pipeline_refuses_a_model_whose_every_route_cannot_shear_steadily():
    with pytest.raises(route_choice.UnstableFit, match="model2: no fitted set can shear steadily"):
        route_choice.guard_shear_stability(quality_rows(), {"model1": "curves", "model2": "curves"},
                                       doc_with(UNSTABLE_MODEL2), doc_with(UNSTABLE_MODEL2), print)


def test_identifiability_says_pole_only_for_model1():
    v = np.linspace(-5.0, 5.0, 21)
    prof = pd.DataFrame({"value": v, "delta": np.where(v < -3.5, np.inf, 0.01 * v**2), "threshold": 4.0})
    assert "the pole, not the data" in profiles.interval(prof, model="model1")["note"]
    note = profiles.interval(prof, model="model2")["note"]
    assert "pole" not in note and "cannot shear steadily" in note
