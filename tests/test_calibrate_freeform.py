"""Free-form alpha1(X), alpha2(X) (calibrate/freeform.py, model.laws.AlphaSpline, simulate_batch(alpha_spline=...)).

The recovery tests fit model-made DEM-layout cases (``calibrate.synthetic``): Model 2's linear law
without noise must come back within the tolerances stated below; a Model 1 truth with a strong pole
(the round-trip tests' truth) at 0.5 x the 500-disk noise must make the cross-validation choose a
small penalty (the pole cannot be followed by a straight line) and show the bend of alpha1 toward the
pole. About 22 s of CPU for the module (measured; no test over 11 s): two calibrations to route 2 with the free-form
fits, and one `python -m calibrate --freeform` on two seeds.
"""
from __future__ import annotations

import time

import numpy as np
import pandas as pd
import pytest

from calibrate import freeform, pipeline, synthetic
from calibrate.problem import pose
from calibrate.settings import Settings
from model import default_params, params_from_dict, steady_shear, steady_state
from model.batched import simulate_batch
from model.laws import AlphaSpline, spline_basis, spline_of_linear

from tests.helpers import truth_params

M2 = default_params().model2   # alpha1 = c1 = -0.3, alpha2 = c2 + c3 X = -2 + 25 X
FAST = freeform.FreeformSettings(n_breaks=4, penalties=(1e-4, 1.0), layouts=((4, 1.0), (4, 2.0)), cv_evals=30,
                                 max_evals=90, n_resamples=500)


def test_spline_law_holds_a_linear_law_exactly_inside_and_outside_its_breaks():
    sp = spline_of_linear((-0.1, -0.02, 0.05, 0.1), -0.3, 2.0, -2.0, 25.0)
    X = np.linspace(-0.4, 0.4, 41)
    a1, a2 = sp(X)
    np.testing.assert_allclose(a1, -0.3 + 2.0 * X, atol=1e-12)
    np.testing.assert_allclose(a2, -2.0 + 25.0 * X, atol=1e-12)
    np.testing.assert_allclose(spline_basis(X, sp.breaks).sum(axis=1), 1.0, atol=1e-12)
    assert sp(0.3) == pytest.approx((0.3, 5.5))


def test_spline_law_on_a_float_equals_its_design_matrix_inside_outside_and_at_the_breaks():
    rng = np.random.default_rng(3)
    sp = AlphaSpline((-0.3, -0.1, 0.0, 0.05, 0.1), rng.normal(size=7), 10.0 * rng.normal(size=7))
    X = np.concatenate([rng.uniform(-0.7, 0.5, 500), sp.breaks, [np.nextafter(0.1, 1.0), np.nan]])
    want = spline_basis(X, sp.breaks) @ np.column_stack([sp.c1, sp.c2])   # the array path
    got = np.array([sp(float(x)) for x in X])                               # the plain-float path
    assert all(type(v) is float for v in sp(0.01))
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)
    assert np.isnan(got[-1]).all()


def test_spline_law_rejects_coefficients_that_do_not_match_its_breaks():
    with pytest.raises(ValueError, match="need 5 coefficients"):
        AlphaSpline((0.0, 0.1, 0.2), [1.0] * 4, [1.0] * 5)


def test_batched_spline_trajectory_equals_model2_with_the_same_linear_law():
    p = default_params()
    a, b, _ = steady_state(p, "model2")
    h = steady_shear(0.4, 1) + steady_shear(0.6, -1)
    sp = spline_of_linear((-0.12, 0.0, 0.12), M2.c1, 0.0, M2.c2, M2.c3)
    ref = simulate_batch(p, h, model="model2", A0=(a, b), friction="quadratic").trajectory(0)
    res = simulate_batch([p, p], h, model=["model2", "model1"], A0=(a, b), friction="quadratic",
                         alpha_spline=[sp, None])
    got = res.trajectory(0)
    for c in ("A_xx", "A_xy", "mu", "theta_A"):
        np.testing.assert_allclose(got[c], ref[c], atol=1e-9)
    assert not np.allclose(res.trajectory(1)["A_xy"], ref["A_xy"], atol=1e-3)   # the other one is Model 1's


def test_batched_spline_needs_an_explicit_start_and_shared_breaks():
    p, h = default_params(), steady_shear(0.5)
    sp = spline_of_linear((-0.1, 0.1), -0.3, 0.0, -2.0, 25.0)
    with pytest.raises(ValueError, match="explicit A0"):
        simulate_batch(p, h, model="model2", alpha_spline=sp)
    other = spline_of_linear((-0.2, 0.1), -0.3, 0.0, -2.0, 25.0)
    with pytest.raises(ValueError, match="share its breaks"):
        simulate_batch([p, p], h, model="model2", A0=(0.0, 0.0), alpha_spline=[sp, other])


