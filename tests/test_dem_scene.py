"""Scene validation and engine lists, with real YADE (the two-disk restitution: test_restitution_engines.py)."""
import copy
import os
import subprocess
import json

import pytest

from tests.helpers import ROOT, YS, yade, yade_module

scenemod = yade_module("scene")  # pure Python, no YADE; yade_scripts/ stays off sys.path
TOOLS = ROOT / "tools"

TINY = json.loads((YS / "examples" / "tiny.json").read_text())


def write(tmp_path, sc, name="scene.json"):
    p = tmp_path / name
    p.write_text(json.dumps(sc))
    return p


def test_example_scene_is_valid():
    sc = scenemod.validate(TINY, "sinusoidal")
    der = scenemod.derived(sc)
    assert 100 < der["N"] < 300 and der["n_wall"] == 32


@pytest.mark.parametrize("mutate, key", [
    (lambda s: s["material"].pop("kappa"), "material.kappa"),
    (lambda s: s["material"].__setitem__("kappa", 5.0), "material.kappa"),
    (lambda s: s["material"].__setitem__("restitution", 1.0), "material.restitution"),
    (lambda s: s["geometry"].__setitem__("H_over_d", "37"), "geometry.H_over_d"),
    (lambda s: s["sampling"].__setitem__("fine_intervall", 0.001), "sampling.fine_intervall"),
    (lambda s: s.__setitem__("colour", "red"), "colour"),
    (lambda s: s.pop("seed"), "seed"),
    (lambda s: s["effects"].__setitem__("gravity", [0, -9.81, 1]), "effects.gravity"),
    (lambda s: s["effects"].__setitem__("measurements", 1), "effects.measurements"),
    (lambda s: s["sampling"].__setitem__("bulk_exclusion_d", 4), "bulk_exclusion_d"),
])
def test_bad_scene_names_the_key(mutate, key):
    sc = copy.deepcopy(TINY)
    mutate(sc)
    with pytest.raises(scenemod.SceneError, match=key.replace(".", r"\.")):
        scenemod.validate(sc)


def test_stage_needs_its_section():
    sc = copy.deepcopy(TINY)
    sc.pop("sinusoidal")
    scenemod.validate(sc, "heaviside")
    with pytest.raises(scenemod.SceneError, match="sinusoidal"):
        scenemod.validate(sc, "sinusoidal")


def test_bad_scene_stops_yade_before_building(tmp_path):
    sc = copy.deepcopy(TINY)
    sc["material"]["friction"] = -0.1
    r = yade(YS / "run_stage.py", write(tmp_path, sc), "pack", tmp_path / "case")
    assert r.returncode == 2, r.stdout + r.stderr
    assert "material.friction" in r.stderr
    assert not (tmp_path / "case").exists()  # nothing built, nothing written
    r = yade(YS / "run_stage.py", write(tmp_path, TINY), "preshear", tmp_path / "case")
    assert r.returncode == 2 and "pack.final.yade.gz" in r.stderr  # missing input named


