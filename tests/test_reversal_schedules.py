"""Reversal schedules: validation (scene and config), the splitter into transients, and real YADE runs.

A schedule is a reversal protocol given as a list of segments (or a train of
them) run in one series from the pre-shear (docs/scene.md); the readers split it
into one transient per reversal (dem_contract.split_transients).
"""
import copy
import json
import shutil

import numpy as np
import pytest
import yaml

import preflight
from campaign.scene_spec import protocol_strain
from dem_contract import (DEMInputError, pre_reversal_state, read_series, read_sidecar, split_transients,
                          synthetic)
from model import default_params
from tests.helpers import (ROOT, RUN, assert_schedule_reversals, kill_preshear_after_first_checkpoint, make_scene, read,
                           yade, yade_module)

scenemod = yade_module("scene")  # pure Python, no YADE

TINY = json.loads((ROOT / "yade_scripts" / "examples" / "tiny.json").read_text())
CI = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
CI["calibration"]["options"] = ""


# --- validation ----------------------------------------------------------------------------

def with_schedule(spec, name="double"):
    sc = copy.deepcopy(TINY)
    sc["schedules"] = {name: spec}
    return sc


def test_a_schedule_and_a_train_expand_to_their_segments():
    sc = scenemod.validate(with_schedule({"schedule": [
        {"strain": 0.2, "direction": -1},
        {"strain": 0.3, "direction": 1, "transition": "half_cosine", "transition_strain": 0.05}]}), "double")
    assert scenemod.segments(sc, "double") == [
        {"strain": 0.2, "direction": -1, "transition": "heaviside"},
        {"strain": 0.3, "direction": 1, "transition": "half_cosine", "transition_strain": 0.05}]
    sc = scenemod.validate(with_schedule({"train": {"every": 0.2, "reversals": 3}}, "train6"), "train6")
    segs = scenemod.segments(sc, "train6")
    assert [s["direction"] for s in segs] == [-1, 1, -1] and all(s["strain"] == 0.2 for s in segs)
    assert scenemod.reversal_strains(segs) == [(0, 0.0), (1, 0.2), (2, 0.4)]
    # heaviside and sinusoidal are one-segment schedules
    assert scenemod.segments(scenemod.validate(TINY), "sinusoidal") == [
        {"strain": 0.3, "direction": -1, "transition": "half_cosine", "transition_strain": 0.1}]


def test_the_protocol_cuts_segments_on_whole_steps_and_turns_the_walls_through_a_half_cosine():
    """yade_scripts/protocol.py, which both engines' stages drive their walls with: segment starts at
    ceil(strain x steps per strain), a reversal recorded with its kind, the old speed at the reversal,
    the half cosine's speed after each of its n steps, then the new direction's."""
    protocol = yade_module("protocol")
    der = dict(U=2.0, dt=1e-3, gammadot=10.0)
    segs = [{"strain": 0.2, "direction": -1, "transition": "heaviside"},
            {"strain": 0.3, "direction": 1, "transition": "half_cosine", "transition_strain": 0.05}]
    st = dict(iter0=100, strain=1.5, window=[[0.0, 1.0]])
    protocol.plan(st, segs, 0.01, 100.0, 100)   # 100 steps per strain
    assert [(s["start"], s["n_transition"]) for s in st["segments"]] == [(0, 0), (20, 5)]
    assert (st["n_steps"], st["fine_window_steps"], st["fine_end"]) == (50, 1, 101)
    assert protocol.enter(st, 0, 100, 7.0, der) == -2.0 and not protocol.in_transition(st, 100)
    assert protocol.next_boundary(st) == 20 and protocol.reverses(st, 1)
    st["strain"] = 1.3
    assert protocol.enter(st, 1, 120, 9.0, der) == -2.0   # the half cosine starts at the old speed
    assert st["reversals"] == [dict(strain=1.5, t=7.0, direction=-1, transition="heaviside"),
                               dict(strain=1.3, t=9.0, direction=1, transition="half_cosine", transition_strain=0.05)]
    assert st["window"] == [] and st["guard_from"] == pytest.approx(0.2) and st["fine_end"] == 126
    assert protocol.next_boundary(st) is None
    speeds = []
    for it in range(120, 127):
        if protocol.in_transition(st, it):
            speeds.append(protocol.transition_speed(st, der, it + 1))
    assert speeds == pytest.approx([-2.0 * np.cos(np.pi * k / 5) for k in range(1, 6)])
    assert speeds[-1] == 2.0 and protocol.half_cosine_speed(2.0, 9, 5, -1, 1) == 2.0
    assert protocol.sidecar_keys("double", st)["segments"] == segs
    assert protocol.sidecar_keys("preshear", st) == {}


