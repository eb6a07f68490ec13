r"""Classical Runge-Kutta (RK4), the paper's method, on one segment, with the step cut where Eq. 4 is stiff.

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

Near Model 1's pole the fixed step is not enough: the pole term
:math:`c_i X^4/(X_c - X)` makes Eq. 4 stiff (the Jacobian of the rate grows as
:math:`(X_c - X)^{-2}`; on a calibrated-looking set just after a reversal its
largest eigenvalue modulus is 130, and 26,000 with X_c just above the mirrored
steady X, against 3 in steady shear), and an explicit step of 0.01 strain then
errs by 0.05 in |A| or jumps over the pole. So each grid step (and each partial
step to a report time) is taken in sub-steps, each no larger than the state at
its start allows, judged with the rate at the sub-step's start and at the grid
step's end time (the rate of a sinusoidal reversal grows within a step):

.. math::
    h \le \frac{\mathrm{STIFF\_LIMIT}}{\max|\lambda(J)|}, \qquad
    h \le \mathrm{POLE\_FRACTION}\,\frac{X_c - X}{\dot X}\ \ (\dot X > 0),

with :math:`J = \partial(\dot a, \dot b)/\partial(a, b)` by forward differences
(two extra evaluations of the rate per sub-step). Where neither bound binds
(Model 2, Model 1 away from the pole at the default step) a grid step is one
plain RK4 step, as in the paper. A segment that would need more than
``MAX_SUBSTEPS`` sub-steps, or a sub-step below ``MIN_STEP_FRACTION`` of the
step (a fabric blowing up), is refused with a message giving the step it needs.
"""
from __future__ import annotations

import cmath
import math

import numpy as np

from .rhs import PoleCrossing, PoleError

#: Largest h * max|eigenvalue of the rate's Jacobian| taken in one RK4 step. RK4 is stable up to
#: 2.8 on the negative real axis; 0.5 keeps the error of a stiff mode below ~3e-4 per step
#: (measured: RK4 at the default step within 2e-6 of LSODA in |A| on calibrated-looking
#: parameters near the pole, against 2e-4 and 0.05 with the fixed step).
STIFF_LIMIT = 0.5
#: Largest fraction of the distance to the pole X_c - X that X may cover in one step (at its current rate).
POLE_FRACTION = 0.25
#: Most sub-steps in one segment before RK4 refuses (an adaptive method is then the tool); the
#: Model 1 set with X_c just above the mirrored steady X needs about 900 for its whole reversal.
MAX_SUBSTEPS = 200_000
#: Smallest sub-step, as a fraction of the grid step, before RK4 refuses: a fabric that blows up
#: in finite time asks for ever smaller steps (the set above needs 2e-3 of the step at most).
MIN_STEP_FRACTION = 1e-6


def _rk4_step(rate, t, a, b, h):
    k1a, k1b = rate(t, a, b)
    k2a, k2b = rate(t + 0.5 * h, a + 0.5 * h * k1a, b + 0.5 * h * k1b)
    k3a, k3b = rate(t + 0.5 * h, a + 0.5 * h * k2a, b + 0.5 * h * k2b)
    k4a, k4b = rate(t + h, a + h * k3a, b + h * k3b)
    return (a + h / 6.0 * (k1a + 2.0 * k2a + 2.0 * k3a + k4a),
            b + h / 6.0 * (k1b + 2.0 * k2b + 2.0 * k3b + k4b))


def stable_step(rate, t, a, b, X_c=math.inf, xfun=None):
    r"""Largest step the state ``(a, b)`` at ``t`` allows (see module Notes), with its reason.

    Parameters
    ----------
    rate : callable
        ``rate(t, a, b) -> (da/dt, db/dt)``.
    t, a, b : float
    X_c : float
        Model 1's pole (``inf`` for none).
    xfun : callable, optional
        ``xfun(t, a, b) -> X`` (NaN where the layer does not deform); without it
        only the stiffness bound applies.

    Returns
    -------
    h : float
        ``min(STIFF_LIMIT / max|lambda|, POLE_FRACTION (X_c - X)/Xdot)`` (``inf`` if neither applies).
    why : str
        Which bound sets ``h``, with its numbers (for messages).
    """
    fa, fb = rate(t, a, b)
    X = xfun(t, a, b) if xfun is not None else math.nan
    gap = X_c - X if math.isfinite(X_c) and math.isfinite(X) else math.inf
    eps = 1e-7 * max(1.0, abs(a), abs(b))
    if math.isfinite(gap):
        eps = min(eps, 0.1 * gap)  # a perturbation moves X by at most sqrt(2) eps: stays below the pole
    ja, jb = rate(t, a + eps, b), rate(t, a, b + eps)
    j11, j21 = (ja[0] - fa) / eps, (ja[1] - fb) / eps
    j12, j22 = (jb[0] - fa) / eps, (jb[1] - fb) / eps
    half_tr = 0.5 * (j11 + j22)
    root = cmath.sqrt(half_tr * half_tr - (j11 * j22 - j12 * j21))
    lam = max(abs(half_tr + root), abs(half_tr - root))
    h, why = (STIFF_LIMIT / lam, f"stiffness max|lambda| = {lam:.4g}") if lam > 0 else (math.inf, "")
    if math.isfinite(gap):
        xdot = xfun(t, fa, fb)  # X is linear in (a, b) at fixed t: this is dX/dt at fixed D'
        if xdot > 0 and POLE_FRACTION * gap / xdot < h:
            h, why = POLE_FRACTION * gap / xdot, f"X = {X:.6g} approaching X_c = {X_c:.6g} at dX/dt = {xdot:.4g}"
    return h, why


