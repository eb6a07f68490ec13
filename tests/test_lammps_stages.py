"""The LAMMPS engine (lammps_scripts/) on the tiny soft cell of tests/test_dem_stages.py: pack ->
preshear -> heaviside, sinusoidal and a reversal schedule write the data contract's files, the
series pass its reader, the wall holds p, the fabric turns after the reversal, the walls follow
the protocol YADE's stages follow (yade_scripts/protocol.py); what the engine does not run is
refused by key.

The cell: H = 8d, W = 4H (211 disks), kappa = 1e3, I = 1e-2, engine: lammps. One module fixture
runs the five stages once (about 30 s of CPU).
"""
import json
import shutil
import signal
import subprocess

import numpy as np
import pytest

from dem_contract import fabric_angle_deg, fabric_norm, read_series, read_sidecar, split_transients
from tests.helpers import (LAMMPS_RUN, RUN, assert_schedule_reversals, command, kill_preshear_after_first_checkpoint,
                           make_scene, read, yade, yade_module)

pytestmark = pytest.mark.lammps

protocol = yade_module("protocol")  # pure Python: the walls' speed both engines' stages set

STAGES = ("pack", "preshear", "heaviside", "sinusoidal", "double")
# a sharp reversal against the pre-shear, then a half cosine back along it
DOUBLE = [{"strain": 0.1, "direction": -1},
          {"strain": 0.15, "direction": 1, "transition": "half_cosine", "transition_strain": 0.05}]
COLUMNS = ["t", "strain", "gammadot", "U_top", "U_bottom", "gap", "A_xx", "A_xy", "n_contacts", "sigma_xy",
           "p", "mu", "sigma_xy_bulk", "p_bulk", "phi", "Z", "inertial_number"]
# every key of a YADE sidecar (docs/data-contract.md), yade_version's counterpart lammps_version
COMMON_KEYS = {"stage", "engine", "scene", "scene_sha256", "seed", "N", "N_wall", "dt", "dt_over_tc", "kn", "kt",
               "kappa", "inertial_number", "U", "gammadot_nominal", "time_unit_s", "steps", "samples", "engines",
               "lammps_version", "wall_time_s", "particle_steps_per_s", "cpu_time_s", "sampler_cpu_s",
               "sampling_cost", "resumed", "t_end", "strain_end", "gap_end", "sampling_steps", "columns",
               "overlap_end_d", "kappa_achieved"}
SHEAR_KEYS = {"strain_start", "t_start", "p_wall_mean", "inertial_number_achieved", "gap_mean"}
STAGE_KEYS = {"pack": {"phi", "gap", "converged_at_t", "phase_steps", "p_wall_end"},
              "preshear": SHEAR_KEYS,
              "heaviside": SHEAR_KEYS | {"reversal_strain", "reversal_t"},
              "sinusoidal": SHEAR_KEYS | {"reversal_strain", "reversal_t", "transition_steps"},
              "double": SHEAR_KEYS | {"reversal_strain", "reversal_t", "reversals", "segments"}}


def lammps_scene():
    sc = make_scene()
    sc["engine"] = "lammps"
    sc["schedules"] = {"double": {"schedule": DOUBLE}}
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
        if stage in ("preshear", "heaviside"):  # (a half cosine takes the rate through zero)
            assert abs(side["inertial_number_achieved"] / 1e-2 - 1) < 0.1
        for k in COLUMNS:
            assert np.all(np.isfinite(r[k])), k
    if stage in ("heaviside", "sinusoidal", "double"):
        pre = json.loads((d / "preshear.json").read_text())
        assert side["reversal_strain"] == pytest.approx(pre["strain_end"])
        assert side["reversal_t"] == pytest.approx(pre["t_end"])
        assert abs(r["strain"][0] - pre["strain_end"]) < 0.003  # first row one fine interval in
    if stage in ("heaviside", "sinusoidal"):
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
    # turned into the reversed quadrant (the pre-shear's theta_A is about 136 deg, the reversed steady
    # state's about 44): the last 0.1 strain's mean of this 211-disk cell spreads by several degrees
    # between realizations (29.6 and 35.6 deg, with and without the checkpoint grid's setups)
    assert 15 < theta < 75
    assert np.all(r["gammadot"][1:] < 0) and r["sigma_xy"][end].mean() < 0