@pytest.mark.parametrize("spec, key", [
    ({"schedule": [{"strain": 0.2, "direction": 0}]}, r"schedules\.double\.schedule\[0\]\.direction"),
    ({"schedule": [{"strain": -0.2, "direction": -1}]}, r"schedules\.double\.schedule\[0\]\.strain = -0\.2 is out of range"),
    ({"schedule": [{"strain": 0.2, "direction": -1, "transition": "half_cosine"}]},
     r"schedules\.double\.schedule\[0\]\.transition_strain"),
    ({"schedule": [{"strain": 0.2, "direction": -1, "transition_strain": 0.1}]},
     r"schedules\.double\.schedule\[0\]\.transition_strain applies to transition = half_cosine only"),
    ({"schedule": [{"strain": 0.2, "direction": -1, "transition": "half_cosine", "transition_strain": 0.3}]},
     r"schedules\.double\.schedule\[0\]\.transition_strain = 0\.3 is out of range \(0, 0\.2\]"),
    ({"schedule": [{"strain": 0.2, "direction": -1, "speed": 2}]}, r"schedules\.double\.schedule\[0\]\.speed"),
    ({"schedule": [{"strain": 0.2, "direction": 1}]}, r"schedules\.double\.schedule has no reversal"),
    ({"train": {"every": 0.2, "reversals": 0}}, r"schedules\.double\.train\.reversals = 0 is out of range \[1, 1000\]"),
    ({"train": {"every": 0.2}}, r"schedules\.double\.train\.reversals"),
    ({"schedule": [], "train": {}}, r"schedules\.double must hold exactly one"),
])
def test_the_scene_rejects_a_bad_segment_naming_the_key(spec, key):
    with pytest.raises(scenemod.SceneError, match=key):
        scenemod.validate(with_schedule(spec))


def test_a_stage_that_is_not_a_schedule_of_the_scene_is_refused():
    with pytest.raises(scenemod.SceneError, match="stage 'triple' is neither"):
        scenemod.validate(with_schedule({"train": {"every": 0.2, "reversals": 2}}), "triple")
    with pytest.raises(scenemod.SceneError, match=r"schedules\.preshear: a schedule's name"):
        scenemod.validate(with_schedule({"train": {"every": 0.2, "reversals": 2}}, "preshear"))


def ci_with_protocol(name, spec):
    config = copy.deepcopy(CI)
    config["protocols"][name] = spec
    return config


@pytest.mark.parametrize("spec, key", [
    ({"schedule": [{"strain": 0.2, "direction": 2}]}, "protocols.double.schedule[0].direction"),
    ({"schedule": [{"strain": 0.2, "direction": -1, "transition": "half_cosine"}]},
     "protocols.double.schedule[0]"),
    ({"schedule": [{"strain": 0.2, "direction": 1}]}, "protocols.double.schedule[*].direction = [1]: no reversal"),
    ({"train": {"every": 0.2, "reversals": 2, "transition": "smooth"}}, "protocols.double.train.transition"),
    ({"schedule": [{"strain": 0.2, "direction": -1}], "train": {"every": 0.2, "reversals": 2}}, "protocols.double"),
])
def test_the_config_schema_rejects_a_bad_segment_naming_the_key(spec, key):
    problems = preflight.check(ci_with_protocol("double", spec))
    assert problems and all(p.startswith("config error: ") for p in problems)
    assert any(p.startswith(f"config error: {key}") for p in problems), problems


def test_a_misspelt_protocol_is_named_with_what_a_schedule_looks_like():
    problems = preflight.check(ci_with_protocol("heavyside", {"strain": 0.4}))
    assert len(problems) == 1 and problems[0].startswith("config error: protocols.heavyside: ")
    assert "is a reversal schedule: {schedule: [segments]} or {train: {every, reversals}}" in problems[0]


def test_the_preflight_names_a_segment_shorter_than_one_sample_and_a_transition_longer_than_its_segment():
    problems = preflight.check(ci_with_protocol("double", {"schedule": [
        {"strain": 0.0001, "direction": -1},
        {"strain": 0.1, "direction": 1, "transition": "half_cosine", "transition_strain": 0.2}]}))
    assert any("protocols.double.schedule[0].strain = 0.0001: shorter than one sample" in p for p in problems), problems
    assert any("protocols.double.schedule[1].transition_strain = 0.2: is longer than" in p for p in problems), problems


