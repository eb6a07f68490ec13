"""campaign.cost, the one cost model of the DEM, and campaign.schedule, the wall time of its jobs.

The model is held against the DEM itself: its disk count against yade_scripts/scene.py's
``derived``, its steps against the steps real runs took (the deciding campaign's release,
data/bulk-decide: five seeds at kappa 1e5 on the narrow cell, their sidecars as YADE wrote them),
and its seconds against their measured CPU time.
"""
import functools
import json
import math

import pytest

from campaign import cost
from campaign.scene_spec import scene_module
from campaign.schedule import chain_makespan, longest_chain, makespan
from tests.helpers import ROOT, YS

RELEASE = ROOT / "data" / "bulk-decide" / "cases"
#: The documented throughput prices real runs within this factor of their measured CPU (docs/findings.md,
#: "The cost model against measured runs": 0.74-1.41 on the narrow cell at kappa 1e3-1e5).
FACTOR = 2.0


def released_sidecars(seeds=None):
    """(case, stage, sidecar) of the deciding release's stages, of ``seeds`` or all."""
    out = []
    for case in sorted(RELEASE.iterdir()):
        if seeds is None or int(case.name.rsplit("_s", 1)[1]) in seeds:
            for path in sorted((case / "sidecars").glob("*.json")):
                side = json.loads(path.read_text())
                if "cpu_time_s" in side:
                    out.append((case.name, path.stem, side))
    return out


def results_with(tmp_path, sidecars):
    """A results folder whose dem/<case>/<stage>.json are the given sidecars."""
    for case, stage, side in sidecars:
        (tmp_path / "dem" / case).mkdir(parents=True, exist_ok=True)
        (tmp_path / "dem" / case / f"{stage}.json").write_text(json.dumps(side))
    return tmp_path


def test_steps_per_strain_follow_the_stable_step_and_the_rate():
    # sqrt(4 kappa/pi)/(I dt_over_tc): ~1.2e5 steps per unit strain at kappa 1e3, I 1e-3, dt 0.3 t_c
    assert cost.steps_per_strain(1e3, 1e-3, 0.3) == pytest.approx(1.19e5, rel=0.01)
    assert cost.steps_per_strain(1e4, 1e-3, 0.3) / cost.steps_per_strain(1e3, 1e-3, 0.3) == pytest.approx(math.sqrt(10))
    assert cost.steps_per_strain(1e3, 5e-3, 0.1) / cost.steps_per_strain(1e3, 6e-5, 0.1) == pytest.approx(6e-5 / 5e-3)


@pytest.mark.parametrize("example, geometry, material", [
    ("tiny.json", {"H_over_d": 37, "W_over_H": 0.5}, {}),                             # the narrow cell: 626
    ("tiny.json", {"H_over_d": 37, "W_over_H": 4}, {}),                               # the paper's cell
    ("tiny_periodic.json", {"H_over_d": 23, "W_over_H": 1}, {}),
    ("tiny.json", {"H_over_d": 12, "W_over_H": 4}, {"size_ratio_min": 1.0, "size_ratio_max": 1.0}),   # monodisperse
    ("tiny.json", {"H_over_d": 20, "W_over_H": 2}, {"size_ratio_min": 0.8, "size_ratio_max": 1.2}),
])
def test_disks_are_counted_as_the_dem_counts_them(example, geometry, material):
    module = scene_module()
    raw = json.loads((YS / "examples" / example).read_text())
    raw["geometry"] = geometry
    raw["material"].update(material)
    scene = module.validate(raw)
    assert cost.scene_disks(scene) == module.derived(scene)["N"]


def test_a_monodisperse_cell_has_d2_disks_and_no_division_by_zero():
    # <D^2> = d^2 s^2 when size_ratio_min == size_ratio_max: N = round(0.8 W (H - 1) / (pi s^2 / 4))
    assert cost.mean_d2(1.2, 1.2) == pytest.approx(1.44)
    assert cost.n_disks(12, 4, 0.8, 1.0, 1.0) == round(0.8 * 48 * 11 / (math.pi / 4))
    assert cost.n_disks(12, 4, 0.8, 1.0, 1.0 + 1e-12) == cost.n_disks(12, 4, 0.8, 1.0, 1.0)


@pytest.mark.parametrize("engine", ["yade", "lammps"])
def test_documented_throughput_interpolates_its_two_points_log_log_and_holds_outside(engine):
    (n0, r0), (n1, r1) = cost.DOCUMENTED[engine]
    t = functools.partial(cost.documented_throughput, engine=engine)
    assert t(n0) == pytest.approx(r0) and t(n1) == pytest.approx(r1)
    assert t(math.sqrt(n0 * n1)) == pytest.approx(math.sqrt(r0 * r1))   # straight in log-log
    assert t(n0 / 10) == pytest.approx(r0) and t(n1 * 10) == pytest.approx(r1)


