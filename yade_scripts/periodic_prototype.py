"""Prototype of the periodic bulk cell (issue 16, part 1): physics validation only.

    OMP_NUM_THREADS=1 yade -n -x yade_scripts/periodic_prototype.py \
        --law frictvisco --servo inertial --I 5e-3 --seed 1 --strain 1.5 --out /tmp/per/run1

A periodic 2D cell (x and y periodic, disks held in the xy plane, cell z size
4 d * size_ratio_max) packed isotropically to p, then sheared by
O.cell.velGrad[0,1] = gammadot (Lees-Edwards through YADE's homoDeform), with
sigma_yy = p held by the cell height. Material and scales as the quick preset:
d = 1 mm, rho = 2500, p = 1e5 Pa, kappa = 1e3, kt/kn = 0.5, e = 0.5,
friction 0.45, diameters uniform in [0.5, 1.5] d, dt = 0.1 sqrt(m_d/kn).

Contact laws (--law):
- viscel: ViscElMat + Law2_ScGeom_ViscElPhys_Basic, as the wall cell. In
  YADE 2023.02a this law adds the periodic image's velocity shift with the
  wrong sign (relative velocity v1 - v2 + shiftVel instead of v1 - v2 -
  shiftVel): every contact across the sheared y boundary sees a spurious
  relative velocity of 2 gammadot L_y (see --check-shift).
- frictvisco: FrictViscoMat + Law2_ScGeom_FrictViscoPhys_CundallStrackVisco:
  the same linear kn, kt = kt_over_kn kn, Coulomb friction, and a normal
  dashpot cn = beta 2 sqrt(m_eff kn) with beta = -ln e / sqrt(pi^2 + ln^2 e)
  (restitution e); it takes the relative velocity from ScGeom, whose periodic
  shift is right. Unlike ViscEl it has no tangential dashpot and does not
  clamp the normal force at zero.

Height control (--servo):
- first:    velGrad_yy = g (sigma_yy - p) / p / T0, every --every steps (massless).
- inertial: M dv/dt = (sigma_yy - p) W d, velGrad_yy = v / L_y, every --every
  steps; M = the wall cell's top-wall mass (W/d disks of diameter d) * --mass.
- ptc:      PeriTriaxController(dynCell=True) on yy only, with the same M
  (its "mass" is M L_y / (W L_z) in its own units), growDamping --damp.
sigma is the Love-Weber stress over the cell from utils.getStress, which is
tension positive (negative in compression), times L_z / d to give the 2D stress of
disks of thickness d: s_yy = -sigma_yy is the compressive normal stress, and the
tension-positive sigma_xy is > 0 for a positive shear rate; mu = |sigma_xy| / s_yy.
Fabric: A = F - I/2 from utils.fabricTensor over all contacts, |A| = sqrt(2 (A_xx^2 +
A_xy^2)), theta_A = atan2(A_xy, A_xx) / 2 mod 180 deg, as measure.py and the tests.
"""
import argparse
import json
import math
import os
import random
import sys
import time

import numpy as np
from yade import utils
import yade._utils as yu
from yade.minieigenHP import Matrix3, Vector3
from yade.wrapper import (
    Bo1_Sphere_Aabb, ForceResetter, FrictViscoMat, Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider,
    InteractionLoop, Ip2_FrictViscoMat_FrictViscoMat_FrictViscoPhys, Ip2_ViscElMat_ViscElMat_ViscElPhys,
    Law2_ScGeom_FrictViscoPhys_CundallStrackVisco, Law2_ScGeom_ViscElPhys_Basic, NewtonIntegrator, Omega,
    PeriTriaxController, PyRunner, ViscElMat)

O = Omega()
D, RHO, P, KAPPA, KT, EN, FRIC, SMIN, SMAX, DTF = 1e-3, 2500.0, 1e5, 1e3, 0.5, 0.5, 0.45, 0.5, 1.5, 0.1
KN = KAPPA * P * D
M_D = RHO * math.pi * D**2 / 4 * D
TC = math.sqrt(M_D / KN)
T0 = D * math.sqrt(RHO / P)
V0 = math.sqrt(P / RHO)
LZ = 4 * D * SMAX


