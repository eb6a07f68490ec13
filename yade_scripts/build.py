"""Build the sheared cell: periodic in x, two rough walls of disks of diameter d,
quasi-2D grains (spheres held in the xy plane with disk masses and inertias).

Layout (stored in O.tags['ys_layout'] so that every later stage finds it):
- grains have ids 0..N-1 (so that per-body lists from YADE's C++ helpers can be
  sliced), then the bottom wall's disks, then the top wall's disks and the top
  clump.
- the bottom wall's centre line is at y = y_bottom; its disks are fixed and move
  at a prescribed x-velocity.
- the top wall is a clump free in y only, loaded by a permanent force -p W d.
"""
import json
import math

import placement
from placement import PlacementError, loose_placement, seeded_diameters  # noqa: F401  (build.PlacementError; the periodic cell)

from yade import utils
from yade.minieigenHP import Matrix3, Vector3
from yade.wrapper import FrictViscoMat, Omega, ViscElMat

O = Omega()


def contact_material(scene, der, radius):
    """ViscElMat for a disk of this radius, with young = kn/R (kn = kappa p d, scene.derived).

    YADE's Ip2 gives each side k_i = 2 E_i R_i = 2 kn, and the two combine in
    series to kn whatever the radii; poisson = kt/kn gives ks = kt; en = et =
    restitution becomes a dashpot from the masses of each pair.
    """
    m, kn = scene["material"], der["kn"]
    if m["contact_law"] == "frictvisco":
        return frictvisco_material(scene, der, radius)
    mat = ViscElMat(
        young=kn / radius, poisson=m["kt_over_kn"], en=m["restitution"], et=m["restitution"],
        frictionAngle=math.atan(m["friction"]), density=m["density"])
    rr = scene["effects"]["rolling_resistance"]
    if rr > 0:
        mat.mR = rr
        mat.mRtype = 1
    return O.materials.append(mat)


def frictvisco_material(scene, der, radius):
    """FrictViscoMat for a disk of this radius: the same kn, kt and Coulomb friction as ViscElMat.

    Ip2_FrictViscoMat gives kn = E_1 R_1 E_2 R_2 / (E_1 R_1 + E_2 R_2) * 2 = kn with E = kn/R,
    kt = poisson kn, and a normal dashpot c_n = beta 2 sqrt(m_eff kn) with
    beta = -ln e / sqrt(pi^2 + ln^2 e), the restitution e of a linear spring-dashpot.
    Unlike ViscEl: no tangential dashpot, and the normal force is not clamped at zero.
    """
    m, kn = scene["material"], der["kn"]
    e = m["restitution"]
    beta = -math.log(e) / math.sqrt(math.pi**2 + math.log(e) ** 2)
    if scene["effects"]["rolling_resistance"] > 0:
        raise ValueError("effects.rolling_resistance needs material.contact_law = viscel")
    return O.materials.append(FrictViscoMat(
        young=kn / radius, poisson=m["kt_over_kn"], betan=beta, frictionAngle=math.atan(m["friction"]),
        density=m["density"]))


def set_disk(body, radius, rho, depth):
    """Disk mass and moment of inertia (thickness `depth`), motion held in the xy plane."""
    mass = rho * math.pi * radius**2 * depth
    body.state.mass = mass
    body.state.inertia = Vector3(1, 1, 1) * (0.5 * mass * radius**2)


def add_disks(scene, der, positions, diameters):
    """Add the disks (held in the plane, masses and inertias of disks) to O.bodies; return their ids."""
    grains, rho, d = [], der["rho"], der["d"]
    for (x, y), D in zip(positions, diameters):
        b = utils.sphere(Vector3(x, y, 0), D / 2, material=contact_material(scene, der, D / 2))
        set_disk(b, D / 2, rho, d)
        b.state.blockedDOFs = "zXY"
        grains.append(O.bodies.append(b))
    return grains


