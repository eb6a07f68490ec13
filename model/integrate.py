r"""``simulate`` and ``steady_state``: the model's entry points.

Output conventions (columns of the table ``simulate`` returns):

- ``t``: time; ``strain``: signed accumulated strain :math:`\int\dot\gamma\,dt`;
  ``gammadot``: signed equivalent shear rate (gammadot in simple shear).
- ``A_xx, A_xy``: the fabric ``A = [[A_xx, A_xy], [A_xy, -A_xx]]``;
  ``A_norm`` = |A|; ``theta_A`` in degrees in [0, 180).
- ``X`` = A:D'/|D'|. Where |D'| = 0 (a rest, a zero crossing of a sinusoidal
  reversal) X is undefined; the table then reports A:N with N the last defined
  direction of D' (the one-sided limit from before; for a history that starts
  at rest, the first direction after it). ``mu`` = |sigma_xy|/p is the friction
  law at that X (the friction the layer would mobilise on resuming);
  ``sigma_xy_over_p`` is Eq. 3 with the signed ratio tau of the law
  (``laws.stress_ratio_eq2``, ``laws.friction_quadratic``):
  :math:`\sqrt2\,\tau(X)\,D'_{xy}/|D'|` (= tau sign(gammadot) in simple shear,
  opposite to gammadot while X > X0 after a reversal), 0 at rest.
- At a boundary where the rate jumps (Heaviside), two rows share the time: the
  left limit, then the right limit (X flips sign there). Where the rate is
  continuous (a zero crossing of the sinusoid) only the left row is reported.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import brentq

from . import laws
from .adaptive import SOLVERS, adaptive_segment
from .histories import History, ShearSegment
from .kinematics import double_contraction
from .params import ModelParams, load_params, params_from_dict
from .rhs import MODELS, PoleError, coefficient_law, make_rate
from .rk4 import rk4_segment

COLUMNS = ["t", "strain", "gammadot", "A_xx", "A_xy", "A_norm", "theta_A", "X", "mu", "sigma_xy_over_p"]
METHODS = ("RK4",) + tuple(SOLVERS)
FRICTIONS = ("eq2", "quadratic")

# Chosen from results/accuracy/ode_work_precision.csv (see model/README.md).
DEFAULT_METHOD = "LSODA"
DEFAULT_RTOL = 1e-10
DEFAULT_ATOL = 1e-12
DEFAULT_RK4_STRAIN_STEP = 1e-2   # RK4 step in units of strain when `step` is None
POINTS_PER_STRAIN = 200          # default report grid


def as_params(params) -> ModelParams:
    """Accept a ``ModelParams``, a parsed dict, or a path to a parameter file."""
    if isinstance(params, ModelParams):
        return params
    if isinstance(params, dict):
        return params_from_dict(params)
    if isinstance(params, (str, Path)):
        return load_params(params)
    raise ValueError(f"params must be ModelParams, a dict or a file path, got {type(params).__name__}")


# --------------------------------------------------------------------------- steady state


def _shear_rate_of_strain(alphas, a, b):
    """d(a, b)/d(strain) in steady simple shear with gammadot > 0 (docs/model.md, Eq. 4 in components)."""
    X = laws.SQRT2 * b
    al1, al2 = alphas(float(X))
    return al2 * a / laws.SQRT2 + b, 0.5 * al1 + al2 * b / laws.SQRT2 - a


def _is_stable(alphas, a, b, X_c):
    eps = 1e-7
    J = np.empty((2, 2))
    for k, (da, db) in enumerate(((eps, 0.0), (0.0, eps))):
        if laws.SQRT2 * (b + db) >= X_c or laws.SQRT2 * (b - db) >= X_c:
            return False
        fp = _shear_rate_of_strain(alphas, a + da, b + db)
        fm = _shear_rate_of_strain(alphas, a - da, b - db)
        J[:, k] = (np.array(fp) - np.array(fm)) / (2 * eps)
    return bool(np.all(np.linalg.eigvals(J).real < 0.0))


def steady_state(params, model="model1", sign=+1):
    r"""Fixed point of Eq. 4 with X-dependent coefficients in steady simple shear.

    Parameters
    ----------
    params : ModelParams, dict or path
    model : {"model1", "model2"}
    sign : {+1, -1}
        Sign of gammadot.

    Returns
    -------
    A_xx, A_xy, X : float

    Notes
    -----
    Solves :math:`X = -\alpha_1(X)\alpha_2(X)/(2 + \alpha_2(X)^2)` (docs/model.md's closed
    form with the alphas taken at X) by bracketing on ``[-1, min(1, X_c))`` and
    ``brentq``; then :math:`a = \alpha_1/(2 + \alpha_2^2)`, :math:`b = -\alpha_2 a/\sqrt2`
    for gammadot > 0. Reversing the shear flips b and keeps a and X. Only
    linearly stable roots with a physical fabric (|A| <= 1/sqrt(2), the bound of
    any fabric deviator) count; if several remain, the one reached from an
    isotropic fabric (A = 0) is returned.
    """
    p = as_params(params)
    if sign not in (1, -1):
        raise ValueError(f"sign = {sign!r} must be +1 or -1")
    alphas, X_c = coefficient_law(p, model)
    stable = stable_steady_states(alphas, X_c)
    if not stable:
        hi = min(1.0, X_c * (1.0 - 1e-9)) if math.isfinite(X_c) else 1.0
        raise ValueError(f"{model}: no stable steady state of simple shear with X in [-1, {hi:.4g}) and "
                         f"|A| <= 1/sqrt(2) for these parameters")
    if len(stable) > 1:
        from .histories import steady_shear
        tab = simulate(p, steady_shear(50.0), model=model, A0=(0.0, 0.0), strain_eval=[50.0], method="Radau")
        Xend = float(tab["X"].iloc[-1])
        stable.sort(key=lambda r: abs(r[2] - Xend))
    a, b, X = stable[0]
    return float(a), float(b) * sign, float(X)


def stable_steady_states(alphas, X_c=math.inf) -> list:
    r"""Every linearly stable, physical fixed point of Eq. 4 in simple shear (gammadot > 0), any law alpha(X).

    The roots of :math:`X = -\alpha_1(X)\alpha_2(X)/(2 + \alpha_2(X)^2)` on
    ``[-1, min(1, X_c))`` (``steady_state``'s bracketing), kept where
    :math:`|A| \le 1/\sqrt2` and the Jacobian of Eq. 4 has eigenvalues with
    negative real parts.

    Parameters
    ----------
    alphas : callable
        ``alphas(X) -> (alpha1, alpha2)``, vectorised over an array of X
        (Models 1 and 2, ``laws.AlphaSpline``).
    X_c : float
        Pole (``inf`` for none).

    Returns
    -------
    list of (a, b, X)
        Empty when simple shear has no stable steady state.
    """
    hi = min(1.0, X_c * (1.0 - 1e-9)) if math.isfinite(X_c) else 1.0
    f = lambda X: X - laws.steady_state_constant(*alphas(float(X)))[2]  # noqa: E731
    grid = np.linspace(-1.0, hi, 4001)
    if math.isfinite(X_c):  # resolve roots pressed against the pole
        grid = np.unique(np.concatenate([grid, X_c - X_c * np.logspace(-9, -1, 161)]))
        grid = grid[grid <= hi]
    vals = grid - laws.steady_state_constant(*alphas(grid))[2]  # vectorised f on the grid
    roots = []
    for i in np.nonzero(vals[:-1] * vals[1:] <= 0.0)[0]:
        if vals[i] == 0.0:
            roots.append(float(grid[i]))
        elif vals[i + 1] != 0.0:
            roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps))
    stable = []
    for X in roots:
        a, b, _ = laws.steady_state_constant(*alphas(float(X)))
        if a * a + b * b <= 0.25 and _is_stable(alphas, a, b, X_c):  # physical: |A| <= 1/sqrt(2)
            stable.append((a, b, X))
    return stable


# --------------------------------------------------------------------------- simulate


def _check_inputs(model, method, rtol, atol, step, friction):
    if model not in MODELS:
        raise ValueError(f"model = {model!r} is not one of {MODELS}")
    if method not in METHODS:
        raise ValueError(f"method = {method!r} is not one of {METHODS}")
    if friction not in FRICTIONS:
        raise ValueError(f"friction = {friction!r} is not one of {FRICTIONS}")
    if method == "RK4":
        if step is not None and not (math.isfinite(step) and step > 0):
            raise ValueError(f"step = {step!r} is outside the allowed range (0, inf)")
    else:
        for name, v in (("rtol", rtol), ("atol", atol)):
            if not (math.isfinite(v) and 0.0 < v < 1.0):
                raise ValueError(f"{name} = {v!r} is outside the allowed range (0, 1)")
        if rtol < 100 * np.finfo(float).eps:
            raise ValueError(f"rtol = {rtol!r} is outside the allowed range [{100 * np.finfo(float).eps:.3g}, 1)")


def report_times(history: History, t_eval, strain_eval, points_per_strain):
    """Return a list, per segment, of sorted report times."""
    segs = history.segments
    if t_eval is not None and strain_eval is not None:
        raise ValueError("give t_eval or strain_eval, not both")
    if strain_eval is not None:
        t_eval = history.times_at_strains(strain_eval)
    out = [[] for _ in segs]
    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float).ravel()
        if not np.all(np.isfinite(t_eval)) or np.any(np.diff(t_eval) < 0):
            raise ValueError("t_eval must be finite and non-decreasing")
        tol = 1e-12 * max(1.0, history.t_end)
        if t_eval.size and (t_eval[0] < -tol or t_eval[-1] > history.t_end * (1 + 1e-12) + tol):
            raise ValueError(f"t_eval must lie in [0, {history.t_end:g}]")
        t_eval = np.clip(t_eval, 0.0, history.t_end)
        idx = history.segment_index(t_eval)
        for k in range(1, len(t_eval)):  # a repeated boundary time: the second is the right limit
            if t_eval[k] == t_eval[k - 1] and idx[k] == idx[k - 1] and idx[k] + 1 < len(segs) \
                    and t_eval[k] == segs[idx[k]].t1:
                idx[k] += 1
        for k, i in enumerate(idx):
            out[i].append(max(t_eval[k], segs[i].t0))
        return [np.array(o) for o in out]
    for i, s in enumerate(segs):
        dstrain = abs(float(s.strain(s.t1)[0]))
        n = max(5, math.ceil(points_per_strain * dstrain) + 1)
        t = np.linspace(s.t0, s.t1, n)
        if i > 0:
            g_left = float(segs[i - 1].gammadot(s.t0)[0])
            g_right = float(s.gammadot(s.t0)[0])
            if abs(g_left - g_right) <= 1e-12 * max(abs(g_left), abs(g_right), 1e-300):
                t = t[1:]
        out[i] = t
    return out


def simulate(params, history: History, model="model1", A0=None, method=DEFAULT_METHOD,
             rtol=DEFAULT_RTOL, atol=DEFAULT_ATOL, step=None, friction="eq2",
             strain_eval=None, t_eval=None, points_per_strain=POINTS_PER_STRAIN,
             max_steps=None) -> pd.DataFrame:
    r"""Integrate Eq. 4 along ``history`` and tabulate fabric, X and friction.

    Parameters
    ----------
    params : ModelParams, dict or path to a parameter file
    history : History
        See ``model.histories`` (heaviside, sinusoidal, tabulated, rest, ...).
    model : {"model1", "model2"}
        Eq. 6 (with pole X_c) or Eq. 5.
    A0 : (A_xx, A_xy), optional
        Initial fabric; default the model's steady state for the sign of the
        first non-zero shear rate (``steady_state``).
    method : {"RK4", "RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA"}
        ``"RK4"`` is the paper's fixed step (cut where stiff); the others are scipy's.
    rtol, atol : float
        Tolerances of the scipy methods.
    step : float, optional
        RK4 time step; default ``1e-2`` units of strain at the largest rate.
        RK4 cuts it where Eq. 4 is stiff or X nears the pole (``model.rk4``),
        and refuses with the step it needs if that takes too many steps.
    friction : {"eq2", "quadratic"}
        Eq. 2 or the quadratic law of [15].
    strain_eval : array, optional
        Strains at which to report, in the order the path visits them (e.g.
        0..3 then 3..0 for a reversal at strain 3); see ``History.times_at_strains``.
    t_eval : array, optional
        Non-decreasing times at which to report instead. A boundary time given
        twice gives its left, then its right limit.
    points_per_strain : int
        Density of the default report grid (uniform in time per segment).
    max_steps : int, optional
        Budget of solver steps per history segment (scipy methods); past it a
        ``RuntimeError`` says so. Default: none. A fitting loop sets one, so
        that a trial parameter set that makes Eq. 4 stiff (an explicit method
        crawling along the pole) costs a bounded time and scores as failed.

    Returns
    -------
    pandas.DataFrame
        Columns ``COLUMNS`` (see the module docstring for the conventions).

    Raises
    ------
    PoleError
        Model 1 reaches X >= X_c unresolved, or a reversal mirrors X to >= X_c.
    ValueError
        Bad parameters or options (the message names the key and its range).
    """
    p = as_params(params)
    _check_inputs(model, method, rtol, atol, step, friction)
    if not isinstance(history, History):
        raise ValueError(f"history must be a model.History, got {type(history).__name__}")
    alphas, X_c = coefficient_law(p, model)
    seg_dir = segment_directions(history.segments)
    y = initial_fabric(p, model, A0, seg_dir[0])
    if method == "RK4" and step is None:
        step = _default_rk4_step(history)
    times = report_times(history, t_eval, strain_eval, points_per_strain)
    t, Y, seg_idx = _integrate_segments(history, alphas, X_c, y, times, method, rtol, atol, step, max_steps)
    return _table(history, p, model, friction, t, Y, seg_idx, seg_dir, X_c)


def segment_directions(segs):
    """Direction of D' per segment, a rest inheriting the last defined one (the first one, at the start)."""
    dirs = [s.direction() for s in segs]
    defined = [d for d in dirs if d is not None]
    last = defined[0] if defined else (0.0, 1.0 / laws.SQRT2)
    seg_dir = []
    for d in dirs:
        last = d if d is not None else last
        seg_dir.append(last)
    return seg_dir


def initial_fabric(p, model, A0, first_direction):
    """``A0`` checked, or the steady state for the sign of the first shear (of D'_xy in ``first_direction``)."""
    if A0 is None:
        a, b, _ = steady_state(p, model, sign=-1 if first_direction[1] < 0 else +1)
        return np.array([a, b])
    y = np.asarray(A0, dtype=float).ravel()
    if y.shape != (2,) or not np.all(np.isfinite(y)):
        raise ValueError(f"A0 = {A0!r} must be two finite numbers (A_xx, A_xy)")
    return y


def _default_rk4_step(history):
    """``DEFAULT_RK4_STRAIN_STEP`` units of strain at the largest rate of the history."""
    g_max = max(float(np.max(np.abs(s.gammadot(np.linspace(s.t0, s.t1, 17))))) for s in history.segments)
    return DEFAULT_RK4_STRAIN_STEP / g_max if g_max > 0 else history.t_end / 100.0


def _integrate_segments(history, alphas, X_c, y, times, method, rtol, atol, step, max_steps):
    """Integrate segment by segment from the fabric ``y``; return report times, states and segment indices."""
    rows_t, rows_Y, rows_seg = [], [], []
    for i, s in enumerate(history.segments):
        rate = make_rate(s.kin, alphas, X_c)
        _check_start_below_pole(history, i, y, X_c)
        t_out = np.asarray(times[i], dtype=float)
        xfun = _xfun(s)
        if method == "RK4":
            Y, y1 = rk4_segment(rate, s.t0, s.t1, y, step, t_out, X_c, xfun)
        else:
            Y, y1, _ = adaptive_segment(rate, s.t0, s.t1, y, method, rtol, atol, t_out, X_c, xfun,
                                        max_steps=max_steps)
        y = np.asarray(y1, dtype=float)
        rows_t.append(t_out)
        rows_Y.append(Y)
        rows_seg.append(np.full(len(t_out), i))
    t = np.concatenate(rows_t)
    Y = np.concatenate(rows_Y) if rows_Y else np.empty((0, 2))
    return t, Y, np.concatenate(rows_seg).astype(int)


def _check_start_below_pole(history, i, y, X_c):
    """Raise ``PoleError`` if segment ``i`` starts (a reversal mirrors X to -X) at or beyond X_c."""
    s = history.segments[i]
    d = s.start_direction()
    if d is None or not math.isfinite(X_c):
        return
    X_start = double_contraction(y[0], y[1], *d)
    if not X_start < X_c:
        raise PoleError(
            f"at t = {s.t0:.6g} (strain {history.strain0[i]:.6g}) the shear direction "
            f"changes and X starts at {X_start:.6g} >= X_c = {X_c:.6g}: Model 1 is undefined "
            "there (a reversal mirrors X to -X); this input is outside the model",
            t=s.t0, X=X_start, X_c=X_c,
        )


def _xfun(seg):
    def xfun(t, a, b):
        d1, d2, _ = seg.kin(t)
        n = math.sqrt(2.0 * (d1 * d1 + d2 * d2))
        if n == 0.0:
            return math.nan
        return double_contraction(a, b, d1, d2) / n
    return xfun


def _table(history, p, model, friction, t, Y, seg_idx, seg_dir, X_c):
    segs = history.segments
    n = len(t)
    n1 = np.empty(n)
    n2 = np.empty(n)
    nD = np.empty(n)
    gd = np.empty(n)
    strain = np.empty(n)
    for i in np.unique(seg_idx):
        m = seg_idx == i
        s = segs[i]
        ti = t[m]
        gd[m] = s.gammadot(ti)
        strain[m] = history.strain0[i] + s.strain(ti)
        kin = np.array([s.kin(float(x))[:2] for x in ti]).reshape(-1, 2)
        nd = np.sqrt(2.0 * (kin[:, 0] ** 2 + kin[:, 1] ** 2))
        nD[m] = nd
        if isinstance(s, ShearSegment):  # fixed direction, also at the zero-rate ends
            n1[m], n2[m] = seg_dir[i]
        else:
            safe = np.where(nd > 0, nd, 1.0)
            n1[m] = np.where(nd > 0, kin[:, 0] / safe, seg_dir[i][0])
            n2[m] = np.where(nd > 0, kin[:, 1] / safe, seg_dir[i][1])
    a, b = Y[:, 0], Y[:, 1]
    X = double_contraction(a, b, n1, n2)
    if math.isfinite(X_c) and np.any(X >= X_c):
        k = int(np.argmax(X >= X_c))
        raise PoleError(f"X = {X[k]:.6g} >= X_c = {X_c:.6g} at t = {t[k]:.6g}: the integration crossed the pole",
                        t=float(t[k]), X=float(X[k]), X_c=X_c)
    if friction == "eq2":
        f = p.friction_eq2
        tau = laws.stress_ratio_eq2(X, f.X0, f.k1, f.k3, f.k5)
    else:
        f = p.friction_quadratic
        tau = laws.friction_quadratic(X, f.m0, f.m1, f.m2)
    tau = np.atleast_1d(np.asarray(tau, dtype=float))
    mu = np.abs(tau)
    # Eq. 3 with the signed ratio: sigma'/p = sqrt2 tau(X) D'/|D'|; zero where the layer does not deform
    sig = np.where((nD > 0) & (gd != 0.0), laws.SQRT2 * tau * n2, 0.0)
    df = pd.DataFrame({
        "t": t, "strain": strain, "gammadot": gd, "A_xx": a, "A_xy": b,
        "A_norm": laws.fabric_norm(a, b), "theta_A": laws.fabric_angle_deg(a, b),
        "X": X, "mu": mu, "sigma_xy_over_p": sig,
    }, columns=COLUMNS)
    if not np.all(np.isfinite(df.to_numpy())):
        bad = df.columns[~np.all(np.isfinite(df.to_numpy()), axis=0)].tolist()
        raise FloatingPointError(f"non-finite values in columns {bad} ({model}); please report this as a bug")
    return df