def parse(argv):
    ap = argparse.ArgumentParser()
    ap.add_argument("--law", choices=["viscel", "frictvisco"], default="frictvisco")
    ap.add_argument("--servo", choices=["first", "inertial", "ptc"], default="inertial")
    ap.add_argument("--I", type=float, default=5e-3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--N", type=int, default=500)
    ap.add_argument("--strain", type=float, default=1.5)
    ap.add_argument("--steady-from", type=float, default=0.5)
    ap.add_argument("--every", type=int, default=5, help="steps between servo updates (first, inertial)")
    ap.add_argument("--gain", type=float, default=1.0, help="first-order servo gain")
    ap.add_argument("--mass", type=float, default=1.0, help="cell mass over the wall cell's top-wall mass")
    ap.add_argument("--damp", type=float, default=0.0, help="PeriTriaxController growDamping")
    ap.add_argument("--homo", type=int, default=2, help="Cell.homoDeform")
    ap.add_argument("--dtf", type=float, default=DTF)
    ap.add_argument("--sample", type=float, default=0.01, help="sampling interval in strain")
    ap.add_argument("--out", required=True)
    ap.add_argument("--check-shift", action="store_true", help="only run the two-pair shift test")
    return ap.parse_args(argv)


def material(law, radius):
    if law == "viscel":
        return O.materials.append(ViscElMat(young=KN / radius, poisson=KT, en=EN, et=EN,
                                            frictionAngle=math.atan(FRIC), density=RHO))
    beta = -math.log(EN) / math.sqrt(math.pi**2 + math.log(EN) ** 2)
    return O.materials.append(FrictViscoMat(young=KN / radius, poisson=KT, betan=beta,
                                            frictionAngle=math.atan(FRIC), density=RHO))


def engines(law, extra):
    if law == "viscel":
        ip, lw = Ip2_ViscElMat_ViscElMat_ViscElPhys(), Law2_ScGeom_ViscElPhys_Basic()
    else:
        ip, lw = Ip2_FrictViscoMat_FrictViscoMat_FrictViscoPhys(), Law2_ScGeom_FrictViscoPhys_CundallStrackVisco()
    return [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()], label="collider"),
            InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [ip], [lw]),
            NewtonIntegrator(damping=0.0, gravity=Vector3(0, 0, 0), label="newton")] + extra


def stress2d():
    """2D stress (Pa, thickness d), tension positive: getStress * L_z / d.

    YADE's getStress is sum f l / V with V = L_x L_y L_z, negative in compression.
    """
    s = yu.getStress()
    f = O.cell.size[2] / D
    return np.array([[float(s[0, 0]), float(s[0, 1])], [float(s[1, 0]), float(s[1, 1])]]) * f


def disk(x, y, r, mat):
    b = utils.sphere(Vector3(x, y, 0), r, material=mat)
    m = RHO * math.pi * r**2 * D
    b.state.mass = m
    b.state.inertia = Vector3(1, 1, 1) * 0.5 * m * r**2
    b.state.blockedDOFs = "zXY"
    return O.bodies.append(b)


def pack(a):
    """Loose random placement at phi 0.4 in a square periodic box, then isotropic compression to p."""
    O.reset()
    O.periodic = True
    rnd = random.Random(a.seed)
    diam = sorted((D * rnd.uniform(SMIN, SMAX) for _ in range(a.N)), reverse=True)
    area = sum(math.pi * x**2 / 4 for x in diam)
    L = math.sqrt(area / 0.4)
    O.cell.setBox(L, L, LZ)
    O.cell.homoDeform = a.homo
    pos = []
    for Dk in diam:
        for _ in range(100000):
            x, y = rnd.uniform(0, L), rnd.uniform(0, L)
            ok = True
            for (xj, yj, Dj) in pos:
                dx = x - xj
                dx -= L * round(dx / L)
                dy = y - yj
                dy -= L * round(dy / L)
                if dx * dx + dy * dy < ((Dk + Dj) / 2) ** 2:
                    ok = False
                    break
            if ok:
                pos.append((x, y, Dk))
                break
        else:
            raise RuntimeError("placement failed")
    for x, y, Dk in pos:
        disk(x, y, Dk / 2, material(a.law, Dk / 2))
    O.dt = a.dtf * TC
    O.engines = engines(a.law, [])
    # packing only: Cundall damping 0.3 to settle fast (the protocol of the packing is not under test)
    O.engines[3].damping = 0.3
    rate_max = 0.02 / T0
    print(f"placed {len(pos)} disks in a {L / D:.1f} d box", flush=True)
    t0 = time.time()
    ok = 0
    while True:
        O.run(50, True)
        s = stress2d()
        vg = Matrix3(0, 0, 0, 0, 0, 0, 0, 0, 0)
        for i in (0, 1):
            e = (-s[i, i] - P) / P  # > 0: too compressed -> expand
            # gain 5e-4/T0: with a bulk stiffness of about kappa p / 2 the stress relaxes in about 4 T0
            vg[i, i] = -rate_max if -s[i, i] < 0.3 * P else max(-rate_max, min(rate_max, 5e-4 * e / T0))
        O.cell.velGrad = vg
        ub = float(utils.unbalancedForce())
        good = abs(-s[0, 0] / P - 1) < 0.01 and abs(-s[1, 1] / P - 1) < 0.01 and ub < 0.02
        ok = ok + 1 if good else 0
        if O.iter % 2000 == 0:
            print(f"  pack t {O.time / T0:.1f} s_xx {-s[0, 0] / P:.3f} s_yy {-s[1, 1] / P:.3f} ub {ub:.3g} "
                  f"phi {area / (O.cell.size[0] * O.cell.size[1]):.3f} ({time.time() - t0:.0f} s)", flush=True)
        if ok >= 5 or O.time > 400 * T0:
            break
    O.engines[3].damping = 0.0
    O.cell.velGrad = Matrix3(0, 0, 0, 0, 0, 0, 0, 0, 0)
    O.run(2, True)
    s = stress2d()
    phi = area / (O.cell.size[0] * O.cell.size[1])
    print(f"packed: t = {O.time / T0:.1f} T0, {time.time() - t0:.1f} s, phi {phi:.4f}, "
          f"s_xx {-s[0, 0] / P:.4f} s_yy {-s[1, 1] / P:.4f}, L {O.cell.size[0] / D:.2f} x {O.cell.size[1] / D:.2f} d",
          flush=True)
    return area


