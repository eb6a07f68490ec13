r"""Least-squares fits of Eq. 2, the quadratic law of [15], Eq. 6 (Model 1) and Model 2.

The laws themselves come from ``model.laws`` (never re-written here). Every fit
adds *steady-state residuals* so the steady state the parameters imply agrees
with the DEM's (docs/model.md's closed form of Eq. 4 with the coefficients taken at the DEM's
steady X):

.. math::
    a_{ss} = \frac{\alpha_1}{2 + \alpha_2^2},\quad b_{ss} = -\frac{\alpha_2 a_{ss}}{\sqrt2}
    \quad\text{(fabric)}, \qquad \mu(X_{ss}) = \mu_{ss}\quad\text{(friction)},

each divided by the standard error of the DEM's ensemble steady value and
multiplied by ``steady_weight``. X_c is bounded below by the mirrored steady
X (:math:`-X_{ss}`), the mirrored X of every run just before its reversal (and
the 97.5 % prediction bound of it for a new seed) and the largest X of any
fitted bin, plus ``xc_margin`` (``xc_lower_bound``), so a reversal from a
calibration run's state, or most likely a new one's, starts below the pole.
``steady_weight`` and ``xc_margin`` are the caller's (``calibrate.settings.Settings`` holds
their defaults, for this fit and the curves route's alike).

Fabric fits (Eq. 6, Model 2) use the back-solved bins (``backsolve.binned``,
``used`` ones only), each whitened by its 2x2 covariance. Friction fits use
every kept sample: X from the smoothed fabric and the *signed* stress ratio
:math:`\tau = g\,\sigma_{xy}/p` (unbiased where mu ~ 0, unlike |sigma_xy|/p).
Eq. 2 is fitted through its signed form ``laws.stress_ratio_eq2``,
:math:`\tau = -\mathrm{sign}(X - X_0)\,\mu(X)`, so its V about X0 follows the
DEM's tau falling through zero (the paper's Fig. 2b plots the modulus).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from model.laws import alpha_model1, alpha_model2, friction_quadratic, steady_state_constant, stress_ratio_eq2

SQRT2 = np.sqrt(2.0)
EQ2_KEYS = ("X0", "k1", "k3", "k5")
QUAD_KEYS = ("m0", "m1", "m2")
M1_KEYS = ("a1", "b1", "c1", "a2", "b2", "c2", "X_c")
M2_KEYS = ("c1", "c2", "c3")
#: Search bounds of Eq. 2 (k5 >= 0: tau keeps falling for X > X0).
EQ2_BOUNDS = ((-0.5, 0.5), (0.0, 1e3), (-1e6, 1e6), (0.0, 1e12))
#: Search bounds of Eq. 6 without X_c (c1 <= 0 <= c2, our reading of Eq. 6, docs/model.md); X_c lies in
#: [``xc_lower_bound``, ``XC_MAX``]. Routes 1 and 2 both use them (``model1_bounds``).
M1_BOUNDS = ((-1e3, 1e3), (-1e5, 1e5), (-1e9, 0.0), (-1e3, 1e3), (-1e5, 1e5), (0.0, 1e9))
XC_MAX = 0.5
#: The sign constraints among those bounds, (block, parameter) -> (low, high), which a
#: fitted value may sit on (``tables.params_table`` notes it).
SIGN_BOUNDS = {("friction_eq2", "k5"): EQ2_BOUNDS[3], ("model1", "c1"): M1_BOUNDS[2], ("model1", "c2"): M1_BOUNDS[5]}


def model1_bounds(xc_lo: float):
    """Lower and upper bounds of the Model 1 parameters (``M1_KEYS`` order), X_c >= ``xc_lo``."""
    lo, hi = zip(*M1_BOUNDS)
    return np.array([*lo, xc_lo]), np.array([*hi, XC_MAX])


@dataclass
class FitResult:
    """One fitted block: values, the residual summary and the fit's settings."""

    block: str
    values: dict
    cost: float = np.nan
    n_data: int = 0
    rms: float = np.nan
    success: bool = True
    message: str = ""
    extra: dict = field(default_factory=dict)


#: Residual per unit of alpha2 > 0 at the steady X (a hinge: zero while alpha2 < 0).
STABILITY_WEIGHT = 1e3
#: Number of steady residuals every fabric fit appends (a, b, stability).
N_STEADY = 3


def steady_fabric_residuals(alpha1, alpha2, steady, weight):
    r"""Steady residuals: the implied steady (a, b) against the DEM's, and a stability hinge.

    With constant coefficients the steady state of Eq. 4 is linearly stable
    only for :math:`\alpha_2 < 0` (the eigenvalues are
    :math:`\alpha_2/\sqrt2 \pm i`). A DEM steady fabric with A_xx > 0 (theta_A
    above 135 deg, which 500-disk ensembles show within their noise) is matched
    by alphas of flipped sign, alpha1 > 0 and alpha2 > 0: an unstable steady
    state. The hinge ``STABILITY_WEIGHT * max(0, alpha2)`` keeps the fits on the
    admissible side, the closest stable steady state to the DEM's.
    """
    a, b, _ = steady_state_constant(alpha1, alpha2)
    return np.array([weight * (a - steady["A_xx"]) / steady["se_A_xx"],
                     weight * (b - steady["A_xy"]) / steady["se_A_xy"],
                     STABILITY_WEIGHT * max(0.0, float(alpha2))])