def rk4_segment(rate, t0, t1, y0, step, t_out, X_c=math.inf, xfun=None):
    """Integrate ``rate`` from ``t0`` to ``t1`` with RK4 steps of at most ``step`` (smaller where stiff).

    Parameters
    ----------
    rate : callable
        ``rate(t, a, b) -> (da/dt, db/dt)``; raises ``PoleCrossing`` beyond X_c.
    t0, t1 : float
    y0 : (a, b)
    step : float
        Largest step (time units): the grid step.
    t_out : array
        Sorted report times in ``[t0, t1]``.
    X_c : float
        Model 1's pole, for the pole bound of the step and the error message.
    xfun : callable, optional
        ``xfun(t, a, b) -> X`` of the segment (see ``stable_step``).

    Returns
    -------
    Y : ndarray, shape (len(t_out), 2)
    y1 : (a, b) at ``t1``

    Raises
    ------
    PoleError
        If a stage lands at X >= X_c despite the pole bound, or if the segment
        needs more than ``MAX_SUBSTEPS`` sub-steps or one below
        ``MIN_STEP_FRACTION`` of the step (the message gives the step needed).
    """
    n = max(1, math.ceil((t1 - t0) / step - 1e-9))
    h = (t1 - t0) / n
    a, b = float(y0[0]), float(y0[1])
    Y = np.empty((len(t_out), 2))
    budget = {"left": MAX_SUBSTEPS, "tightest": (math.inf, t0, "")}

    def advance(t, a, b, dt):
        """RK4 from t over dt; each sub-step no larger than the state at its start allows at its start and end time."""
        end = t + dt
        while True:
            remaining = end - t
            h_ok, why = min(stable_step(rate, t, a, b, X_c, xfun), stable_step(rate, end, a, b, X_c, xfun),
                            key=lambda x: x[0])
            if h_ok < budget["tightest"][0]:
                budget["tightest"] = (h_ok, t, why)
            m = 1 if remaining <= h_ok else math.ceil(remaining / h_ok)
            budget["left"] -= 1
            if budget["left"] < 0 or h_ok < MIN_STEP_FRACTION * h:
                h_min, t_min, why_min = budget["tightest"]
                what = (f"needs more than {MAX_SUBSTEPS} steps" if budget["left"] < 0 else
                        f"needs steps below {MIN_STEP_FRACTION:g} of the step {h:.3g} (the fabric may blow up)")
                raise PoleError(
                    f"RK4: the segment [{t0:.6g}, {t1:.6g}] {what}: at t = {t_min:.6g} the step must be at most "
                    f"{h_min:.3g} ({why_min}); use an adaptive method (LSODA, Radau)",
                    t=t_min, X=xfun(t_min, a, b) if xfun is not None else math.nan, X_c=X_c)
            if m == 1:
                return _rk4_step(rate, t, a, b, remaining)
            hs = remaining / m
            a, b = _rk4_step(rate, t, a, b, hs)
            t += hs

    j = 0
    t = t0
    try:
        for i in range(n + 1):
            t = t0 + i * h if i < n else t1
            # report times in [t, t + h) from this grid point
            t_next = t1 if i >= n - 1 else t0 + (i + 1) * h
            while j < len(t_out) and (t_out[j] < t_next or i == n):
                dt = t_out[j] - t
                Y[j] = (a, b) if dt <= 0.0 else advance(t, a, b, dt)
                j += 1
            if i == n:
                break
            a, b = advance(t, a, b, t_next - t)
    except PoleCrossing as exc:
        raise PoleError(
            f"RK4 with step {h:.3g}: a stage reached X = {exc.X:.6g} >= X_c = {X_c:.6g} at "
            f"t = {exc.t:.6g} (step from t = {t:.6g}); the step is too large for the approach "
            "to the pole: reduce 'step' or use an adaptive method",
            t=exc.t, X=exc.X, X_c=X_c,
        ) from None
    return Y, (a, b)
