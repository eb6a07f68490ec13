r"""Classical fixed-step Runge-Kutta (RK4), the paper's method, on one segment.

Notes
-----
.. math::
    k_1 = f(t_n, y_n),\ k_2 = f(t_n + h/2, y_n + h k_1/2),\
    k_3 = f(t_n + h/2, y_n + h k_2/2),\ k_4 = f(t_n + h, y_n + h k_3),

.. math::
    y_{n+1} = y_n + \tfrac{h}{6} (k_1 + 2 k_2 + 2 k_3 + k_4).

The segment ``[t0, t1]`` is cut into ``n = ceil((t1 - t0)/step)`` equal steps so
that its ends (reversals, zero crossings) are hit exactly. A report time between
two grid points gets its own partial RK4 step from the grid point before it,
which keeps fourth-order accuracy and does not perturb the grid.
"""
from __future__ import annotations

import math

import numpy as np

from .rhs import PoleCrossing, PoleError


def _rk4_step(rate, t, a, b, h):
    k1a, k1b = rate(t, a, b)
    k2a, k2b = rate(t + 0.5 * h, a + 0.5 * h * k1a, b + 0.5 * h * k1b)
    k3a, k3b = rate(t + 0.5 * h, a + 0.5 * h * k2a, b + 0.5 * h * k2b)
    k4a, k4b = rate(t + h, a + h * k3a, b + h * k3b)
    return (a + h / 6.0 * (k1a + 2.0 * k2a + 2.0 * k3a + k4a),
            b + h / 6.0 * (k1b + 2.0 * k2b + 2.0 * k3b + k4b))


def rk4_segment(rate, t0, t1, y0, step, t_out, X_c=math.inf):
    """Integrate ``rate`` from ``t0`` to ``t1`` with fixed RK4 steps of at most ``step``.

    Parameters
    ----------
    rate : callable
        ``rate(t, a, b) -> (da/dt, db/dt)``; raises ``PoleCrossing`` beyond X_c.
    t0, t1 : float
    y0 : (a, b)
    step : float
        Largest step (time units).
    t_out : array
        Sorted report times in ``[t0, t1]``.
    X_c : float
        Only for the error message.

    Returns
    -------
    Y : ndarray, shape (len(t_out), 2)
    y1 : (a, b) at ``t1``

    Raises
    ------
    PoleError
        If a stage lands at X >= X_c: the step is too large for the approach to the pole.
    """
    n = max(1, math.ceil((t1 - t0) / step - 1e-9))
    h = (t1 - t0) / n
    a, b = float(y0[0]), float(y0[1])
    Y = np.empty((len(t_out), 2))
    j = 0
    t = t0
    try:
        for i in range(n + 1):
            t = t0 + i * h if i < n else t1
            # report times in [t, t + h) from this grid point
            t_next = t1 if i >= n - 1 else t0 + (i + 1) * h
            while j < len(t_out) and (t_out[j] < t_next or i == n):
                dt = t_out[j] - t
                Y[j] = (a, b) if dt <= 0.0 else _rk4_step(rate, t, a, b, dt)
                j += 1
            if i == n:
                break
            a, b = _rk4_step(rate, t, a, b, t_next - t)
    except PoleCrossing as exc:
        raise PoleError(
            f"RK4 with step {h:.3g}: a stage reached X = {exc.X:.6g} >= X_c = {X_c:.6g} at "
            f"t = {exc.t:.6g} (step from t = {t:.6g}); the step is too large for the approach "
            "to the pole: reduce 'step' or use an adaptive method",
            t=exc.t, X=exc.X, X_c=X_c,
        ) from None
    return Y, (a, b)
