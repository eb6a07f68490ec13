"""Measurements of one sample, with YADE's C++ helpers where they exist.

Conventions (docs/data-contract.md, docs/model.md): tension-positive Cauchy stress, p > 0 in compression,
sigma_xy > 0 when the top wall moving towards +x is dragged back.
A = -I/2 + mean n(x)n over the bulk contacts.
"""
import json
import math

import numpy as np
import yade._utils as yu
from yade.minieigenHP import Vector3
from yade.wrapper import Omega

from rows import COLUMNS, overlap_stats  # noqa: F401  (measure.COLUMNS, measure.overlap_stats)

O = Omega()
EX, EY = Vector3(1, 0, 0), Vector3(0, 1, 0)
BIG = 1e30


def walls(lay):
    """Positions, speeds and contact forces of the walls (SI); see periodic_walls for a periodic cell."""
    if lay.get("kind") == "periodic":
        return periodic_walls(lay, lay["d"], lay["W"])
    top = O.bodies[lay["clump"]].state
    bot = O.bodies[lay["bottom"][0]].state
    return dict(
        x_top=float(top.pos[0]), y_top=float(top.pos[1]), u_top=float(top.vel[0]), v_top=float(top.vel[1]),
        x_bot=float(bot.pos[0]), y_bot=float(bot.pos[1]), u_bot=float(bot.vel[0]),
        fx_top=float(yu.sumForces(lay["top"], EX)), fy_top=float(yu.sumForces(lay["top"], EY)),
        fx_bot=float(yu.sumForces(lay["bottom"], EX)), fy_bot=float(yu.sumForces(lay["bottom"], EY)))


class Bulk:
    """Bulk-band measurements: fabric, contacts, Love-Weber stress, solid fraction, Z."""

    def __init__(self, lay, d):
        self.N = lay["N"]
        self.d = d
        r = np.array([float(O.bodies[i].shape.radius) for i in range(self.N)])
        self.area = math.pi * r**2  # disk areas
        self.vol3 = 4.0 / 3.0 * math.pi * r**3  # bodyStressTensors divides by the sphere volume

    def measure(self, lay, y_lo, y_hi, W):
        N, d = self.N, self.d
        lo, hi = Vector3(-BIG, y_lo, -BIG), Vector3(BIG, y_hi, BIG)
        F = yu.fabricTensor(extrema=[lo, hi])[0]
        ys = np.asarray(yu.coordsAndDisplacements(1)[0][:N])
        inband = (ys >= y_lo) & (ys <= y_hi)
        nb = int(inband.sum())
        nint = np.asarray(yu.numIntrsOfEachBody()[:N], dtype=float)
        band_area = W * (y_hi - y_lo)
        phi = float(self.area[inband].sum() / band_area) if nb else math.nan
        Z = float(nint[inband].mean()) if nb else math.nan
        # contacts of the fabric (contact point in the band): half the contact
        # ends of the band's disks, a C++-only estimate (exact up to the
        # contacts that straddle the band's edges)
        n_contacts = int(round(nint[inband].sum() / 2))
        st = yu.bodyStressTensors()
        idx = np.nonzero(inband)[0]
        s = np.zeros(3)
        for i in idx:
            m = st[int(i)]
            w = self.vol3[i]
            s[0] += w * float(m[0, 0])
            s[1] += w * float(m[1, 1])
            s[2] += w * 0.5 * (float(m[0, 1]) + float(m[1, 0]))
        vol = band_area * d
        s /= vol
        a_xx = float(F[0, 0]) - 0.5
        a_xy = 0.5 * (float(F[0, 1]) + float(F[1, 0]))
        return dict(A_xx=a_xx, A_xy=a_xy, n_contacts=n_contacts, sigma_xy_bulk=s[2],
                    p_bulk=-(s[0] + s[1]) / 2, phi=phi, Z=Z, ys=ys)

    def ys(self):
        """Disk heights (unwrapped: the wall cell is not periodic in y)."""
        return np.asarray(yu.coordsAndDisplacements(1)[0][: self.N])


def max_overlap_d(d, smax):
    """Largest overlap of any contact, in d.

    C++ bound first (maxOverlapRatio gives u_N / (2 r_eff), and 2 r_eff <= smax d / 2);
    the exact Python loop over contacts runs only when the bound is above `limit`.
    """
    ratio = float(yu.maxOverlapRatio())
    return ratio * smax / 2


