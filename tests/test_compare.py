"""The model-against-DEM comparison (compare/): exactness on model-made data, the claims, robustness."""
import numpy as np
import pandas as pd
import pytest

from compare import comparison, metrics
from compare.cli import main
from compare.dem import load_reversal
from compare.predict import clean_rate, predict
from dem_contract.synthetic import write_case, write_ensemble
from model import default_params, params_from_dict, save_params


@pytest.fixture(scope="module")
def params_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("params") / "params.yaml"
    save_params(default_params(), path)
    return path


@pytest.mark.parametrize("model, friction", [("model1", "eq2"), ("model2", "quadratic")])
def test_generating_model_has_zero_error_on_its_own_data(tmp_path, params_file, model, friction):
    dirs = write_ensemble(tmp_path, default_params(), seeds=(1, 2), model=model, friction=friction,
                          preshear_strain=0.3, reversal_strain=0.4)
    c = comparison.run(dirs, params_file, ["heaviside", "sinusoidal"])
    mine = c.errors[c.errors["model"] == model]
    assert len(mine) == 2 * 2 + 2        # 2 seeds x 2 protocols, 2 ensembles
    assert (mine["status"] == "ok").all()
    assert mine[["max_A_norm", "max_mu"]].to_numpy().max() < 1e-8
    assert mine["max_theta_A"].max() < 1e-5
    other = c.errors[c.errors["model"] != model]
    assert other["max_A_norm"].min() > 1e-4   # the comparison does discriminate


def test_generating_model_has_zero_error_through_the_command_line(tmp_path, params_file):
    dirs = write_ensemble(tmp_path / "dem", default_params(), seeds=(1,), preshear_strain=0.3, reversal_strain=0.3)
    out = tmp_path / "out"
    assert main(["predict", "--dem", *map(str, dirs), "--params", str(params_file), "--out", str(out)]) == 0
    err = pd.read_csv(out / "errors.csv")
    assert err.loc[err["model"] == "model1", "max_A_norm"].max() < 1e-8
    for name in ("predictions.csv", "claims.csv", "fig4_heaviside.png", "fig5_sinusoidal.png"):
        assert (out / name).stat().st_size > 0


def _angles(start, stop, n=200, jitter=0.0, seed=0):
    th = np.linspace(start, stop, n) + np.random.default_rng(seed).normal(0.0, jitter, n)
    return np.mod(th, 180.0)


@pytest.mark.parametrize("start, stop, expected", [
    (125.0, 55.0, "90"),          # the paper's claim: clockwise through the vertical
    (125.0, 235.0, "0/180"),      # the other way round, through the horizontal (wraps 180 -> 0)
    (55.0, -55.0, "0/180"),       # through 0, wrapping below
    (135.0, 100.0, "neither"),    # monotone, stops short of 90
    (100.0, 170.0, "neither"),    # monotone the other way, stops short of 180
    (170.0, 10.0, "90"),          # a long clockwise turn through 90 only
    (135.0, -100.0, "both"),      # more than half a turn
])
def test_theta_passage_names_the_axis_crossed(start, stop, expected):
    assert metrics.theta_passage(_angles(start, stop)) == expected


def test_theta_passage_ignores_jitter_across_an_axis():
    th = np.concatenate([_angles(125, 92, 50), _angles(92, 88, 20, jitter=1.5), _angles(88, 95, 30),
                         _angles(95, 125, 50)])
    assert metrics.theta_passage(th) == "neither"
    assert metrics.theta_passage(_angles(125, 55, jitter=3.0)) == "90"


def test_claims_find_minimum_and_recovery_of_a_constructed_curve():
    s = np.linspace(0, 1, 1001)
    A = 0.07 * (1 - 0.9 * np.exp(-((s - 0.2) / 0.05) ** 2))       # minimum 0.007 at s = 0.2
    c = metrics.claims(s, np.zeros_like(s), -A / np.sqrt(2), A, steady_A=0.07, steady_mu=0.07)
    assert c["min_A"] == pytest.approx(0.007, rel=1e-6) and c["s_min_A"] == pytest.approx(0.2)
    # 0.9 of steady: 0.9 exp(-x^2) = 0.1 -> x = sqrt(ln 9) * 0.05
    assert c["s_recover_A"] == pytest.approx(0.2 + 0.05 * np.sqrt(np.log(9)), abs=1e-3)
    assert c["s_recover_mu"] == c["s_recover_A"]