class Shear:
    def __init__(self, a, area):
        self.a, self.area = a, area
        self.gd = a.I / T0
        self.W = float(O.cell.size[0])
        self.M = (self.W / D) * M_D * a.mass
        self.vy = 0.0
        self.strain = 0.0
        self.rows = []
        self.k = 0
        dt = O.dt
        self.steps_sample = max(1, int(round(a.sample / (self.gd * dt))))
        self.n_steps = int(math.ceil(a.strain / (self.gd * dt)))
        extra = []
        O.cell.trsf = Matrix3(1, 0, 0, 0, 1, 0, 0, 0, 1)
        if a.servo in ("first", "inertial"):
            extra.append(PyRunner(command="_servo()", iterPeriod=a.every, label="servo"))
        else:
            Ly = float(O.cell.hSize[1, 1])
            extra.append(PeriTriaxController(
                dynCell=True, goal=Vector3(0, -P * D / LZ, 0), stressMask=0b010,
                maxStrainRate=Vector3(0, 1.0 / T0, 0), mass=self.M * Ly / (self.W * LZ), growDamping=a.damp,
                globUpdate=1, relStressTol=1e9, absStressTol=1e99, maxUnbalanced=-1, label="ptc"))
        extra.append(PyRunner(command="_sample()", iterPeriod=self.steps_sample, label="sampler"))
        O.engines = engines(a.law, []) + extra
        import builtins
        builtins._servo = self.servo
        builtins._sample = self.sample
        O.cell.velGrad = Matrix3(0, self.gd, 0, 0, 0, 0, 0, 0, 0)

    def servo(self):
        a = self.a
        s = stress2d()
        syy = -s[1, 1]
        Ly = float(O.cell.hSize[1, 1])  # not O.cell.size[1], the length of the sheared column
        if a.servo == "first":
            vgyy = a.gain * (syy - P) / P / T0
        else:
            self.vy += a.every * O.dt * (syy - P) * self.W * D / self.M
            vgyy = self.vy / Ly
        O.cell.velGrad = Matrix3(0, self.gd, 0, 0, vgyy, 0, 0, 0, 0)

    def sample(self):
        self.strain = (O.iter + 1 - self.iter0) * O.dt * self.gd
        s = stress2d()
        F = yu.fabricTensor()[0]
        axx = float(F[0, 0]) - 0.5
        axy = 0.5 * (float(F[0, 1]) + float(F[1, 0]))
        nint = np.asarray(yu.numIntrsOfEachBody(), dtype=float)
        Ly = float(O.cell.hSize[1, 1])  # O.cell.size[1] is the sheared column's length: phi 4 % low
        vg = O.cell.velGrad
        self.rows.append(dict(strain=self.strain, s_xy=float(s[0, 1] + s[1, 0]) / 2 / P, s_yy=-s[1, 1] / P,
                              s_xx=-s[0, 0] / P, A_xx=axx, A_xy=axy, phi=self.area / (self.W * Ly),
                              Z=float(nint.mean()), Ly=Ly / D, vgyy=float(vg[1, 1]) * T0, vgxy=float(vg[0, 1]) * T0))
        # keep the cell's skew small: flip by whole periods (Lees-Edwards images)
        h = O.cell.hSize
        if abs(float(h[0, 1]) / float(h[1, 1])) > 0.5:
            O.cell.flipCell()

    def run(self):
        self.iter0 = O.iter
        t0 = time.time()
        O.run(self.n_steps, True)
        self.wall = time.time() - t0
        self.pps = self.n_steps * len(O.bodies) / self.wall


