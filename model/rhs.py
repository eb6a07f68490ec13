r"""Right-hand side of the fabric evolution (Eq. 4) for one history segment.

Notes
-----
With :math:`A = [[a, b], [b, -a]]`, :math:`D' = [[d_1, d_2], [d_2, -d_1]]`,
:math:`W = [[0, w], [-w, 0]]` and the Jaumann rate
:math:`\mathring A = \dot A - W A + A W`, Eq. 4
:math:`\mathring A = \alpha_1(X) D' + \alpha_2(X) |D'| A` reads

.. math::
    \dot a = 2 w b + \alpha_1 d_1 + \alpha_2 |D'| a, \qquad
    \dot b = -2 w a + \alpha_1 d_2 + \alpha_2 |D'| b,

with :math:`X = A:D'/|D'| = 2 (a d_1 + b d_2)/|D'|`. Model 1 takes the alphas
from Eq. 6 (``laws.alpha_model1``), Model 2 from Eq. 5 (``laws.alpha_model2``).
Where :math:`|D'| = 0` the alpha terms vanish whatever X is, so X is not
needed there. Simple shear (:math:`d_1 = 0`, :math:`d_2 = w = \dot\gamma/2`)
gives the component form of docs/model.md, Eq. 4.

A fabric beyond :math:`|A| = 1/\sqrt 2` (the bound of any contact network)
raises :class:`FabricDivergence`, so that parameters that make Eq. 4 blow up
stop with a message instead of overflowing into NaN.

Model 1 is undefined for :math:`X \ge X_c`: the right-hand side raises
:class:`PoleCrossing` there instead of returning NaN; the integrators turn it
into a smaller step or a :class:`PoleError`.
"""
from __future__ import annotations

import math
from functools import partial

from . import laws

MODELS = ("model1", "model2")


class PoleError(ValueError):
    """The fabric reached or would start beyond the pole X_c of Model 1.

    Attributes ``t``, ``X`` and ``X_c`` name where it happened.
    """

    def __init__(self, message, t=math.nan, X=math.nan, X_c=math.nan):
        super().__init__(message)
        self.t, self.X, self.X_c = t, X, X_c


class FabricDivergence(ValueError):
    """The fabric left the physical range |A| <= 1/sqrt(2) (or became non-finite).

    A = -I/2 + <n (x) n> has eigenvalues in [-1/2, 1/2], so |A| <= 1/sqrt(2)
    for any contact network; a model that leaves that range has parameters
    that make Eq. 4 grow without bound (alpha2 |D'| > 0 for long).
    """

    def __init__(self, t, a, b):
        super().__init__(f"the fabric diverged at t = {t:.6g}: |A| = {math.sqrt(2 * (a * a + b * b)):.4g} "
                         "exceeds 1/sqrt(2), the bound of any fabric deviator (check alpha2 and its growth with X)")
        self.t = t


class PoleCrossing(ArithmeticError):
    """Internal signal: the right-hand side was asked for X >= X_c (a trial stage)."""

    def __init__(self, t, X):
        super().__init__(f"X = {X!r} >= X_c at t = {t!r}")
        self.t, self.X = t, X


def coefficient_law(params, model: str):
    """Return ``(alphas, X_c)``: ``alphas(X) -> (alpha1, alpha2)`` for plain floats, and the pole.

    ``X_c`` is ``inf`` for Model 2 (no pole).
    """
    if model == "model1":
        m = params.model1
        f = partial(laws.alpha_model1, a1=m.a1, b1=m.b1, c1=m.c1, a2=m.a2, b2=m.b2, c2=m.c2, X_c=m.X_c)
        return f, m.X_c
    if model == "model2":
        m = params.model2
        return partial(laws.alpha_model2, c1=m.c1, c2=m.c2, c3=m.c3), math.inf
    raise ValueError(f"model = {model!r} is not one of {MODELS}")


def make_rate(kin, alphas, X_c):
    """Build ``rate(t, a, b) -> (da/dt, db/dt)`` on plain floats (see module Notes).

    Parameters
    ----------
    kin : callable
        ``kin(t) -> (d1, d2, w)`` of the segment.
    alphas : callable
        ``alphas(X) -> (alpha1, alpha2)``.
    X_c : float
        Pole position (``inf`` for none). Raises :class:`PoleCrossing` if X >= X_c.
    """

    def rate(t, a, b):
        if not a * a + b * b <= 0.25:  # |A| > 1/sqrt(2), or NaN
            raise FabricDivergence(t, a, b)
        d1, d2, w = kin(t)
        nD = math.sqrt(2.0 * (d1 * d1 + d2 * d2))
        if nD == 0.0:
            return 2.0 * w * b, -2.0 * w * a
        X = 2.0 * (a * d1 + b * d2) / nD
        if not X < X_c:
            raise PoleCrossing(t, X)
        al1, al2 = alphas(float(X))
        return 2.0 * w * b + al1 * d1 + al2 * nD * a, -2.0 * w * a + al1 * d2 + al2 * nD * b

    return rate
