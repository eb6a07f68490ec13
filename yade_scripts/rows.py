"""One row of a stage's series from the walls' state, and what the guards and sidecars share.

Python and numpy (no YADE, no LAMMPS): both engines' stages write their rows through it, so the
series' columns, units and signs (docs/data-contract.md) are defined once.
"""
import math

import numpy as np

COLUMNS = ["t", "strain", "gammadot", "U_top", "U_bottom", "gap", "A_xx", "A_xy", "n_contacts",
           "sigma_xy", "p", "mu", "sigma_xy_bulk", "p_bulk", "phi", "Z", "inertial_number"]
PACK_COLUMNS = ["ke", "wall_speed", "load"]  # pack.csv's own, after COLUMNS
BULK_COLUMNS = ("A_xx", "A_xy", "n_contacts", "sigma_xy_bulk", "p_bulk", "phi", "Z")


def fmt(x):
    """A CSV field: floats as repr (every bit kept), non-finite as nan."""
    if isinstance(x, float):
        return repr(x) if math.isfinite(x) else "nan"
    return str(x)


def wall_row(der, st, w, t):
    """The wall columns of one row (SI inputs, the series' units out); advances st's strain.

    strain += (x_rel - x_rel_before) / mean gap (the walls' relative displacement between
    samples); gammadot = (u_top - u_bottom)/gap; sigma_xy = (f_x,bottom - f_x,top)/(2 W d),
    p = (f_y,top - f_y,bottom)/(2 W d), both in p (the mean of the two walls; sigma_xy > 0
    when the top wall moving towards +x is dragged back); mu = |sigma_xy|/p and
    I = |gammadot| d / sqrt(p_measured / rho).

    Parameters
    ----------
    der : dict
        scene.derived of the scene.
    st : dict
        The stage's state: its ``strain``, ``x_rel`` and ``gap`` (the last row's) are updated.
    w : dict
        The walls (measure.walls): x_top, y_top, u_top, x_bot, y_bot, u_bot, fx_top, fy_top,
        fx_bot, fy_bot, in SI.
    t : float
        Time of the row since the stage's time origin, s.

    Returns
    -------
    (row, pw, gd)
        The row (bulk columns NaN), the wall pressure in p and the shear rate in 1/s.
    """
    d, p, T0, V0, W = der["d"], der["p"], der["T0"], der["V0"], der["W"]
    gap = w["y_top"] - w["y_bot"]
    x_rel = w["x_top"] - w["x_bot"]
    st["strain"] += (x_rel - st["x_rel"]) / (0.5 * (gap + st["gap"]))
    st["x_rel"], st["gap"] = x_rel, gap
    gd = (w["u_top"] - w["u_bot"]) / gap
    sxy = (w["fx_bot"] - w["fx_top"]) / (2 * W * d) / p
    pw = (w["fy_top"] - w["fy_bot"]) / (2 * W * d) / p
    row = dict(t=t / T0, strain=st["strain"], gammadot=gd * T0,
               U_top=w["u_top"] / V0, U_bottom=w["u_bot"] / V0, gap=gap / d, sigma_xy=sxy, p=pw,
               mu=abs(sxy) / pw if pw > 0 else math.nan,
               inertial_number=abs(gd) * T0 / math.sqrt(pw) if pw > 0 else math.nan)
    for k in BULK_COLUMNS:
        row[k] = math.nan
    return row, pw, gd


def pressure_guard_tolerance(guards, W_over_d):
    """The largest deviation of the window-mean wall pressure from p that the guard lets pass.

    tol = max(guards.pressure_tolerance, guards.pressure_noise_z * sqrt(d / W)): the relative
    fluctuation of the wall pressure falls as one over the square root of the number of wall
    contacts, about W/d. Measured on the released narrow cell (W = 18.5d, kappa 1e5, I 1e-3),
    the largest 0.1-strain window mean of a run departs from p by up to about 1.0 sqrt(d/W)
    (0.23 p; 0.6 sqrt(d/W) in the W = 96d cell); a blow-up or a failed pressure control departs
    by multiples of p. With the default z = 2.5 the narrow cell's guard is at 0.58 p, a cell
    wider than about 150 d keeps the configured 0.2.
    """
    return max(guards["pressure_tolerance"], guards["pressure_noise_z"] / W_over_d ** 0.5)


def state_problem(row, w, ys, d, at):
    """The blow-up guards on one sample: NaN in the row's strain, stresses, gap or the top wall's
    forces, or in the disks' heights ``ys``; a disk outside the walls. ``at`` names the sample
    ("iteration 123", "step 123"). Returns the guard's message, or None."""
    vals = [row[k] for k in ("strain", "sigma_xy", "p", "gap")] + [w["fx_top"], w["fy_top"]]
    if not all(math.isfinite(v) for v in vals) or not np.all(np.isfinite(ys)):
        return f"NaN in positions or forces at {at} (t = {row['t']:.4f})"
    out = np.nonzero((ys < w["y_bot"]) | (ys > w["y_top"]))[0]
    if len(out):
        return (f"disk {int(out[0])} left the cell at {at} "
                f"(y = {ys[out[0]] / d:.3f} d, walls at {w['y_bot'] / d:.3f} d and {w['y_top'] / d:.3f} d)")
    return None


def pressure_window_problem(st, guards, der, steps, p_row):
    """The pressure guard: the row's wall pressure joins the window of the last
    guards.pressure_window_strain of strain (st['window'], at nominal rate since the stage's
    start, ``steps`` steps in); once the window is full (past st['guard_from'], a reversal's
    restart) its mean must lie within ``pressure_guard_tolerance`` of p. Returns the guard's
    message, or None."""
    elapsed = steps * der["dt"] * der["gammadot"]
    win = st["window"]
    win.append([elapsed, p_row])
    span = guards["pressure_window_strain"]
    while win and win[0][0] < elapsed - span:
        win.pop(0)
    if elapsed - st.get("guard_from", 0.0) >= span and len(win) >= 3:
        pm = sum(x[1] for x in win) / len(win)
        tol = pressure_guard_tolerance(guards, der["W"] / der["d"])
        if abs(pm - 1) > tol:
            return (f"wall pressure {pm:.4f} p on average over the last {span:g} strain, "
                    f"off by more than {tol:.3g} = max(guards.pressure_tolerance "
                    f"{guards['pressure_tolerance']:g}, guards.pressure_noise_z "
                    f"{guards['pressure_noise_z']:g} x sqrt(d/W))")
    return None


def overlap_stats(overlaps_d):
    """Mean, median, 90th percentile, max and count of a list of overlaps (in d).

    The paper states its stiffness as a mean overlap delta/d; kappa = kn/(p d) sets it
    (docs/findings.md, "The stiffness axis in the campaign's cell": delta/d = 1.4-1.7/kappa).
    """
    ov = sorted(overlaps_d)
    if not ov:
        return dict(n=0, mean=math.nan, median=math.nan, p90=math.nan, max=math.nan)

    def q(f):
        return ov[min(len(ov) - 1, int(f * len(ov)))]

    return dict(n=len(ov), mean=sum(ov) / len(ov), median=q(0.5), p90=q(0.9), max=ov[-1])