def test_a_good_schedule_passes_the_preflight_and_reaches_the_scene():
    config = ci_with_protocol("train4", {"train": {"every": 0.2, "reversals": 4}})
    assert preflight.check(config) == []
    from campaign.cases import cases
    from campaign.scenes import scene_from_config
    label, case = next(iter(cases(config).items()))
    scene = scenemod.validate(scene_from_config(config, case, label), "train4")
    assert len(scenemod.segments(scene, "train4")) == 4
    assert protocol_strain("train4", config["protocols"]["train4"]) == pytest.approx(0.8)


# --- the splitter on model-made series -------------------------------------------------------

@pytest.fixture(scope="module")
def two_reversals(tmp_path_factory):
    case = synthetic.write_case(tmp_path_factory.mktemp("syn") / "p1_I0.001_s1", default_params(), seed=1,
                                preshear_strain=1.5, protocols=("heaviside",),
                                schedules={"double": [(0.3, -1), (0.3, 1)]})
    pre, run = read_series(case / "preshear.csv"), read_series(case / "double.csv")
    return case, pre, run, read_sidecar(case / "double.csv")


def test_the_splitter_returns_one_transient_per_reversal_with_the_state_before_it(two_reversals):
    case, pre, run, meta = two_reversals
    first, second = split_transients(pre, run, meta)
    assert (first.index, second.index, first.n_reversals) == (1, 2, 2)
    assert (first.sign, second.sign) == (-1.0, 1.0)   # against the pre-shear, then back with it
    assert [first.t0, second.t0] == [r["t"] for r in meta["reversals"]]
    # the first starts from the end of the pre-shear, the second from the end of the first transient
    assert first.initial == pre_reversal_state(pre)
    assert second.initial == pre_reversal_state(first.data, estimate="line")   # a moving leg: the line at its end
    # the state at the second reversal (noise-free: its last sample), not a mean lagging over the last 0.1 strain
    for c in ("A_xx", "A_xy"):
        assert second.initial[c] == pytest.approx(first.data[c].iloc[-1], abs=2e-4)
    assert second.initial["gammadot_sign"] == -1.0
    # every row in exactly one transient, in order; the row at the second reversal closes the first
    assert len(first.data) + len(second.data) == len(run)
    assert first.data["t"].iloc[-1] == second.t0 and second.data["t"].iloc[0] > second.t0
    assert np.all(np.sign(second.data["gammadot"]) > 0) and np.all(np.sign(first.data["gammadot"]) < 0)


def test_the_splitter_finds_the_same_reversals_without_the_sidecar(two_reversals):
    case, pre, run, meta = two_reversals
    stated, found = split_transients(pre, run, meta), split_transients(pre, run)
    assert [(t.t0, t.strain0, len(t.data)) for t in stated] == [(t.t0, t.strain0, len(t.data)) for t in found]


def test_a_single_reversal_run_is_one_transient_the_whole_run_from_the_pre_shear(two_reversals):
    case, pre, run, meta = two_reversals
    h = read_series(case / "heaviside.csv")
    (only,) = split_transients(pre, h, read_sidecar(case / "heaviside.csv"))
    assert only.data.equals(h) and only.initial == pre_reversal_state(pre) and only.sign == -1.0


def test_a_sidecar_listing_reversals_the_rate_does_not_make_is_an_error(two_reversals):
    case, pre, run, meta = two_reversals
    bad = dict(meta, reversals=meta["reversals"] + [dict(meta["reversals"][1], t=meta["reversals"][1]["t"] + 50)])
    with pytest.raises(DEMInputError, match="the sidecar lists 3 reversals, the rate reverses 2 time"):
        split_transients(pre, run, bad, what="double.csv")


