"""A binary collision gives the configured restitution for every pair size the polydispersity allows
(size ratios 0.5 .. 1.5): measured in both engines by two disks colliding head on at the scene's dt.

YADE's ViscElMat sets the dashpot per pair: every pair rebounds with e = 0.5 within the time step's
error. LAMMPS's gran/hooke/history has one gamma_n for all pairs and a dashpot proportional to the
pair's mass: gamma_n is set so that two disks of diameter d rebound with e = 0.5, and the other pairs
spread from 0.38 (two of 1.5 d) to 0.69 (two of 0.5 d) as lammps_scripts/contact.py predicts
(docs/scene.md, "The LAMMPS engine"). Measured values: docs/scene.md.
"""
import json

import pytest

from tests.helpers import ROOT, YS, yade

TOOLS = ROOT / "tools"
SIZES = (0.5, 0.75, 1.0, 1.25, 1.5)
ALL_PAIRS = {(a, b) for i, a in enumerate(SIZES) for b in SIZES[i:]}


def measured(tmp_path, tool):
    out = tmp_path / "e.json"
    r = yade(TOOLS / tool, YS / "examples" / "tiny.json", out)
    assert r.returncode == 0, r.stderr[-2000:]
    res = json.loads(out.read_text())
    assert res["restitution"] == 0.5 and res["dt_over_tc"] == 0.1
    e = {(p["D1"], p["D2"]): p for p in res["pairs"]}
    assert set(e) == ALL_PAIRS
    return e


@pytest.mark.yade
def test_yade_gives_every_pair_the_configured_restitution(tmp_path):
    e = {k: p["e"] for k, p in measured(tmp_path, "restitution.py").items()}
    print("YADE restitution per pair:", e)
    assert abs(e[(1.0, 1.0)] - 0.5) < 0.03, e
    assert all(0.45 < v < 0.52 for v in e.values()), e   # within the time step's error of 0.5


@pytest.mark.lammps
def test_lammps_gives_the_reference_pair_the_restitution_and_the_others_their_measured_spread(tmp_path):
    e = measured(tmp_path, "lammps_restitution.py")
    print("LAMMPS restitution per pair:", {k: round(p["e"], 4) for k, p in e.items()})
    assert e[(1.0, 1.0)]["e"] == pytest.approx(0.5, abs=0.005)
    for p in e.values():   # LAMMPS integrates the contact as contact.mean_rebound does
        assert p["e"] == pytest.approx(p["e_theory"], abs=0.005)
    # the spread at a fixed gamma_n: heavier pairs are damped more
    assert e[(1.5, 1.5)]["e"] == pytest.approx(0.376, abs=0.01)
    assert e[(0.5, 0.5)]["e"] == pytest.approx(0.692, abs=0.01)
    assert e[(0.5, 0.5)]["e"] > e[(1.0, 1.0)]["e"] > e[(1.5, 1.5)]["e"]
