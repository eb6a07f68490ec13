"""The wall cell in LAMMPS: the disks, the walls, the contact law and the fixes that drive them.

Layout (as yade_scripts/build.py; kept in the stage's state and the sidecar's `engine_state`):
atom IDs 1..N are the grains (type 1), N+1..N+n_wall the bottom wall's disks (type 2),
N+n_wall+1..N+2 n_wall the top wall's (type 3). `units si`, `dimension 2`, periodic in x.

- Grains: `fix nve/sphere disc` (disks: moment of inertia m D^2 / 8), masses of disks of
  thickness d (rho pi D^2 d / 4, set per atom).
- Bottom wall: integrated (`fix nve`) with its force set to zero: it moves at the velocity
  imposed on it (`set_wall_speeds`).
- Top wall: one rigid row, free in y only: `fix aveforce` gives each of its disks the row's mean
  y force plus -load / n_wall, so the row moves as one body of mass n_wall m_d under
  sum f_y - load, as YADE's clump under its permanent force -p W d; its x force is set to zero
  and its x velocity imposed.
- `fix store/force` (first of the fixes, so before the walls' own) keeps the contact forces on
  the walls' disks for the wall stresses.
- Wall disks never interact with each other (`neigh_modify exclude`).
"""
import math
import os

import numpy as np

import contact
import placement

GRAIN, BOTTOM, TOP = 1, 2, 3
SKIN_D = 0.2  # neighbour skin, in d
WALL_FORCES = "wallforce"  # fix store/force on the walls


def header(lmp):
    """The session's settings before any atom: SI units, 2D disks, periodic in x.

    On several MPI ranks the cell is cut along x only (`processors * 1 1`): the box is taller than the
    packed layer (room for the loose packing above it), so LAMMPS's own choice, a cut across the longer
    side, put every disk of a W = 4H cell on one rank and left the other idle. One rank: no effect.
    """
    for c in ("units si", "dimension 2", "processors * 1 1", "atom_style sphere", "atom_modify map array",
              "boundary p f p", "comm_modify vel yes", "newton off"):
        lmp.command(c)


def write_data(path, der, cell, box_top):
    """A LAMMPS data file (atom_style sphere) of the loose cell: grains, then the bottom and the top wall."""
    d = der["d"]
    rows = [(GRAIN, D, x, y) for D, (x, y) in zip(cell["diameters"], cell["positions"])]
    rows += [(BOTTOM, d, x, y) for x, y in cell["bottom"]] + [(TOP, d, x, y) for x, y in cell["top"]]
    with open(path, "w") as f:
        f.write(f"wall cell (lammps_scripts)\n\n{len(rows)} atoms\n3 atom types\n\n"
                f"0 {der['W']!r} xlo xhi\n0 {box_top!r} ylo yhi\n{-d!r} {d!r} zlo zhi\n\nAtoms # sphere\n\n")
        for k, (t, D, x, y) in enumerate(rows, start=1):
            # density: overwritten by the disk masses (set_masses)
            f.write(f"{k} {t} {D!r} {der['rho']!r} {x!r} {y!r} 0.0\n")
    return len(rows)


def new_cell(lmp, scene, der, folder):
    """Create the loose cell of the pack stage (placement.wall_cell) in the session. Returns the layout."""
    cell = placement.wall_cell(scene, der)
    d = der["d"]
    header(lmp)
    data = os.path.join(folder, "cell.data")
    write_data(data, der, cell, cell["y_top"] + 4 * d + 2 * cell["H0"])
    lmp.command(f"read_data {data}")
    N, n_w = len(cell["diameters"]), der["n_wall"]
    set_masses(lmp, der)
    groups(lmp)
    return dict(N=N, n_wall=n_w, y_bottom=cell["y_bottom"])


def set_masses(lmp, der):
    """Every atom's mass: a disk of its diameter and thickness d (rho pi D^2 d / 4)."""
    radius = lmp.numpy.extract_atom("radius")
    rmass = lmp.numpy.extract_atom("rmass")
    n = lmp.extract_global("nlocal")
    rmass[:n] = der["rho"] * math.pi * radius[:n] ** 2 * der["d"]


