"""Contact census of a saved DEM state: overlaps, and the fabric under each reading of "the contacts".

usage: python3 yade_scripts/contact_census.py <scene.json> <state.yade.gz> [--out <census.json>]

Loads the final state of a stage (a wall cell; ``<stage>.final.yade.gz``) and writes one JSON
object (to ``--out``, else standard output):

- ``overlap_d``: the overlap u_N = r1 + r2 - |x2 - x1| of every grain-grain contact that carries a
  normal force, in units of d: mean, median, 90th percentile, max, and their count. The
  paper states its stiffness as a mean overlap (delta / d, "the hard particle limit"); this
  is that number for the run's kappa = kn / (p d).
- ``fabric``: A = -I/2 + <n (x) n> (paper, Eq. 1) and X = A:D'/|D'| = sqrt(2) A_xy s
  (s = the sign of the shear rate, so that X < 0 in steady shear), under each reading of
  which contacts the paper's "unit contact vectors between particles" in "a volume V" are:

  ``contract``         the data contract's: grain-grain and grain-wall contacts whose contact
                       point lies in the bulk band (YADE's fabricTensor with extrema, the
                       series' A_xx, A_xy);
  ``centres``          grain-grain contacts both of whose centres lie in the band;
  ``force``            ``contract``, force-carrying only (normal force above 1e-3 of the mean
                       normal force of the band's contacts);
  ``no_rattlers``      ``force``, without the contacts of rattlers (grains left with fewer than
                       two force-carrying contacts, removed until none is left);
  ``whole_cell``       every grain-grain and grain-wall contact of the cell, walls included.

  The readings are measured on the same snapshot, so their differences carry far less
  noise than one snapshot's A itself.

Pure measurement: the state is only read. Runs under YADE's interpreter like the stages
(``yadelib``), with no remote server.
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))

import yadelib  # noqa: E402

USAGE = "usage: python3 yade_scripts/contact_census.py <scene.json> <state.yade.gz> [--out <census.json>]"
#: A contact carries force when its normal force exceeds this fraction of the band's mean.
FORCE_FRACTION = 1e-3


def fabric(normals):
    """A_xx, A_xy, |A|, theta_A (deg) and the count of a list of unit normals (2D, n and -n alike)."""
    n = len(normals)
    if n == 0:
        return dict(n=0, A_xx=math.nan, A_xy=math.nan, A_norm=math.nan, theta_A_deg=math.nan)
    fxx = sum(nx * nx for nx, _ in normals) / n
    fxy = sum(nx * ny for nx, ny in normals) / n
    a_xx, a_xy = fxx - 0.5, fxy
    theta = 0.5 * math.degrees(math.atan2(a_xy, a_xx)) % 180.0
    return dict(n=n, A_xx=a_xx, A_xy=a_xy, A_norm=math.sqrt(2 * (a_xx**2 + a_xy**2)), theta_A_deg=theta)


def overlap(O, it):
    """u_N = r1 + r2 - |x2 - x1| of a contact, from the positions (a saved state does not keep
    ScGeom.penetrationDepth); x2 shifted by the periods the contact spans (Interaction.cellDist)."""
    b1, b2 = O.bodies[it.id1], O.bodies[it.id2]
    x1, x2 = b1.state.pos, b2.state.pos
    dx, dy = float(x2[0] - x1[0]), float(x2[1] - x1[1])
    if O.periodic:
        h, c = O.cell.hSize, it.cellDist
        dx += sum(float(h[0, k]) * c[k] for k in range(3))
        dy += sum(float(h[1, k]) * c[k] for k in range(3))
    return float(b1.shape.radius + b2.shape.radius) - math.hypot(dx, dy)


def rattlers(pairs, n_grains):
    """Grains with fewer than two force-carrying contacts, removed until none is left (walls never are)."""
    out = set()
    while True:
        count = [0] * n_grains
        for i, j in pairs:
            if i in out or j in out:
                continue
            for k in (i, j):
                if k < n_grains:
                    count[k] += 1
        new = {k for k in range(n_grains) if k not in out and count[k] < 2}
        if not new:
            return out
        out |= new


def census(scene_path, state_path):
    import scene as scenemod

    scene, _ = scenemod.load(scene_path)
    yadelib.import_yade()
    from yade.wrapper import Omega

    import build
    import measure

    O = Omega()
    O.load(state_path)
    lay = build.layout()
    if lay.get("kind") == "periodic":
        raise SystemExit("contact_census: a periodic cell has no walls or band; only wall cells are read")
    der = scenemod.derived(scene)
    d, N = der["d"], lay["N"]
    w = measure.walls(lay)
    excl = scene["sampling"]["bulk_exclusion_d"] * d
    y_lo, y_hi = w["y_bot"] + excl, w["y_top"] - excl
    sign = 1.0 if w["u_top"] - w["u_bot"] >= 0 else -1.0
    rows = []   # (i, j, nx, ny, contact point y, overlap, normal force)
    for it in O.interactions:
        if not it.isReal:
            continue
        g, ph = it.geom, it.phys
        n = g.normal
        rows.append((it.id1, it.id2, float(n[0]), float(n[1]), float(g.contactPoint[1]),
                     overlap(O, it), float(ph.normalForce.norm())))
    ys = [float(O.bodies[i].state.pos[1]) for i in range(N)]

    def in_band(y):
        return y_lo <= y <= y_hi

    band = [r for r in rows if in_band(r[4])]
    mean_f = sum(r[6] for r in band) / len(band) if band else 0.0
    carrying = [r for r in band if r[6] > FORCE_FRACTION * mean_f]
    ratt = rattlers([(r[0], r[1]) for r in rows if r[6] > FORCE_FRACTION * mean_f], N)
    grain = [r for r in rows if r[0] < N and r[1] < N]
    readings = {
        "contract": band,
        "centres": [r for r in grain if in_band(ys[r[0]]) and in_band(ys[r[1]])],
        "force": carrying,
        "no_rattlers": [r for r in carrying if r[0] not in ratt and r[1] not in ratt],
        "whole_cell": rows,
    }
    fab = {}
    for name, rs in readings.items():
        f = fabric([(r[2], r[3]) for r in rs])
        f["X"] = math.sqrt(2.0) * f["A_xy"] * sign
        fab[name] = f
    # the series' own measurement, for the check that ``contract`` is the contract's reading
    import yade._utils as yu
    from yade.minieigenHP import Vector3

    F = yu.fabricTensor(extrema=[Vector3(-measure.BIG, y_lo, -measure.BIG), Vector3(measure.BIG, y_hi, measure.BIG)])[0]
    fab["series"] = dict(A_xx=float(F[0, 0]) - 0.5, A_xy=0.5 * (float(F[0, 1]) + float(F[1, 0])))
    ov_stats = measure.overlap_stats([r[5] / d for r in grain if r[6] > 0 and math.isfinite(r[5])])
    return dict(state=os.path.abspath(state_path), kappa=scene["material"]["kappa"], N=N,
                rattlers=len(ratt), rattler_fraction=len(ratt) / N, band=[y_lo / d, y_hi / d],
                shear_sign=sign, overlap_d=ov_stats, fabric=fab, force_fraction=FORCE_FRACTION)


def main(argv):
    argv = list(argv)
    out = None
    if "--out" in argv:
        k = argv.index("--out")
        if k + 1 >= len(argv):
            print(USAGE, file=sys.stderr)
            return 2
        out = argv[k + 1]
        del argv[k:k + 2]
    if len(argv) != 2 or not all(os.path.isfile(p) for p in argv):
        print(USAGE, file=sys.stderr)
        return 2
    result = census(*argv)
    text = json.dumps(result, indent=1, sort_keys=True)
    if out:
        tmp = out + ".tmp"
        with open(tmp, "w") as fh:
            fh.write(text + "\n")
        os.replace(tmp, out)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    if yadelib.under_the_launcher():
        print("contact_census.py is not run by the yade launcher: " + USAGE.removeprefix("usage: "), file=sys.stderr)
        os._exit(2)
    try:
        yadelib.run_under_yade_interpreter()
    except yadelib.YadeNotFound as e:
        print(f"YADE not found: {e}", file=sys.stderr)
        os._exit(2)
    rc = main(sys.argv[1:])
    sys.stdout.flush()
    os._exit(rc)
