"""The DEM resolution study (dem_study/): grid expansion, scenes, cost estimate, and the
analysis on constructed series with known deviations and a known linear mu(I)."""
import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from campaign import cost
from campaign.schedule import makespan
from dem_study import analysis, grid
from dem_study.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def paper():
    return yaml.safe_load((ROOT / "config" / "config.yaml").read_text())


# --- grid -------------------------------------------------------------------

def test_default_subset_expands_one_factor_at_a_time(paper):
    acc = paper["accuracy"]
    table = grid.expand(acc)
    base = acc["base"]
    for axis, values in acc["default_subset"].items():
        rows = table[table["axis"] == axis]
        assert sorted(rows["value"]) == sorted({*map(float, values), float(base[axis])})
        assert rows["finest"].sum() == 1
        # every other axis stays at the base
        for other in grid.AXES:
            if other != axis and not {axis, other} <= {"fine_interval", "coarse_interval"}:
                assert np.allclose(rows[other], base[other])
        # the base value of the axis is the base point
        assert set(rows[rows["is_base"]]["point"]) == {f"base_s{acc['seeds'][0]}"}
    assert table.loc[table["axis"] == "kappa"].query("finest")["value"].item() == max(acc["default_subset"]["kappa"])
    assert table.loc[table["axis"] == "inertial_number"].query("finest")["value"].item() == 1e-3
    assert table.loc[table["axis"] == "dt_over_tc"].query("finest")["value"].item() == 0.1
    seeds = table[table["axis"] == "seed"]
    assert list(seeds["point"]) == [f"base_s{s}" for s in acc["seeds"]]
    points = grid.unique_points(table)
    n_axis_points = sum(len(set(v) - {base[a]}) for a, v in acc["default_subset"].items())
    n_repeats = sum(len(v) for v in acc.get("repeat", {}).values()) * (len(acc["seeds"]) - 1)
    assert len(points) == n_axis_points + len(acc["seeds"]) + n_repeats
    assert "kappa-100000_s1" in set(points["point"]) and "H-37_s1" in set(points["point"])


def test_full_subset_runs_every_grid_value(paper):
    acc = {**paper["accuracy"], "subset": "full"}
    table = grid.expand(acc)
    for axis, values in acc["dem_grid"].items():
        assert set(table[table["axis"] == axis]["value"]) == {*map(float, values), float(acc["base"][axis])}


def test_subset_value_outside_the_grid_is_named(paper):
    acc = {**paper["accuracy"], "default_subset": {"kappa": [2.0e+3]}}
    with pytest.raises(ValueError, match=r"default_subset\.kappa: 2000 is not in accuracy\.dem_grid\.kappa"):
        grid.expand(acc)


def test_sampling_intervals_stay_ordered():
    base = dict(kappa=1e3, inertial_number=1e-2, H_over_d=8, dt_over_tc=0.1, fine_interval=0.002, coarse_interval=0.01)
    assert grid.setting_of(base, "fine_interval", 0.02)["coarse_interval"] == 0.02
    assert grid.setting_of(base, "coarse_interval", 0.001)["fine_interval"] == 0.001
    assert grid.setting_of(base, "kappa", 1e4) == {**base, "kappa": 1e4}


def test_point_scene_changes_one_key_and_passes_the_scene_validator(paper):
    sys.path.insert(0, str(ROOT / "yade_scripts"))
    try:
        from scene import validate
    finally:
        sys.path.pop(0)
    acc = paper["accuracy"]
    base_scene = grid.point_scene(paper, "base_s1")
    scene = grid.point_scene(paper, "kappa-100000_s1")
    assert scene["material"]["kappa"] == 1e5 and base_scene["material"]["kappa"] == acc["base"]["kappa"]
    assert scene["geometry"]["H_over_d"] == acc["base"]["H_over_d"]
    assert scene["loading"]["inertial_number"] == acc["base"]["inertial_number"]
    assert scene["preshear"]["strain"] == acc["preshear_strain"]
    assert scene["heaviside"]["strain"] == acc["heaviside_strain"] and "sinusoidal" not in scene
    diff = {(sec, k) for sec in scene if isinstance(scene[sec], dict)
            for k in scene[sec] if scene[sec][k] != base_scene[sec].get(k)}
    assert diff == {("material", "kappa"), ("meta", "case")}
    for point in grid.unique_points(grid.expand(acc))["point"]:
        validate(grid.point_scene(paper, point), stage="heaviside")