def grain_overlaps_d(n_grains, d):
    """Overlaps u_N / d of the grain-grain contacts that carry a normal force, now (ScGeom.penetrationDepth)."""
    out = []
    for i in O.interactions:
        if not i.isReal or i.id1 >= n_grains or i.id2 >= n_grains:
            continue
        if float(i.phys.normalForce.norm()) > 0:
            out.append(float(i.geom.penetrationDepth) / d)
    return out


def exact_max_overlap_d(d):
    best = 0.0
    for i in O.interactions:
        try:
            best = max(best, float(i.geom.penetrationDepth))
        except AttributeError:
            pass
    return best / d


# ------------------------------------------------------------ periodic cell
def cell_stress_2d(d):
    """Love-Weber stress of the whole periodic cell as the 2D stress of disks of thickness d (Pa).

    sigma = (1/(W L_y d)) sum_c f_c (x) l_c = getStress() L_z / d: YADE divides by the cell volume
    W L_y L_z; tension positive (YADE's sign), so sigma_yy < 0 in compression.
    """
    s = yu.getStress()
    f = float(O.cell.hSize[2, 2]) / d
    return [[float(s[0, 0]) * f, float(s[0, 1]) * f], [float(s[1, 0]) * f, float(s[1, 1]) * f]]


def periodic_walls(lay, d, W):
    """The periodic cell in the terms of the wall cell's `walls` (SI).

    Imaginary walls at y = 0 and y = L_y moving with the cell: x_top is the shear displacement
    of the cell's top edge (hSize_xy plus the whole periods removed by flips), u_top = -u_bottom
    = gammadot L_y / 2, v_top the cell's height rate; the 'forces' are the whole cell's stress
    times W d, so that the wall cell's formulas give sigma_xy, p = sigma_yy and the strain
    integral of gammadot.
    """
    h, L = O.cell.hSize, O.cell.velGrad
    Ly = float(h[1, 1])
    shift = json.loads(O.tags["ys_layout"]).get("x_shift", 0.0)
    s = cell_stress_2d(d)
    sxy = 0.5 * (s[0][1] + s[1][0])
    syy = -s[1][1]
    gd = float(L[0, 1])
    return dict(x_top=float(h[0, 1]) + shift, y_top=Ly, u_top=gd * Ly / 2, v_top=float(L[1, 1]) * Ly,
                x_bot=0.0, y_bot=0.0, u_bot=-gd * Ly / 2,
                fx_top=-sxy * W * d, fy_top=syy * W * d, fx_bot=sxy * W * d, fy_bot=-syy * W * d)


class PeriodicBulk:
    """Whole-cell measurements of the periodic cell: fabric over all contacts, Love-Weber stress,
    solid fraction and Z over all disks (the band arguments are ignored: the whole cell is bulk)."""

    def __init__(self, lay, d):
        self.N, self.d, self.area = lay["N"], d, lay["area"]

    def ys(self):
        """Disk heights wrapped into the cell [0, L_y) (YADE does not wrap positions)."""
        Ly = float(O.cell.hSize[1, 1])
        y = np.asarray(yu.coordsAndDisplacements(1)[0][: self.N])
        return y - Ly * np.floor(y / Ly)

    def measure(self, lay, y_lo, y_hi, W):
        F = yu.fabricTensor()[0]
        Ly = float(O.cell.hSize[1, 1])
        nint = np.asarray(yu.numIntrsOfEachBody()[: self.N], dtype=float)
        s = cell_stress_2d(self.d)
        return dict(A_xx=float(F[0, 0]) - 0.5, A_xy=0.5 * (float(F[0, 1]) + float(F[1, 0])),
                    n_contacts=int(round(nint.sum() / 2)), sigma_xy_bulk=0.5 * (s[0][1] + s[1][0]),
                    p_bulk=-(s[0][0] + s[1][1]) / 2, phi=self.area / (W * Ly), Z=float(nint.mean()), ys=self.ys())


def bulk_for(lay, d):
    """The bulk measurer of this cell kind."""
    return PeriodicBulk(lay, d) if lay.get("kind") == "periodic" else Bulk(lay, d)
