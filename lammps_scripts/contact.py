"""The contact law of the LAMMPS stages: `pair gran/hooke/history` set from the scene.

Pure Python (no LAMMPS): the pair style's arguments and the restitution they give.

LAMMPS's linear spring-dashpot (Brilliantov et al.; LAMMPS manual, pair gran/hooke/history):

.. math:: F_n = k_n \\delta - m_{eff} \\gamma_n v_n, \\qquad
          F_t = -(k_t \\xi + m_{eff} \\gamma_t v_t), \\quad |F_t| \\le \\mu |F_n|

with m_eff = m_i m_j / (m_i + m_j). The dashpot is proportional to the pair's mass at a
fixed gamma_n, so its damping ratio zeta = (gamma_n / 2) sqrt(m_eff / k_n) and with it the
restitution e = exp(-pi zeta / sqrt(1 - zeta^2)) vary over the pairs. gamma_n is set so that
the reference pair, two disks of diameter d (m_eff = m_d / 2), has the scene's restitution,
as YADE's ViscElMat gives every pair: zeta_ref = beta = -ln e / sqrt(pi^2 + ln^2 e).
"""
import math

#: pair gran/hooke/history's tangential damping flag: 1 with the tangential dashpot (viscel), 0 without.
DAMPFLAG = {"viscel": 1, "frictvisco": 0}


def damping_ratio(e):
    """beta = -ln e / sqrt(pi^2 + ln^2 e): the damping ratio of a linear spring-dashpot of restitution e."""
    return -math.log(e) / math.sqrt(math.pi**2 + math.log(e) ** 2)


def reference_mass(der):
    """m_eff of the reference pair, two disks of diameter d: m_d / 2."""
    return der["m_d"] / 2


def gran_hooke_history(scene, der, friction=None):
    """The arguments of `pair_style gran/hooke/history` for the scene (SI).

    gamma_n = 2 beta sqrt(k_n / m_ref), gamma_t = 2 beta sqrt(k_t / m_ref) (1/s): the reference
    pair's normal and tangential dashpots are those of YADE's ViscElMat with en = et = e.
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
    beta = damping_ratio(m["restitution"])
    mref = reference_mass(der)
    law = m["contact_law"]
    out = dict(kn=der["kn"], kt=der["kt"], gamma_n=2 * beta * math.sqrt(der["kn"] / mref),
               gamma_t=2 * beta * math.sqrt(der["kt"] / mref), xmu=m["friction"] if friction is None else friction,
               dampflag=DAMPFLAG[law], limit_damping=law == "viscel")
    out["command"] = ("pair_style gran/hooke/history {kn!r} {kt!r} {gamma_n!r} {gamma_t!r} {xmu!r} {dampflag}"
                      .format(**out) + (" limit_damping" if out["limit_damping"] else ""))
    return out


def disk_mass(der, D):
    """Mass of a disk of diameter D and thickness d: rho pi D^2 d / 4."""
    return der["rho"] * math.pi * D**2 / 4 * der["d"]


def pair_restitution(scene, der, D1, D2):
    """The restitution gran/hooke/history gives two grains of diameters D1, D2 (m), in continuous time:
    e = exp(-pi zeta / sqrt(1 - zeta^2)), zeta = (gamma_n / 2) sqrt(m_eff / k_n) (the clamp of the
    normal force at zero and the time step change it slightly: tools/lammps_restitution.py measures it)."""
    m1, m2 = disk_mass(der, D1), disk_mass(der, D2)
    zeta = gran_hooke_history(scene, der)["gamma_n"] / 2 * math.sqrt(m1 * m2 / (m1 + m2) / der["kn"])
    return math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)) if zeta < 1 else 0.0