def test_roughness_penalty_is_zero_for_lines_and_the_integral_of_the_squared_curvature():
    br = (-0.1, -0.03, 0.02, 0.1)
    R = freeform.roughness_matrix(br)
    line = spline_of_linear(br, 1.0, 2.0, 3.0, -4.0)
    assert np.abs(R @ line.c1).max() < 1e-10 and np.abs(R @ line.c2).max() < 1e-10
    x = np.linspace(br[0], br[-1], 60)
    c = np.linalg.lstsq(spline_basis(x, br), x**2, rcond=None)[0]   # X^2 exactly: alpha'' = 2
    assert np.sum((R @ c) ** 2) == pytest.approx(4.0 * (br[-1] - br[0]), rel=1e-9)


def _to_curves(root, params, model, noise):
    """The calibration to its curve fit on a model-made ensemble, with the free-form settings ``FAST``."""
    fr = "quadratic" if model == "model2" else "eq2"
    dirs = synthetic.write_ensemble(root, params, seeds=(1, 2, 3), model=model, friction=fr,
                                    fabric_noise=noise * synthetic.FABRIC_NOISE, mu_noise=noise * synthetic.MU_NOISE)
    problem = pose(dirs, Settings(freeform=FAST))
    backsolve = pipeline.fit_backsolve(problem, pipeline.fit_friction(problem))
    doc2 = pipeline.fit_curves(problem, backsolve, lambda m: None).doc
    return dict(problem=problem, replays=problem.replays, doc2=doc2, steady=problem.steady,
                sigma_mu=problem.sigma_mu, s2=problem.settings.curves)


@pytest.fixture(scope="module")
def model2_truth(tmp_path_factory):
    d = _to_curves(tmp_path_factory.mktemp("ff2"), default_params(), "model2", noise=0.0)
    t = time.process_time()
    d["res"] = freeform.run(d["problem"], d["doc2"], log=lambda m: None)
    d["cpu"] = time.process_time() - t
    return d


@pytest.fixture(scope="module")
def model1_truth(tmp_path_factory):
    d = _to_curves(tmp_path_factory.mktemp("ff1"), truth_params(), "model1", noise=0.5)
    d["res"] = freeform.run(d["problem"], d["doc2"], log=lambda m: None)
    return d


def _central_X(d):
    lo, hi = np.percentile(freeform.sample_X(d["replays"]), [5, 95])
    return np.linspace(lo, hi, 50)


def test_freeform_fit_recovers_model2_linear_alphas_from_noise_free_model_data(model2_truth):
    """Tolerance over the central 90 % of the X visited: 0.02 in alpha1 (-0.3), 0.3 in alpha2 (-4 to -0.3)."""
    x = _central_X(model2_truth)
    a1, a2 = model2_truth["res"]["spline"](x)
    assert np.abs(a1 - M2.c1).max() < 0.02
    assert np.abs(a2 - (M2.c2 + M2.c3 * x)).max() < 0.3


def test_freeform_fit_runs_in_seconds_of_cpu(model2_truth):
    assert model2_truth["cpu"] < 20.0


def test_freeform_table_holds_breaks_coefficients_cv_scores_and_pole_bends(model2_truth):
    tab = model2_truth["res"]["table"]
    assert set(tab["section"]) == {"breaks", "coefficients", "cv", "score", "difference", "pole", "heldout"}
    held = tab[tab["section"] == "heldout"]       # claim 9 per figure: every held-out run's early MSE, per law
    errors = model2_truth["res"]["errors"]
    assert len(held) == len(errors) and np.allclose(held["value"], errors["early_A_mse"], equal_nan=True)
    assert np.allclose(errors["early_A_mse"], errors["early_A_norm"] ** 2, equal_nan=True)
    pole = tab[tab["section"] == "pole"].iloc[0]       # the jackknife at t_{n-1} (3 seeds: 4.30), not 1.96
    se = (pole["high"] - pole["low"]) / 2 / freeform.t95(int(pole["n"]))
    assert freeform.t95(3) == pytest.approx(4.302652729911275) and se >= 0
    assert (tab["section"] == "coefficients").sum() == 2 * (FAST.n_breaks + 2)
    chosen = tab[(tab["section"] == "cv") & tab["detail"].str.contains("chosen")]
    assert len(chosen) == 1 and chosen["value"].iloc[0] == tab.loc[tab["section"] == "cv", "value"].min()
    diff = tab[tab["section"] == "difference"]
    assert np.isfinite(diff[["value", "low", "high"]].to_numpy()).all() and (diff["n"] == 3).all()


