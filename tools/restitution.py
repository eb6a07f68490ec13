"""Measure the restitution the scene's time step really gives: two disks collide head on.

python3 tools/restitution.py <scene.json> [<out.json>]

Prints (and writes) JSON: {"dt_over_tc": ..., "pairs": [{"D1": .., "D2": .., "e": ..}, ...]}
with diameters in d, for every pair of placement.pair_sizes (5 sizes over the polydispersity's
range and d). The disks are built exactly as in the cell (build.py).
"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0]))), "yade_scripts"))

import yadelib  # noqa: E402

yadelib.run_under_yade_interpreter()  # YADE as a library: no remote servers (docs/scene.md)
yadelib.import_yade()

import placement  # noqa: E402
import scene as scenemod  # noqa: E402

scene, _ = scenemod.load(sys.argv[1])
der = scenemod.derived(scene)

import build  # noqa: E402
import engines  # noqa: E402
from yade import utils  # noqa: E402
from yade.minieigenHP import Vector3  # noqa: E402
from yade.wrapper import Omega  # noqa: E402

O = Omega()


def collide(D1, D2, v=0.1):
    """Disks of diameters D1, D2 (in d) approach at relative speed 2v sqrt(p/rho)."""
    O.reset()
    d, V0 = der["d"], der["V0"]
    r1, r2 = D1 * d / 2, D2 * d / 2
    a = utils.sphere(Vector3(0, 0, 0), r1, material=build.contact_material(scene, der, r1))
    b = utils.sphere(Vector3(r1 + r2 + 1e-3 * d, 0, 0), r2, material=build.contact_material(scene, der, r2))
    for body, r in ((a, r1), (b, r2)):
        build.set_disk(body, r, der["rho"], d)
        body.state.blockedDOFs = "zXY"
    ia, ib = O.bodies.append(a), O.bodies.append(b)
    O.bodies[ia].state.vel = Vector3(v * V0, 0, 0)
    O.bodies[ib].state.vel = Vector3(-v * V0, 0, 0)
    O.engines = engines.build(scene, 10**9, "pass")[:-1]  # no sampler
    O.dt = der["dt"]
    vin = 2 * v * V0
    for _ in range(10**6):
        O.step()
        if O.iter > 10 and not O.interactions.countReal() and \
                O.bodies[ib].state.vel[0] - O.bodies[ia].state.vel[0] > 0:
            break
    vout = O.bodies[ib].state.vel[0] - O.bodies[ia].state.vel[0]
    return vout / vin


pairs = placement.pair_sizes(scene)
out = dict(dt_over_tc=scene["timestep"]["dt_over_tc"], restitution=scene["material"]["restitution"],
           pairs=[dict(D1=a, D2=b, e=collide(a, b)) for a, b in pairs])
print("RESTITUTION " + json.dumps(out), flush=True)
if len(sys.argv) > 2:
    with open(sys.argv[2], "w") as f:
        json.dump(out, f, indent=1)