# --------------------------------------------------------------------------- friction


def fit_eq2(X, mu, sigma_mu, steady, steady_weight, x0=(0.028, 2.7, 20.0, 9.0e4)) -> FitResult:
    r"""Fit Eq. 2, :math:`\mu(X; X_0, k_1, k_3, k_5)`, through its signed form ``model.laws.stress_ratio_eq2``.

    Parameters
    ----------
    X, mu : arrays
        State variable and signed stress ratio :math:`g\,\sigma_{xy}/p` of the kept samples.
    sigma_mu : float
        Noise of one friction sample.
    steady : dict
        ``io.steady_values``: ``X``, ``mu``, ``se_mu``.
    """
    X, mu = np.asarray(X, float), np.asarray(mu, float)
    scale = np.array([0.01, 1.0, 10.0, 1e4])

    def res(p):
        X0, k1, k3, k5 = p * scale
        r = (stress_ratio_eq2(X, X0, k1, k3, k5) - mu) / sigma_mu
        rs = steady_weight * (stress_ratio_eq2(steady["X"], X0, k1, k3, k5) - steady["mu"]) / steady["se_mu"]
        return np.append(r, rs)

    lo, hi = (np.array(b) / scale for b in zip(*EQ2_BOUNDS))
    best = None
    for start in (np.array(x0), np.array([0.0, 3.0, 0.0, 0.0]), np.array([0.03, 2.0, 100.0, 1e5])):
        sol = least_squares(res, np.clip(start / scale, lo + 1e-9, hi - 1e-9), bounds=(lo, hi), x_scale="jac")
        if best is None or sol.cost < best.cost:
            best = sol
    vals = dict(zip(EQ2_KEYS, (best.x * scale).tolist()))
    r = best.fun[:-1] * sigma_mu
    return FitResult("friction_eq2", vals, float(best.cost), len(X), float(np.sqrt(np.mean(r**2))),
                     bool(best.success), best.message)


def fit_quadratic(X, mu, sigma_mu, steady, steady_weight) -> FitResult:
    r"""Fit :math:`\mu = m_0 + m_1 X + m_2 X^2` ([15]; ``model.laws.friction_quadratic``): linear least squares."""
    X, mu = np.asarray(X, float), np.asarray(mu, float)
    G = np.stack([np.ones_like(X), X, X**2], axis=1) / sigma_mu
    y = mu / sigma_mu
    w = steady_weight / steady["se_mu"]
    G = np.vstack([G, w * np.array([1.0, steady["X"], steady["X"] ** 2])])
    y = np.append(y, w * steady["mu"])
    coef, *_ = np.linalg.lstsq(G, y, rcond=None)
    vals = dict(zip(QUAD_KEYS, coef.tolist()))
    r = friction_quadratic(X, *coef) - mu
    return FitResult("friction_quadratic", vals, float(0.5 * np.sum((G @ coef - y) ** 2)), len(X),
                     float(np.sqrt(np.mean(r**2))))


# --------------------------------------------------------------------------- fabric


SE_FLOOR_REL = 0.01   # floor of a bin's standard error: 1 % of |alpha| ...
SE_FLOOR_ABS = 1e-3   # ... plus this, so bins of near-identical (steady) samples cannot outweigh the rest


def _whiteners(bins):
    """Per bin the 2x2 inverse Cholesky factor of its covariance (standard errors floored, see SE_FLOOR_*)."""
    out = []
    for _, row in bins.iterrows():
        s1 = max(row.se_alpha1, SE_FLOOR_REL * abs(row.alpha1) + SE_FLOOR_ABS)
        s2 = max(row.se_alpha2, SE_FLOOR_REL * abs(row.alpha2) + SE_FLOOR_ABS)
        rho = np.clip(row.cov12 / (row.se_alpha1 * row.se_alpha2), -0.999, 0.999) \
            if row.se_alpha1 > 0 and row.se_alpha2 > 0 else 0.0
        C = np.array([[s1**2, rho * s1 * s2], [rho * s1 * s2, s2**2]])
        C += np.eye(2) * 1e-12 * np.trace(C)
        out.append(np.linalg.inv(np.linalg.cholesky(C)))
    return np.array(out)


def _bin_residuals(alpha1, alpha2, bins, W):
    d = np.stack([alpha1 - bins["alpha1"].to_numpy(), alpha2 - bins["alpha2"].to_numpy()], axis=1)
    return np.einsum("kij,kj->ki", W, d).ravel()


