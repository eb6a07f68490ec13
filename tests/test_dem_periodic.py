"""The periodic bulk cell (cell.kind = periodic) with real YADE, on a tiny soft cell.

The cell: W = H = 16 d (about 240 disks, periodic in x and y), kappa = 1e3, I = 1e-2.
One module fixture runs pack -> preshear -> heaviside, sinusoidal once.
"""
import json
import shutil

import numpy as np
import pytest

from tests.helpers import (RUN, assert_pack_restored_the_grains_own_friction_and_damping,
                           assert_resumed_without_gap_or_duplicate, kill_preshear_after_first_checkpoint, read,
                           run_all_stages, yade)
from tests.helpers import make_scene as make_stage_scene

pytestmark = pytest.mark.yade


def make_scene():
    return make_stage_scene("tiny_periodic.json")


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    return run_all_stages(tmp_path_factory.mktemp("periodic"), make_scene())


def test_periodic_stages_write_the_contract(case):
    for stage in ("pack", "preshear", "heaviside"):
        side = json.loads((case["dir"] / f"{stage}.json").read_text())
        assert side["N_wall"] == 0 and side["scene"]["cell"]["kind"] == "periodic"
        assert side["samples"] == len(read(case["dir"] / f"{stage}.csv"))
        assert any(e.startswith("PeriTriaxController") for e in side["engines"])
        assert any("FrictVisco" in e for e in side["engines"])


def test_periodic_pack_restores_the_grains_friction_and_damping(case, tmp_path):
    assert_pack_restored_the_grains_own_friction_and_damping(case, tmp_path)


def test_periodic_cell_holds_sigma_yy_within_2_percent_over_preshear(case):
    s = read(case["dir"] / "preshear.csv")
    assert abs(s["p"].mean() - 1) < 0.02
    assert np.allclose(s["p"], s["p"])  # no NaN
    # the cell is sheared: a steady friction coefficient and a fabric leaning near 135 degrees
    late = s["strain"] > 0.5
    assert 0.15 < np.mean(s["sigma_xy"][late]) / np.mean(s["p"][late]) < 0.5
    theta = np.degrees(np.arctan2(s["A_xy"][late].mean(), s["A_xx"][late].mean()) / 2) % 180
    assert 120 < theta < 150


def test_reversal_flips_the_sign_of_the_shear_rate(case):
    pre, rev = read(case["dir"] / "preshear.csv"), read(case["dir"] / "heaviside.csv")
    assert np.all(pre["gammadot"] > 0) and np.all(rev["gammadot"] < 0)
    assert np.allclose(rev["gammadot"], -pre["gammadot"][-1], rtol=1e-9)
    assert np.all(np.diff(rev["strain"]) < 0)  # the strain falls after the reversal
    assert np.mean(rev["sigma_xy"][rev["strain"] < rev["strain"][0] - 0.2]) < 0  # and so does the stress
    assert np.allclose(rev["U_top"], -rev["U_bottom"]) and np.all(rev["U_top"] < 0)


def test_sinusoidal_shear_rate_follows_half_cosine(case):
    r = read(case["dir"] / "sinusoidal.csv")
    sc = make_scene()
    I = sc["loading"]["inertial_number"]  # the nominal rate, in 1/(d sqrt(rho/p))
    T = sc["sinusoidal"]["transition_strain"] / I
    tau = r["t"] - json.loads((case["dir"] / "sinusoidal.json").read_text())["reversal_t"]
    expect = np.where(tau < T, I * np.cos(np.pi * np.clip(tau / T, 0, 1)), -I)
    assert np.allclose(r["gammadot"], expect, atol=I * 0.02)
    assert np.allclose(r["U_bottom"], -r["U_top"])
    # the per-step shear rate must not freeze the cell's height control (it did: p fell to 0.15)
    assert abs(r["p"][tau < T].mean() - 1) < 0.05 and abs(r["p"].mean() - 1) < 0.02


def test_strain_accumulates_as_the_integral_of_the_shear_rate(case):
    # strain comes from the cell's shape (hSize_xy and the flips), gammadot from velGrad: they must agree
    side = json.loads((case["dir"] / "preshear.json").read_text())
    for stage in ("preshear", "heaviside"):
        s = read(case["dir"] / f"{stage}.csv")
        sd = json.loads((case["dir"] / f"{stage}.json").read_text())
        integral = sd["strain_start"] + s["gammadot"][0] * (s["t"] - sd["t_start"])  # constant rate
        assert np.allclose(s["strain"], integral, atol=2e-4), stage  # a missed flip would be off by about 1
    assert side["strain_end"] == pytest.approx(1.2, rel=1e-3)  # past a flip of the cell (at 0.5)


def test_killed_periodic_stage_resumes_without_gap_or_duplicate(case, tmp_path):
    cdir = tmp_path / "case"
    cdir.mkdir()
    for f in ("pack.final.yade.gz", "pack.json"):
        shutil.copy(case["dir"] / f, cdir / f)
    sc = make_scene()
    sc["preshear"]["strain"] = 2.5
    sc["run"]["checkpoint_every_s"] = 1
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(sc))
    kill_preshear_after_first_checkpoint(scene, cdir)
    r = yade(RUN, scene, "preshear", cdir)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "resumed from" in r.stdout
    s, side = assert_resumed_without_gap_or_duplicate(cdir)
    t, strain = s["t"], s["strain"]
    # the strain bookkeeping (flips included) survives the restart: still the integral of the rate
    assert np.allclose(strain, s["gammadot"][0] * (t - side["t_start"]), atol=2e-4)
    assert strain[-1] == pytest.approx(2.5, rel=1e-3)
