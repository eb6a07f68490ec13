"""Constitutive laws of the fabric-friction model (see ``docs/model.md``).

Pure functions of the scalar state variable ``X = A:D'/|D'|``; they broadcast
over numpy arrays and know nothing of time integration. They are the single
place where Eq. 2, Eq. 5 and Eq. 6 of the paper are written down: the
integrators (``model``) and the fits (``calibrate``) both call them.
"""
from __future__ import annotations

import bisect
import math

import numpy as np

SQRT2 = np.sqrt(2.0)


def friction_eq2(X, X0, k1, k3, k5):
    r"""Effective friction of Eq. 2 as a function of X.

    Parameters
    ----------
    X : float or array_like
        State variable ``A:D'/|D'|`` (dimensionless).
    X0, k1, k3, k5 : float
        Eq. 2 parameters (OUR READING defaults: 0.028, 2.7, 20, 9.0e4).

    Returns
    -------
    mu : float or ndarray
        ``|sigma_xy| / p``.

    Notes
    -----
    With :math:`y = X - X_0`,

    .. math::
        \mu = \begin{cases} -k_1 y + k_3 y^3 & y < 0 \\
                             k_1 y + k_5 y^5 & y \ge 0 \end{cases}

    a V about :math:`X_0`: continuous, :math:`\mu(X_0) = 0`, with a kink there
    (the slope jumps from :math:`-k_1` to :math:`+k_1`).
    """
    y = np.asarray(X, dtype=float) - X0
    y3 = y * y * y   # products, not y**3: pow() of a negative base is ~10x slower
    mu = np.where(y < 0.0, -k1 * y + k3 * y3, k1 * y + k5 * y3 * y * y)
    return mu if mu.ndim else float(mu)


def stress_ratio_eq2(X, X0, k1, k3, k5):
    r"""Signed stress ratio behind Eq. 2: :math:`\tau = g\,\sigma_{xy}/p` with g = sign(gammadot).

    Eq. 2 gives only the modulus, :math:`\mu = |\sigma_{xy}|/p` (the V of the
    paper's Fig. 2b, zero at X0). OUR READING of its sign, measured on our DEM
    (``results/calibration/<set>/fig2b_mu_vs_X.png``, right panel): the signed
    ratio falls through zero at X0 and stays negative for X > X0, because just
    after a reversal the contact network still carries the stress of the old
    direction. So

    .. math::
        \tau(X) = -\mathrm{sign}(X - X_0)\,\mu(X) = \begin{cases}
            -k_1 y + k_3 y^3 & y < 0 \\ -k_1 y - k_5 y^5 & y \ge 0 \end{cases}

    a single decreasing curve (slope :math:`-k_1` on both sides of X0), with
    :math:`|\tau| = \mu` of ``friction_eq2``. Eq. 3 uses it as
    :math:`\sigma'/p = \sqrt2\,\tau(X)\,D'/|D'|`: still along D', but
    opposite to it while X > X0.
    """
    y = np.asarray(X, dtype=float) - X0
    y3 = y * y * y   # products, not y**3: pow() of a negative base is ~10x slower
    tau = np.where(y < 0.0, -k1 * y + k3 * y3, -k1 * y - k5 * y3 * y * y)
    return tau if tau.ndim else float(tau)


def friction_quadratic(X, m0, m1, m2):
    r"""Friction law of the previous model [15]: :math:`\tau = m_0 + m_1 X + m_2 X^2`.

    A signed stress ratio :math:`g\,\sigma_{xy}/p` (it may change sign, like
    ``stress_ratio_eq2``); the effective friction is its modulus, :math:`\mu = |\tau|`.
    """
    X = np.asarray(X, dtype=float)
    mu = m0 + m1 * X + m2 * X**2
    return mu if mu.ndim else float(mu)


def alpha_model1(X, a1, b1, c1, a2, b2, c2, X_c):
    r"""Coefficients alpha1, alpha2 of Model 1 (Eq. 6, pole term OUR READING).

    Parameters
    ----------
    X : float or array_like
        State variable; must stay below ``X_c``.
    a1, b1, c1, a2, b2, c2 : float
        Linear part ``a_i + b_i X`` and pole strength ``c_i``.
    X_c : float
        Position of the pole (paper: 0.0827).

    Returns
    -------
    alpha1, alpha2 : float or ndarray
        NaN where ``X >= X_c``, where the law is undefined. Callers that
        integrate must stop before the pole (see ``model.integrate``).

    Notes
    -----
    .. math::
        \alpha_i = a_i + b_i X + [X > 0]\, \frac{c_i X^4}{X_c - X}

    continuous and differentiable at X = 0 (the pole term starts as X^4).
    """
    if type(X) is float:
        # Scalar path (plain floats, no numpy): the integrators call this once
        # per right-hand-side evaluation, where numpy's overhead dominates.
        if not X < X_c:
            pole = math.nan
        else:
            pole = X**4 / (X_c - X) if X > 0.0 else 0.0
    else:
        X = np.asarray(X, dtype=float)
        pos = np.clip(X, 0.0, None)
        with np.errstate(divide="ignore", invalid="ignore"):
            pole = np.where(X < X_c, pos**4 / (X_c - X), np.nan)
    alpha1 = a1 + b1 * X + c1 * pole
    alpha2 = a2 + b2 * X + c2 * pole
    if type(alpha1) is float:
        return alpha1, alpha2
    if alpha1.ndim == 0:
        return float(alpha1), float(alpha2)
    return alpha1, alpha2