def test_default_subset_takes_about_half_an_hour_on_two_cores(paper):
    # 0.48 h with the damped packing's PACK_TIME (100 time units); 0.85 h with the former 665
    est = grid.estimate({**paper, "accuracy": {**paper["accuracy"], "repeat": {}}})
    hours = makespan(est["est_core_s"], 2) / 3600
    assert 0.35 < hours < 0.7, hours
    with_repeats = grid.estimate(paper)
    assert len(with_repeats) == len(est) + 3 and with_repeats["est_core_s"].sum() > est["est_core_s"].sum()
    full = grid.estimate({**paper, "accuracy": {**paper["accuracy"], "subset": "full"}})
    assert full["est_core_s"].sum() > est["est_core_s"].sum()


def test_a_lammps_study_is_estimated_at_lammps_documented_throughput(paper):
    yade, lammps = grid.estimate(paper), grid.estimate({**paper, "engine": "lammps"})
    assert np.allclose(lammps["est_core_s"], yade["est_core_s"] / cost.LAMMPS_OVER_YADE, rtol=1e-12)


# --- analysis on constructed series -------------------------------------------

MU_C, B = 0.28, 6.0          # known mu(I) = MU_C + B I
THETA0 = 130.0               # steady theta_A, deg
A0 = 0.12                    # steady |A|


def A_components(norm, theta_deg):
    """a, b of A with |A| = norm and major direction theta (docs/model.md)."""
    t = np.radians(2 * np.asarray(theta_deg))
    r = np.asarray(norm) / np.sqrt(2)
    return r * np.cos(t), r * np.sin(t)


def transient(x):
    """A made-up Heaviside transient: mu dips and recovers, |A| collapses and recovers, theta 130 -> 50."""
    mu = 0.3 * (1 - 0.8 * np.exp(-x / 0.03))
    norm = A0 * (1 - 0.9 * np.exp(-x / 0.04))
    theta = 50 + 80 * np.exp(-x / 0.05)
    return mu, norm, theta


def write_case(d: Path, I, dmu=0.0, dA=0.0, dtheta=0.0, tmu=0.0, tA=0.0, ttheta=0.0, wall=10.0, pss=1e6,
               fine=0.002, preshear_strain=1.0, heaviside_strain=0.2):
    """A case folder: steady pre-shear at mu(I) + dmu, |A| = A0 + dA, theta = THETA0 + dtheta;
    the transient shifted by (tmu, tA, ttheta); sidecars with the given wall time and throughput."""
    d.mkdir(parents=True, exist_ok=True)
    s = np.arange(0, preshear_strain + 1e-12, 0.005)
    a, b = A_components(A0 + dA, THETA0 + dtheta)
    cols = dict(t=s / I, strain=s, mu=MU_C + B * I + dmu, A_xx=a, A_xy=b, inertial_number=I)
    pd.DataFrame({k: np.broadcast_to(v, s.shape) for k, v in cols.items()}).to_csv(d / "preshear.csv", index=False)
    x = np.arange(fine, heaviside_strain + 1e-12, fine)
    mu, norm, theta = transient(x)
    a, b = A_components(norm + tA, theta + ttheta)
    pd.DataFrame(dict(t=x, strain=preshear_strain - x, mu=mu + tmu, A_xx=a, A_xy=b,
                      inertial_number=I)).to_csv(d / "heaviside.csv", index=False)
    common = dict(N=500, particle_steps_per_s=pss, kappa_achieved=1000.0)
    sides = {
        "pack": dict(steps=1000, wall_time_s=wall / 2, strain_start=0.0, strain_end=0.0),
        "preshear": dict(steps=10000, wall_time_s=wall, strain_start=0.0, strain_end=preshear_strain),
        "heaviside": dict(steps=2000, wall_time_s=wall / 5, strain_start=preshear_strain,
                          strain_end=preshear_strain - heaviside_strain, reversal_strain=preshear_strain),
    }
    for stage, side in sides.items():
        side.update(cpu_time_s=side["wall_time_s"] * 0.9, sampler_cpu_s=side["wall_time_s"] * 0.09)
        (d / f"{stage}.json").write_text(json.dumps({**common, **side}))


