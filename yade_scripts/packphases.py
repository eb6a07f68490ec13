"""The pack stage's phases, compress -> ramp -> settle -> done (docs/scene.md, Packing), as pure
functions of the stage's state: yade_scripts/packing.py and lammps_scripts/packing.py call them at
every check (every pack.check_interval) and act on the phases entered.

Pure Python (no YADE, no LAMMPS). The state ``st`` holds ``phase``, ``phase_steps`` (the steps each
finished phase took), ``load`` (the top wall's load, N), ``ramp_start``, ``pack_ok`` (checks in a
row that passed the settling's criteria) and, once done, ``converged_at_t``.
"""


def damping(scene, phase):
    """Cundall damping of the grains in ``phase``: pack.damping in the ramp and the settling;
    effects.damping in the compression (damped grains resist the falling wall and slow the creep of
    the packing under the compaction load: measured, docs/scene.md) and once done (the saved packing)."""
    return scene["pack"]["damping"] if phase in ("ramp", "settle") else scene["effects"]["damping"]


def friction(scene, phase):
    """The grains' friction coefficient in ``phase``: pack.friction (material.friction if null) in the
    compression and the ramp, material.friction from the settling on."""
    mu = scene["pack"]["friction"]
    if phase in ("compress", "ramp") and mu is not None:
        return mu
    return scene["material"]["friction"]


def enter(st, phase, steps):
    """Enter ``phase`` ``steps`` steps into the stage: the phase that ends gets its steps in st['phase_steps']."""
    ps = st.setdefault("phase_steps", {})
    ps[st["phase"]] = steps - sum(ps.values())
    st["phase"] = phase


def check(st, scene, der, t, steps, ke, wall_speed, pw):
    r"""One check of the pack's phases; returns the phases entered at it, in order.

    compress: the top wall moves under the compaction load (pack.compaction_pressure p W d) with the
    grains' friction at pack.friction, until jammed: wall speed below pack.wall_speed_max and
    ke below 100 pack.ke_max (a looser kinetic criterion: the low compaction load makes the last
    rattlers slow to calm down);
    ramp: the load goes linearly to p W d in pack.ramp_time,

    .. math:: F(t) = F_0 + (p W d - F_0) \min\left(1, \frac{t - t_{ramp}}{T_{ramp}}\right),

    and the settling starts once it is full (the engine then sets the grains' friction back to
    material.friction and, with pack.quench, the grains at rest);
    settle: done after two checks in a row with ke < pack.ke_max, wall speed < pack.wall_speed_max
    and |p_wall - p| < pack.pressure_tolerance p.

    Parameters
    ----------
    st : dict
        The stage's state (module docstring), updated.
    scene, der : dict
        The scene and scene.derived.
    t : float
        Simulated time, s; ``steps``: steps since the stage's start.
    ke, wall_speed, pw : float
        Mean squared grain velocity in p/rho, the top wall's speed in sqrt(p/rho), the wall
        pressure in p (the check's sample).
    """
    pk = scene["pack"]
    full = der["p"] * der["W"] * der["d"]
    entered = []
    if st["phase"] == "compress" and wall_speed < pk["wall_speed_max"] and ke < 100 * pk["ke_max"]:
        enter(st, "ramp", steps)
        entered.append("ramp")
        st["ramp_start"] = t
        print(f"[pack] jammed at the compaction load, t = {t / der['T0']:.1f}: ramping to p", flush=True)
    if st["phase"] == "ramp":
        f0 = pk["compaction_pressure"] * full
        ramp = pk["ramp_time"] * der["T0"]
        x = min(1.0, (t - st["ramp_start"]) / ramp) if ramp > 0 else 1.0
        st["load"] = f0 + (full - f0) * x
        if x >= 1.0:
            enter(st, "settle", steps)
            entered.append("settle")
            st["pack_ok"] = 0
    elif st["phase"] == "settle":
        ok = ke < pk["ke_max"] and wall_speed < pk["wall_speed_max"] and abs(pw - 1) < pk["pressure_tolerance"]
        st["pack_ok"] = st["pack_ok"] + 1 if ok else 0
        if st["pack_ok"] >= 2:
            st["converged_at_t"] = t / der["T0"]
            enter(st, "done", steps)
            entered.append("done")
    return entered