def alpha_model2(X, c1, c2, c3):
    r"""Coefficients of Model 2 ([15], Eq. 5): alpha1 = c1, alpha2 = c2 + c3 X."""
    if type(X) is float:  # scalar path for the integrators (see alpha_model1)
        return float(c1), c2 + c3 * X
    X = np.asarray(X, dtype=float)
    alpha1 = np.full_like(X, float(c1))
    alpha2 = c2 + c3 * X
    if alpha1.ndim == 0:
        return float(alpha1), float(alpha2)
    return alpha1, alpha2


def steady_state_constant(alpha1, alpha2):
    r"""Steady fabric of Eq. 4 in simple shear (gammadot > 0), constant alphas.

    Returns
    -------
    a, b, X : float
        ``A = [[a, b], [b, -a]]`` and ``X = sqrt(2) b``.

    Notes
    -----
    .. math::
        a = \frac{\alpha_1}{2 + \alpha_2^2}, \quad b = -\frac{\alpha_2 a}{\sqrt 2},
        \quad X = -\frac{\alpha_1 \alpha_2}{2 + \alpha_2^2}
    """
    a = alpha1 / (2.0 + alpha2**2)
    b = -alpha2 * a / SQRT2
    return a, b, SQRT2 * b


def fabric_norm(a, b):
    """|A| = sqrt(A:A) = sqrt(2 (a^2 + b^2)) for A = [[a, b], [b, -a]]."""
    return np.sqrt(2.0 * (np.asarray(a) ** 2 + np.asarray(b) ** 2))


def fabric_angle_deg(a, b):
    """Major principal direction of A in degrees, counter-clockwise from x, in [0, 180)."""
    return np.mod(np.degrees(0.5 * np.arctan2(b, a)), 180.0)


class AlphaSpline:
    r"""Free-form coefficients of Eq. 4: alpha1(X), alpha2(X) as cubic B-splines.

    Parameters
    ----------
    breaks : sequence of float
        Increasing breakpoints :math:`x_0 < \dots < x_m` (the X range the data visit).
    c1, c2 : sequence of float
        The ``m + 3`` B-spline coefficients of alpha1 and alpha2.

    Notes
    -----
    With the clamped cubic knot vector on the breaks and its basis :math:`B_k`,

    .. math::
        \alpha_i(X) = \sum_k c_{ik}\, \tilde B_k(X), \qquad
        \tilde B_k(X) = B_k(\bar X) + (X - \bar X)\, B_k'(\bar X),\quad
        \bar X = \min(\max(X, x_0), x_m),

    the spline inside the breaks, continued linearly (value and slope of the
    end) outside them. A linear law :math:`a + bX` is represented exactly, and
    stays exact outside the breaks. No pole: ``X_c`` is infinite.
    """

    degree = 3

    def __init__(self, breaks, c1, c2):
        self.breaks = tuple(float(x) for x in breaks)
        if len(self.breaks) < 2 or not np.all(np.diff(self.breaks) > 0):
            raise ValueError(f"AlphaSpline: breaks must be at least 2 increasing values, got {self.breaks}")
        self.c1, self.c2 = np.asarray(c1, dtype=float), np.asarray(c2, dtype=float)
        n = spline_size(self.breaks)
        if self.c1.shape != (n,) or self.c2.shape != (n,):
            raise ValueError(f"AlphaSpline: {len(self.breaks)} breaks need {n} coefficients per alpha, "
                             f"got {self.c1.shape} and {self.c2.shape}")

        self._pieces, self._ends = _scalar_pieces(self.breaks, self.c1, self.c2)

    def __call__(self, X):
        """``(alpha1, alpha2)`` at X (floats for a float, arrays for an array)."""
        if type(X) is float:
            return self._scalar(X)
        B = spline_basis(np.atleast_1d(np.asarray(X, dtype=float)), self.breaks)
        a1, a2 = B @ self.c1, B @ self.c2
        if np.ndim(X) == 0:
            return float(a1[0]), float(a2[0])
        return a1, a2

    def _scalar(self, X: float):
        """``__call__`` on a plain float without numpy: the cubic of X's interval by Horner's rule.

        The stability check (``model.stable_steady_states``, ``calibrate.shear_stability``)
        and the loop integrators call the law once per right-hand side, where building a
        design matrix for one point cost 80 us; this path costs about 1 us and agrees with
        ``spline_basis`` to rounding (tests/test_calibrate_freeform.py).
        """
        br = self.breaks
        if X != X:
            return math.nan, math.nan
        if X < br[0] or X > br[-1]:
            end, (v1, d1, v2, d2) = (br[0], self._ends[0]) if X < br[0] else (br[-1], self._ends[1])
            return v1 + (X - end) * d1, v2 + (X - end) * d2
        i = min(bisect.bisect_right(br, X), len(br) - 1) - 1
        h = X - br[i]
        p3, p2, p1, p0, q3, q2, q1, q0 = self._pieces[i]
        return ((p3 * h + p2) * h + p1) * h + p0, ((q3 * h + q2) * h + q1) * h + q0