def steps_since_reversal(side, t, t_rev):
    """Rows' steps since a reversal at t_rev, from their times (series' unit)."""
    return np.rint((t - t_rev) * side["time_unit_s"] / side["dt"]).astype(int)


def test_sinusoidal_walls_move_at_the_protocols_half_cosine_at_every_sampled_step(case):
    """The wall speed in every row is yade_scripts/protocol.half_cosine_speed at the row's step since
    the reversal, to the rounding: the same function YADE's per-step runner calls."""
    side = json.loads((case["dir"] / "sinusoidal.json").read_text())
    r = read(case["dir"] / "sinusoidal.csv")
    sc = json.loads(case["scene"].read_text())
    V0 = (sc["material"]["pressure"] / sc["material"]["density"]) ** 0.5
    n = side["transition_steps"]
    assert n == int(np.ceil(sc["sinusoidal"]["transition_strain"] / (side["gammadot_nominal"] * side["dt"])))
    k = steps_since_reversal(side, r["t"], side["reversal_t"])
    expect = np.array([protocol.half_cosine_speed(side["U"], int(j), n, 1, -1) for j in k]) / V0
    assert np.allclose(r["U_top"], expect, rtol=1e-12, atol=1e-15) and np.array_equal(r["U_bottom"], -r["U_top"])
    assert k[0] < n < k[-1] and r["U_top"][0] > 0 > r["U_top"][-1]   # the rows span the turn


def test_a_schedule_with_two_reversals_writes_one_series_whose_reversals_the_readers_find(case):
    side, run = assert_schedule_reversals(case["dir"], "double", DOUBLE)
    assert side["segments"] == [dict(seg, transition=seg.get("transition", "heaviside")) for seg in DOUBLE]
    # the second reversal's half cosine, step by step, from -U back to +U
    rev = side["reversals"][1]
    k = steps_since_reversal(side, run["t"].to_numpy(), rev["t"])
    n = int(np.ceil(rev["transition_strain"] / (side["gammadot_nominal"] * side["dt"])))
    after = k >= 0
    V0 = (side["scene"]["material"]["pressure"] / side["scene"]["material"]["density"]) ** 0.5
    expect = np.array([protocol.half_cosine_speed(side["U"], int(j), n, -1, 1) for j in k[after]]) / V0
    assert np.allclose(run["U_top"].to_numpy()[after], expect, rtol=1e-12, atol=1e-15)


def test_a_schedule_samples_finely_again_after_each_reversal(case):
    side = json.loads((case["dir"] / "double.json").read_text())
    run = read(case["dir"] / "double.csv")
    dt_fine = side["sampling_steps"]["fine"] * side["dt"] / side["time_unit_s"]
    for rev in side["reversals"]:
        assert np.any(np.abs(run["t"] - rev["t"]) < 1e-9) or rev is side["reversals"][0]  # the row before it
        after = run["t"][run["t"] > rev["t"]][:20]
        assert np.allclose(np.diff(after), dt_fine, rtol=1e-6)


# a step against the pre-shear, then a half cosine back over 1.5 strain: about 54,000 steps run one at
# a time, across several of the checkpoints' grid points (lammps_scripts/checkpoint.py)
LONG = [{"strain": 0.3, "direction": -1},
        {"strain": 3.0, "direction": 1, "transition": "half_cosine", "transition_strain": 1.5}]


def long_case(case, root, **run):
    """A case under ``root`` with the module's pack and pre-shear and a scene scheduling LONG."""
    cdir = root / "case"
    cdir.mkdir(parents=True)
    for f in ("pack.final.lammps", "pack.json", "preshear.final.lammps", "preshear.json", "preshear.csv"):
        shutil.copy(case["dir"] / f, cdir / f)
    sc = lammps_scene()
    sc["schedules"] = {"long": {"schedule": LONG}}
    sc["run"].update(run)
    scene = root / "scene.json"
    scene.write_text(json.dumps(sc))
    return scene, cdir