def test_strong_roughness_penalty_straightens_a_curved_start(model2_truth):
    d = model2_truth
    br = d["res"]["spline"].breaks
    xi = np.linspace(br[0], br[-1], len(br) + 2)
    bent = AlphaSpline(br, M2.c1 + 30.0 * xi**2, M2.c2 + M2.c3 * xi - 300.0 * xi**2)   # integrable: alpha2 < 0
    R = freeform.roughness_matrix(br)
    sp, _ = freeform.fit_spline(d["replays"], d["doc2"], bent, d["steady"], d["sigma_mu"], 1e4, FAST, d["s2"], 60)
    before = np.linalg.norm(R @ bent.c2)
    assert np.linalg.norm(R @ sp.c2) < 0.05 * before
    assert np.linalg.norm(R @ sp.c1) < 0.05 * np.linalg.norm(R @ bent.c1)


def test_cross_validation_picks_a_small_penalty_and_a_bend_for_a_strong_pole(model1_truth):
    """Model 1 truth (c1 = -3000, X_c = 0.0827): a straight alpha cannot follow it, so CV keeps the curvature."""
    res = model1_truth["res"]
    cv = res["cv"].set_index("penalty")["cv_score"]
    assert res["penalty"] == min(FAST.penalties) and cv[min(FAST.penalties)] < cv[max(FAST.penalties)]
    tab = res["table"].set_index("key")
    bend = tab.loc["alpha1 bend at X_hi"]
    assert bend["high"] < 0.0   # alpha1 falls toward the pole, as c1 < 0 makes it


def test_early_score_is_the_claims_early_rmse_after_the_first_reversal_as_before(model2_truth):
    """The free-form early |A| score (``run_errors``) is ``claims.measures.early_rmse``: the same numbers as
    the former inline RMS over s_rev < s <= s_rev + early_strain, for runs reversed at once and after a lead."""
    from dataclasses import replace

    from calibrate import curves_integration
    from dem_contract import fabric_norm

    d = model2_truth
    curves = curves_integration.curves([(params_from_dict(d["doc2"]), "model1", "eq2")], d["replays"], d["s2"])[0]
    w = FAST.early_strain
    checked = 0
    for c, r in zip(curves, d["replays"]):
        g_pre = -np.sign(r.A0[1])          # a lead sheared as the pre-shear was moves the reversal to 0.05
        for rep in (r, replace(r, pieces=[(g_pre, 0.05), *r.pieces], s=r.s + 0.05)):
            s_rev = freeform.reversal_strain(rep)
            early = (rep.s > s_rev) & (rep.s <= s_rev + w)
            dA = fabric_norm(c[:, 0], c[:, 1]) - fabric_norm(rep.a, rep.b)
            former = float(np.sqrt(np.mean(dA[early] ** 2)))
            assert early.sum() > 10 and former > 0.0
            assert freeform.run_errors(c, rep, w)["early_A_norm"] == former
            checked += 1
    assert checked == 2 * len(d["replays"])


def test_claims_table_gets_the_upper_bound_per_figure_and_pole_rows_from_freeform_csv(model2_truth, tmp_path):
    from claims import inputs, stats, table

    path = tmp_path / "freeform.csv"
    model2_truth["res"]["table"].to_csv(path, index=False)
    ff = inputs.read_freeform(path)
    rng = np.random.default_rng(0)
    dem = {}          # the comparison's DEM curves of the held-out runs: their kind and noise floor
    for label in {r.label for r in model2_truth["replays"]}:
        case, proto = label.split("/")
        s = np.linspace(0.0, 0.3, 301)
        dem[(case, "g", proto)] = pd.DataFrame({"s_rev": s, "A_norm": 0.1 + rng.normal(0, 0.01, s.size),
                                                "kind": "sinusoidal" if proto == "sinusoidal" else "heaviside"})
    rows = table.freeform_rows(ff, dem, table.Bootstrap(200))
    assert [r["claim_id"] for r in rows] == ["9-step", "9-sin", "9-pooled", "10"]
    err = model2_truth["res"]["errors"]
    wide = err.pivot_table(index=["case", "run"], columns="law", values="early_A_mse")
    step = wide[~wide.index.get_level_values("run").str.endswith("sinusoidal")]
    d = (step["freeform"] - step["model2"]).groupby(level="case").mean()
    assert rows[0]["estimate"] == pytest.approx(d.mean()) and rows[0]["n"] == 3
    assert all(r["verdict"] in stats.VERDICTS or "," in r["verdict"] for r in rows)
    pole = ff.set_index("key").loc["alpha1 bend at X_hi"]    # 95 % t of freeform.csv -> the table's 90 % t
    half90 = (rows[-1]["high"] - rows[-1]["low"]) / 2
    assert half90 == pytest.approx((pole["high"] - pole["low"]) / 2 * stats.t_quantile(3) / freeform.t95(3))
    assert table.freeform_rows(freeform.note_table("one seed"), dem, table.Bootstrap(200)) == []


