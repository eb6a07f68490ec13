"""The engine list, in one place, built from the scene's declared effects.

Nothing runs every step that the scene did not ask for: gravity, damping and
rolling resistance enter only when declared; Python runs only at the sampling
interval (and every step only during a sinusoidal transition, which needs the
wall speed set each step).
"""
import builtins
import json
import math

from yade.minieigenHP import Vector3
from yade.wrapper import (
    Bo1_Sphere_Aabb, ForceResetter, GravityEngine, Ig2_Sphere_Sphere_ScGeom, Ig2_Sphere_Sphere_ScGeom6D,
    InsertionSortCollider, InteractionLoop, Ip2_FrictViscoMat_FrictViscoMat_FrictViscoPhys,
    Ip2_ViscElMat_ViscElMat_ViscElPhys, Law2_ScGeom_FrictViscoPhys_CundallStrackVisco, Law2_ScGeom_ViscElPhys_Basic,
    NewtonIntegrator, Omega, PeriTriaxController, PyRunner)

import build as cellbuild

O = Omega()
FLIP_EVERY = 100  # steps between checks of the periodic cell's skew


def build(scene, sample_every, sample_command, wall_command=None, wall_steps=0, damping=None):
    """Return the engine list.

    damping: Cundall's local damping of the NewtonIntegrator, if not effects.damping
    (the pack stage's pack.damping, see `set_damping`).
    sample_every: steps between samples (PyRunner, the stage's controller).
    wall_command: if given, a per-step PyRunner (sinusoidal transition) run
    `wall_steps` times.
    """
    fx = scene["effects"]
    ig2 = Ig2_Sphere_Sphere_ScGeom6D() if fx["rolling_resistance"] > 0 else Ig2_Sphere_Sphere_ScGeom()
    if scene["material"]["contact_law"] == "frictvisco":
        ip2, law2 = Ip2_FrictViscoMat_FrictViscoMat_FrictViscoPhys(), Law2_ScGeom_FrictViscoPhys_CundallStrackVisco()
    else:
        ip2, law2 = Ip2_ViscElMat_ViscElMat_ViscElPhys(), Law2_ScGeom_ViscElPhys_Basic()
    engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb()], label="collider"),
        InteractionLoop([ig2], [ip2], [law2]),
    ]
    if scene["cell"]["kind"] == "periodic":
        engines.append(cell_controller(scene))
    if fx["gravity"]:
        gx, gy = fx["gravity"]
        engines.append(GravityEngine(gravity=Vector3(gx, gy, 0), label="gravity"))
    engines.append(NewtonIntegrator(damping=fx["damping"] if damping is None else damping, gravity=Vector3(0, 0, 0), label="newton"))
    if wall_command is not None and wall_steps > 0:
        # before the sampler, so that a sample sees the speed of its own step
        engines.append(PyRunner(command=wall_command, iterPeriod=1, nDo=wall_steps, label="wallspeed"))
    if scene["cell"]["kind"] == "periodic":
        builtins._ys_flip = cellbuild.flip_cell
        engines.append(PyRunner(command="_ys_flip()", iterPeriod=FLIP_EVERY, label="flip"))
    engines.append(PyRunner(command=sample_command, iterPeriod=max(1, int(sample_every)), label="sampler"))
    return engines


def set_damping(damping):
    """Cundall's local damping of the NewtonIntegrator in O.engines: each grain's force component f_i
    becomes f_i (1 - damping sign(f_i v_i)) (the same for torques)."""
    newton = [e for e in O.engines if isinstance(e, NewtonIntegrator)]
    if len(newton) != 1:
        raise RuntimeError(f"expected one NewtonIntegrator in O.engines, found {len(newton)}")
    newton[0].damping = damping


def cell_controller(scene):
    """PeriTriaxController holding sigma_yy of a periodic cell with inertia (cell.kind = periodic).

    dynCell: d(velGrad_yy)/dt = (goal - sigma_yy) / m_c, no damping of its own (growDamping 0),
    with m_c = M L_y / (W L_z), so that M d^2 L_y / dt^2 = (sigma_yy - p) W d (2D, compression
    positive) as for the wall cell's top wall of mass M; the width and depth stay fixed
    (strain-controlled at zero rate). The goal comes from the current load (build.set_cell_load).
    """
    lay = json.loads(O.tags["ys_layout"])
    m = scene["material"]
    T0 = m["diameter"] * math.sqrt(m["density"] / m["pressure"])
    h = O.cell.hSize
    Ly, Lz = float(h[1, 1]), float(h[2, 2])
    load = float(O.tags["ys_cell_load"])  # set by build.set_cell_load before the engines are built
    # from this stage's scene (the layout's M is the pack stage's)
    M = scene["cell"]["mass"] * (lay["W"] / lay["d"]) * m["density"] * math.pi * lay["d"] ** 3 / 4
    return PeriTriaxController(
        dynCell=True, stressMask=0b010, goal=Vector3(0, cellbuild.cell_goal(lay, load), 0),
        maxStrainRate=Vector3(0, 1.0 / T0, 0), mass=M * Ly / (lay["W"] * Lz), growDamping=0.0,
        globUpdate=1, relStressTol=1e9, absStressTol=1e99, maxUnbalanced=-1, label=cellbuild.CELL_CONTROLLER)


def describe(engines):
    """Engine list as names (for tests and the sidecar)."""
    out = []
    for e in engines:
        name = type(e).__name__
        if isinstance(e, InteractionLoop):
            name += "[" + ",".join(type(f).__name__ for f in list(e.geomDispatcher.functors)
                                   + list(e.physDispatcher.functors) + list(e.lawDispatcher.functors)) + "]"
        if isinstance(e, NewtonIntegrator) and e.damping > 0:
            name += f"(damping={e.damping:g})"
        if isinstance(e, PyRunner):
            name += f"({e.label})"
        if isinstance(e, PeriTriaxController):
            name += "(dynCell, sigma_yy)"
        out.append(name)
    return out
