"""Measure the restitution the LAMMPS contact law gives at the scene's time step: two disks collide head on.

python3 tools/lammps_restitution.py <scene.json> [<out.json>]

Prints (and writes) JSON: {"dt_over_tc": ..., "restitution": ..., "pairs": [{"D1": .., "D2": .., "e": ..,
"e_theory": ..}, ...]} with diameters in d, for every pair of placement.pair_sizes, as
tools/restitution.py for YADE. The disks, masses and pair style are the stages'
(lammps_scripts/cell.py, contact.py); e_theory is contact.pair_restitution (the same collisions integrated in Python).
"""
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0])))
sys.path[:0] = [os.path.join(ROOT, "lammps_scripts"), os.path.join(ROOT, "yade_scripts")]

import lammpslib  # noqa: E402

lammpslib.run_under_lammps_interpreter()

import cell  # noqa: E402
import contact  # noqa: E402
import placement  # noqa: E402
import scene as scenemod  # noqa: E402


def restitution(scene, der, D1, D2):
    """The rebound's e of disks of diameters D1, D2 (in d), mean over contact.PHASES impact phases."""
    return sum(collide(scene, der, D1, D2, k / contact.PHASES) for k in range(contact.PHASES)) / contact.PHASES


def collide(scene, der, D1, D2, phase, v=0.1):
    """Disks of diameters D1, D2 (in d) approach at relative speed 2 v sqrt(p/rho) from a gap they
    close in ``phase`` steps; the rebound's e."""
    d, V0 = der["d"], der["V0"]
    lmp = lammpslib.open_lammps()
    try:
        cell.header(lmp)
        r1, r2 = D1 * d / 2, D2 * d / 2
        L = 10 * d
        for c in (f"region box block {-L!r} {L!r} {-L!r} {L!r} {-d!r} {d!r}", "create_box 1 box",
                  "create_atoms 1 single 0.0 0.0 0.0 units box",
                  f"create_atoms 1 single {r1 + r2 + phase * 2 * v * V0 * der['dt']!r} 0.0 0.0 units box",
                  f"set atom 1 diameter {2 * r1!r}", f"set atom 2 diameter {2 * r2!r}"):
            lmp.command(c)
        cell.set_masses(lmp, der)
        lmp.command(contact.gran_hooke_history(scene, der)["command"])
        lmp.command("pair_coeff * *")
        lmp.command(f"neighbor {0.2 * d!r} bin")
        lmp.command(f"timestep {der['dt']!r}")
        lmp.command("fix move all nve/sphere disc")
        lmp.command("fix plane all enforce2d")
        lmp.command("velocity all set 0.0 0.0 0.0 units box")
        lmp.command(f"set atom 1 vx {v * V0!r}")
        lmp.command(f"set atom 2 vx {-v * V0!r}")
        vin = 2 * v * V0
        lmp.command("run 0")
        for _ in range(100000):
            lmp.command("run 10 pre no post no")
            x = cell.ordered(lmp, "x", 2)
            vel = cell.ordered(lmp, "v", 2)
            if x[1, 0] - x[0, 0] > r1 + r2 and vel[1, 0] - vel[0, 0] > 0:
                break
        return (vel[1, 0] - vel[0, 0]) / vin
    finally:
        lammpslib.close_lammps(lmp)


def main(argv):
    scene, _ = scenemod.load(argv[0])
    der = scenemod.derived(scene)
    d = der["d"]
    out = dict(dt_over_tc=scene["timestep"]["dt_over_tc"], restitution=scene["material"]["restitution"],
               pair_style=contact.gran_hooke_history(scene, der)["command"],
               pairs=[dict(D1=a, D2=b, e=restitution(scene, der, a, b),
                           e_theory=contact.pair_restitution(scene, der, a * d, b * d))
                      for a, b in placement.pair_sizes(scene)])
    print("RESTITUTION " + json.dumps(out), flush=True)
    if len(argv) > 1:
        with open(argv[1], "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