def test_stage_refuses_to_run_under_the_yade_launcher(tmp_path):
    """`yade -x` opens a TCP Python prompt and an XMLRPC server before it runs a script:
    run_stage.py stops at once (exit 2, nothing written) and names the command to use."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    r = subprocess.run(["yade", "-n", "-x", str(YS / "run_stage.py"), str(write(tmp_path, TINY)), "pack",
                        str(tmp_path / "case")], capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 2, r.stdout + r.stderr
    assert "not run by the yade launcher" in r.stderr and "python3 yade_scripts/run_stage.py" in r.stderr
    assert not (tmp_path / "case").exists()


ENGINE_CASES = [
    ({}, "preshear", ["ForceResetter", "InsertionSortCollider",
                      "InteractionLoop[Ig2_Sphere_Sphere_ScGeom,Ip2_ViscElMat_ViscElMat_ViscElPhys,"
                      "Law2_ScGeom_ViscElPhys_Basic]", "NewtonIntegrator", "PyRunner(sampler)"]),
    ({"gravity": [0, -9.81], "damping": 0.2}, "preshear",
     ["ForceResetter", "InsertionSortCollider",
      "InteractionLoop[Ig2_Sphere_Sphere_ScGeom,Ip2_ViscElMat_ViscElMat_ViscElPhys,Law2_ScGeom_ViscElPhys_Basic]",
      "GravityEngine", "NewtonIntegrator(damping=0.2)", "PyRunner(sampler)"]),
    ({"rolling_resistance": 0.1}, "heaviside",
     ["ForceResetter", "InsertionSortCollider",
      "InteractionLoop[Ig2_Sphere_Sphere_ScGeom6D,Ip2_ViscElMat_ViscElMat_ViscElPhys,Law2_ScGeom_ViscElPhys_Basic]",
      "NewtonIntegrator", "PyRunner(sampler)"]),
    ({}, "sinusoidal", ["ForceResetter", "InsertionSortCollider",
                        "InteractionLoop[Ig2_Sphere_Sphere_ScGeom,Ip2_ViscElMat_ViscElMat_ViscElPhys,"
                        "Law2_ScGeom_ViscElPhys_Basic]", "NewtonIntegrator", "PyRunner(wallspeed)",
                        "PyRunner(sampler)"]),
]


@pytest.mark.parametrize("effects, stage, expected", ENGINE_CASES)
def test_engine_list_holds_only_declared_effects(tmp_path, effects, stage, expected):
    sc = copy.deepcopy(TINY)
    sc["effects"] = effects
    r = yade(TOOLS / "show_engines.py", write(tmp_path, sc), stage)
    assert r.returncode == 0, r.stderr
    line = [ln for ln in r.stdout.splitlines() if ln.startswith("ENGINES ")][0]
    assert json.loads(line[len("ENGINES "):]) == expected


def _periodic(**cell):
    sc = copy.deepcopy(TINY)
    sc["sampling"].pop("bulk_exclusion_d")
    sc["geometry"] = {"H_over_d": 16, "W_over_H": 1}
    sc["cell"] = dict(kind="periodic", **cell)
    return sc


def test_a_periodic_scene_without_wall_keys_is_valid():
    sc = scenemod.validate(_periodic(mass=0.5), "preshear")
    assert sc["cell"] == {"kind": "periodic", "mass": 0.5}
    assert scenemod.validate(TINY)["cell"]["kind"] == "walls"  # the default


@pytest.mark.parametrize("key", ["sampling.bulk_exclusion_d"])
def test_a_periodic_scene_rejects_wall_only_keys_naming_them(key):
    sc = _periodic()
    sec, k = key.split(".")
    sc[sec][k] = 2.0
    with pytest.raises(scenemod.SceneError, match=rf"{key} applies to a wall cell only"):
        scenemod.validate(sc)


def test_a_wall_scene_rejects_periodic_only_keys_naming_them():
    sc = copy.deepcopy(TINY)
    sc["cell"] = {"mass": 0.5}
    with pytest.raises(scenemod.SceneError, match=r"cell.mass applies to a periodic cell only"):
        scenemod.validate(sc)


def test_an_unknown_cell_kind_is_named():
    sc = copy.deepcopy(TINY)
    sc["cell"] = {"kind": "box"}
    with pytest.raises(scenemod.SceneError, match=r"cell.kind = 'box' must be one of walls, periodic"):
        scenemod.validate(sc)


def test_a_periodic_scene_must_be_about_square():
    sc = _periodic()
    sc["geometry"]["W_over_H"] = 4
    with pytest.raises(scenemod.SceneError, match=r"geometry.W_over_H = 4 is out of range \[0.5, 1.1\]"):
        scenemod.validate(sc)


def test_a_periodic_scene_refuses_the_viscel_contact_law_and_defaults_to_frictvisco():
    assert scenemod.validate(_periodic())["material"]["contact_law"] == "frictvisco"
    assert scenemod.validate(TINY)["material"]["contact_law"] == "viscel"
    sc = _periodic()
    sc["material"]["contact_law"] = "viscel"
    with pytest.raises(scenemod.SceneError, match=r"material.contact_law = 'viscel' cannot be used with cell.kind"):
        scenemod.validate(sc)