def engine_scene(scene, engine):
    """``scene`` run by ``engine`` (as campaign.scenes writes it: no ``engine`` key for YADE)."""
    out = {k: v for k, v in scene.items() if k != "engine"}
    return {**out, "engine": engine} if engine != "yade" else out


@pytest.mark.parametrize("W_over_H", [0.5, 4])   # the narrow cell (626 disks) and the paper's (about 5,000)
def test_a_lammps_scene_is_priced_cheaper_than_the_same_yade_scene_by_the_documented_ratio(W_over_H):
    (_, _, side), = [s for s in released_sidecars({1}) if s[1] == "preshear"]
    yade = engine_scene({**side["scene"], "geometry": {**side["scene"]["geometry"], "W_over_H": W_over_H}}, "yade")
    lammps = engine_scene(yade, "lammps")
    assert cost.engine_of(yade) == "yade" and cost.engine_of(lammps) == "lammps"
    for stage in cost.scene_stages(yade):
        ratio = cost.stage_seconds(yade, stage) / cost.stage_seconds(lammps, stage)
        assert ratio == pytest.approx(cost.LAMMPS_OVER_YADE), stage
    assert "LAMMPS" in cost.scene_throughput(lammps).source and "YADE 2023" in cost.scene_throughput(yade).source


def test_a_scene_is_never_priced_at_the_other_engines_throughput():
    (_, _, side), = [s for s in released_sidecars({1}) if s[1] == "preshear"]
    with pytest.raises(ValueError, match="a LAMMPS scene priced at YADE's throughput"):
        cost.stage_seconds(engine_scene(side["scene"], "lammps"), "preshear", cost.DOCUMENTED_THROUGHPUT)
    with pytest.raises(ValueError, match="a YADE scene priced at LAMMPS's throughput"):
        cost.stage_seconds(side["scene"], "preshear", cost.documented("lammps"))


def test_the_model_gives_the_steps_and_disks_real_runs_took():
    """Every shear stage of the deciding release (pre-shear, sinusoidal, a train, a schedule): the steps
    YADE ran; the pack, which runs until it converges: within a factor 3 of its projection."""
    stages = released_sidecars()
    assert {stage for _, stage, _ in stages} == {"pack", "preshear", "sinusoidal", "train03", "train05"}
    for case, stage, side in stages:
        scene = side["scene"]
        assert cost.scene_disks(scene) == side["N"], case
        if stage == "pack":
            assert 1 / 3 < side["steps"] / cost.stage_steps(scene, stage) < 3, case
        else:
            assert cost.stage_steps(scene, stage) == side["steps"], (case, stage)


def test_the_documented_throughput_prices_real_runs_within_the_stated_factor():
    stages = released_sidecars()
    projected = sum(cost.stage_seconds(side["scene"], stage) for _, stage, side in stages)
    measured = sum(side["cpu_time_s"] for _, _, side in stages)
    assert 1 / FACTOR < projected / measured < FACTOR, projected / measured


def test_a_throughput_measured_on_some_seeds_prices_the_others_to_a_few_percent(tmp_path):
    learned = cost.measured_throughput(results_with(tmp_path, released_sidecars({1, 3})))
    assert learned.measured and learned.factor != 1.0
    assert "measured on this machine: 8 stage sidecars of 2 cases" in learned.source
    others = [(case, stage, side) for case, stage, side in released_sidecars({4, 5, 6}) if stage != "pack"]
    projected = sum(cost.stage_seconds(side["scene"], stage, learned) for _, stage, side in others)
    measured = sum(side["cpu_time_s"] for _, _, side in others)
    assert projected / measured == pytest.approx(1.0, abs=0.05)


def test_the_measured_throughput_is_the_shear_stages_own_rate_at_their_disk_count(tmp_path):
    stages = released_sidecars({1})
    t = cost.measured_throughput(results_with(tmp_path, stages))
    shear = [side for _, stage, side in stages if stage != "pack"]
    assert t(626) == pytest.approx(sum(s["N"] * s["steps"] for s in shear) / sum(s["cpu_time_s"] for s in shear))


def test_packs_alone_measure_the_throughput_until_a_shear_stage_is_done(tmp_path):
    packs = [(case, stage, side) for case, stage, side in released_sidecars({1, 3}) if stage == "pack"]
    t = cost.measured_throughput(results_with(tmp_path, packs))
    assert "2 stage sidecars (packs only) of 2 cases" in t.source
    assert t(626) == pytest.approx(sum(s["N"] * s["steps"] for *_, s in packs) / sum(s["cpu_time_s"] for *_, s in packs))


