"""The four stages on a tiny soft cell with real YADE: outputs, physics, guards,
reproducibility and kill-and-resume.

The cell: H = 8d, W = 4H (about 210 disks), kappa = 1e3, I = 1e-2. One module
fixture runs pack -> preshear -> heaviside, sinusoidal once (about a minute).
"""
import json
import math
import shutil

import numpy as np
import pandas as pd
import pytest
import yaml

from dem_contract import fabric_angle_deg, fabric_norm, read_series, split_transients
from dem_contract.importer import MINIMAL_COLUMNS, import_cases
from tests.helpers import (RUN, YS, assert_pack_restored_the_grains_own_friction_and_damping,
                           assert_resumed_without_gap_or_duplicate, kill_preshear_after_first_checkpoint,
                           make_scene, read, run_all_stages, yade)

COLUMNS = ["t", "strain", "gammadot", "U_top", "U_bottom", "gap", "A_xx", "A_xy", "n_contacts", "sigma_xy",
           "p", "mu", "sigma_xy_bulk", "p_bulk", "phi", "Z", "inertial_number"]


def fabric(a, b):
    return fabric_norm(a, b), fabric_angle_deg(a, b)


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    return run_all_stages(tmp_path_factory.mktemp("dem"), make_scene())


@pytest.mark.parametrize("stage", ["pack", "preshear", "heaviside", "sinusoidal"])
def test_every_stage_writes_the_contract(case, stage):
    d = case["dir"]
    for suffix in (".csv", ".json", ".final.yade.gz"):
        assert (d / f"{stage}{suffix}").is_file()
    assert not (d / ".partial").exists()  # work files gone once the stage completes
    header = (d / f"{stage}.csv").read_text().splitlines()[0].split(",")
    assert header[: len(COLUMNS)] == COLUMNS
    r = read(d / f"{stage}.csv")
    assert len(r) > 10
    assert np.all(np.diff(r["t"]) > 0)
    side = json.loads((d / f"{stage}.json").read_text())
    for k in ("scene", "seed", "N", "dt", "kappa_achieved", "yade_version", "wall_time_s", "particle_steps_per_s",
              "samples", "engines"):
        assert k in side, k
    assert side["samples"] == len(r)
    assert abs(side["kappa_achieved"] / 1e3 - 1) < 0.05
    if stage != "pack":
        if stage != "sinusoidal":  # slower through the transition
            assert abs(side["inertial_number_achieved"] / 1e-2 - 1) < 0.1
        for k in COLUMNS:
            assert np.all(np.isfinite(r[k])), k
    if stage in ("heaviside", "sinusoidal"):
        pre = json.loads((d / "preshear.json").read_text())
        assert side["reversal_strain"] == pytest.approx(pre["strain_end"])
        assert side["reversal_t"] == pytest.approx(pre["t_end"])
        assert abs(r["strain"][0] - pre["strain_end"]) < 0.003  # first row one fine interval in
        assert r["strain"][-1] < r["strain"][0]  # strain falls after the reversal