@pytest.mark.slow
def test_a_stage_killed_then_stopped_by_sigterm_resumes_to_the_byte_of_the_uninterrupted_run(case, tmp_path):
    """SIGKILL just after a checkpoint past the second reversal (inside its half cosine on a fast
    machine), then SIGTERM as soon as the rerun has resumed (exit 4, the same checkpoint kept), then a
    last rerun: the series is the uninterrupted run's, byte for byte, its sidecar's reversals too."""
    ref_scene, ref_dir = long_case(case, tmp_path / "ref")
    r = yade(LAMMPS_RUN, ref_scene, "long", ref_dir)
    assert r.returncode == 0, r.stderr[-2000:]
    ref_side = json.loads((ref_dir / "long.json").read_text())
    ref = read(ref_dir / "long.csv")
    rows_before = int(np.sum(ref["t"] <= ref_side["reversals"][1]["t"]))
    scene, cdir = long_case(case, tmp_path / "killed", checkpoint_every_s=1)
    pid = kill_preshear_after_first_checkpoint(scene, cdir, "long", lambda resume: resume["rows"] > rows_before + 5,
                                               runner=LAMMPS_RUN)
    assert not (cdir / "long.csv").exists()
    proc = subprocess.Popen(command(LAMMPS_RUN, scene, "long", cdir), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        lines = []
        for line in proc.stdout:
            lines.append(line)
            if "resumed from" in line:
                proc.send_signal(signal.SIGTERM)
                break
        out, err = proc.communicate(timeout=600)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert f"stale lock of PID {pid} on host" in "".join(lines)   # SIGKILL left the lock file behind
    assert proc.returncode == 4 and "interrupted: SIGTERM received: checkpoint at step" in err, err[-2000:]
    r = yade(LAMMPS_RUN, scene, "long", cdir)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "resumed from" in r.stdout
    side = json.loads((cdir / "long.json").read_text())
    assert side["resumed"] == 2 and side["reversals"] == ref_side["reversals"]
    assert (cdir / "long.csv").read_bytes() == (ref_dir / "long.csv").read_bytes()
    for k in ("strain_end", "t_end", "gap_end", "overlap_end_d", "p_wall_mean", "steps", "samples"):
        assert side[k] == ref_side[k], k
    assert not (cdir / ".partial" / "long").exists()


@pytest.mark.parametrize("change, stage, match", [
    (lambda sc: sc["effects"].__setitem__("rolling_resistance", 0.1), "sinusoidal", "effects.rolling_resistance"),
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
    (dict(effects={"rolling_resistance": 0.1}), "effects.rolling_resistance = 0.1 (supported: 0)"),
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


def test_the_preflight_lets_the_lammps_engine_run_the_sinusoidal_reversal_and_every_schedule():
    """The bulk preset (sinusoidal and the schedule `alternate`) passes with engine: lammps; the
    bulk-vs-walls study (its periodic cells) is still refused, by key."""
    import yaml

    from preflight.checks import check
    from tests.helpers import ROOT

    def config(*names):
        out = {}
        for name in names:   # an overlay, as Snakemake merges config files (one level deep)
            for k, v in yaml.safe_load((ROOT / "config" / name).read_text()).items():
                out[k] = {**out[k], **v} if isinstance(v, dict) and isinstance(out.get(k), dict) else v
        return {**out, "engine": "lammps"}

    bulk = config("bulk.yaml")
    assert {"sinusoidal", "alternate"} <= set(bulk["protocols"]) and check(bulk) == []
    problems = check(config("quick.yaml", "bulk_validation.yaml"))
    assert any(p.startswith("config error: accuracy.bulk_vs_walls.run = True") and "run in yade only" in p
               for p in problems), problems