def new_cell(scene, der):
    """Create the loose cell of the pack stage. Returns the layout dict."""
    if scene["cell"]["kind"] == "periodic":
        return new_periodic_cell(scene, der)
    O.reset()
    d, rho, W = der["d"], der["rho"], der["W"]
    cell = placement.wall_cell(scene, der)
    N, y_bottom, y_top = len(cell["diameters"]), cell["y_bottom"], cell["y_top"]
    O.periodic = True
    O.cell.setBox(W, y_top + 4 * d + 2 * cell["H0"], 4 * d * scene["material"]["size_ratio_max"])
    grains = add_disks(scene, der, cell["positions"], cell["diameters"])
    n_w = der["n_wall"]
    wall_mat = contact_material(scene, der, d / 2)
    bottom = []
    for x, y in cell["bottom"]:
        b = utils.sphere(Vector3(x, y, 0), d / 2, material=wall_mat, fixed=True)
        set_disk(b, d / 2, rho, d)
        b.state.blockedDOFs = "xyzXYZ"
        bottom.append(O.bodies.append(b))
    top_members = []
    for x, y in cell["top"]:
        b = utils.sphere(Vector3(x, y, 0), d / 2, material=wall_mat)
        set_disk(b, d / 2, rho, d)
        top_members.append(b)
    clump_id, top = O.bodies.appendClumped(top_members)
    top = list(top)
    cl = O.bodies[clump_id]
    m_wall = n_w * rho * math.pi * d**2 / 4 * d
    cl.state.mass = m_wall
    cl.state.inertia = Vector3(1, 1, 1) * m_wall * W**2  # rotation is blocked anyway
    cl.state.blockedDOFs = "xzXYZ"
    layout = dict(N=N, grains=[grains[0], grains[-1] + 1], bottom=bottom, top=top, clump=clump_id,
                  y_bottom=y_bottom, n_wall=n_w)
    assert grains == list(range(N)), "grains must have ids 0..N-1"
    O.tags["ys_layout"] = json.dumps(layout)
    return layout


def layout():
    return json.loads(O.tags["ys_layout"])


def quench_grains(lay):
    """Set every grain's velocity and angular velocity to zero (and the top wall's vertical speed).

    Used once, at the start of the pack's settling: the rattlers (grains without contacts)
    keep their speed in free flight, where Cundall damping does not act, and cross their
    cages in tens of time units; a packing out of equilibrium picks its speed up again
    within the settling's first check interval, so the settling criterion still tests it.
    """
    zero = Vector3(0, 0, 0)
    for i in range(lay["N"]):
        s = O.bodies[i].state
        s.vel = zero
        s.angVel = zero
    if lay.get("kind") != "periodic":
        cl = O.bodies[lay["clump"]].state
        cl.vel = Vector3(cl.vel[0], 0, 0)


def set_wall_damped(lay, damped):
    """Whether the NewtonIntegrator's Cundall damping acts on the top wall (State.isDamped of the clump;
    a periodic cell has no wall body: nothing to do)."""
    if lay.get("kind") != "periodic":
        O.bodies[lay["clump"]].state.isDamped = bool(damped)


def set_friction(mu):
    """Coulomb friction coefficient ``mu`` on every material and every existing interaction.

    Materials get frictionAngle = atan(mu) (the Ip2 functors give new contacts
    tan(min(angle_1, angle_2)) = mu); existing contacts get
    phys.tangensOfFrictionAngle = mu, the coefficient of the Coulomb limit
    |f_t| <= mu f_n in Law2_ScGeom_ViscElPhys_Basic and Law2_ScGeom_FrictViscoPhys_CundallStrackVisco.
    Lowering mu on a static packing is not neutral; raising it is (the Coulomb cone only widens).
    """
    angle = math.atan(mu)
    for m in O.materials:
        m.frictionAngle = angle
    for i in O.interactions:
        if i.isReal:
            i.phys.tangensOfFrictionAngle = mu


def set_wall_load(lay, force):
    """Permanent force on the top clump (not saved with the state: set after every load)."""
    if lay.get("kind") == "periodic":
        set_cell_load(lay, force)
        return
    O.forces.setPermF(lay["clump"], Vector3(0, -force, 0))


def set_wall_speeds(lay, u_top, u_bottom):
    if lay.get("kind") == "periodic":  # the same nominal shear rate: (u_top - u_bottom) / H
        set_shear_rate((u_top - u_bottom) / lay["H"])
        return
    cl = O.bodies[lay["clump"]].state
    cl.vel = Vector3(u_top, cl.vel[1], 0)
    for i in lay["bottom"]:
        O.bodies[i].state.vel = Vector3(u_bottom, 0, 0)