@pytest.mark.parametrize("stage", ["preshear", "heaviside", "sinusoidal"])
def test_real_runs_pass_the_contract_reader(case, stage):
    """Real YADE output passes every check of dem_contract.read_series: whole rows, physical bounds,
    strain = integral of gammadot (the sinusoidal run takes its rate through zero) within a tenth
    of the allowance; a 0.3 strain jump written into the same run is named."""
    from dem_contract import DEMInputError, read_series
    from dem_contract.series import STRAIN_REL_TOL
    path = case["dir"] / f"{stage}.csv"
    data = read_series(path)
    t, s, g = (data[c].to_numpy() for c in ("t", "strain", "gammadot"))
    ds, dt = np.diff(s), np.diff(t)
    trap = 0.5 * (g[1:] + g[:-1]) * dt
    allowance = STRAIN_REL_TOL * (np.maximum(np.abs(ds), np.abs(trap)) + np.median(np.abs(g)) * dt)
    assert np.max(np.abs(ds - trap) / allowance) < 0.1
    jumped = data.copy()
    jumped.loc[len(jumped) // 2:, "strain"] += 0.3
    jumped.to_csv(case["root"] / f"jumped_{stage}.csv", index=False)
    with pytest.raises(DEMInputError, match=f"jumped_{stage}.csv: strain jumps by"):
        read_series(case["root"] / f"jumped_{stage}.csv")


def test_sampling_is_fine_after_reversal_and_coarse_later(case):
    r = read(case["dir"] / "heaviside.csv")
    s0 = r["strain"][0]
    ds = np.abs(np.diff(r["strain"]))
    travelled = np.abs(r["strain"][1:] - s0)
    assert ds[travelled < 0.09].max() < 0.0025  # fine_interval 0.002 at the nominal rate
    assert ds[travelled > 0.15].min() > 0.008  # coarse_interval 0.01


def test_wall_pressure_holds_p(case):
    r = read(case["dir"] / "preshear.csv")
    assert abs(r["p"].mean() - 1) < 0.02
    side = json.loads((case["dir"] / "preshear.json").read_text())
    assert abs(side["p_wall_mean"] - 1) < 0.02


def test_steady_preshear(case):
    r = read(case["dir"] / "preshear.csv")
    s = r["strain"] > 0.5
    mu = r["mu"][s].mean()
    normA, theta = fabric(r["A_xx"][s].mean(), r["A_xy"][s].mean())
    print(f"steady pre-shear: mu = {mu:.3f}, |A| = {normA:.3f}, theta_A = {theta:.1f} deg")
    assert 0.2 < mu < 0.35
    assert 0.03 < normA < 0.15
    assert 100 < theta < 150
    assert np.all(r["gammadot"][1:] > 0) and abs(r["inertial_number"][s].mean() / 1e-2 - 1) < 0.1
    # bulk stress (Love-Weber over the band) agrees with the walls on average
    assert abs(r["sigma_xy_bulk"][s].mean() - r["sigma_xy"][s].mean()) < 0.05
    assert abs(r["p_bulk"][s].mean() - 1) < 0.1


def test_heaviside_fabric_turns(case):
    r = read(case["dir"] / "heaviside.csv")
    end = r["strain"] < r["strain"][-1] + 0.1
    normA, theta = fabric(r["A_xx"][end].mean(), r["A_xy"][end].mean())
    print(f"after Heaviside: |A| = {normA:.3f}, theta_A = {theta:.1f} deg")
    assert 30 < theta < 80
    assert np.all(r["gammadot"][1:] < 0)
    assert r["sigma_xy"][end].mean() < 0


def test_sinusoidal_wall_speed_follows_half_cosine(case):
    r = read(case["dir"] / "sinusoidal.csv")
    sc = make_scene()
    U = sc["loading"]["inertial_number"] * sc["geometry"]["H_over_d"] / 2  # in sqrt(p/rho)
    T = sc["sinusoidal"]["transition_strain"] / sc["loading"]["inertial_number"]  # in d sqrt(rho/p)
    tau = r["t"] - json.loads((case["dir"] / "sinusoidal.json").read_text())["reversal_t"]
    expect = np.where(tau < T, U * np.cos(np.pi * np.clip(tau / T, 0, 1)), -U)
    assert np.allclose(r["U_top"], expect, atol=U * 0.02)
    assert np.allclose(r["U_bottom"], -r["U_top"])


def test_pack_restores_the_grains_friction_and_damping(case, tmp_path):
    assert_pack_restored_the_grains_own_friction_and_damping(case, tmp_path)


def test_pack_converges_through_its_phases(case):
    side = json.loads((case["dir"] / "pack.json").read_text())
    ps = side["phase_steps"]
    assert set(ps) == {"compress", "ramp", "settle"} and all(v > 0 for v in ps.values())
    assert sum(ps.values()) == side["steps"]
    assert side["converged_at_t"] is not None and abs(side["p_wall_end"] - 1) < 0.02
    r = read(case["dir"] / "pack.csv")
    assert r["ke"][-1] < side["scene"]["pack"]["ke_max"]


def _packing_cost_module():
    from dem_study import packing_cost

    return packing_cost


def test_packing_cost_is_the_pack_share_of_the_case_sidecars(case, tmp_path):
    pc = _packing_cost_module()
    stages = ["pack", "preshear", "heaviside", "sinusoidal"]
    side = {s: json.loads((case["dir"] / f"{s}.json").read_text()) for s in stages}
    # a second case: the same sidecars with a pack twice as long
    other = tmp_path / "other"
    other.mkdir()
    for s in stages:
        d = dict(side[s])
        if s == "pack":
            d.update(cpu_time_s=2 * d["cpu_time_s"], steps=2 * d["steps"])
        (other / f"{s}.json").write_text(json.dumps(d))
    row = pc.packing_cost("tiny", [case["dir"], other], stages).iloc[0]
    cpu = sum(side[s]["cpu_time_s"] for s in stages)
    f1 = side["pack"]["cpu_time_s"] / cpu
    f2 = 2 * side["pack"]["cpu_time_s"] / (cpu + side["pack"]["cpu_time_s"])
    assert row["n_cases"] == 2 and row["campaign"] == "tiny"
    assert row["pack_cpu_fraction_mean"] == pytest.approx((f1 + f2) / 2)
    assert row["pack_cpu_fraction_max"] == pytest.approx(f2)
    assert row["pack_steps_max"] == 2 * side["pack"]["steps"]
    assert row["case_cpu_s_mean"] == pytest.approx(cpu + side["pack"]["cpu_time_s"] / 2)
    (other / "heaviside.json").write_text(json.dumps({"steps": 1}))
    with pytest.raises(pc.DEMInputError, match="heaviside.json.*cpu_time_s"):
        pc.packing_cost("tiny", [case["dir"], other], stages)


def test_packing_cost_orders_the_stages_of_a_campaign_with_a_reversal_schedule():
    pc = _packing_cost_module()
    paths = [f"r/dem/c{k}/{s}.json" for k in (1, 2) for s in ("sinusoidal", "alternate", "preshear", "pack")]
    assert pc.stage_order(paths) == ["pack", "preshear", "sinusoidal", "alternate"]


def test_same_seed_same_packing(tmp_path):
    sc = make_scene()
    sc["geometry"].update(H_over_d=5, W_over_H=2)
    sc["sampling"]["bulk_exclusion_d"] = 1
    outs = []
    for seed, name in ((7, "a"), (7, "b"), (8, "c")):
        sc["seed"] = seed
        p = tmp_path / f"{name}.json"
        p.write_text(json.dumps(sc))
        r = yade(RUN, p, "pack", tmp_path / name)
        assert r.returncode == 0, r.stderr[-2000:]
        outs.append((tmp_path / name / "pack.csv").read_text())
    assert outs[0] == outs[1]
    assert outs[0] != outs[2]


def _case_from_pack(case, tmp_path, **changes):
    cdir = tmp_path / "case"
    cdir.mkdir(parents=True)
    for f in ("pack.final.yade.gz", "pack.json"):
        shutil.copy(case["dir"] / f, cdir / f)
    sc = make_scene()
    for sec, kv in changes.items():
        sc[sec].update(kv)
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(sc))
    return p, cdir


