r"""Can a fitted parameter set shear steadily? The guard every fitted Model 1, Model 2 and free-form set passes.

A parameter table that cannot shear steadily is not a model of the material.
Two tests, on the law :math:`\alpha_1(X), \alpha_2(X)` of the set (Eq. 6 with
its pole :math:`X_c`, Eq. 5, or the free-form spline):

1. **A stable steady state of simple shear** (``model.stable_steady_states``):
   a root of :math:`X = -\alpha_1\alpha_2/(2 + \alpha_2^2)` with
   :math:`|A| \le 1/\sqrt2` where the Jacobian of Eq. 4 has eigenvalues with
   negative real parts. The constant-alpha hinge of the fits
   (``fits._steady_fabric_residuals``: :math:`\alpha_2 < 0` at the DEM's
   steady X) misses an X-dependent law whose fixed point has moved away from
   the DEM's X, or is unstable there.
2. **Forward shear from isotropy stays physical** for ``FORWARD_STRAIN``:
   Eq. 4 in simple shear,

   .. math:: \frac{da}{d\gamma} = \frac{\alpha_2 a}{\sqrt2} + b, \qquad
             \frac{db}{d\gamma} = \frac{\alpha_1}{2} + \frac{\alpha_2 b}{\sqrt2} - a, \qquad X = \sqrt2 b

   from :math:`A = 0`, integrated (``scipy.integrate.LSODA``)
   until :math:`|A| = \sqrt{2(a^2 + b^2)}` exceeds :math:`1/\sqrt2` (the bound
   of any fabric deviator) or X reaches the pole: the strain where it does is
   reported.

``check`` returns the verdict and a sentence naming the failure;
``calibrate.pipeline`` writes it per set in ``fit_quality.csv``
(``shear_stable``, ``shear_note``) and the log, and never makes an unstable
set a model's default.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import LSODA
from scipy.optimize import brentq

from model import params_from_dict
from model.laws import SQRT2
from model.integrate import stable_steady_states
from model.rhs import coefficient_law

#: Strain of forward shear from isotropy a set must survive ("within a few strains").
FORWARD_STRAIN = 5.0
#: |A|^2 / 2 = a^2 + b^2 at the bound |A| = 1/sqrt(2) of any fabric deviator.
AB2_MAX = 0.25
EPS = np.finfo(float).eps


def law_of(params, model: str):
    """``(alphas, X_c)`` of the ``model`` block of a parameter document or ``ModelParams`` (``model.rhs.coefficient_law``)."""
    return coefficient_law(params_from_dict(params) if isinstance(params, dict) else params, model)


def forward_divergence(alphas, X_c=math.inf, strain: float = FORWARD_STRAIN):
    r"""Strain at which forward simple shear from isotropy leaves the physical fabrics, or None.

    Integrates the module's Eq. 4 in simple shear from :math:`a = b = 0` with scipy's LSODA
    (rtol 1e-6, atol 1e-9); stops where :math:`a^2 + b^2 = 1/4` (:math:`|A| = 1/\sqrt2`) or
    :math:`\sqrt2 b = X_c`.

    The loop is ``solve_ivp``'s with its two terminal events, written out for plain floats:
    the same LSODA steps, an event where its function changes sign over a step, located by
    ``brentq`` on the step's dense output to 4 eps, the earliest of the two. This test is run
    for every trial set of every fit, a third of a calibration set's time through
    ``solve_ivp``, whose generic event bookkeeping (numpy on two-element arrays, every step)
    was a third of the test; the results are the same to the bit
    (tests/test_calibrate_shear_stability.py).

    Returns
    -------
    (float, str) or None
        The strain and what happened ("|A| > 1/sqrt 2", "X reaches the pole X_c",
        "the integration fails"), or None if the fabric stays physical for ``strain``.
    """
    def rate(_, y):
        a, b = y
        al1, al2 = alphas(float(SQRT2 * b))
        return [al2 * a / SQRT2 + b, 0.5 * al1 + al2 * b / SQRT2 - a]

    events = ((lambda y: AB2_MAX - (y[0] ** 2 + y[1] ** 2), "|A| > 1/sqrt 2"),
              (lambda y: (X_c - SQRT2 * y[1]) if math.isfinite(X_c) else 1.0, "X reaches the pole X_c"))
    with np.errstate(all="ignore"):
        try:
            solver = LSODA(rate, 0.0, [0.0, 0.0], strain, rtol=1e-6, atol=1e-9)
            g, finite = [f(solver.y) for f, _ in events], True
            while solver.status == "running":
                message = solver.step()
                if solver.status == "failed":
                    return float(solver.t), f"the integration fails ({message})"
                g_new = [f(solver.y) for f, _ in events]
                crossed = [k for k in (0, 1) if g[k] <= 0 <= g_new[k] or g[k] >= 0 >= g_new[k]]
                if crossed:
                    sol = solver.dense_output()
                    t, k = min((brentq(lambda t, f=events[k][0]: f(sol(t)), solver.t_old, solver.t,
                                       xtol=4 * EPS, rtol=4 * EPS), k) for k in crossed)
                    return float(t), events[k][1]
                g, finite = g_new, finite and math.isfinite(solver.y[0]) and math.isfinite(solver.y[1])
        except (ValueError, ArithmeticError) as exc:
            return 0.0, f"the integration fails ({exc})"
    if not finite:
        return float(solver.t), "the integration fails (a state is not finite)"
    return None


def check(alphas, X_c=math.inf, strain: float = FORWARD_STRAIN) -> dict:
    """Whether the law ``alphas`` (pole ``X_c``) can shear steadily (module tests 1 and 2).

    Returns
    -------
    dict
        ``stable`` (bool), ``note`` ("" when stable, else the failures in words),
        ``steady_X`` (the stable steady X reached, or NaN) and ``diverges_at`` (the strain
        of forward shear from isotropy where the fabric leaves the physical range, or NaN).
    """
    notes = []
    with np.errstate(all="ignore"):
        roots = stable_steady_states(alphas, X_c)
    if not roots:
        notes.append("no stable steady state of simple shear")
    div = forward_divergence(alphas, X_c, strain)
    if div is not None:
        notes.append(f"forward shear from isotropy: {div[1]} after {div[0]:.3g} strain (of {strain:g})")
    return {"stable": not notes, "note": "; ".join(notes),
            "steady_X": float(roots[0][2]) if roots else math.nan,
            "diverges_at": div[0] if div is not None else math.nan}


def check_block(params, model: str, strain: float = FORWARD_STRAIN) -> dict:
    """``check`` of the Model 1 or Model 2 block of a parameter document or ``ModelParams``."""
    return check(*law_of(params, model), strain=strain)