def groups(lmp):
    for c in (f"group grains type {GRAIN}", f"group bottom type {BOTTOM}", f"group top type {TOP}",
              f"group walls type {BOTTOM} {TOP}"):
        lmp.command(c)


def load_state(lmp, path):
    """A stage's final state (write_restart): atoms, velocities, groups and the contacts' history."""
    header(lmp)
    lmp.command(f"read_restart {path}")


def interactions(lmp, scene, der, friction=None):
    """The contact law (contact.gran_hooke_history), the neighbour lists and the time step.

    Returns the pair style's line."""
    law = contact.gran_hooke_history(scene, der, friction)
    lmp.command(law["command"])
    lmp.command("pair_coeff * *")
    lmp.command(f"neighbor {SKIN_D * der['d']!r} bin")
    lmp.command(f"neigh_modify delay 0 every 1 check yes exclude type {BOTTOM} {BOTTOM} "
                f"exclude type {TOP} {TOP} exclude type {BOTTOM} {TOP}")
    lmp.command(f"timestep {der['dt']!r}")
    lmp.command("thermo 0")
    lmp.command("thermo_modify norm no lost error")
    return law["command"]


def set_friction(lmp, scene, der, mu):
    """Coulomb coefficient ``mu`` on every contact, existing ones included (the pair style's xmu:
    LAMMPS caps every contact's tangential force with it at each step)."""
    lmp.command(contact.gran_hooke_history(scene, der, mu)["command"])


def fixes(lmp, n_wall, load):
    """The integrators and the walls' drives (module docstring), in their order; returns their lines."""
    lines = [f"fix {WALL_FORCES} walls store/force",
             "fix grains_nve grains nve/sphere disc",
             "fix walls_nve walls nve",
             "fix bottom_hold bottom setforce 0.0 0.0 0.0",
             "fix top_load top aveforce NULL v_topload NULL",
             "fix top_slide top setforce 0.0 NULL 0.0",
             "fix plane all enforce2d"]
    set_wall_load(lmp, load, n_wall)
    for c in lines:
        lmp.command(c)
    return lines


def set_wall_load(lmp, force, n_wall):
    """The top wall's load ``force`` (N, downwards), shared by its n_wall disks."""
    lmp.command(f"variable topload equal {-force / n_wall!r}")


def set_grain_damping(lmp, gamma):
    """Viscous drag -gamma v on every grain (`fix viscous`; gamma 0: none). Returns the fix's line or None.

    Stands in for YADE's Cundall damping in the pack's ramp and settling (LAMMPS 2021 has no local
    damping): gamma = pack.damping sqrt(kn m_d), the rate pack.damping / t_c on a disk of diameter d."""
    if lmp.has_id("fix", "grain_drag"):
        lmp.command("unfix grain_drag")
    if gamma > 0:
        # before enforce2d (its z forces are zeroed after every other fix)
        lmp.command("unfix plane")
        lmp.command(f"fix grain_drag grains viscous {gamma!r}")
        lmp.command("fix plane all enforce2d")
        return f"fix grain_drag grains viscous {gamma!r}"
    return None


def set_wall_speeds(lmp, u_top, u_bottom):
    """Impose the walls' x velocities (m/s); the top wall keeps its vertical speed."""
    lmp.command(f"velocity bottom set {u_bottom!r} 0.0 0.0 units box")
    lmp.command(f"velocity top set {u_top!r} NULL 0.0 units box")


def quench_grains(lmp):
    """Every grain at rest and the top wall's vertical speed zero (YADE's build.quench_grains)."""
    lmp.command("velocity grains set 0.0 0.0 0.0 units box")
    lmp.command("set group grains omega 0.0 0.0 0.0")
    lmp.command("velocity top set NULL 0.0 NULL units box")


def ordered(lmp, name, n):
    """Per-atom array ``name`` (extract_atom) in ID order, as a numpy copy."""
    ids = lmp.numpy.extract_atom("id")[:n]
    a = np.asarray(lmp.numpy.extract_atom(name))[:n]
    out = np.empty_like(a)
    out[ids - 1] = a
    return out