@pytest.mark.parametrize("guard, match", [
    (dict(guards=dict(max_overlap_d=1e-4)), "overlap"),
    # the bare tolerance, without the cell's fluctuation scale (pressure_noise_z 0)
    (dict(guards=dict(pressure_tolerance=1e-3, pressure_window_strain=0.02, pressure_noise_z=0)), "wall pressure"),
])
def test_guards_stop_the_run(case, tmp_path, guard, match):
    scene, cdir = _case_from_pack(case, tmp_path, **guard)
    r = yade(RUN, scene, "preshear", cdir)
    assert r.returncode == 3, r.stdout[-1000:] + r.stderr[-1000:]
    assert match in r.stderr
    assert not (cdir / "preshear.csv").exists()  # no half outputs


def test_pressure_guard_lets_the_cells_own_fluctuation_pass(case, tmp_path):
    """A tolerance far below the tiny cell's fluctuation (which stops the run above, with z = 0)
    is raised to 2.5 sqrt(d/W) by default: a physical run is not refused for its size."""
    scene, cdir = _case_from_pack(case, tmp_path, guards=dict(pressure_tolerance=1e-3, pressure_window_strain=0.02))
    r = yade(RUN, scene, "preshear", cdir)
    assert r.returncode == 0, r.stdout[-1000:] + r.stderr[-1000:]