def test_angle_errors_wrap_at_180_degrees():
    e = metrics.errors({"A_norm": [0.0], "theta_A": [179.0], "mu": [0.0]},
                       {"A_norm": [0.0], "theta_A": [1.0], "mu": [0.0]})
    assert e["max_theta_A"] == pytest.approx(2.0)


def test_heaviside_rate_is_cleaned_to_one_sharp_constant(tmp_path):
    case = write_case(tmp_path / "p1_I0.001_s1", default_params(), preshear_strain=0.3, reversal_strain=0.3,
                      fabric_noise=0.0125, mu_noise=0.04, protocols=("heaviside",))
    rev = load_reversal(case, "heaviside")
    assert rev.data["gammadot"].std() > 0          # the measured rate fluctuates with the gap
    g, width = clean_rate(rev)
    assert width == 0 and np.all(g == g[0]) and g[0] == pytest.approx(-1e-3, rel=1e-3)


def test_noisy_sinusoidal_rate_is_smoothed_to_a_single_reversal(tmp_path):
    case = write_case(tmp_path / "p1_I0.001_s1", default_params(), preshear_strain=0.3, reversal_strain=0.3,
                      protocols=("sinusoidal",))
    rev = load_reversal(case, "sinusoidal")
    assert clean_rate(rev)[1] == 1                   # a clean rate is used as it is
    g = rev.data["gammadot"].to_numpy().copy()
    k = int(np.argmax(g < 0))                        # first sample after the true reversal
    g[k + 2] = abs(g[k + 2])                         # measurement noise flips two samples near zero
    g[k - 3] = -abs(g[k - 3])
    rev.data["gammadot"] = g
    g, width = clean_rate(rev)
    assert width > 1
    s = np.sign(g[g != 0])
    assert np.count_nonzero(s[1:] != s[:-1]) == 1
    assert predict(rev, default_params(), "model1").status == "ok"


def test_pole_error_of_model1_is_a_table_row_not_a_crash(tmp_path):
    p = default_params().to_dict()
    p["model1"]["X_c"] = 0.065             # below the mirrored steady X (0.070): Model 1 cannot start
    bad = tmp_path / "bad.yaml"
    save_params(params_from_dict(p), bad)
    dirs = write_ensemble(tmp_path / "dem", default_params(), seeds=(1, 2), preshear_strain=0.3,
                          reversal_strain=0.3, fabric_noise=0.0125, mu_noise=0.04)
    out = tmp_path / "out"
    assert main(["predict", "--dem", *map(str, dirs), "--params", str(bad), "--out", str(out)]) == 0
    err = pd.read_csv(out / "errors.csv")
    m1 = err[err["model"] == "model1"]
    assert m1["status"].str.contains("PoleError").any()
    assert (err.loc[err["model"] == "model2", "status"] == "ok").all()
    # a failed model has no curve, so no errors (not the DEM's own against itself)
    failed = m1[m1["status"].str.contains("PoleError") & (m1["level"] == "seed")]
    assert failed[["rmse_A_norm", "max_theta_A", "rmse_mu"]].isna().all().all()
    pred = pd.read_csv(out / "predictions.csv")
    assert set(pred.loc[pred["case"].isin(failed["case"]), "source"]) == {"dem", "model2"}


def test_in_sample_flag_follows_the_training_cases_and_protocols(tmp_path, params_file):
    dirs = write_ensemble(tmp_path, default_params(), seeds=(1, 2), preshear_strain=0.3, reversal_strain=0.2)
    c = comparison.run(dirs, params_file, ["heaviside", "sinusoidal"], train_cases=["p1_I0.001_s1", "p1_I0.001_s2"],
                       train_protocols=["heaviside"])
    flags = c.errors.groupby("protocol")["in_sample"].unique()
    assert list(flags["heaviside"]) == [True] and list(flags["sinusoidal"]) == [False]


def test_missing_column_is_reported_with_the_file(tmp_path, params_file, capsys):
    case = write_case(tmp_path / "p1_I0.001_s1", default_params(), preshear_strain=0.3, reversal_strain=0.2,
                      protocols=("heaviside",))
    df = pd.read_csv(case / "heaviside.csv").drop(columns=["A_xy"])
    df.to_csv(case / "heaviside.csv", index=False)
    assert main(["predict", "--dem", str(case), "--params", str(params_file), "--protocols", "heaviside",
                 "--out", str(tmp_path / "out")]) == 2
    assert "heaviside.csv" in capsys.readouterr().err