ACC = dict(
    base=dict(kappa=1e3, inertial_number=3e-3, H_over_d=12, dt_over_tc=0.1, fine_interval=0.002, coarse_interval=0.005),
    dem_grid=dict(kappa=[1e3, 1e4, 1e5], inertial_number=[1e-3, 3e-3, 1e-2, 3e-2], fine_interval=[0.002, 0.01]),
    seeds=[1, 2, 3], subset="full", preshear_strain=1.0, heaviside_strain=0.2,
)
# offsets written into each point; the base seeds' mu offsets average to zero, so that
# the I axis with the seeds lies exactly on mu = MU_C + B I
KNOWN = {
    "kappa-100000_s1": dict(dmu=-0.03),                                   # finest kappa
    "kappa-10000_s1": dict(dmu=-0.02, dA=-0.004, dtheta=1.0, tmu=0.02),
    "I-0.001_s1": dict(),
    "I-0.01_s1": dict(),
    "I-0.03_s1": dict(),
    "fine-0.01_s1": dict(fine=0.01),
    "base_s1": dict(dmu=0.0, dA=0.006, dtheta=-3.0, tmu=-0.01, tA=0.02, ttheta=4.0),
    "base_s2": dict(dmu=0.01, dA=0.006, dtheta=-3.0, tmu=-0.01, tA=0.02, ttheta=4.0),
    "base_s3": dict(dmu=-0.01, dA=0.006, dtheta=-3.0, tmu=-0.01 + 0.004, tA=0.02, ttheta=4.0),
}


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    root = tmp_path_factory.mktemp("study")
    points = grid.expand(ACC)
    assert set(points["point"]) == set(KNOWN)
    for row in grid.unique_points(points).to_dict("records"):
        kw = dict(KNOWN[row["point"]])
        # the I axis: only the mu(I) line; wall time scales as 1/I
        write_case(root / "dem" / row["point"], row["inertial_number"], wall=0.03 / row["inertial_number"], **kw)
    points.to_csv(root / "points.csv", index=False)
    return root, points


def loaded(root, points):
    edges = analysis.strain_edges(0.2, 0.01)
    return {p: analysis.load_point(root / "dem" / p, p, 0.5, edges) for p in points["point"].unique()}


