"""The cell's disks before any engine: diameters and loose placement by seed, the walls' rows.

Pure Python (no YADE, no LAMMPS): both engines' pack stages build the same cell from it,
so that a scene gives the same disk sizes and positions in either.
"""
import random


class PlacementError(RuntimeError):
    pass


def loose_placement(rnd, diameters, W, y_lo, y_hi, periodic_y=False):
    """Random sequential placement of non-overlapping disks, periodic in x (and in y if ``periodic_y``).

    Centres in [0, W) x [y_lo + r, y_hi - r] between walls, or in [0, W) x [y_lo, y_hi)
    in a box periodic in y too. Returns a list of (x, y).
    """
    cell = max(diameters)
    nx = max(1, int(W // cell))
    cw = W / nx
    Hc = y_hi - y_lo
    ny = max(1, int(Hc // cell)) if periodic_y else None
    ch = Hc / ny if periodic_y else cell
    grid = {}
    pos = [None] * len(diameters)
    # largest first: random sequential placement then reaches denser loose states
    for i in sorted(range(len(diameters)), key=lambda k: -diameters[k]):
        D = diameters[i]
        r = D / 2
        for _ in range(20000):
            x = rnd.uniform(0, W)
            y = rnd.uniform(y_lo, y_hi) if periodic_y else rnd.uniform(y_lo + r, y_hi - r)
            ix, iy = int(x // cw) % nx, int((y - y_lo) // ch)
            if periodic_y:
                iy %= ny
            ok = True
            for jx in (ix - 1, ix, ix + 1):
                for jy in (iy - 1, iy, iy + 1):
                    for j in grid.get((jx % nx, jy % ny if periodic_y else jy), ()):  # noqa: B007
                        xj, yj = pos[j]
                        dx = x - xj
                        dx -= W * round(dx / W)
                        dy = y - yj
                        if periodic_y:
                            dy -= Hc * round(dy / Hc)
                        if dx * dx + dy ** 2 < (r + diameters[j] / 2) ** 2:
                            ok = False
                            break
                    if not ok:
                        break
                if not ok:
                    break
            if ok:
                grid.setdefault((ix, iy), []).append(i)
                pos[i] = (x, y)
                break
        else:
            raise PlacementError("loose placement failed: lower pack.initial_solid_fraction")
    return pos


def seeded_diameters(scene, der):
    """The scene's random stream (seeded by ``seed``) and the N disk diameters drawn first from it,
    uniform in [size_ratio_min, size_ratio_max] d; the stream goes on to place them."""
    m = scene["material"]
    rnd = random.Random(scene["seed"])
    return rnd, [der["d"] * rnd.uniform(m["size_ratio_min"], m["size_ratio_max"]) for _ in range(der["N"])]


def wall_cell(scene, der):
    """The loose wall cell of the pack stage: grains, the walls' disks and their heights.

    The grains' diameters come first from the scene's random stream (``seeded_diameters``),
    then their loose placement between the walls; the initial gap is that of the loose
    placement at ``pack.initial_solid_fraction``: H0 = d + (H - d) guess / initial. The
    bottom wall's n_wall disks of diameter d lie at y_bottom = 2 d, x = (i + 1/2) W/n_wall,
    the top wall's at y_top = y_bottom + H0, x = i W/n_wall.

    Returns
    -------
    dict
        diameters, positions (x, y) of the grains; bottom, top: the walls' (x, y); y_bottom,
        y_top, H0 (m).
    """
    d, W, H = der["d"], der["W"], der["H"]
    pk = scene["pack"]
    rnd, diam = seeded_diameters(scene, der)
    H0 = d + (H - d) * pk["solid_fraction_guess"] / pk["initial_solid_fraction"]
    y_bottom = 2 * d
    y_top = y_bottom + H0
    pos = loose_placement(rnd, diam, W, y_bottom + d / 2, y_top - d / 2)
    n_w = der["n_wall"]
    s = W / n_w
    return dict(diameters=diam, positions=pos, H0=H0, y_bottom=y_bottom, y_top=y_top,
                bottom=[((i + 0.5) * s, y_bottom) for i in range(n_w)],
                top=[(i * s, y_top) for i in range(n_w)])


def pair_sizes(scene, n=5):
    """Pairs (D1, D2), in d, of ``n`` diameters evenly spaced over [size_ratio_min, size_ratio_max]
    (and d itself): every pair size the polydispersity allows, for the two-disk restitution tests."""
    m = scene["material"]
    lo, hi = m["size_ratio_min"], m["size_ratio_max"]
    sizes = sorted({round(lo + (hi - lo) * k / (n - 1), 12) for k in range(n)} | {1.0})
    return [(a, b) for i, a in enumerate(sizes) for b in sizes[i:]]