@pytest.mark.heavy
def test_calibrate_freeform_option_writes_freeform_csv_and_draws_it_on_fig3(tmp_path):
    from calibrate.__main__ import main

    dirs = synthetic.write_ensemble(tmp_path / "dem", default_params(), seeds=(1, 2), model="model2",
                                    friction="quadratic")
    out = tmp_path / "cal"
    argv = ["--dem", *map(str, dirs), "--out", str(out), "--bootstrap", "2",
            "--bootstrap-evals", "10", "--route2-evals", "40", "--freeform", "--freeform-breaks", "3"]
    assert main(argv) == 0
    tab = pd.read_csv(out / "freeform.csv")
    assert list(tab.columns) == ["section", "key", "value", "low", "high", "n", "detail"]
    # one row per score and law (Model 1 and the free-form bound, each against Model 2), over the 2 seeds
    assert (tab["section"] == "difference").sum() == 2 * len(freeform.SCORES)
    assert (tab.loc[tab["section"] == "difference", "n"] == 2).all()
    assert (out / "fig3a_alpha1_vs_X.png").stat().st_size > 0


# --------------------------------------------------------------------------- knots chosen by cross-validation
# The free-form upper bound of claims 9 and 10: its breaks chosen by cross-validation, crowded toward the
# largest X visited (where Model 1's pole acts), with the penalty.
def test_crowded_breaks_span_the_same_range_and_shrink_toward_the_largest_X():
    even = np.array(freeform.breaks_over(-0.1, 0.1, 6, 1.0))
    crowded = np.array(freeform.breaks_over(-0.1, 0.1, 6, 2.0))
    assert np.allclose(np.diff(even), 0.04)
    assert crowded[0] == -0.1 and crowded[-1] == pytest.approx(0.1)
    gaps = np.diff(crowded)
    assert np.all(np.diff(gaps) < 0) and gaps[-1] == pytest.approx(0.2 / 25)   # (1 - 4/5)^2 of the span


def test_default_layouts_offer_even_and_crowded_breaks_and_more_of_them():
    s = freeform.FreeformSettings(n_breaks=5)
    assert s.knot_layouts() == ((5, 1.0), (5, freeform.CROWDING), (7, freeform.CROWDING))
    with pytest.raises(ValueError, match="knot layout"):
        freeform.FreeformSettings(layouts=((1, 1.0),))


def test_cross_validation_chooses_the_layout_and_the_penalty_together(model1_truth):
    res = model1_truth["res"]
    cv = res["cv_all"]
    assert len(cv) == len(FAST.knot_layouts()) * len(FAST.penalties) and cv["chosen"].sum() == 1
    best = cv.loc[cv["chosen"]].iloc[0]
    assert best["cv_score"] == cv["cv_score"].min()
    n, crowd = res["layout"]
    assert (n, crowd) == (best["n_breaks"], best["crowding"]) and res["penalty"] == best["penalty"]
    assert res["spline"].breaks == freeform.breaks_for(model1_truth["replays"], n, crowd)
    rows = res["table"][res["table"]["section"] == "cv"]
    assert len(rows) == len(cv) and rows["detail"].str.contains("crowding").all()


def test_command_line_narrows_the_cross_validation_grid_to_the_layouts_and_penalties_named():
    from calibrate.__main__ import freeform_settings, parser

    argv = ["--dem", "d", "--out", "o", "--freeform", "--freeform-layouts", "5:2", "--freeform-penalties", "1e-4", "1"]
    s = freeform_settings(parser().parse_args(argv))
    assert s.knot_layouts() == ((5, 2.0),) and s.penalties == (1e-4, 1.0)
    assert freeform_settings(parser().parse_args(argv[:4])) is None
    default = freeform_settings(parser().parse_args(argv[:5]))
    assert default == freeform.FreeformSettings()


@pytest.mark.parametrize("option, words", [("--freeform-layouts 1:2", "BREAKS an integer >= 2"),
                                           ("--freeform-layouts 5:0.5", "CROWDING >= 1"),
                                           ("--freeform-layouts 5", "BREAKS:CROWDING"),
                                           ("--freeform-penalties 0", "positive number")])
def test_preflight_refuses_a_bad_cross_validation_grid_naming_the_calibration_options(option, words):
    from preflight.checks import options_problems

    problems = options_problems({"calibration": {"options": option}, "compare": {"options": ""}})
    assert len(problems) == 1 and "calibration.options" in problems[0] and words in problems[0], problems