def test_stiffness_run_summary_of_a_real_case_reads_steady_x_early_transient_and_overlap(case, tmp_path):
    from dem_contract import read_series, steady_values
    from dem_study import stiffness

    sc = json.loads(case["scene"].read_text())
    cdir = tmp_path / "case"
    shutil.copytree(case["dir"], cdir)
    shutil.copy(case["scene"], cdir / "scene.json")
    r = yade(YS / "contact_census.py", cdir / "scene.json", cdir / "preshear.final.yade.gz",
             "--out", cdir / stiffness.CENSUS)
    assert r.returncode == 0, r.stderr[-2000:]
    row = stiffness.run_summary(cdir, steady_window=0.6, early_strain=0.1)
    pre = read_series(cdir / "preshear.csv")
    st = steady_values(pre, last_strain=0.6)
    assert row["kappa"] == sc["material"]["kappa"] and row["seed"] == sc["seed"]
    assert row["X"] == pytest.approx(math.sqrt(2) * st["A_xy"])     # sheared along +x
    assert row["X"] < 0 and row["A_norm"] == pytest.approx(st["A_norm"])
    assert 0 <= row["A_min_early"] < row["A_norm"]                # the fabric collapses after the reversal
    assert 0 < row["strain_at_A_min"] < 0.1
    census = json.loads((cdir / stiffness.CENSUS).read_text())
    assert row["overlap_mean_d"] == json.loads((cdir / "preshear.json").read_text())["overlap_end_d"]["mean"]
    assert row["overlap_mean_d"] == pytest.approx(census["overlap_d"]["mean"], rel=0.05)
    assert row["X_contract"] == census["fabric"]["contract"]["X"]
    assert row["core_hours"] > row["core_hours_preshear"] > 0


def test_killed_stage_resumes_without_gap_or_duplicate_to_the_same_bit(case, tmp_path):
    """SIGKILL after the first checkpoint, then a rerun: the series is the uninterrupted run's,
    byte for byte (every run reloads its state where checkpoints are taken: checkpoint.py)."""
    ref_scene, ref_dir = _case_from_pack(case, tmp_path / "ref", preshear=dict(strain=2.5))
    r = yade(RUN, ref_scene, "preshear", ref_dir)
    assert r.returncode == 0, r.stderr[-2000:]
    scene, cdir = _case_from_pack(case, tmp_path, preshear=dict(strain=2.5), run=dict(checkpoint_every_s=1))
    pid = kill_preshear_after_first_checkpoint(scene, cdir)
    assert not (cdir / "preshear.csv").exists()
    r = yade(RUN, scene, "preshear", cdir)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "resumed from" in r.stdout
    assert f"stale lock of PID {pid} on host" in r.stdout  # SIGKILL left the lock file behind
    s, side = assert_resumed_without_gap_or_duplicate(cdir)
    strain = s["strain"]
    assert strain[-1] == pytest.approx(2.5, rel=0.05)
    assert (cdir / "preshear.csv").read_bytes() == (ref_dir / "preshear.csv").read_bytes()


def census_of(case, tmp_path, stage="preshear"):
    out = tmp_path / "census.json"
    r = yade(YS / "contact_census.py", case["scene"], case["dir"] / f"{stage}.final.yade.gz", "--out", out)
    assert r.returncode == 0, r.stderr[-2000:]
    return json.loads(out.read_text())


def test_contact_census_reads_the_series_fabric_as_its_contract_reading(case, tmp_path):
    c = census_of(case, tmp_path)
    contract, series = c["fabric"]["contract"], c["fabric"]["series"]
    assert contract["A_xx"] == pytest.approx(series["A_xx"], abs=1e-12)
    assert contract["A_xy"] == pytest.approx(series["A_xy"], abs=1e-12)
    # steady shear along +x: the contacts gather along the compressive diagonal, A_xy < 0, X < 0
    assert c["shear_sign"] == 1.0 and contract["X"] < 0
    f = c["fabric"]
    # the readings are nested sets: force-carrying within the band, rattlers out of those, the cell holds all
    assert f["no_rattlers"]["n"] <= f["force"]["n"] <= f["contract"]["n"] < f["whole_cell"]["n"]
    assert 0 < c["rattlers"] < c["N"] / 2


