"""scipy's adaptive solvers on one history segment, guarded against the pole X_c.

scipy's ``OdeSolver`` classes are stepped one step at a time. When a trial
stage (or the Jacobian's finite differences) asks for the right-hand side at
X >= X_c, the right-hand side raises ``PoleCrossing``; the step is thrown away
and the solver restarts from the last accepted state with a step four times
smaller. The exact solution never reaches X_c when the pole is repulsive, so
this only removes the overshoot of trial steps. If the step needed falls below
``1e-12`` of the segment, the approach is not resolvable and ``PoleError``
names the time, X and X_c. Every accepted state is also checked directly.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, Radau

from .rhs import PoleCrossing, PoleError

SOLVERS = {"RK23": RK23, "RK45": RK45, "DOP853": DOP853, "Radau": Radau, "BDF": BDF, "LSODA": LSODA}


def adaptive_segment(rate, t0, t1, y0, method, rtol, atol, t_out, X_c=math.inf, xfun=None, max_steps=None):
    """Integrate ``rate`` over ``[t0, t1]`` with ``scipy.integrate.<method>``.

    Parameters
    ----------
    rate : callable
        ``rate(t, a, b) -> (da/dt, db/dt)``; raises ``PoleCrossing`` beyond X_c.
    y0 : (a, b)
    method : str
        A key of ``SOLVERS``.
    rtol, atol : float
    t_out : array
        Sorted report times in ``[t0, t1]``, read from the solver's dense output.
    max_steps : int, optional
        Raise ``RuntimeError`` after this many attempted steps (none by default).
    X_c : float
    xfun : callable, optional
        ``xfun(t, a, b) -> X`` for the messages.

    Returns
    -------
    Y : ndarray, shape (len(t_out), 2)
    y1 : ndarray, state at ``t1``
    nfev : int
    """
    cls = SOLVERS[method]
    span = t1 - t0
    h_min = 1e-12 * span
    nfev = [0]

    def fun(t, y):
        nfev[0] += 1
        return np.array(rate(t, y[0], y[1]))

    def fail(t, y, why):
        return _pole_error(method, why, t, y, X_c, xfun)

    def start(t, y, first_step):
        return _start(cls, fun, t, y, t1, rtol, atol, first_step, h_min, fail)

    Y = np.empty((len(t_out), 2))
    j = 0
    while j < len(t_out) and t_out[j] <= t0:
        Y[j] = y0
        j += 1
    solver = start(t0, np.asarray(y0, dtype=float), None)
    steps = 0
    while solver.status == "running":
        steps += 1
        if max_steps is not None and steps > max_steps:
            raise _budget_error(method, max_steps, solver.t, t1)
        t_prev, y_prev = solver.t, solver.y.copy()
        try:
            message = solver.step()
            if solver.status != "failed":
                rate(solver.t, solver.y[0], solver.y[1])  # accepted state must lie below X_c
        except PoleCrossing:
            h = getattr(solver, "h_abs", None) or solver.step_size or 1e-3 * span
            h = min(h, t1 - t_prev) / 4.0
            if h < h_min:
                raise fail(t_prev, y_prev, "the step needed to stay below the pole vanished")
            solver = start(t_prev, y_prev, h)
            continue
        if solver.status == "failed":
            raise RuntimeError(f"{method} failed at t = {solver.t:.6g}: {message}")
        j = _report(solver, t_out, Y, j)
    Y[j:] = solver.y  # round-off at t1
    return Y, solver.y.copy(), nfev[0]


def _start(cls, fun, t, y, t1, rtol, atol, first_step, h_min, fail):
    """Build the solver at ``(t, y)``, shrinking ``first_step`` by 4 while its first evaluations cross X_c."""
    while True:
        try:
            return cls(fun, t, y, t1, rtol=rtol, atol=atol, first_step=first_step)
        except PoleCrossing:
            first_step = (first_step or 1e-3 * (t1 - t)) / 4.0
            if first_step < h_min:
                raise fail(t, y, "the right-hand side is undefined at the start")


def _report(solver, t_out, Y, j):
    """Fill ``Y`` at the report times ``t_out[j:]`` the last accepted step covered; return the next index."""
    dense = None
    while j < len(t_out) and t_out[j] <= solver.t:
        if t_out[j] == solver.t:
            Y[j] = solver.y
        else:
            dense = dense or solver.dense_output()
            Y[j] = dense(t_out[j])
        j += 1
    return j


def _pole_error(method, why, t, y, X_c, xfun):
    """The ``PoleError`` for an approach to X_c that no step resolves."""
    X = xfun(t, y[0], y[1]) if xfun else math.nan
    return PoleError(
        f"{method}: {why} at t = {t:.6g}, X = {X:.6g}, X_c = {X_c:.6g}; the approach to the "
        "pole is not resolvable (check the parameters: c1 + c2 X_c < 0 makes it repulsive)",
        t=t, X=X, X_c=X_c,
    )


def _budget_error(method, max_steps, t, t1):
    return RuntimeError(f"{method} needed more than {max_steps} steps by t = {t:.6g} "
                        f"(of {t1:.6g}): the problem is stiff here; an implicit method (Radau, BDF, "
                        "LSODA) handles it")