def test_without_sidecars_or_with_other_json_files_only_the_documented_figure_is_used(tmp_path):
    assert cost.measured_throughput(tmp_path / "nothing") is cost.DOCUMENTED_THROUGHPUT
    case = tmp_path / "dem" / "p1_I0.001_s1"
    case.mkdir(parents=True)
    (case / "preshear.census.json").write_text(json.dumps({"N": 626, "overlap_d": {"mean": 0.001}}))
    (case / "scene.json").write_text(json.dumps({"seed": 1}))
    t = cost.measured_throughput(tmp_path)
    assert not t.measured and t.factor == 1.0 and t.source.startswith("the documented figure")


def test_the_measured_throughput_ignores_the_other_engines_sidecars(tmp_path):
    """Seed 1's sidecars as YADE wrote them (no ``engine`` key: YADE's) and seed 3's relabelled as LAMMPS's,
    at half the CPU: each engine's throughput is measured by its own stages alone."""
    yade = released_sidecars({1})
    lammps = [(case, stage, {**side, "engine": "lammps", "cpu_time_s": side["cpu_time_s"] / 2})
              for case, stage, side in released_sidecars({3})]
    results_with(tmp_path, yade + lammps)

    def rate(stages):
        shear = [side for _, stage, side in stages if stage != "pack"]
        return sum(s["N"] * s["steps"] for s in shear) / sum(s["cpu_time_s"] for s in shear)

    t_yade, t_lammps = cost.measured_throughput(tmp_path), cost.measured_throughput(tmp_path, engine="lammps")
    assert (t_yade.engine, t_lammps.engine) == ("yade", "lammps")
    assert all("_s1" in p for p in t_yade.sidecars) and all("_s3" in p for p in t_lammps.sidecars)
    assert t_yade(626) == pytest.approx(rate(yade)) and t_lammps(626) == pytest.approx(rate(lammps))
    assert "4 stage sidecars of 1 case" in t_lammps.source and "of LAMMPS at 626 disks" in t_lammps.source
    # measured against LAMMPS's own documented curve: its factor is the ratio to that curve
    assert t_lammps.factor == pytest.approx(rate(lammps) / cost.documented_throughput(626, "lammps"))
    yade_only = results_with(tmp_path / "yade_only", yade)
    assert cost.measured_throughput(yade_only, engine="lammps") is cost.documented("lammps")


def test_cases_left_out_of_the_measurement_are_not_read(tmp_path):
    results_with(tmp_path, released_sidecars({1, 3}))
    both = cost.measured_throughput(tmp_path)
    one = cost.measured_throughput(tmp_path, exclude={"p100000_I0.001_s3"})
    assert "8 stage sidecars of 2 cases" in both.source and "4 stage sidecars of 1 case in" in one.source
    assert one.sidecars == tuple(p for p in both.sidecars if "_s3" not in p)


# --- schedule ------------------------------------------------------------------------------

def test_independent_jobs_go_longest_first():
    assert makespan([3, 2, 2, 1], cores=2) == 4


def test_a_case_chain_runs_its_reversals_side_by_side_after_the_preshear():
    case = {"pack": 1.0, "preshear": 10.0, "heaviside": 4.0, "sinusoidal": 5.0}
    assert longest_chain({"a": case}) == 16.0
    assert chain_makespan({"a": case}, cores=1) == 20.0
    assert chain_makespan({"a": case}, cores=2) == 16.0
    assert chain_makespan({"a": case, "b": case}, cores=100) == 16.0


def test_on_two_cores_two_cases_share_them_and_the_longest_chain_starts_first():
    short = {"pack": 1.0, "preshear": 1.0, "heaviside": 1.0}
    long = {"pack": 1.0, "preshear": 8.0, "heaviside": 1.0}
    # longest chain first: the long case never waits; the short one fills the other core
    assert chain_makespan({"s1": short, "s2": short, "l": long}, cores=2) == 10.0
    assert chain_makespan({"s1": short, "s2": short, "l": long}, cores=1) == 16.0


def test_a_running_stage_keeps_its_core_from_the_start():
    cases = {"a": {"preshear": 1.0, "heaviside": 1.5}, "b": {"pack": 3.0}, "c": {"pack": 3.0}}
    # by priority b and c (3 s each) go before a's chain (2.5 s from its pre-shear): a waits for them
    assert chain_makespan(cases, cores=2) == 5.5
    # a's pre-shear runs already: it holds a core from the start, c takes the core it frees
    assert chain_makespan(cases, cores=2, running=[("a", "preshear")]) == 4.5