def test_contact_census_overlap_is_the_force_over_the_stiffness_in_units_of_d(case, tmp_path):
    # linear contacts kn = kappa p d: a contact carrying the typical force p d overlaps by d / kappa
    c = census_of(case, tmp_path)
    ov, kappa = c["overlap_d"], c["kappa"]
    assert ov["n"] > 100
    assert 0.2 < ov["mean"] * kappa < 5
    assert ov["median"] <= ov["p90"] <= ov["max"] < 0.05   # below the overlap guard


@pytest.mark.parametrize("stage", ["pack", "preshear", "heaviside"])
def test_every_sidecar_records_the_mean_overlap_the_census_reads_from_the_saved_state(case, tmp_path, stage):
    """The sidecar's overlap_end_d (ScGeom.penetrationDepth at the stage's last step) is the census's
    (positions of the saved state): the same contacts, one integration step apart."""
    side = json.loads((case["dir"] / f"{stage}.json").read_text())["overlap_end_d"]
    ov = census_of(case, tmp_path, stage)["overlap_d"]
    assert abs(side["n"] - ov["n"]) <= 0.02 * ov["n"]
    assert side["mean"] == pytest.approx(ov["mean"], rel=0.05)
    assert side["median"] <= side["p90"] <= side["max"] < 0.05


def test_stiffness_study_from_a_release_equals_the_study_from_the_cases(case, tmp_path):
    """The release carries the census beside the sidecars, so `dem_study stiffness --releases` (no YADE)
    gives the per-run table the case folders give, readings and overlap included."""
    import subprocess
    import sys

    from dem_study import stiffness

    label = "p100000_I0.01_s1"
    cdir = tmp_path / "results" / "dem" / label
    shutil.copytree(case["dir"], cdir)
    shutil.copy(case["scene"], cdir / "scene.json")
    r = yade(YS / "contact_census.py", cdir / "scene.json", cdir / "preshear.final.yade.gz",
             "--out", cdir / stiffness.CENSUS)
    assert r.returncode == 0, r.stderr[-2000:]
    (tmp_path / "config.yaml").write_text(yaml.safe_dump({"campaign": "tiny"}))
    out = {}
    for how, args in (("cases", ["--cases", str(cdir)]), ("releases", ["--releases", str(tmp_path / "data" / "tiny")])):
        if how == "releases":
            made = subprocess.run([sys.executable, "-m", "dem_contract", "release", "--cases", str(cdir), "--config",
                                   str(tmp_path / "config.yaml"), "--out", str(tmp_path / "data" / "tiny")],
                                  capture_output=True, text=True)
            assert made.returncode == 0, made.stderr
            assert (tmp_path / "data" / "tiny" / "cases" / label / "sidecars" / stiffness.CENSUS).is_file()
        run = subprocess.run([sys.executable, "-m", "dem_study", "stiffness", *args, "--out", str(tmp_path / how)],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        out[how] = pd.read_csv(tmp_path / how / "stiffness_runs.csv")
    assert "X_no_rattlers" in out["releases"] and "overlap_mean_d" in out["releases"]
    pd.testing.assert_frame_equal(out["releases"], out["cases"])


@pytest.mark.slow
def test_a_small_stiff_cell_is_not_refused_for_its_own_pressure_fluctuation(tmp_path):
    """Kappa 1e5 (the campaign's stiffness) on the tiny cell: its wall pressure's 0.05-strain window means
    depart from p by more than a bare tolerance of 1e-3 (the guard with pressure_noise_z = 0 stops the
    run), while the default scale 2.5 sqrt(d/W) lets the same physical run finish."""
    sc = make_scene()
    sc["material"]["kappa"] = 1e5
    sc["timestep"]["dt_over_tc"] = 0.3
    sc["preshear"]["strain"] = 0.3
    sc["guards"].update(pressure_tolerance=1e-3, pressure_window_strain=0.05)
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(sc))
    r = yade(RUN, scene, "pack", tmp_path / "case")
    assert r.returncode == 0, r.stderr[-2000:]
    shutil.copytree(tmp_path / "case", tmp_path / "bare")
    r = yade(RUN, scene, "preshear", tmp_path / "case")
    assert r.returncode == 0, r.stdout[-1000:] + r.stderr[-1000:]
    assert json.loads((tmp_path / "case" / "preshear.json").read_text())["strain_end"] >= 0.3
    sc["guards"]["pressure_noise_z"] = 0
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps(sc))
    r = yade(RUN, bare, "preshear", tmp_path / "bare")
    assert r.returncode == 3 and "wall pressure" in r.stderr, r.stdout[-1000:] + r.stderr[-1000:]