def test_analysis_returns_the_known_deviations_and_seed_spread(study):
    root, points = study
    table = analysis.cost_table(points, loaded(root, points)).set_index(["axis", "value"])
    k4, k3 = table.loc[("kappa", 1e4)], table.loc[("kappa", 1e3)]
    assert k4["d_mu"] == pytest.approx(0.01, abs=1e-12)
    assert k4["d_A_norm"] == pytest.approx(-0.004, abs=1e-12)
    assert k4["d_theta_A_deg"] == pytest.approx(1.0, abs=1e-9)
    assert k4["d_transient_mu"] == pytest.approx(0.02, abs=1e-12)
    assert k4["d_transient_A_norm"] == pytest.approx(0.0, abs=1e-12)
    # the base on the kappa axis, against the finest kappa
    assert k3["d_mu"] == pytest.approx(0.03, abs=1e-12)
    assert k3["d_theta_A_deg"] == pytest.approx(-3.0, abs=1e-9)
    # |A| and theta_A come from the bin-mean A, so a rotating A shifts them slightly
    assert k3["d_transient_A_norm"] == pytest.approx(0.02, abs=1e-4)
    assert k3["d_transient_theta_A_deg"] == pytest.approx(4.0, abs=0.05)
    assert table.loc[("kappa", 1e5), "d_mu"] == 0.0 and table.loc[("kappa", 1e5), "finest"]
    # seed spread: RMS of the pairwise differences (0.01, 0.01, 0.02 in mu; 0, 0.004, 0.004 in transient mu)
    assert k4["seed_spread_mu"] == pytest.approx(math.sqrt((0.01**2 + 0.01**2 + 0.02**2) / 3))
    assert k4["seed_spread_transient_mu"] == pytest.approx(math.sqrt(2 * 0.004**2 / 3))
    assert k4["seed_spread_A_norm"] == pytest.approx(0.0, abs=1e-12)
    # cost: pack + preshear + heaviside; particle-steps/s over the shear stages
    assert k4["wall_time_s"] == pytest.approx(10 * 1.7)
    assert k4["particle_steps_per_s"] == pytest.approx(1e6)
    assert k4["wall_time_per_strain_s"] == pytest.approx(12 / 1.2)
    assert k4["cpu_time_s"] == pytest.approx(0.9 * 17)
    assert k4["sampling_cost"] == pytest.approx(0.09 / 0.81)       # sampler CPU over the rest
    # tolerance (defaults: mu 0.02, transient_mu 0.03, theta 2, transient |A| 0.015)
    assert bool(k4["within_tolerance"]) is True
    assert bool(k3["within_tolerance"]) is False
    # sampling 0.01 against the base's 0.002 (which also carries the offset tmu = -0.01)
    assert 0.005 < table.loc[("fine_interval", 0.01), "d_transient_mu"] < 0.03
    cheapest = analysis.cheapest_within_tolerance(table.reset_index())
    assert cheapest["kappa"]["value"] == 1e4


def sampled_transient(interval, heaviside_strain=0.2):
    x = np.arange(interval, heaviside_strain + 1e-12, interval)
    mu, norm, theta = transient(x)
    a, b = A_components(norm, theta)
    return pd.DataFrame(dict(strain=1.0 - x, mu=mu, A_xx=a, A_xy=b))


def test_transients_land_on_a_common_grid_whatever_the_sampling():
    edges = analysis.strain_edges(0.2, 0.01)
    ref = analysis.transient_curves(sampled_transient(0.0005), 1.0, edges)
    half = analysis.curve_rms(analysis.transient_curves(sampled_transient(0.005), 1.0, edges), ref)
    coarse = analysis.curve_rms(analysis.transient_curves(sampled_transient(0.02), 1.0, edges), ref)
    assert half["transient_mu"] < 0.003 and half["transient_theta_A_deg"] < 1.0
    # sampling at 0.02 misses the fast start of the transient: the study must see it
    assert coarse["transient_mu"] > 3 * half["transient_mu"]
    assert coarse["transient_theta_A_deg"] > 3 * half["transient_theta_A_deg"]


def test_mu_of_I_fit_recovers_the_line_and_checks_the_campaign(study):
    root, points = study
    results = loaded(root, points)
    sub = points[points["axis"] == "inertial_number"]
    fit = analysis.fit_mu_of_I([results[p].steady["inertial_number"] for p in sub["point"]],
                               [results[p].steady["mu"] for p in sub["point"]])
    assert fit.mu_c == pytest.approx(MU_C) and fit.b == pytest.approx(B)
    check = analysis.quasi_static_check(fit, [1e-3, 1e-2], tolerance=0.05)
    assert list(check["rel_excess"]) == pytest.approx([B * 1e-3 / MU_C, B * 1e-2 / MU_C])
    assert list(check["within_quasi_static"]) == [True, False]


