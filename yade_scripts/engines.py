"""The engine list, in one place, built from the scene's declared effects.

Nothing runs every step that the scene did not ask for: gravity, damping and
rolling resistance enter only when declared; Python runs only at the sampling
interval (and every step only during a sinusoidal transition, which needs the
wall speed set each step).
"""
from yade.minieigenHP import Vector3
from yade.wrapper import (
    Bo1_Sphere_Aabb, ForceResetter, GravityEngine, Ig2_Sphere_Sphere_ScGeom, Ig2_Sphere_Sphere_ScGeom6D,
    InsertionSortCollider, InteractionLoop, Ip2_ViscElMat_ViscElMat_ViscElPhys, Law2_ScGeom_ViscElPhys_Basic,
    NewtonIntegrator, PyRunner)


def build(scene, sample_every, sample_command, wall_command=None, wall_steps=0):
    """Return the engine list.

    sample_every: steps between samples (PyRunner, the stage's controller).
    wall_command: if given, a per-step PyRunner (sinusoidal transition) run
    `wall_steps` times.
    """
    fx = scene["effects"]
    ig2 = Ig2_Sphere_Sphere_ScGeom6D() if fx["rolling_resistance"] > 0 else Ig2_Sphere_Sphere_ScGeom()
    engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb()], label="collider"),
        InteractionLoop([ig2], [Ip2_ViscElMat_ViscElMat_ViscElPhys()], [Law2_ScGeom_ViscElPhys_Basic()]),
    ]
    if fx["gravity"]:
        gx, gy = fx["gravity"]
        engines.append(GravityEngine(gravity=Vector3(gx, gy, 0), label="gravity"))
    engines.append(NewtonIntegrator(damping=fx["damping"], gravity=Vector3(0, 0, 0), label="newton"))
    if wall_command is not None and wall_steps > 0:
        # before the sampler, so that a sample sees the speed of its own step
        engines.append(PyRunner(command=wall_command, iterPeriod=1, nDo=wall_steps, label="wallspeed"))
    engines.append(PyRunner(command=sample_command, iterPeriod=max(1, int(sample_every)), label="sampler"))
    return engines


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
        out.append(name)
    return out
