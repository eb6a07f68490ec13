"""yade_scripts/runwait.py: the stage's wait for a run chunk, on real YADE (a few bodies, about 3 s)."""
from __future__ import annotations

import json

from tests.helpers import YS, yade

SCRIPT = f"""
import json, sys, time
sys.path.insert(0, {str(YS)!r})
import runwait
from yade import utils
O.bodies.append([utils.sphere((0, 0, 2 * k), 0.5) for k in range(5)])
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                             [Law2_ScGeom_FrictPhys_CundallStrack()]),
             NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 1e-5
out = {{}}
i0 = O.iter; out["first"] = runwait.run_and_wait(O, 500); out["first_steps"] = O.iter - i0
t0 = time.perf_counter(); i0 = O.iter
out["overslept"] = runwait.run_and_wait(O, 500, steps_per_s=2000.0)   # predicts 0.25 s: slept 0.225 s
out["overslept_wall"] = time.perf_counter() - t0; out["overslept_steps"] = O.iter - i0
t0 = time.perf_counter()
out["fast"] = runwait.run_and_wait(O, 500, steps_per_s=1e9); out["fast_wall"] = time.perf_counter() - t0
out["running"] = O.running
print("RESULT " + json.dumps(out))
"""


def test_the_wait_returns_after_exactly_n_steps_and_distrusts_the_rate_of_an_overslept_run(tmp_path):
    script = tmp_path / "wait.py"
    script.write_text(SCRIPT)
    res = yade(script, timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    out = json.loads(next(line for line in res.stdout.splitlines() if line.startswith("RESULT "))[7:])
    assert out["first_steps"] == 500 and out["overslept_steps"] == 500
    assert out["first"] > 2000.0            # 5 spheres: far faster than the rate that oversleeps below
    assert out["overslept"] is None         # ended inside the sleep: no rate to predict from
    assert out["overslept_wall"] >= 0.225   # it did sleep through 90 % of the predicted 0.25 s
    assert out["fast"] > 0 and out["fast_wall"] < 0.2
    assert out["running"] is False