def _scalar_pieces(breaks, c1, c2):
    """Per interval of ``breaks``, the cubic coefficients of both alphas in ``X - x_i`` (highest first),
    and at both ends the values and slopes of the linear continuation: ``AlphaSpline._scalar``'s tables.

    The cubics are ``scipy.interpolate.PPoly.from_spline`` of the B-splines; the ends come from
    ``_basis_ends``, as in ``spline_basis``.
    """
    from scipy.interpolate import BSpline, PPoly

    t, k = spline_knots(breaks), AlphaSpline.degree
    pp1, pp2 = (PPoly.from_spline(BSpline(t, c, k)) for c in (c1, c2))
    first = int(np.searchsorted(pp1.x, breaks[0], side="right")) - 1   # past the repeated end knots' empty intervals
    pieces = [tuple(float(v) for v in (*pp1.c[:, first + i], *pp2.c[:, first + i]))
              for i in range(len(breaks) - 1)]
    (v_lo, v_hi), (d_lo, d_hi) = _basis_ends(breaks)
    ends = tuple(tuple(float(v) for v in (v @ c1, d @ c1, v @ c2, d @ c2)) for v, d in ((v_lo, d_lo), (v_hi, d_hi)))
    return pieces, ends


def spline_knots(breaks):
    """Clamped knot vector of the cubic B-splines on ``breaks`` (ends repeated 4 times)."""
    b = np.asarray(breaks, dtype=float)
    return np.concatenate([[b[0]] * 3, b, [b[-1]] * 3])


def spline_size(breaks) -> int:
    """Number of cubic B-spline basis functions on ``breaks``: ``len(breaks) + 2``."""
    return len(breaks) + 2


_BASIS_ENDS = {}


def _basis_ends(breaks):
    """Basis values and slopes at both ends of the breaks (cached per breaks)."""
    if breaks not in _BASIS_ENDS:
        from scipy.interpolate import BSpline

        t, k, n = spline_knots(breaks), AlphaSpline.degree, spline_size(breaks)
        basis = BSpline(t, np.eye(n), k)
        ends = np.array([breaks[0], breaks[-1]])
        _BASIS_ENDS[breaks] = (basis(ends), basis.derivative()(ends))
    return _BASIS_ENDS[breaks]


def spline_basis(X, breaks) -> np.ndarray:
    r"""Design matrix :math:`\tilde B_k(X)` (shape ``(len(X), len(breaks) + 2)``) of ``AlphaSpline``.

    Inside the breaks it is ``scipy.interpolate.BSpline.design_matrix``; outside,
    the value and slope at the nearer end (linear continuation, see ``AlphaSpline``).
    """
    from scipy.interpolate import BSpline

    breaks = tuple(float(x) for x in breaks)
    X = np.asarray(X, dtype=float)
    lo, hi = breaks[0], breaks[-1]
    Xb = np.clip(np.nan_to_num(X, nan=lo), lo, hi)
    B = BSpline.design_matrix(Xb, spline_knots(breaks), AlphaSpline.degree).toarray()
    below, above = X < lo, X > hi
    if below.any() or above.any():
        (v_lo, v_hi), (d_lo, d_hi) = _basis_ends(breaks)
        B[below] = v_lo + (X[below] - lo)[:, None] * d_lo
        B[above] = v_hi + (X[above] - hi)[:, None] * d_hi
    B[np.isnan(X)] = np.nan
    return B


def spline_of_linear(breaks, a1, b1, a2, b2) -> AlphaSpline:
    """The ``AlphaSpline`` equal to ``alpha1 = a1 + b1 X``, ``alpha2 = a2 + b2 X`` everywhere.

    Cubic B-splines reproduce a linear function with the Greville abscissae as
    coefficients: :math:`X = \\sum_k \\xi_k B_k(X)`, :math:`\\xi_k` the mean of knots k+1..k+3.
    """
    t = spline_knots(breaks)
    n = spline_size(breaks)
    xi = np.array([t[k + 1:k + 4].mean() for k in range(n)])
    return AlphaSpline(breaks, a1 + b1 * xi, a2 + b2 * xi)