def test_command_line_writes_every_output(study, tmp_path):
    root, points = study
    out = tmp_path / "out"
    rc = main(["analyse", "--points", str(root / "points.csv"), "--dem-dir", str(root / "dem"), "--out", str(out),
               "--heaviside-strain", "0.2", "--campaign-I", "0.001", "--tolerance", "mu=0.05"])
    assert rc == 0
    for name in ["dem_cost.csv", "dem_cost.png", "dem_transients.png", "mu_of_I.csv", "mu_of_I.png", "dem_study.json"]:
        assert (out / name).stat().st_size > 0, name
    summary = json.loads((out / "dem_study.json").read_text())
    assert summary["tolerance"]["mu"] == 0.05
    assert summary["campaign_quasi_static"]["0.001"]["within"] is True
    rec = summary["recommended_setting"]
    assert set(rec) == set(grid.AXES) and rec["kappa"] == summary["cheapest_within_tolerance"]["kappa"]["value"]
    assert rec["H_over_d"] == ACC["base"]["H_over_d"]        # not studied here: the base
    mu = pd.read_csv(out / "mu_of_I.csv")
    assert mu["mu_c"].iloc[0] == pytest.approx(MU_C, abs=1e-5)   # written with 6 significant digits
    cost = pd.read_csv(out / "dem_cost.csv")
    assert len(cost) == len(points)


def test_missing_run_is_named(study, tmp_path, capsys):
    root, points = study
    rc = main(["analyse", "--points", str(root / "points.csv"), "--dem-dir", str(tmp_path), "--out", str(tmp_path / "o"),
               "--heaviside-strain", "0.2", "--campaign-I", "0.001"])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("dem_study analyse: error: ") and "Traceback" not in err and err.count("\n") == 1
    point = next(p for p in points["point"] if p in err)                          # names the run ...
    assert "missing" in err and str(tmp_path / point) in err                      # ... and the file it lacks


# --- repeats: a setting run with every seed -------------------------------------

def test_repeated_value_runs_with_every_seed_and_must_be_on_the_grid():
    table = grid.expand({**ACC, "repeat": {"kappa": [1e5]}})
    rep = table[table["axis"] == "repeat:kappa"]
    assert list(rep["point"]) == ["kappa-100000_s2", "kappa-100000_s3"] and np.allclose(rep["kappa"], 1e5)
    assert set(table[table["axis"] != "repeat:kappa"]["point"]) == set(KNOWN)      # the rest is unchanged
    with pytest.raises(ValueError, match=r"accuracy\.repeat\.kappa: 3000"):
        grid.expand({**ACC, "repeat": {"kappa": [3e3]}})
    with pytest.raises(ValueError, match=r"accuracy\.repeat\.kappa"):
        grid.expand({**ACC, "repeat": {"kappa": [1e3]}})                         # the base itself


def test_repeat_table_sets_the_mean_over_seeds_against_the_base_seeds(tmp_path):
    points = grid.expand({**ACC, "repeat": {"kappa": [1e5]}})
    offsets = {"kappa-100000_s1": 0.019, "kappa-100000_s2": 0.020, "kappa-100000_s3": 0.021}
    for p, dA in offsets.items():
        write_case(tmp_path / p, 3e-3, dA=dA)
    for p in ("base_s1", "base_s2", "base_s3"):
        write_case(tmp_path / p, 3e-3, **KNOWN[p])
    edges = analysis.strain_edges(0.2, 0.01)
    results = {p: analysis.load_point(tmp_path / p, p, 0.5, edges) for p in [*offsets, "base_s1", "base_s2", "base_s3"]}
    tab = analysis.repeat_table(points, results).set_index("quantity")
    row = tab.loc["A_norm"]
    assert row["n_seeds"] == 3 and row["n_base_seeds"] == 3
    assert row["mean"] == pytest.approx(A0 + 0.020, abs=1e-9) and row["base_mean"] == pytest.approx(A0 + 0.006, abs=1e-9)
    assert row["difference"] == pytest.approx(0.014, abs=1e-9)
    assert row["z"] == pytest.approx(0.014 / (0.001 / np.sqrt(3)), rel=1e-6)   # base seeds agree: se 0
    assert tab.loc["theta_A_deg", "difference"] == pytest.approx(3.0, abs=1e-6)   # base seeds sit at -3 deg
    # without repeats the table is empty, with its columns
    assert analysis.repeat_table(grid.expand(ACC), results).empty
