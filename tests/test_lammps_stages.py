"""The LAMMPS engine (lammps_scripts/) on the tiny soft cell of tests/test_dem_stages.py: pack ->
preshear -> heaviside write the data contract's files, the series pass its reader, the wall holds
p, the fabric turns after the reversal; what the engine does not run is refused by key.

The cell: H = 8d, W = 4H (211 disks), kappa = 1e3, I = 1e-2, engine: lammps. One module fixture
runs the three stages once (about 15 s of CPU).
"""
import json

import numpy as np
import pytest

from dem_contract import fabric_angle_deg, fabric_norm, read_series, read_sidecar, split_transients
from tests.helpers import LAMMPS_RUN, RUN, make_scene, read, yade

pytestmark = pytest.mark.lammps

STAGES = ("pack", "preshear", "heaviside")
COLUMNS = ["t", "strain", "gammadot", "U_top", "U_bottom", "gap", "A_xx", "A_xy", "n_contacts", "sigma_xy",
           "p", "mu", "sigma_xy_bulk", "p_bulk", "phi", "Z", "inertial_number"]
# every key of a YADE sidecar (docs/data-contract.md), yade_version's counterpart lammps_version
COMMON_KEYS = {"stage", "engine", "scene", "scene_sha256", "seed", "N", "N_wall", "dt", "dt_over_tc", "kn", "kt",
               "kappa", "inertial_number", "U", "gammadot_nominal", "time_unit_s", "steps", "samples", "engines",
               "lammps_version", "wall_time_s", "particle_steps_per_s", "cpu_time_s", "sampler_cpu_s",
               "sampling_cost", "resumed", "t_end", "strain_end", "gap_end", "sampling_steps", "columns",
               "overlap_end_d", "kappa_achieved"}
STAGE_KEYS = {"pack": {"phi", "gap", "converged_at_t", "phase_steps", "p_wall_end"},
              "preshear": {"strain_start", "t_start", "p_wall_mean", "inertial_number_achieved", "gap_mean"},
              "heaviside": {"strain_start", "t_start", "p_wall_mean", "inertial_number_achieved", "gap_mean",
                            "reversal_strain", "reversal_t"}}


def lammps_scene():
    sc = make_scene()
    sc["engine"] = "lammps"
    return sc


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    root = tmp_path_factory.mktemp("lammps")
    scene = root / "scene.json"
    scene.write_text(json.dumps(lammps_scene()))
    for stage in STAGES:
        r = yade(LAMMPS_RUN, scene, stage, root / "case")
        assert r.returncode == 0, f"{stage}: {r.stdout[-2000:]}\n{r.stderr[-2000:]}"
    return dict(dir=root / "case", scene=scene, root=root)


@pytest.mark.parametrize("stage", STAGES)
def test_every_stage_writes_the_contract(case, stage):
    d = case["dir"]
    for suffix in (".csv", ".json", ".final.lammps"):
        assert (d / f"{stage}{suffix}").is_file()
    assert not (d / ".partial" / stage).exists()  # work files gone once the stage completes
    assert (d / f"{stage}.csv").read_text().splitlines()[0].split(",")[: len(COLUMNS)] == COLUMNS
    r = read(d / f"{stage}.csv")
    assert len(r) > 10 and np.all(np.diff(r["t"]) > 0)
    side = json.loads((d / f"{stage}.json").read_text())
    assert COMMON_KEYS | STAGE_KEYS[stage] <= set(side), sorted(COMMON_KEYS | STAGE_KEYS[stage] - set(side))
    assert side["engine"] == "lammps" and side["samples"] == len(r)
    assert abs(side["kappa_achieved"] / 1e3 - 1) < 0.05
    if stage != "pack":
        assert abs(side["inertial_number_achieved"] / 1e-2 - 1) < 0.1
        for k in COLUMNS:
            assert np.all(np.isfinite(r[k])), k
    if stage == "heaviside":
        pre = json.loads((d / "preshear.json").read_text())
        assert side["reversal_strain"] == pytest.approx(pre["strain_end"])
        assert side["reversal_t"] == pytest.approx(pre["t_end"])
        assert abs(r["strain"][0] - pre["strain_end"]) < 0.003  # first row one fine interval in
        assert r["strain"][-1] < r["strain"][0]


def test_the_same_scene_gives_the_same_disks_as_yade(case):
    """Disk sizes and count by seed are the scene's (placement.py), whichever engine runs it."""
    side = json.loads((case["dir"] / "pack.json").read_text())
    assert side["N"] == 211 and side["N_wall"] == 32


def test_the_series_pass_the_contract_reader_and_split_into_one_transient(case):
    pre = read_series(case["dir"] / "preshear.csv")
    run = read_series(case["dir"] / "heaviside.csv")
    (tr,) = split_transients(pre, run, read_sidecar(case["dir"] / "heaviside.csv"))
    assert tr.sign == -1.0 and len(tr.data) == len(run)