def new_periodic_cell(scene, der):
    """Create the loose periodic cell of the pack stage (cell.kind = periodic). Returns the layout dict.

    A box periodic in x and y, width W, height H0 = H guess/initial (the packed height is then
    close to H); z size 4 d size_ratio_max so that the collider accepts the largest disk.
    No walls: the layout has kind 'periodic' and the cell mass M = cell.mass * (W/d) m_d (the
    wall cell's top-wall mass).
    """
    O.reset()
    d, W, H = der["d"], der["W"], der["H"]
    m, pk = scene["material"], scene["pack"]
    rnd, diam = seeded_diameters(scene, der)
    N = len(diam)
    H0 = H * pk["solid_fraction_guess"] / pk["initial_solid_fraction"]
    O.periodic = True
    O.cell.setBox(W, H0, 4 * d * m["size_ratio_max"])
    O.cell.homoDeform = 2  # Lees-Edwards: particle velocities follow changes of velGrad
    pos = loose_placement(rnd, diam, W, 0.0, H0, periodic_y=True)
    grains = add_disks(scene, der, pos, diam)
    assert grains == list(range(N)), "grains must have ids 0..N-1"
    lay = dict(kind="periodic", N=N, grains=[0, N], n_wall=0, d=d, W=W, H=H, area=sum(math.pi * D * D / 4 for D in diam),
               x_shift=0.0)
    O.tags["ys_layout"] = json.dumps(lay)
    set_cell_load(lay, scene["pack"]["compaction_pressure"] * der["p"] * W * d)
    return lay


def set_shear_rate(gammadot):
    """Impose d v_x / d y = gammadot, keeping the cell's other velocity gradient components.

    Called every step (the sinusoidal transition, PyRunner labelled 'wallspeed' after
    NewtonIntegrator), a Python write of velGrad replaces the whole tensor at the next
    NewtonIntegrator, so the PeriTriaxController's update of velGrad_yy in that step is lost:
    it is redone here with the controller's own law,
    velGrad_yy += dt (goal_yy - sigma_yy) / m_c, limited to its maxStrainRate.
    """
    L = O.cell.velGrad
    vyy = float(L[1, 1])
    ctl = [e for e in O.engines if e.label == CELL_CONTROLLER]
    if ctl and any(e.label == "wallspeed" for e in O.engines):
        c = ctl[0]
        vyy += O.dt * (float(c.goal[1]) - float(utils.getStress()[1, 1])) / c.mass
        cap = float(c.maxStrainRate[1])
        vyy = max(-cap, min(cap, vyy))
    O.cell.velGrad = Matrix3(L[0, 0], gammadot, L[0, 2], L[1, 0], vyy, L[1, 2], L[2, 0], L[2, 1], L[2, 2])


CELL_CONTROLLER = "cellctl"


def cell_goal(lay, force):
    """PeriTriaxController's goal sigma_yy (3D, YADE's sign) for a load `force` = sigma_yy W d."""
    return -force / (lay["W"] * float(O.cell.hSize[2, 2]))


def set_cell_load(lay, force):
    """The load of the periodic cell's controller (kept in O.tags so that engines built later find it)."""
    O.tags["ys_cell_load"] = repr(float(force))
    for e in O.engines:
        if e.label == CELL_CONTROLLER:
            e.goal = Vector3(0, cell_goal(lay, force), 0)


def flip_cell():
    """Keep the sheared cell's skew within half a period: flip by whole periods (the same
    Lees-Edwards images) and add the removed shear displacement to layout x_shift."""
    h = O.cell.hSize
    if abs(float(h[0, 1])) <= 0.5 * float(h[0, 0]):
        return
    before = float(h[0, 1])
    O.cell.flipCell()
    h = O.cell.hSize
    if abs(float(h[1, 0])) > 1e-12 * float(h[0, 0]) or float(h[1, 1]) <= 0:
        # flipCell also reduces the first column against the second when W > 1.15 L_y
        print(f"flipCell mixed the cell's axes (hSize = {h}): the periodic cell needs W <= 1.1 H", flush=True)
        O.pause()
        return
    lay = json.loads(O.tags["ys_layout"])
    lay["x_shift"] = lay.get("x_shift", 0.0) + before - float(O.cell.hSize[0, 1])
    O.tags["ys_layout"] = json.dumps(lay)
