"""The contact law of the LAMMPS stages: `pair gran/hooke/history` set from the scene.

Pure Python (no LAMMPS): the pair style's arguments and the restitution they give.

LAMMPS's linear spring-dashpot (Brilliantov et al.; LAMMPS manual, pair gran/hooke/history):

.. math:: F_n = k_n \\delta - m_{eff} \\gamma_n v_n, \\qquad
          F_t = -(k_t \\xi + m_{eff} \\gamma_t v_t), \\quad |F_t| \\le \\mu |F_n|

with m_eff = m_i m_j / (m_i + m_j). The dashpot is proportional to the pair's mass at a
fixed gamma_n, so its damping ratio zeta = (gamma_n / 2) sqrt(m_eff / k_n) and with it the
restitution e = exp(-pi zeta / sqrt(1 - zeta^2)) vary over the pairs. gamma_n is set so that
the reference pair, two disks of diameter d (m_eff = m_d / 2), rebounds with the scene's
restitution at the scene's time step (`reference_gamma_n`), as YADE's ViscElMat gives every
pair its restitution.
"""
import math

#: pair gran/hooke/history's tangential damping flag: 1 with the tangential dashpot (viscel), 0 without.
DAMPFLAG = {"viscel": 1, "frictvisco": 0}


def reference_mass(der):
    """m_eff of the reference pair, two disks of diameter d: m_d / 2."""
    return der["m_d"] / 2


PHASES = 8  # impact phases within a step over which a restitution is averaged


def rebound(kn, meff, gamma_n, dt, clamp, phase=0.0, v=1.0):
    """Restitution of a head-on collision of the linear spring-dashpot, integrated as LAMMPS does.

    The relative coordinate under m_eff ddot(delta) = -F, F = k_n delta - m_eff gamma_n dot(delta)
    (F clamped at >= 0 when ``clamp``, `limit_damping`) at speed v, from a gap of phase v dt, with
    velocity Verlet at the step dt (fix nve/sphere: half kick, drift, force, half kick);
    e = v_out / v. At dt = 0.1 sqrt(m_d/kn) e depends on where in a step the contact begins (by up
    to 0.03 with the clamp): `mean_rebound` averages over PHASES of them.
    """
    x, u = -phase * v * dt, v  # overlap and its rate
    f = 0.0
    for _ in range(10**6):
        u -= 0.5 * dt * f / meff
        x += dt * u
        f = kn * x + meff * gamma_n * u if x > 0 else 0.0
        if clamp:
            f = max(f, 0.0)
        u -= 0.5 * dt * f / meff
        if x <= 0 and u < 0:
            return -u / v
    raise RuntimeError("the two disks never separate: the dashpot is overdamped")


def mean_rebound(kn, meff, gamma_n, dt, clamp):
    """`rebound` averaged over PHASES impact phases k / PHASES, k = 0 .. PHASES - 1."""
    return sum(rebound(kn, meff, gamma_n, dt, clamp, k / PHASES) for k in range(PHASES)) / PHASES


def reference_gamma_n(scene, der):
    """gamma_n (1/s) with which two disks of diameter d rebound with material.restitution at the
    scene's dt on average over the impact phases (`mean_rebound`, the clamp as the contact law), by bisection on the damping ratio
    zeta = (gamma_n / 2) sqrt(m_ref / k_n) in [0, 0.99] (continuous time without the clamp:
    e = exp(-pi zeta / sqrt(1 - zeta^2)); the clamp and the step raise e a little at a given zeta)."""
    m = scene["material"]
    e, kn, mref, dt = m["restitution"], der["kn"], reference_mass(der), der["dt"]
    clamp = m["contact_law"] == "viscel"
    scale = 2 * math.sqrt(kn / mref)  # gamma_n = zeta * scale
    lo, hi = 0.0, 0.99
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if mean_rebound(kn, mref, mid * scale, dt, clamp) > e:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi) * scale


def gran_hooke_history(scene, der, friction=None):
    """The arguments of `pair_style gran/hooke/history` for the scene (SI).

    gamma_n = reference_gamma_n (the reference pair rebounds with e at dt), gamma_t =
    gamma_n sqrt(k_t / k_n) (1/s): the reference pair's tangential dashpot has the damping ratio of
    its normal one, as YADE's ViscElMat with en = et = e.
    material.contact_law viscel: tangential dashpot on (dampflag 1) and the normal force clamped
    at zero (`limit_damping`), as Law2_ScGeom_ViscElPhys_Basic; frictvisco: neither, as
    Law2_ScGeom_FrictViscoPhys_CundallStrackVisco.

    Parameters
    ----------
    friction : float, optional
        The Coulomb coefficient (default material.friction; the pack's compression uses pack.friction).

    Returns
    -------
    dict
        kn, kt (N/m), gamma_n, gamma_t (1/s), xmu, dampflag, limit_damping, and ``command``,
        the pair_style line.
    """
    m = scene["material"]
    gamma_n = reference_gamma_n(scene, der)
    law = m["contact_law"]
    out = dict(kn=der["kn"], kt=der["kt"], gamma_n=gamma_n, gamma_t=gamma_n * math.sqrt(der["kt"] / der["kn"]),
               xmu=m["friction"] if friction is None else friction,
               dampflag=DAMPFLAG[law], limit_damping=law == "viscel")
    out["command"] = ("pair_style gran/hooke/history {kn!r} {kt!r} {gamma_n!r} {gamma_t!r} {xmu!r} {dampflag}"
                      .format(**out) + (" limit_damping" if out["limit_damping"] else ""))
    return out


def disk_mass(der, D):
    """Mass of a disk of diameter D and thickness d: rho pi D^2 d / 4."""
    return der["rho"] * math.pi * D**2 / 4 * der["d"]


def pair_restitution(scene, der, D1, D2, gamma_n=None):
    """The restitution gran/hooke/history gives two grains of diameters D1, D2 (m) at the scene's dt
    (`mean_rebound` with their m_eff; tools/lammps_restitution.py measures it in LAMMPS)."""
    m1, m2 = disk_mass(der, D1), disk_mass(der, D2)
    gamma_n = reference_gamma_n(scene, der) if gamma_n is None else gamma_n
    return mean_rebound(der["kn"], m1 * m2 / (m1 + m2), gamma_n, der["dt"], scene["material"]["contact_law"] == "viscel")