def test_wall_pressure_holds_p(case):
    r = read(case["dir"] / "preshear.csv")
    assert abs(r["p"].mean() - 1) < 0.02
    assert abs(json.loads((case["dir"] / "preshear.json").read_text())["p_wall_mean"] - 1) < 0.02


def test_steady_preshear(case):
    r = read(case["dir"] / "preshear.csv")
    s = r["strain"] > 0.5
    mu = r["mu"][s].mean()
    normA, theta = fabric_norm(r["A_xx"][s].mean(), r["A_xy"][s].mean()), fabric_angle_deg(r["A_xx"][s].mean(),
                                                                                           r["A_xy"][s].mean())
    print(f"steady pre-shear (lammps): mu = {mu:.3f}, |A| = {normA:.3f}, theta_A = {theta:.1f} deg")
    assert 0.2 < mu < 0.35 and 0.03 < normA < 0.15 and 100 < theta < 150
    # the bulk band's Love-Weber stress agrees with the walls on average
    assert abs(r["sigma_xy_bulk"][s].mean() - r["sigma_xy"][s].mean()) < 0.05
    assert abs(r["p_bulk"][s].mean() - 1) < 0.1


def test_heaviside_fabric_turns(case):
    r = read(case["dir"] / "heaviside.csv")
    end = r["strain"] < r["strain"][-1] + 0.1
    theta = fabric_angle_deg(r["A_xx"][end].mean(), r["A_xy"][end].mean())
    print(f"after Heaviside (lammps): theta_A = {theta:.1f} deg")
    assert 30 < theta < 80
    assert np.all(r["gammadot"][1:] < 0) and r["sigma_xy"][end].mean() < 0


@pytest.mark.parametrize("change, stage, match", [
    (lambda sc: None, "sinusoidal", "stage 'sinusoidal'"),
    (lambda sc: sc["effects"].__setitem__("damping", 0.2), "pack", "effects.damping"),
    (lambda sc: sc["effects"].__setitem__("gravity", [0, -9.81]), "pack", "effects.gravity"),
])
def test_what_the_engine_cannot_run_is_refused_by_key(tmp_path, change, stage, match):
    sc = lammps_scene()
    change(sc)
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(sc))
    r = yade(LAMMPS_RUN, p, stage, tmp_path / "case")
    assert r.returncode == 2 and match in r.stderr, r.stderr
    assert not (tmp_path / "case" / f"{stage}.csv").exists()


def test_each_runner_refuses_the_other_engines_scene(tmp_path):
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(make_scene()))   # no engine key: yade's
    r = yade(LAMMPS_RUN, p, "pack", tmp_path / "a")
    assert r.returncode == 2 and "engine = 'yade'" in r.stderr and "yade_scripts/run_stage.py" in r.stderr
    p.write_text(json.dumps(lammps_scene()))
    r = yade(RUN, p, "pack", tmp_path / "b")
    assert r.returncode == 2 and "engine = 'lammps'" in r.stderr and "lammps_scripts/run_stage.py" in r.stderr


def test_the_workflow_runs_a_lammps_stage_as_one_job_with_its_restart_file_between_stages(tmp_path):
    """engine: lammps in the config: every DEM stage is one job of lammps_scripts/run_stage.py, its
    arguments quoted, and a stage's input is the previous one's LAMMPS restart file."""
    import yaml

    from tests.helpers import TINY, dry_run, workflow_copy

    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump({**TINY, "engine": "lammps"}))
    target = "results/dem/p100000_I0.01_s1/heaviside.csv"
    r = dry_run(target, "--configfile", path, "-p", cwd=workflow_copy(tmp_path / "workflow"), quiet=False)
    assert r.returncode == 0, r.stderr[-3000:]
    cmds = [ln for ln in r.stdout.splitlines() if "run_stage.py" in ln]
    assert len(cmds) == 3 and all("python3 lammps_scripts/run_stage.py" in c for c in cmds), cmds
    assert "preshear.final.lammps" in r.stdout and "yade" not in " ".join(cmds)


@pytest.mark.parametrize("change, expected", [
    (dict(protocols={"heaviside": {"strain": 0.05}, "sinusoidal": {"strain": 0.05, "transition_strain": 0.01}}),
     "config error: protocols.sinusoidal = {...}: the lammps engine does not run this protocol yet"),
    (dict(cell={"H_over_d": 10, "W_over_H": 1, "kind": "periodic"}), "cell.kind = 'periodic' (supported: walls"),
    (dict(effects={"damping": 0.1}), "effects.damping = 0.1 (supported: 0"),
])
def test_the_preflight_refuses_what_the_lammps_engine_cannot_run_naming_the_key(change, expected):
    import copy

    from preflight.checks import check
    from tests.helpers import TINY

    config = {**copy.deepcopy(TINY), "engine": "lammps", **change}
    if "kind" in config["cell"]:
        config["sampling"] = {k: v for k, v in config["sampling"].items() if k != "bulk_exclusion_d"}
    problems = check(config)
    assert any(expected in p for p in problems), problems
    assert check({**copy.deepcopy(TINY), "engine": "lammps"}) == []