def stats(rows, frm):
    r = [x for x in rows if x["strain"] >= frm] or rows
    out = {}
    arr = {k: np.array([x[k] for x in r]) for k in r[0]}
    # tau > 0 resisting a positive shear rate: tension-positive s_xy > 0 (getStress sign: see below)
    sxy = arr["s_xy"]
    mu = np.abs(sxy) / arr["s_yy"]
    amag = np.sqrt(2 * (arr["A_xx"] ** 2 + arr["A_xy"] ** 2))
    th = np.degrees(np.arctan2(arr["A_xy"], arr["A_xx"]) / 2) % 180
    for k, v in dict(mu=mu, s_xy=sxy, s_yy=arr["s_yy"], s_xx=arr["s_xx"], A=amag, theta=th, phi=arr["phi"],
                     Z=arr["Z"]).items():
        out[k] = (float(np.mean(v)), float(np.std(v)))
    # fabric of the mean tensor
    mx, my = arr["A_xx"].mean(), arr["A_xy"].mean()
    out["A_of_mean"] = float(math.sqrt(2 * (mx * mx + my * my)))
    out["theta_of_mean"] = float(np.degrees(math.atan2(my, mx) / 2) % 180)
    out["n"] = len(r)
    return out


def check_shift(law):
    """Two touching pairs, one inside the cell and one across the y boundary, moving with the affine field:
    their shear-force increments must be equal."""
    O.reset()
    O.periodic = True
    H = W = 10 * D
    O.cell.setBox(W, H, LZ)
    mat = material(law, D / 2)
    ov = 0.01 * D
    dy = math.sqrt((D - ov) ** 2 - (0.2 * D) ** 2)
    for (x, y, x2, y2) in ((2 * D, 4 * D, 2.2 * D, 4 * D + dy), (6 * D, H - 0.3 * D, 6.2 * D, H - 0.3 * D + dy - H)):
        for (xx, yy) in ((x, y), (x2, y2)):
            b = utils.sphere(Vector3(xx, yy, 0), D / 2, material=mat)
            b.state.blockedDOFs = "xyzXYZ"
            O.bodies.append(b)
    O.engines = engines(law, [])
    O.cell.velGrad = Matrix3(0, 10.0, 0, 0, 0, 0, 0, 0, 0)
    O.dt = 1e-7
    O.run(3, True)
    out = {}
    for i in O.interactions:
        out[str(tuple(i.cellDist))] = [float(x) for x in i.phys.shearForce]
    print(law, json.dumps(out), flush=True)
    return out


def main(argv):
    a = parse(argv)
    os.makedirs(a.out, exist_ok=True)
    if a.check_shift:
        res = {law: check_shift(law) for law in ("viscel", "frictvisco")}
        json.dump(res, open(os.path.join(a.out, "shift_check.json"), "w"), indent=1)
        return
    cache = f"/tmp/per_pack_{a.law}_{a.seed}_{a.N}_{a.homo}_{a.dtf}.yade.gz"
    t0 = time.time()
    if os.path.exists(cache):
        O.load(cache)
        area = float(O.tags["area"])
    else:
        area = pack(a)
        O.tags["area"] = repr(area)
        O.save(cache)
    t_pack = time.time() - t0
    sh = Shear(a, area)
    sh.run()
    st = stats(sh.rows, a.steady_from)
    st.update(vars(a))
    st.update(pps=sh.pps, wall_s=sh.wall, t_pack_s=t_pack, N=len(O.bodies), steps=sh.n_steps)
    with open(os.path.join(a.out, "series.csv"), "w") as f:
        keys = list(sh.rows[0])
        f.write(",".join(keys) + "\n")
        for r in sh.rows:
            f.write(",".join(repr(r[k]) for k in keys) + "\n")
    json.dump(st, open(os.path.join(a.out, "summary.json"), "w"), indent=1)
    print("RESULT", json.dumps({k: st[k] for k in ("law", "servo", "I", "seed", "mu", "s_xy", "s_yy", "A", "theta",
                                                   "A_of_mean", "theta_of_mean", "phi", "Z", "pps", "wall_s")}),
          flush=True)


try:
    main(sys.argv[1:])
except SystemExit as e:
    sys.stdout.flush()
    os._exit(e.code or 0)
except BaseException:
    import traceback
    traceback.print_exc()
    sys.stdout.flush()
    os._exit(1)
sys.stdout.flush()
os._exit(0)