@pytest.mark.yade
def test_a_real_branched_run_imports_as_it_is_to_the_dems_own_values(case, tmp_path):
    """The Heaviside and sinusoidal stages branch from the pre-shear's saved state (preshear.final.yade.gz),
    as most YADE scripts run their reversals. Given to ``dem_contract import`` as a user brings them, in the
    minimal columns, the pre-shear as its own file and each reversal as a branch whose first row is the state
    at the reversal (the pre-shear's last row: YADE writes no row at the start of a stage), the import reads
    back through the contract's reader with the DEM's reversal and the DEM's own values."""
    d, scene = case["dir"], json.loads(case["scene"].read_text())
    pre = pd.read_csv(d / "preshear.csv")
    pre[list(MINIMAL_COLUMNS)].to_csv(tmp_path / "pre.csv", index=False)
    runs = []
    for protocol in ("heaviside", "sinusoidal"):
        side = json.loads((d / f"{protocol}.json").read_text())
        assert side["reversal_t"] == pre["t"].iloc[-1]          # the branch starts where the pre-shear's rows end
        branch = pd.concat([pre.iloc[-1:], pd.read_csv(d / f"{protocol}.csv")], ignore_index=True)
        branch[list(MINIMAL_COLUMNS)].to_csv(tmp_path / f"{protocol}_branch.csv", index=False)
        rev = {"strain": side["reversal_strain"]}
        if protocol == "sinusoidal":
            rev.update(transition="half_cosine", transition_strain=scene["sinusoidal"]["transition_strain"])
        runs.append({"file": f"{protocol}_branch.csv", "protocol": protocol, "reversals": [rev]})
    meta = {"pressure": scene["material"]["pressure"], "inertial_number": scene["loading"]["inertial_number"],
            "simulator": "YADE", "cell": {"H_over_d": scene["geometry"]["H_over_d"]},
            "cases": [{"seed": scene["seed"], "preshear": "pre.csv", "runs": runs}]}
    (tmp_path / "case.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    (out,) = import_cases(tmp_path / "case.yaml", tmp_path / "dem")
    got_pre = read_series(out / "preshear.csv", finite=[*MINIMAL_COLUMNS, "mu"])
    assert got_pre[list(MINIMAL_COLUMNS)].equals(pre[list(MINIMAL_COLUMNS)])
    for protocol in ("heaviside", "sinusoidal"):
        dem, dem_side = read_series(d / f"{protocol}.csv"), json.loads((d / f"{protocol}.json").read_text())
        got, got_side = read_series(out / f"{protocol}.csv", finite=[*MINIMAL_COLUMNS, "mu"]), json.loads((out / f"{protocol}.json").read_text())
        assert got[list(MINIMAL_COLUMNS)].equals(dem[list(MINIMAL_COLUMNS)])
        assert np.allclose(got["mu"], dem["mu"], rtol=1e-12, atol=0)
        (mine,) = split_transients(got_pre, got, got_side, what=protocol)
        (own,) = split_transients(read_series(d / "preshear.csv"), dem, dem_side, what=protocol)
        assert (mine.t0, mine.strain0) == (own.t0, own.strain0) == (dem_side["reversal_t"], dem_side["reversal_strain"])
        assert mine.data[list(MINIMAL_COLUMNS)].equals(own.data[list(MINIMAL_COLUMNS)])
        assert mine.initial == pytest.approx(own.initial, rel=1e-12, abs=1e-15)
