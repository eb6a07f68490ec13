"""The pack's phases as both engines' stages run them (yade_scripts/packphases.py, pure Python):
compress until jammed, a linear ramp of the load to p W d, the settling with the grains' own friction,
done after two quiet checks in a row. Constructed samples; the real packings are in
test_dem_stages.py (YADE) and test_lammps_stages.py (LAMMPS)."""
import pytest

from tests.helpers import make_scene, yade_module

packphases = yade_module("packphases")
scenemod = yade_module("scene")
DER = dict(p=1.0, W=10.0, d=1.0, T0=1.0)   # full load p W d = 10
QUIET = dict(ke=1e-8, wall_speed=1e-5, pw=1.0)


def state():
    return dict(phase="compress", phase_steps={}, load=0.5 * 10.0, pack_ok=0)


def test_the_pack_jams_ramps_its_load_linearly_then_settles_with_the_grains_own_friction():
    sc = scenemod.validate(make_scene())   # compaction_pressure 0.5, ramp_time 3, pack.friction 0.2, material.friction 0.45
    st = state()
    assert packphases.check(st, sc, DER, 10.0, 100, ke=1e-3, wall_speed=1e-2, pw=0.5) == []   # still falling
    assert packphases.check(st, sc, DER, 11.0, 110, ke=1e-5, wall_speed=1e-4, pw=0.5) == ["ramp"]
    assert st["load"] == 5.0 and st["phase_steps"] == {"compress": 110}
    assert packphases.check(st, sc, DER, 12.5, 125, **QUIET) == [] and st["load"] == pytest.approx(7.5)
    assert packphases.check(st, sc, DER, 14.0, 140, **QUIET) == ["settle"] and st["load"] == 10.0
    assert st["phase_steps"] == {"compress": 110, "ramp": 30}
    assert [packphases.friction(sc, ph) for ph in ("compress", "ramp", "settle", "done")] == [0.2, 0.2, 0.45, 0.45]
    assert [packphases.damping(sc, ph) for ph in ("compress", "ramp", "settle", "done")] == [0.0, 0.5, 0.5, 0.0]


def test_the_settling_ends_after_two_quiet_checks_in_a_row_at_the_right_pressure():
    sc = scenemod.validate(make_scene())
    st = dict(state(), phase="settle", phase_steps={"compress": 110, "ramp": 30})
    assert packphases.check(st, sc, DER, 15.0, 150, **QUIET) == [] and st["pack_ok"] == 1
    assert packphases.check(st, sc, DER, 15.5, 155, **dict(QUIET, pw=1.05)) == [] and st["pack_ok"] == 0  # p off
    assert packphases.check(st, sc, DER, 16.0, 160, **QUIET) == []
    assert packphases.check(st, sc, DER, 16.5, 165, **QUIET) == ["done"]
    assert st["converged_at_t"] == 16.5 and st["phase_steps"] == {"compress": 110, "ramp": 30, "settle": 25}