def test_calibration_and_comparison_read_each_reversal_as_one_transient(two_reversals):
    from calibrate import io
    from compare.dem import load_reversal, load_reversals
    case, pre, run, meta = two_reversals
    c = io.read_case(case, protocols=("heaviside", "double"))
    assert sorted(c.runs) == ["double_r1", "double_r2", "heaviside"]
    assert c.runs["heaviside"].initial_state is None and c.runs["heaviside"].data.equals(
        io.read_run(case / "heaviside.csv", "heaviside").data)
    second = c.runs["double_r2"]
    assert second.schedule == "double" and second.initial_state["gammadot_sign"] == -1.0
    revs = load_reversals(case, "double")
    assert [r.meta["reversal"] for r in revs] == [1, 2]
    assert revs[1].A0 == (second.initial_state["A_xx"], second.initial_state["A_xy"])
    assert revs[1].data["s_rev"].iloc[0] > 0 and revs[1].data["tau"].iloc[0] > 0
    assert load_reversal(case, "heaviside").A0 == (pre_reversal_state(pre)["A_xx"], pre_reversal_state(pre)["A_xy"])


# --- real YADE: a schedule with two reversals -------------------------------------------------

SCHEDULES = {
    # walls: two sharp reversals; periodic: a sharp one, then a half cosine back
    "walls": [{"strain": 0.15, "direction": -1}, {"strain": 0.15, "direction": 1}],
    "periodic": [{"strain": 0.15, "direction": -1},
                 {"strain": 0.2, "direction": 1, "transition": "half_cosine", "transition_strain": 0.05}],
}


def schedule_scene(kind, segments, **run):
    sc = make_scene("tiny.json" if kind == "walls" else "tiny_periodic.json")
    sc["schedules"] = {"double": {"schedule": segments}}
    sc["run"].update(run)
    return sc


#: What the schedule's stage starts from: the pack and the pre-shear (the scene's schedules do not change them).
PRESHEAR_FILES = ("pack.final.yade.gz", "pack.json", "preshear.final.yade.gz", "preshear.json", "preshear.csv")


@pytest.fixture(scope="module")
def preshear_of(tmp_path_factory):
    """kind -> a case folder holding the pack and the pre-shear of that cell kind, each run once for the module
    (every schedule below starts from them, as the campaign's reversals start from one pre-shear)."""
    done = {}

    def of(kind):
        if kind not in done:
            root = tmp_path_factory.mktemp(f"preshear_{kind}")
            scene = root / "scene.json"
            scene.write_text(json.dumps(schedule_scene(kind, SCHEDULES[kind])))
            cdir = root / "p100000_I0.01_s1"
            for stage in ("pack", "preshear"):
                r = yade(RUN, scene, stage, cdir)
                assert r.returncode == 0, f"{stage}: {r.stdout[-2000:]}\n{r.stderr[-2000:]}"
            done[kind] = cdir
        return done[kind]
    return of


def schedule_case(preshear_of, root, kind, segments, **run):
    """A case under ``root`` with the module's pack and pre-shear of ``kind`` and a scene scheduling ``segments``:
    (scene, case folder)."""
    cdir = root / "p100000_I0.01_s1"
    cdir.mkdir(parents=True)
    for f in PRESHEAR_FILES:
        shutil.copy(preshear_of(kind) / f, cdir / f)
    scene = root / "scene.json"
    scene.write_text(json.dumps(schedule_scene(kind, segments, **run)))
    return scene, cdir


@pytest.fixture(scope="module", params=["walls", "periodic"])
def yade_schedule(request, tmp_path_factory, preshear_of):
    kind = request.param
    root = tmp_path_factory.mktemp(f"sched_{kind}")
    scene, cdir = schedule_case(preshear_of, root, kind, SCHEDULES[kind])
    r = yade(RUN, scene, "double", cdir)
    assert r.returncode == 0, f"double: {r.stdout[-2000:]}\n{r.stderr[-2000:]}"
    return dict(kind=kind, dir=cdir, scene=scene, root=root)


@pytest.mark.yade
def test_a_schedule_with_two_reversals_writes_one_series_whose_reversals_the_readers_find(yade_schedule):
    assert_schedule_reversals(yade_schedule["dir"], "double", SCHEDULES[yade_schedule["kind"]])


@pytest.mark.yade
def test_a_schedule_samples_finely_again_after_each_reversal(yade_schedule):
    side = json.loads((yade_schedule["dir"] / "double.json").read_text())
    run = read(yade_schedule["dir"] / "double.csv")
    dt_fine = side["sampling_steps"]["fine"] * side["dt"] / side["time_unit_s"]
    t2 = side["reversals"][1]["t"]
    assert np.any(np.abs(run["t"] - t2) < 1e-9)   # a row at the reversal: the state just before it
    after = run["t"][(run["t"] > t2)][:20]
    assert np.allclose(np.diff(after), dt_fine, rtol=1e-6)