def test_heldout_table_separates_in_and_out_of_sample_and_notes_a_missing_split(tmp_path, params_file):
    from compare.heldout import heldout_table
    dirs = write_ensemble(tmp_path / "dem", default_params(), seeds=(1, 2), preshear_strain=0.3, reversal_strain=0.2)
    paths = []
    for name, train in (("all", None), ("heaviside_only", ["heaviside"])):
        out = tmp_path / name
        out.mkdir()
        comparison.run(dirs, params_file, ["heaviside", "sinusoidal"], set_name=name,
                       train_protocols=train).errors.to_csv(out / "errors.csv", index=False)
        paths.append(out / "errors.csv")
    only_all = heldout_table(paths[:1])
    assert (only_all["n_out"] == 0).all() and only_all["note"].str.contains("no other calibration set").all()
    both = heldout_table(paths).set_index(["set", "model"])
    row = both.loc[("heaviside_only", "model1")]
    assert row["n_in"] == 2 and row["n_out"] == 2 and "sinusoidal" in row["held_out"]
    assert row["rmse_A_norm_out"] < 1e-8            # generating model: exact out of sample too


def test_sensitivity_moves_predictions_more_at_5_than_at_1_percent_and_records_poles(tmp_path):
    from compare import sensitivity
    dirs = write_ensemble(tmp_path / "dem", default_params(), seeds=(1,), preshear_strain=0.3, reversal_strain=0.2,
                          protocols=("heaviside",))
    p = default_params().to_dict()
    p["intervals"] = {"model1": {"X_c": [0.06, 0.09]}}    # the low end puts the pole below the mirrored X
    path = tmp_path / "p.yaml"
    save_params(params_from_dict(p), path)
    table, n = sensitivity.run(dirs, path, ["heaviside"], tmp_path / "band.png")
    assert n <= 2 * 60 and (tmp_path / "band.png").stat().st_size > 0
    a1 = table[(table["model"] == "model1") & (table["parameter"] == "a1")].set_index("kind")
    assert 0 < a1.loc["+1%", "dmax_A_norm"] < a1.loc["+5%", "dmax_A_norm"]
    low = table[(table["parameter"] == "X_c") & (table["kind"] == "interval low")]
    assert low["status"].str.startswith("PoleError").all()


def test_reversal_start_comes_from_the_sidecar_when_the_first_sample_is_later(tmp_path, params_file):
    case = write_case(tmp_path / "p1_I0.001_s1", default_params(), preshear_strain=0.3, reversal_strain=0.3,
                      protocols=("heaviside",))
    df = pd.read_csv(case / "heaviside.csv")
    df.iloc[3:].to_csv(case / "heaviside.csv", index=False)      # samples start 0.003 strain after the reversal
    rev = load_reversal(case, "heaviside")
    assert rev.strain0 == pytest.approx(0.3) and rev.data["s_rev"].iloc[0] == pytest.approx(0.003)
    pred = predict(rev, default_params(), "model1")
    assert np.max(np.abs(pred.table["A_norm"].to_numpy() - rev.data["A_norm"].to_numpy())) < 1e-8


def test_cases_with_different_protocols_are_compared_each_on_the_runs_it_has(tmp_path, params_file):
    dirs = write_ensemble(tmp_path, default_params(), seeds=(1, 2), preshear_strain=0.3, reversal_strain=0.3)
    (dirs[1] / "sinusoidal.csv").unlink()
    c = comparison.run(dirs, params_file, ["heaviside", "sinusoidal"])
    seeds = c.errors[(c.errors["level"] == "seed") & (c.errors["model"] == "model1")]
    assert sorted(zip(seeds["case"], seeds["protocol"])) == [
        ("p1_I0.001_s1", "heaviside"), ("p1_I0.001_s1", "sinusoidal"), ("p1_I0.001_s2", "heaviside")]
    for d in dirs:
        (d / "sinusoidal.csv").unlink(missing_ok=True)
    with pytest.raises(comparison.DEMInputError, match="no case holds a sinusoidal run"):
        comparison.run(dirs, params_file, ["sinusoidal"])