def xc_lower_bound(steady, margin, bins=None):
    """Smallest X_c allowed, ``margin`` above the largest X the model must reach.

    That is the mirrored steady X of the ensemble, the X a reversal from the
    DEM state starts from (``steady["X_reversal_bound"]``: every run's, and the
    97.5 % prediction bound for a new seed, ``io.steady_values``; a reversal
    must begin below the pole), and, for the back-solve fit, every fitted bin's
    mean X.
    """
    xs = [-steady["X"], steady.get("X_reversal_bound", -np.inf)]
    if bins is not None and len(bins):
        xs.append(float(bins["X_mean"].max()))
    return max(xs) + margin


def fit_model1(bins, steady, steady_weight, xc_margin, x0=None) -> FitResult:
    r"""Fit Eq. 6 to the used back-solved bins (``model.laws.alpha_model1``).

    .. math::
        \alpha_i = a_i + b_i X + [X > 0]\,\frac{c_i X^4}{X_c - X}

    with :math:`c_1 \le 0 \le c_2` (our reading of Eq. 6, docs/model.md) and
    :math:`X_c \ge` ``xc_lower_bound``. Several starts; the lowest cost wins.
    Region A (X <= 0) sets a_i, b_i; region B (X > 0) the c_i and X_c.
    """
    b = bins[bins["used"]].reset_index(drop=True)
    if len(b) < 4:
        raise ValueError(f"Model 1 fit: only {len(b)} usable bins of alpha(X); at least 4 are needed")
    W = _whiteners(b)
    X = b["X_mean"].to_numpy()
    xc_lo = xc_lower_bound(steady, xc_margin, b)
    scale = np.array([1.0, 10.0, 1e3, 1.0, 10.0, 1e3, 0.01])

    def unpack(p):
        return p * scale

    def res(p):
        a1, b1, c1, a2, b2, c2, Xc = unpack(p)
        al1, al2 = alpha_model1(X, a1, b1, c1, a2, b2, c2, Xc)
        r = _bin_residuals(np.asarray(al1), np.asarray(al2), b, W)
        s1, s2 = alpha_model1(steady["X"], a1, b1, c1, a2, b2, c2, Xc)
        return np.concatenate([r, steady_fabric_residuals(s1, s2, steady, steady_weight)])

    lo, hi = (b / scale for b in model1_bounds(xc_lo))
    # linear start from region A
    A = b[b["X_mean"] <= 0]
    if len(A) >= 2:
        p1 = np.polyfit(A["X_mean"], A["alpha1"], 1, w=1 / A["se_alpha1"])
        p2 = np.polyfit(A["X_mean"], A["alpha2"], 1, w=1 / A["se_alpha2"])
        lin = (p1[1], p1[0], p2[1], p2[0])
    else:
        lin = (-0.5, 0.0, -5.0, 50.0)
    starts = [] if x0 is None else [np.array([x0[k] for k in M1_KEYS])]
    for c1, c2, dx in ((-1e3, 1e3, 0.01), (-1e2, 1e2, 0.03), (-1e4, 1e3, 0.005)):
        starts.append(np.array([lin[0], lin[1], c1, lin[2], lin[3], c2, xc_lo + dx]))
    best = None
    for st in starts:
        st = np.clip(st / scale, lo + 1e-9 * np.abs(lo) + 1e-12, hi - 1e-9 * np.abs(hi) - 1e-12)
        sol = least_squares(res, st, bounds=(lo, hi), x_scale="jac", max_nfev=2000)
        if best is None or sol.cost < best.cost:
            best = sol
    vals = dict(zip(M1_KEYS, unpack(best.x).tolist()))
    return FitResult("model1", vals, float(best.cost), len(b), float(np.sqrt(np.mean(best.fun[:-N_STEADY] ** 2))),
                     bool(best.success), best.message, {"X_c_lower_bound": xc_lo})


def fit_model2(bins, steady, steady_weight) -> FitResult:
    r"""Fit Model 2, :math:`\alpha_1 = c_1`, :math:`\alpha_2 = c_2 + c_3 X` (``model.laws.alpha_model2``), to the used bins."""
    b = bins[bins["used"]].reset_index(drop=True)
    if len(b) < 2:
        raise ValueError(f"Model 2 fit: only {len(b)} usable bins of alpha(X); at least 2 are needed")
    W = _whiteners(b)
    X = b["X_mean"].to_numpy()

    def res(p):
        al1, al2 = alpha_model2(X, *p)
        r = _bin_residuals(np.asarray(al1), np.asarray(al2), b, W)
        s1, s2 = alpha_model2(steady["X"], *p)
        return np.concatenate([r, steady_fabric_residuals(s1, s2, steady, steady_weight)])

    p1 = float(np.average(b["alpha1"], weights=1 / b["se_alpha1"] ** 2))
    p2 = np.polyfit(X, b["alpha2"], 1, w=1 / b["se_alpha2"])
    best = None
    for st in (np.array([p1, p2[1], p2[0]]), np.array([-0.5, -5.0, 50.0])):
        sol = least_squares(res, st, x_scale="jac")
        if best is None or sol.cost < best.cost:
            best = sol
    vals = dict(zip(M2_KEYS, best.x.tolist()))
    return FitResult("model2", vals, float(best.cost), len(b), float(np.sqrt(np.mean(best.fun[:-N_STEADY] ** 2))),
                     bool(best.success), best.message)