@pytest.mark.yade
@pytest.mark.slow
def test_a_schedule_killed_in_its_second_segment_resumes_with_no_gap_and_no_duplicated_row(yade_schedule, preshear_of,
                                                                                          tmp_path):
    if yade_schedule["kind"] != "walls":
        pytest.skip("the resume path is the same for both cell kinds; the periodic cell's own resume is "
                    "tests/test_dem_periodic.py")
    segments = [{"strain": 0.1, "direction": -1}, {"strain": 0.9, "direction": 1}]
    runs = {}
    for name, kill in (("reference", False), ("killed", True)):
        scene, cdir = schedule_case(preshear_of, tmp_path / name, "walls", segments, checkpoint_every_s=1)
        if kill:
            t2 = json.loads(runs["reference"][1])["reversals"][1]["t"]
            rows_before = int(np.sum(runs["reference"][0]["t"] <= t2))
            kill_preshear_after_first_checkpoint(scene, cdir, "double", lambda resume: resume["rows"] > rows_before + 5)
            assert not (cdir / "double.csv").exists()
        r = yade(RUN, scene, "double", cdir)
        assert r.returncode == 0, r.stderr[-2000:]
        assert ("resumed from" in r.stdout) == kill
        runs[name] = (read(cdir / "double.csv"), (cdir / "double.json").read_text())
    (ref, ref_side), (got, got_side) = runs["reference"], runs["killed"]
    ref_side, got_side = json.loads(ref_side), json.loads(got_side)
    assert got_side["resumed"] == 1
    # the same rows at the same times as the uninterrupted run: no gap, no duplicate, no foreign row
    assert len(got) == len(ref) == got_side["samples"]
    assert np.array_equal(got["t"], ref["t"])
    assert got_side["reversals"] == ref_side["reversals"]
    assert np.all(np.diff(got["t"]) > 0)
    # and the resumed run goes on shearing as scheduled: the same direction and strain path
    assert np.array_equal(np.sign(got["gammadot"]), np.sign(ref["gammadot"]))
    assert np.abs(got["strain"] - ref["strain"]).max() < 0.01


def test_the_comparison_scores_each_reversal_of_a_schedule_as_one_transient(two_reversals, tmp_path):
    from compare import comparison
    from model import save_params
    case, pre, run, meta = two_reversals
    params = tmp_path / "params.yaml"
    save_params(default_params(), params)   # the truth of the synthetic case
    c = comparison.run([case], params, ["heaviside", "double"])
    seeds = c.errors[c.errors["level"] == "seed"]
    assert sorted(seeds["protocol"].unique()) == ["double_r1", "double_r2", "heaviside"]
    assert sorted(k[1] for k in c.ensembles) == ["double_r1", "double_r2", "heaviside"]
    # the model started from each transient's own initial state follows the model-made series
    assert seeds["status"].eq("ok").all()
    assert seeds.loc[seeds["protocol"] == "double_r2", "rmse_A_norm"].max() < 0.01


@pytest.mark.yade
def test_a_schedule_that_first_continues_the_pre_shear_runs_and_reverses_where_scheduled(preshear_of, tmp_path):
    """A first segment in the pre-shear's direction (no reversal) runs, sampled finely from its start, and
    the one reversal comes after it (this stage failed with KeyError 'fine_end' before its fix)."""
    segments = [{"strain": 0.1, "direction": 1}, {"strain": 0.15, "direction": -1}]
    scene, cdir = schedule_case(preshear_of, tmp_path, "walls", segments)
    r = yade(RUN, scene, "double", cdir)
    assert r.returncode == 0, f"double: {r.stdout[-2000:]}\n{r.stderr[-2000:]}"
    side = json.loads((cdir / "double.json").read_text())
    assert [r["direction"] for r in side["reversals"]] == [-1]
    I, step = side["inertial_number"], side["gammadot_nominal"] * side["dt"]
    assert abs((side["reversals"][0]["t"] - side["t_start"]) * I - 0.1) <= step * 1.001
    run = read(cdir / "double.csv")
    dt_fine = side["sampling_steps"]["fine"] * side["dt"] / side["time_unit_s"]
    assert np.allclose(np.diff(run["t"][:10]), dt_fine, rtol=1e-6)   # fine from the stage's start
    assert run["gammadot"][0] > 0 > run["gammadot"][-1]
    found = split_transients(read_series(cdir / "preshear.csv"), read_series(cdir / "double.csv"), side)
    assert len(found) == 1 and found[0].sign == -1.0
