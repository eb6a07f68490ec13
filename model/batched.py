r"""Many simple-shear trajectories integrated together, each with its own error control.

``simulate_batch`` advances N trajectories (runs, seeds, bootstrap replicates,
parameter sets, Model 1 and Model 2 mixed) at once with numpy arrays, and
returns the table ``model.simulate`` would return for each, in one long
DataFrame. Scope: simple shear, i.e. histories made of ``ShearSegment``\ s
(``steady_shear``, ``heaviside``, ``sinusoidal``, ``tabulated``) and rests
(``rest``); anything else is rejected with a ``ValueError`` (use ``simulate``).

Formulation: path strain as the independent variable
-----------------------------------------------------
In simple shear (docs/model.md, Sec. 1) :math:`d_1 = 0`,
:math:`d_2 = w = \dot\gamma/2`, :math:`|D'| = |\dot\gamma|/\sqrt2`, and Eq. 4
with the Jaumann rate (``model/rhs.py``) reads

.. math::
    \dot a = \dot\gamma\, b + \alpha_2 \frac{|\dot\gamma|}{\sqrt2} a, \qquad
    \dot b = -\dot\gamma\, a + \alpha_1 \frac{\dot\gamma}{2} + \alpha_2 \frac{|\dot\gamma|}{\sqrt2} b .

Every term carries the rate, so with the path strain :math:`s`
(:math:`ds = |\dot\gamma|\,dt`) and :math:`g = \mathrm{sign}\,\dot\gamma`, constant
on each segment of a history (segments are cut at every zero of the rate,
``model.histories``),

.. math::
    \frac{da}{ds} = \frac{\alpha_2(X)}{\sqrt2} a + g\, b, \qquad
    \frac{db}{ds} = \frac{g\,\alpha_1(X)}{2} + \frac{\alpha_2(X)}{\sqrt2} b - g\, a, \qquad
    X = \sqrt2\, g\, b ,

the form of docs/model.md, Eq. 4. A history becomes a list of *pieces*
``(g, L)``, L the path strain of the segment (0 for a rest, where
:math:`\dot A = 0`); a report time t of segment k becomes the path strain
:math:`|\gamma(t) - \gamma(t_k)|` inside piece k. The rate profile (constant,
half cosine, table) then no longer enters the integration at all. The
coefficients are Eq. 6 (Model 1),
:math:`\alpha_i = a_i + b_i X + [X > 0]\, c_i X^4/(X_c - X)`; Model 2 (Eq. 5,
:math:`\alpha_1 = c_1`, :math:`\alpha_2 = c_2 + c_3 X`) is the same expression
with :math:`(a_1, b_1, c_1, a_2, b_2, c_2, X_c) = (c_1, 0, 0, c_2, c_3, 0, \infty)`,
so one array expression serves a batch that mixes both models.

Integrator
----------
Dormand-Prince 5(4) with the coefficients of ``scipy.integrate.RK45`` (its
tableau, error weights and 4th-order dense output are read from that class),
the same step-size controller (safety 0.9, factor in [0.2, 10], no growth
right after a rejection, scipy's initial step at the start of every piece) and
the same error norm (RMS of the error over ``atol + rtol max(|y|, |y_new|)``),
but with one step size, one accept/reject decision and one report pointer per
trajectory, vectorised over the trajectories with masks. Steps end exactly on
piece ends; report points inside a step come from the dense output. Finished
trajectories leave the working arrays once they are half of them.

Pole guard and fallback to ``simulate``
---------------------------------------
Each trajectory is guarded alone; the others go on:

- a trial step whose stages ask for :math:`X \ge X_c` (or give a non-finite
  value) is rejected and retried 4 times shorter, as ``model/adaptive.py``
  does;
- an accepted state with :math:`|A| > 1/\sqrt2` (the bound of any fabric)
  stops the trajectory with ``FabricDivergence``, as ``simulate`` does; its
  message names the time at which the batch met it;
- a piece whose first X (a reversal mirrors X to -X) is :math:`\ge X_c`; a
  step size that falls below ``h_min`` (the approach to an attracting pole); a
  trajectory found stiff by the test of DOPRI5 (Hairer and Wanner, Solving
  ODEs II, Sec. IV.2: fifteen steps limited by stability rather than accuracy,
  as where a repelling pole holds X just below X_c) whose remaining path would
  take more than ``STIFF_STEPS`` such steps; more than ``max_steps`` steps; or
  a reported X at or beyond X_c: the trajectory stops in the batch and is
  handed to the per-trajectory ``model.simulate`` (default LSODA, rtol 1e-10,
  which switches to BDF where the problem is stiff) with the same history,
  start and report times. Its table, or its error (``PoleError``, or the
  ``RuntimeError`` of a step budget), is therefore exactly ``simulate``'s. The
  ``status`` table says which trajectories fell back and why.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.integrate import RK45

from . import laws
from .histories import GradientSegment, History, ShearSegment
from .integrate import (
    COLUMNS, DEFAULT_ATOL, DEFAULT_METHOD, DEFAULT_RTOL, FRICTIONS, METHODS, POINTS_PER_STRAIN, as_params,
    initial_fabric, report_times, segment_directions, simulate,
)
from .rhs import MODELS, FabricDivergence, PoleError

SQRT2 = math.sqrt(2.0)

# Dormand-Prince 5(4), read from scipy so that no coefficient is retyped here.
_A, _B, _E, _P = RK45.A, RK45.B, RK45.E, RK45.P
_NSTAGES = RK45.n_stages                       # 6, plus the first-same-as-last 7th
_ERR_EXP = -1.0 / (RK45.error_estimator_order + 1)
SAFETY, MIN_FACTOR, MAX_FACTOR, POLE_FACTOR = 0.9, 0.2, 10.0, 0.25

# Defaults of the batched solver: every case of model/work_precision.py and the simple-shear hard cases
# agree with simulate's default (LSODA, rtol 1e-10) to better than 1e-6 in |A|, theta_A (deg) and mu
# (at most 3e-10 in |A| and mu, 2e-7 deg in theta_A; tests/test_model_batched.py).
BATCH_RTOL = 1e-10
BATCH_ATOL = 1e-12
BATCH_H_MIN = 1e-9           # step (in strain) below which a trajectory falls back (approach to a pole)
BATCH_STEPS_PER_STRAIN = 1000  # step budget: this many attempts per unit of path strain, plus BATCH_MIN_STEPS
BATCH_MIN_STEPS = 1000
STIFF_STEPS = 500            # a stiff trajectory falls back if the rest of its path needs more steps than this

# Status codes of the batched solver (internal), and the reason each gives for the fallback: a
# trajectory stopped for one of these reasons is integrated again by simulate; a diverged one is
# not (its FabricDivergence names where the batch met |A| > 1/sqrt2).
_RUNNING, _DONE, _POLE_START, _COLLAPSE, _STIFF, _BUDGET, _DIVERGED, _BAD_OUTPUT = range(8)
FALLBACK_REASONS = {
    _POLE_START: "X starts at or beyond X_c",
    _COLLAPSE: "step size collapsed (pole)",
    _STIFF: "stiff (stability-limited steps)",
    _BUDGET: "step budget exceeded (stiff)",
    _BAD_OUTPUT: "a reported X at or beyond X_c",
}
_COEFFS = ("a1", "b1", "c1", "a2", "b2", "c2", "X_c")


# --------------------------------------------------------------------------- the array solver


def _rate(y, co, out, pole=True):
    r"""d(a, b)/ds of the module Notes for the states ``y`` (shape (2, n)), written to ``out``.

    ``co`` holds per trajectory the coefficients of the current piece: ``gs = (g, -g)``,
    ``sq2g`` = sqrt2 g, ``a2s, b2g, c2s`` = (a2, b2 sqrt2 g, c2)/sqrt2 and ``ha1, hb1g, hc1``
    = (a1, b1 sqrt2 g, c1) g/2, so that
    :math:`\alpha_2/\sqrt2 = a_{2s} + b_{2g} b + c_{2s} q` and
    :math:`g\alpha_1/2 = h_{a1} + h_{b1g} b + h_{c1} q` with :math:`q = X_+^4/(X_c - X)`.
    Returns the mask of trajectories where Eq. 6 is undefined (X >= X_c), or None when no
    trajectory has a pole (``pole=False``: all Model 2, whose q is 0 and is skipped).
    With free-form alphas (``co["basis"]``, the design matrix of ``laws.spline_basis``),
    :math:`\alpha_2/\sqrt2` gains :math:`\sum_k B_k(X) c_{2k}/\sqrt2` (``s2s``) and
    :math:`g\alpha_1/2` gains :math:`\sum_k B_k(X)\, g c_{1k}/2` (``hs1``).
    """
    b = y[1]
    if pole:
        X = co["sq2g"] * b
        gap = co["X_c"] - X
        q = np.maximum(X, 0.0)
        q *= q
        q *= q
        q /= gap                                     # X^4 / (X_c - X) for X > 0; 0 for Model 2
        al2 = co["c2s"] * q
        al2 += co["a2s"]
        t1 = co["hc1"] * q
        t1 += co["ha1"]
    else:
        al2, t1 = co["a2s"], co["ha1"]
    if "basis" in co:                                # free-form alphas (laws.AlphaSpline), shared breaks
        B = co["basis"](co["sq2g"] * b).T            # (K, n)
        al2 = al2 + (B * co["s2s"]).sum(axis=0)
        t1 = t1 + (B * co["hs1"]).sum(axis=0)
    al2 = al2 + co["b2g"] * b                        # alpha2 / sqrt2
    np.multiply(al2, y, out=out)                     # alpha2 (a, b) / sqrt2
    out += co["gs"] * y[::-1]                        # + (g b, -g a)
    out[1] += t1 + co["hb1g"] * b                    # + g alpha1 / 2
    return gap <= 0.0 if pole else None


def _combine(c, K):
    """sum_i c[i] K[i], added row after row: the same bits for a trajectory whatever the batch.

    (A BLAS matrix product would group the sums differently by position in the array.)
    """
    return (c.reshape((-1,) + (1,) * (K.ndim - 1)) * K).sum(axis=0)


def _rms(x, y):
    return np.sqrt(0.5 * (x * x + y * y))


_PER_PIECE = ("g", "hg", "sq2g")   # set from the piece's sign on entry


class _Solver:
    """Dormand-Prince 5(4) on many trajectories of pieces ``(g, L)``; see the module Notes.

    Inputs are flat arrays: the pieces of trajectory i are ``g[poff[i]:poff[i+1]]`` and
    ``L[...]``; its report points are ``out_piece[ooff[i]:ooff[i+1]]`` (absolute piece index)
    and ``out_s`` (path strain inside the piece), sorted by (piece, path strain). Results:
    ``Y`` (a, b at every report point), ``status`` and ``steps`` per trajectory.

    Report points are located by a global key, ``key0[piece] + s`` with ``key0`` the running
    sum of ``L + 1`` over all pieces of all trajectories: increasing, with a gap of 1 between
    pieces, so that the points a step covers are one ``searchsorted`` away.

    The working arrays (one column per trajectory still in the batch) are stepped whole;
    a trajectory that stops gets a zero step until the dead ones are half of the columns,
    when the arrays are compacted.
    """

    def __init__(self, coef, A0, g, L, poff, out_piece, out_s, ooff, rtol, atol, h_min, max_steps, spline=None):
        n = len(A0)
        self.g_all, self.L_all = g, L
        self.out_s = out_s
        self.key0 = np.concatenate([[0.0], np.cumsum(L + 1.0)])[:-1]
        self.key = self.key0[out_piece] + out_s
        # path strain after each piece, to the end of its trajectory
        total = np.repeat(np.add.reduceat(L, poff[:-1]) if len(L) else L, np.diff(poff))
        self.after = total - (np.cumsum(L) - np.repeat(np.cumsum(L)[poff[:-1]] - L[poff[:-1]], np.diff(poff)))
        self.Y = np.full((len(out_piece), 2), np.nan)
        self.status = np.full(n, _RUNNING)
        self.steps = np.zeros(n, dtype=int)
        self.where = np.zeros((n, 4))   # piece, path strain in it, a, b where each trajectory stopped
        self.rtol, self.atol, self.h_min = rtol, atol, h_min
        self.pole = bool(np.isfinite(coef[:, 6]).any())
        a1, b1, c1, a2, b2, c2, X_c = coef.T
        self.w = {
            "gid": np.arange(n), "y": A0.T.copy(), "f": np.zeros((2, n)),
            "k": poff[:-1].copy(), "kend": poff[1:].copy(), "j": ooff[:-1].copy(),
            "s": np.zeros(n), "Lk": np.zeros(n), "h": np.zeros(n), "rej": np.zeros(n, dtype=bool),
            "n": np.zeros(n, dtype=int), "nstiff": np.zeros(n, dtype=int), "ncalm": np.zeros(n, dtype=int), "live": np.ones(n, dtype=bool),
            "a1": a1.copy(), "b1": b1.copy(), "c1": c1.copy(), "X_c": X_c.copy(),
            "a2s": a2 / SQRT2, "b2s": b2 / SQRT2, "c2s": c2 / SQRT2, "maxn": np.asarray(max_steps).copy(),
            **{c: np.ones(n) for c in ("sq2g", "b2g", "ha1", "hb1g", "hc1")}, "gs": np.ones((2, n)),
        }
        self.basis = None
        if spline is not None:   # (basis(X) -> (n, K), S (n, 2, K)): see _rate
            self.basis, S = spline
            self.w.update(s1=S[:, 0, :].T.copy(), hs1=np.zeros((S.shape[2], n)), s2s=S[:, 1, :].T / SQRT2)
        with np.errstate(all="ignore"):
            self._enter(np.arange(n))

    def _co(self, sl=None):
        w = self.w
        keys = ("sq2g", "X_c", "a2s", "b2g", "c2s", "gs", "ha1", "hb1g", "hc1")
        if self.basis is not None:
            keys += ("hs1", "s2s")
        co = {c: w[c] for c in keys} if sl is None else {c: w[c][..., sl] for c in keys}
        if self.basis is not None:
            co["basis"] = self.basis
        return co

    def _stop(self, sl, code):
        """Take slots ``sl`` out of the batch with status ``code``."""
        if len(sl):
            w = self.w
            gid = w["gid"][sl]
            self.status[gid] = code
            self.steps[gid] = w["n"][sl]
            self.where[gid] = np.column_stack([w["k"][sl], w["s"][sl], w["y"][0, sl], w["y"][1, sl]])
            w["live"][sl] = False
            w["h"][sl] = 0.0

    def _fill(self, sl, limit, value):
        """Write the report points of slots ``sl`` whose path strain in the current piece is <= ``limit``.

        Report points are found by one ``searchsorted`` on their global key (see ``__init__``).
        ``value(p, s)`` gives (a, b) at path strains ``s`` for the slots ``sl[p]`` (1-D arrays).
        """
        w = self.w
        j = w["j"][sl]
        cnt = np.searchsorted(self.key, self.key0[w["k"][sl]] + limit, side="right") - j
        np.maximum(cnt, 0, out=cnt)
        total = int(cnt.sum())
        if total == 0:
            return
        p = np.repeat(np.arange(len(sl)), cnt)
        idx = np.arange(total) + np.repeat(j - (np.cumsum(cnt) - cnt), cnt)
        self.Y[idx, 0], self.Y[idx, 1] = value(p, self.out_s[idx])
        w["j"][sl] = j + cnt

    def _state(self, sl):
        """``value`` for ``_fill``: the current state of the slots, whatever the path strain."""
        a, b = self.w["y"][0, sl], self.w["y"][1, sl]
        return lambda p, s: (a[p], b[p])

    # ---- pieces
    def _enter(self, sl):
        """Start the next piece on slots ``sl`` (their ``k`` already points to it)."""
        w = self.w
        while len(sl):
            done = w["k"][sl] >= w["kend"][sl]
            self._stop(sl[done], _DONE)
            sl = sl[~done]
            k = w["k"][sl]
            g = self.g_all[k]
            w["gs"][0, sl], w["gs"][1, sl], w["sq2g"][sl] = g, -g, SQRT2 * g
            w["b2g"][sl] = w["b2s"][sl] * w["sq2g"][sl]
            w["ha1"][sl], w["hc1"][sl] = 0.5 * g * w["a1"][sl], 0.5 * g * w["c1"][sl]
            w["hb1g"][sl] = 0.5 * g * w["b1"][sl] * w["sq2g"][sl]
            if self.basis is not None:
                w["hs1"][:, sl] = 0.5 * g * w["s1"][:, sl]
            w["Lk"][sl], w["s"][sl] = self.L_all[k], 0.0
            pole = ~(w["sq2g"][sl] * w["y"][1, sl] < w["X_c"][sl])   # a reversal mirrors X past X_c
            self._stop(sl[pole], _POLE_START)
            sl = sl[~pole]
            self._fill(sl, np.zeros(len(sl)), self._state(sl))
            rest = w["Lk"][sl] <= 0.0
            self._fill(sl[rest], np.full(int(rest.sum()), 0.5), self._state(sl[rest]))
            w["k"][sl[rest]] += 1
            self._initial_step(sl[~rest])
            sl = sl[rest]

    def _initial_step(self, sl):
        """scipy's ``select_initial_step`` (error estimate of order 4) per slot, capped by the piece."""
        if not len(sl):
            return
        w, rtol, atol = self.w, self.rtol, self.atol
        y, co = w["y"][:, sl], self._co(sl)
        f, f1 = np.empty_like(y), np.empty_like(y)
        _rate(y, co, f, self.pole)
        sc = atol + np.abs(y) * rtol
        d0, d1 = _rms(*(y / sc)), _rms(*(f / sc))
        h0 = np.where((d0 < 1e-5) | (d1 < 1e-5), 1e-6, 0.01 * d0 / d1)
        bad = _rate(y + h0 * f, co, f1, self.pole)
        bad = np.zeros(len(sl), dtype=bool) if bad is None else bad
        d2 = _rms(*((f1 - f) / sc)) / h0
        dm = np.maximum(d1, d2)
        h1 = np.where(dm <= 1e-15, np.maximum(1e-6, h0 * 1e-3), (0.01 / dm) ** (1.0 / 5.0))
        h = np.where(bad, h0, np.minimum(100 * h0, h1))
        w["f"][:, sl] = f
        w["h"][sl] = np.minimum(h, w["Lk"][sl])
        w["rej"][sl] = False

    # ---- stepping
    def run(self):
        with np.errstate(all="ignore"):
            while True:
                live = self.w["live"]
                nlive = int(np.count_nonzero(live))
                if nlive == 0:
                    return self
                if nlive <= len(live) // 2:
                    self.w = {key: v[..., live] for key, v in self.w.items()}
                self._step()

    def _step(self):
        w = self.w
        n = len(w["s"])
        y, co, s, Lk, live, pole = w["y"], self._co(), w["s"], w["Lk"], w["live"], self.pole
        rest = Lk - s
        h = np.minimum(w["h"], rest)                   # 0 for stopped slots
        ends = h >= rest
        K = np.empty((_NSTAGES + 1, 2, n))
        K[0] = w["f"]
        Kf = K.reshape(_NSTAGES + 1, 2 * n)
        bad = np.zeros(n, dtype=bool)
        for st in range(1, _NSTAGES):
            ys = y + h * _combine(_A[st, :st], Kf[:st]).reshape(2, n)
            if pole:
                bad |= _rate(ys, co, K[st])
            else:
                _rate(ys, co, K[st], False)
        yn = y + h * _combine(_B, Kf[:_NSTAGES]).reshape(2, n)
        if pole:
            bad |= _rate(yn, co, K[_NSTAGES])
        else:
            _rate(yn, co, K[_NSTAGES], False)
        e = _combine(_E, Kf).reshape(2, n) * h
        e /= np.maximum(np.abs(y), np.abs(yn)) * self.rtol + self.atol
        e *= e
        err = np.sqrt(0.5 * e.sum(axis=0))             # RMS norm, as scipy
        ok = (err <= 1.0) & ~bad                       # NaN err: not ok
        # scipy's controller: factor in [0.2, 10], none above 1 right after a rejection
        fac = np.clip(SAFETY * err ** _ERR_EXP, MIN_FACTOR, MAX_FACTOR)
        fac = np.where(w["rej"] & ok, np.minimum(1.0, fac), fac)
        fac[bad | np.isnan(err)] = POLE_FACTOR
        w["h"] = h * fac
        w["rej"] = ~ok
        w["n"] += live
        ok &= live
        dK, dy = K[_NSTAGES] - K[_NSTAGES - 1], yn - ys    # for the stiffness test, before K is reused
        acc = np.flatnonzero(ok)
        if len(acc) == n:                              # all accepted: no gathers
            self._accept(acc, K, y, s, h, yn, ends)
        elif len(acc):
            self._accept(acc, K[:, :, acc], y[:, acc], s[acc], h[acc], yn[:, acc], ends[acc])
        self._stiffness(ok, h, dK, dy)
        if len(acc) < n:
            self._stop(np.flatnonzero(w["live"] & ~ok & (w["h"] < self.h_min)), _COLLAPSE)
        over = w["n"] > w["maxn"]
        if over.any():
            self._stop(np.flatnonzero(w["live"] & over), _BUDGET)

    def _stiffness(self, acc, h, dK, dy):
        """Hairer's stiffness test of DOPRI5 on accepted steps (Hairer and Wanner, Solving ODEs II, IV.2).

        The last two stages are both at the step's end, so
        :math:`\\rho = h |f(y_{new}) - f(y_6)| / |y_{new} - y_6|` estimates h times the
        largest eigenvalue; :math:`\\rho > 3.25` means the step is limited by stability,
        not accuracy. Fifteen such accepted steps (fewer than six normal ones in
        between) mark the trajectory stiff; it falls back to ``simulate`` if the
        rest of its path would still take more than ``STIFF_STEPS`` steps of the
        current size (a long steady shear at the stability limit stays in the batch).
        """
        w = self.w
        stiff = (h * h * (dK[0] * dK[0] + dK[1] * dK[1]) > 3.25**2 * (dy[0] * dy[0] + dy[1] * dy[1])) & acc
        w["nstiff"] += stiff
        w["ncalm"] += acc & ~stiff
        w["ncalm"][stiff] = 0
        w["nstiff"][w["ncalm"] >= 6] = 0
        suspect = (w["nstiff"] >= 15) & w["live"]
        if suspect.any():
            left = w["Lk"] - w["s"] + self.after[np.minimum(w["k"], len(self.after) - 1)]
            self._stop(np.flatnonzero(suspect & (left > STIFF_STEPS * h)), _STIFF)

    def _accept(self, acc, K, y, s, h, yn, ends):
        w = self.w
        s_new = np.where(ends, w["Lk"][acc], s + h)

        Q = []

        def dense(p, x_s):
            """scipy RK45's dense output: y_old + h sum_q Q_q x^(q+1), x = (s - s_old)/h."""
            if not Q:   # (4, 2, len(acc)), once per step
                Q.append((_P.T[:, :, None] * K.reshape(_NSTAGES + 1, -1)[None]).sum(axis=1).reshape(-1, 2, len(s)))
            Qp = Q[0][:, :, p]
            hp = h[p]
            x = (x_s - s[p]) / hp
            ya, yb = Qp[-1, 0] * x, Qp[-1, 1] * x
            for q in range(Qp.shape[0] - 2, -1, -1):               # Horner
                ya = (ya + Qp[q, 0]) * x
                yb = (yb + Qp[q, 1]) * x
            return y[0, p] + hp * ya, y[1, p] + hp * yb

        self._fill(acc, s_new, dense)
        w["y"][:, acc], w["s"][acc], w["f"][:, acc] = yn, s_new, K[_NSTAGES]
        diverged = ~(yn[0] ** 2 + yn[1] ** 2 <= 0.25)           # |A| > 1/sqrt2, as rhs.make_rate
        self._stop(acc[diverged], _DIVERGED)
        fin = acc[ends & ~diverged]
        if len(fin):
            self._fill(fin, w["Lk"][fin] + 0.5, self._state(fin))   # round-off past the piece end
            w["k"][fin] += 1
            self._enter(fin)


# --------------------------------------------------------------------------- histories -> pieces


def _coefficients(p, model):
    """Eq. 6 coefficients of a trajectory; Model 2 as Model 1 without pole (module Notes)."""
    if model == "model1":
        m = p.model1
        return (m.a1, m.b1, m.c1, m.a2, m.b2, m.c2, m.X_c)
    m = p.model2
    return (m.c1, 0.0, 0.0, m.c2, m.c3, 0.0, math.inf)


def _friction_row(p, friction):
    if friction == "eq2":
        f = p.friction_eq2
        return (f.X0, f.k1, f.k3, f.k5)
    f = p.friction_quadratic
    return (f.m0, f.m1, f.m2, 0.0)


@dataclass
class _Layout:
    """A history as pieces, and its report rows: what the solver and the table need."""

    g: np.ndarray          # sign of each piece (a rest inherits the last defined one)
    L: np.ndarray          # path strain of each piece
    piece: np.ndarray      # piece of each report row
    s: np.ndarray          # path strain of each report row inside its piece
    t: np.ndarray
    strain: np.ndarray
    gammadot: np.ndarray


def _layout(history: History, t_eval, strain_eval, points_per_strain, label):
    if not isinstance(history, History):
        raise ValueError(f"{label}: history must be a model.History, got {type(history).__name__}")
    for k, seg in enumerate(history.segments):
        rest = isinstance(seg, GradientSegment) and seg.is_rest and seg.kin(seg.t0)[2] == 0.0
        if not (isinstance(seg, ShearSegment) or rest):
            raise ValueError(f"{label}: segment {k} ({type(seg).__name__}) is not simple shear or a rest; "
                             "simulate_batch handles simple shear only, use model.simulate")
    dirs = segment_directions(history.segments)
    g = np.array([1.0 if d[1] >= 0 else -1.0 for d in dirs])
    times = report_times(history, t_eval, strain_eval, points_per_strain)
    L, piece, s, t, strain, gd = [], [], [], [], [], []
    for k, (seg, tk) in enumerate(zip(history.segments, times)):
        tk = np.asarray(tk, dtype=float)
        if isinstance(seg, ShearSegment):
            L.append(abs(float(seg.strain(np.array([seg.t1]))[0])))
            dk = seg.strain(tk)
            gd.append(seg.gammadot(tk))
        else:
            L.append(0.0)
            dk = np.zeros_like(tk)
            gd.append(np.zeros_like(tk))
        s.append(np.clip(np.abs(dk), 0.0, L[-1]))
        strain.append(history.strain0[k] + dk)
        piece.append(np.full(len(tk), k))
        t.append(tk)
    cat = np.concatenate
    return _Layout(g, np.array(L), cat(piece), cat(s), cat(t), cat(strain), cat(gd))


# --------------------------------------------------------------------------- public API


@dataclass
class BatchResult:
    """What ``simulate_batch`` returns.

    Attributes
    ----------
    table : pandas.DataFrame
        Column ``trajectory`` (0..N-1), then ``model.COLUMNS``: one block of rows per
        trajectory that succeeded, in trajectory order, equal to ``simulate``'s table.
        Trajectories that failed have no rows.
    status : pandas.DataFrame
        One row per trajectory: ``trajectory``; ``status`` ("ok", "pole", "diverged",
        "failed"); ``solver`` ("batched" or "simulate", the per-trajectory fallback);
        ``fallback_reason`` (why the batch handed it over, "" if it did not); ``steps``
        (attempted batched steps); ``message`` (the error's text, "" if none).
    errors : list
        Per trajectory, the exception ``simulate`` raised (``PoleError``,
        ``FabricDivergence``, ``RuntimeError``, ...), or None.
    """

    table: pd.DataFrame
    status: pd.DataFrame
    errors: list
    _start: np.ndarray
    _stop: np.ndarray

    def __len__(self):
        return len(self.errors)

    def trajectory(self, i: int) -> pd.DataFrame:
        """The table of trajectory ``i`` (``model.COLUMNS``), or its error raised, as ``simulate`` would."""
        if self.errors[i] is not None:
            raise self.errors[i]
        return self.table.iloc[self._start[i]:self._stop[i]][COLUMNS].reset_index(drop=True)

    @property
    def ok(self) -> np.ndarray:
        """Boolean per trajectory: it has a table."""
        return (self.status["status"] == "ok").to_numpy()


def _per_trajectory(name, value, n_or_none, single):
    """``value`` as a list, broadcasting a single one; ``single(value)`` says whether it is one."""
    if single(value):
        return None if n_or_none is None else [value] * n_or_none
    value = list(value)
    if n_or_none is not None and len(value) != n_or_none:
        raise ValueError(f"{name} has {len(value)} entries, the batch has {n_or_none} trajectories")
    return value


def _is_number(x):
    return x is not None and np.ndim(x) == 0


def _is_grid(v):
    """One report grid (None or numbers), as opposed to a sequence of grids."""
    if v is None:
        return True
    if isinstance(v, (list, tuple)):
        return all(_is_number(x) for x in v)
    return np.ndim(v) == 1


def _is_pair(v):
    """One A0 (None or two numbers), as opposed to a sequence of them."""
    if v is None:
        return True
    if isinstance(v, (list, tuple)):
        return len(v) == 2 and all(_is_number(x) for x in v)
    return np.shape(v) == (2,)


def simulate_batch(params, histories, model="model1", A0=None, friction="eq2", strain_eval=None, t_eval=None,
                   points_per_strain=POINTS_PER_STRAIN, rtol=BATCH_RTOL, atol=BATCH_ATOL, h_min=BATCH_H_MIN,
                   max_steps=None, fallback_method=DEFAULT_METHOD, fallback_rtol=DEFAULT_RTOL,
                   fallback_atol=DEFAULT_ATOL, fallback_max_steps=None, alpha_spline=None) -> BatchResult:
    r"""Integrate Eq. 4 for N simple-shear trajectories at once (see the module Notes).

    Every argument that ``simulate`` takes per run may be given once (shared by the
    whole batch) or as a sequence of N (one per trajectory); N is the length of the
    sequences given (they must agree), or 1.

    Parameters
    ----------
    params : ModelParams, dict or path, or a sequence of them
    histories : History or sequence of History
        Simple shear: ``ShearSegment`` pieces and rests (``steady_shear``, ``heaviside``,
        ``sinusoidal``, ``tabulated``, ``rest`` and chains of them).
    model : {"model1", "model2"} or a sequence
    A0 : (A_xx, A_xy), None, or a sequence of them
        None: the steady state for the first shear's sign, as in ``simulate``.
    friction : {"eq2", "quadratic"} or a sequence
    strain_eval, t_eval : array, or a sequence of arrays (one grid per trajectory)
        As in ``simulate``; default its grid of ``points_per_strain`` per unit strain.
    rtol, atol : float
        Tolerances of the batched Dormand-Prince 5(4).
    h_min : float
        A trajectory whose step (in strain) falls below this falls back to ``simulate``.
    max_steps : int, optional
        Batched step attempts allowed per trajectory before it falls back; default
        ``BATCH_MIN_STEPS + BATCH_STEPS_PER_STRAIN * path strain``.
    fallback_method, fallback_rtol, fallback_atol, fallback_max_steps
        Passed to ``simulate`` (``method``, ``rtol``, ``atol``, ``max_steps``) for the
        trajectories the batch hands over.
    alpha_spline : laws.AlphaSpline, None, or a sequence of them
        Free-form coefficients: a trajectory with one takes alpha1, alpha2 from it
        instead of its ``model`` block (the friction law is still ``friction``'s);
        it needs an explicit ``A0``, and every spline of a batch must share its
        breaks. ``simulate`` has no spline law, so such a trajectory that the batch
        cannot finish fails with a ``RuntimeError`` instead of falling back.

    Returns
    -------
    BatchResult
        ``table`` (long format), ``status`` and ``errors``; ``result.trajectory(i)`` is
        ``simulate``'s table for trajectory i, or raises its error.

    Raises
    ------
    ValueError
        Bad options or parameters, a history that is not simple shear, or sequences of
        different lengths (the message names the argument). Per-trajectory failures of
        the integration are never raised: they are in ``status`` and ``errors``.
    """
    lists, n = _per_trajectory_lists(params, histories, model, A0, friction, strain_eval, t_eval, alpha_spline)
    _check_options(rtol, atol, h_min, fallback_method)
    P, coef, fric, A0s, lays, errors = _batch_inputs(lists, n, points_per_strain)
    spline = _spline_inputs(lists["alpha_spline"], coef)
    poff, rows, ooff, out_piece = _offsets(lays)
    solver = _integrate_batch(coef, A0s, lays, poff, rows, ooff, out_piece, rtol, atol, h_min, max_steps, spline)
    cols, traj, code = _batch_table(solver, lays, lists["friction"], coef, fric, rows, out_piece, n)
    fallback = dict(method=fallback_method, rtol=fallback_rtol, atol=fallback_atol, max_steps=fallback_max_steps)
    _fall_back(code, errors, cols, solver, lists, P, A0s, poff, rows, points_per_strain, fallback)
    return _batch_result(cols, traj, rows, code, errors, solver.steps, n)


def _per_trajectory_lists(params, histories, model, A0, friction, strain_eval, t_eval, alpha_spline=None):
    """The per-trajectory arguments as lists of N (a single value broadcast), and N; ValueError if lengths differ."""
    seqs = {"params": (params, lambda v: not isinstance(v, (list, tuple))),
            "alpha_spline": (alpha_spline, lambda v: v is None or isinstance(v, laws.AlphaSpline)),
            "histories": (histories, lambda v: isinstance(v, History)),
            "model": (model, lambda v: isinstance(v, str)),
            "A0": (A0, _is_pair), "friction": (friction, lambda v: isinstance(v, str)),
            "strain_eval": (strain_eval, _is_grid), "t_eval": (t_eval, _is_grid)}
    sizes = {k: len(v) for k, (v, single) in seqs.items() if not single(v)}
    if len(set(sizes.values())) > 1:
        raise ValueError(f"per-trajectory arguments of different lengths: {sizes}")
    n = next(iter(sizes.values())) if sizes else 1
    if n == 0:
        raise ValueError("the batch is empty")
    return {k: _per_trajectory(k, v, n, single) for k, (v, single) in seqs.items()}, n


def _check_options(rtol, atol, h_min, fallback_method):
    """ValueError, naming the option, for tolerances outside (0, 1) or an unknown fallback method."""
    for name, v in (("rtol", rtol), ("atol", atol), ("h_min", h_min)):
        if not (math.isfinite(v) and 0.0 < v < 1.0):
            raise ValueError(f"{name} = {v!r} is outside the allowed range (0, 1)")
    if fallback_method not in METHODS or fallback_method == "RK4":
        raise ValueError(f"fallback_method = {fallback_method!r} is not one of {METHODS[1:]}")


def _batch_inputs(lists, n, points_per_strain):
    """Per trajectory: parameters, coefficient and friction rows, A0, report layout, and A0's error if any.

    Returns ``(P, coef, fric, A0s, lays, errors)``: lists of N ``ModelParams`` and
    ``_Layout``, arrays (N, 7), (N, 4) and (N, 2), and N errors (the ``ValueError`` of a
    trajectory with no stable steady state to start from, whose A0 is then 0; else None).
    Parameters, layouts and steady states shared by several trajectories are built once.
    Raises ValueError, naming the trajectory, for an unknown model or friction.
    """
    p_cache, lay_cache, a0_cache = {}, {}, {}
    P, coef, fric, A0s, lays, errors = [], np.empty((n, 7)), np.empty((n, 4)), np.empty((n, 2)), [], [None] * n
    for i in range(n):
        label = f"trajectory {i}"
        m, fr = lists["model"][i], lists["friction"][i]
        if m not in MODELS:
            raise ValueError(f"{label}: model = {m!r} is not one of {MODELS}")
        if fr not in FRICTIONS:
            raise ValueError(f"{label}: friction = {fr!r} is not one of {FRICTIONS}")
        raw = lists["params"][i]
        key = id(raw)
        if key not in p_cache:
            p_cache[key] = as_params(raw)
        p = p_cache[key]
        h, te, se = lists["histories"][i], lists["t_eval"][i], lists["strain_eval"][i]
        key = (id(h), id(te), id(se))
        if key not in lay_cache:
            lay_cache[key] = _layout(h, te, se, points_per_strain, label)
        lay = lay_cache[key]
        P.append(p)
        lays.append(lay)
        coef[i] = _coefficients(p, m)
        fric[i] = _friction_row(p, fr)
        a0 = lists["A0"][i]
        if lists["alpha_spline"][i] is not None and a0 is None:
            raise ValueError(f"{label}: a trajectory with alpha_spline needs an explicit A0")
        key = (id(p), m, lay.g[0]) if a0 is None else None
        try:
            if key is not None and key in a0_cache:
                A0s[i] = a0_cache[key]
            else:
                A0s[i] = initial_fabric(p, m, a0, (0.0, lay.g[0]))
                if key is not None:
                    a0_cache[key] = A0s[i]
        except ValueError as exc:   # no stable steady state: this trajectory fails, as simulate would
            errors[i] = exc
            A0s[i] = 0.0
    return P, coef, fric, A0s, lays, errors


def _spline_inputs(splines, coef):
    """``(basis, S)`` for the solver, or None without splines; zeroes ``coef`` of the spline trajectories.

    ``S`` (N, 2, K) holds each trajectory's coefficients of alpha1 and alpha2 (zero
    for a trajectory without a spline); ``basis(X)`` is ``laws.spline_basis`` on the
    breaks every spline of the batch shares (ValueError otherwise).
    """
    have = [i for i, sp in enumerate(splines) if sp is not None]
    if not have:
        return None
    breaks = {splines[i].breaks for i in have}
    if len(breaks) > 1:
        raise ValueError(f"alpha_spline: every spline of a batch must share its breaks, got {len(breaks)} sets")
    (br,) = breaks
    S = np.zeros((len(splines), 2, laws.spline_size(br)))
    for i in have:
        S[i] = splines[i].c1, splines[i].c2
        coef[i] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, math.inf)
    return (lambda X: laws.spline_basis(X, br)), S


def _offsets(lays):
    """Where each trajectory's pieces and output rows sit in the flat arrays.

    Returns ``(poff, rows, ooff, out_piece)``: piece offsets (N + 1), output rows per
    trajectory (N), output-row offsets (N + 1), and each output row's flat piece index.
    """
    poff = np.concatenate([[0], np.cumsum([len(x.g) for x in lays])])
    rows = np.array([len(x.piece) for x in lays])
    ooff = np.concatenate([[0], np.cumsum(rows)])
    out_piece = np.concatenate([x.piece + poff[i] for i, x in enumerate(lays)])
    return poff, rows, ooff, out_piece


def _integrate_batch(coef, A0s, lays, poff, rows, ooff, out_piece, rtol, atol, h_min, max_steps, spline=None):
    """Run the batched Dormand-Prince 5(4) over all trajectories; the finished ``_Solver``.

    Each trajectory's step budget is ``max_steps``, or by default
    ``BATCH_MIN_STEPS + BATCH_STEPS_PER_STRAIN * path strain``. ``A0s`` is not modified.
    """
    out_s = np.concatenate([x.s for x in lays])
    path = np.array([x.L.sum() for x in lays])
    n = len(lays)
    budget = (BATCH_MIN_STEPS + BATCH_STEPS_PER_STRAIN * path).astype(int) if max_steps is None \
        else np.full(n, int(max_steps))
    A0_run = A0s.copy()
    return _Solver(coef, A0_run, np.concatenate([x.g for x in lays]), np.concatenate([x.L for x in lays]),
                   poff, out_piece, out_s, ooff, rtol, atol, h_min, budget, spline).run()


def _batch_table(solver, lays, frictions, coef, fric, rows, out_piece, n):
    """The output columns of every row from the batched states, and the bad-output check.

    Returns ``(cols, traj, code)``: a dict of ``"trajectory"`` and ``model.COLUMNS``
    arrays over all rows (failed trajectories included), each row's trajectory, and the
    solver's per-trajectory status codes, a finished trajectory with a row at or beyond
    X_c or not finite set to ``_BAD_OUTPUT``.
    """
    code = solver.status.copy()
    Y = solver.Y
    traj = np.repeat(np.arange(n), rows)
    gflat = np.concatenate([x.g for x in lays])
    g_row = gflat[out_piece]
    a, b = Y[:, 0], Y[:, 1]
    X = SQRT2 * g_row * b
    tau = np.empty_like(X)
    with np.errstate(all="ignore"):
        for name, law, nargs in (("eq2", laws.stress_ratio_eq2, 4), ("quadratic", laws.friction_quadratic, 3)):
            sel = np.repeat(np.array([f == name for f in frictions]), rows)
            if sel.any():
                tau[sel] = law(X[sel], *(np.repeat(fric[:, c], rows)[sel] for c in range(nargs)))
    gd = np.concatenate([x.gammadot for x in lays])
    cols = {
        "trajectory": traj, "t": np.concatenate([x.t for x in lays]),
        "strain": np.concatenate([x.strain for x in lays]), "gammadot": gd, "A_xx": a, "A_xy": b,
        "A_norm": laws.fabric_norm(a, b), "theta_A": laws.fabric_angle_deg(a, b), "X": X, "mu": np.abs(tau),
        "sigma_xy_over_p": np.where(gd != 0.0, tau * g_row, 0.0),
    }
    bad_row = ~(X < np.repeat(coef[:, 6], rows)) | ~np.isfinite(a) | ~np.isfinite(b) | ~np.isfinite(tau)
    bad_traj = np.bincount(traj[bad_row], minlength=n) > 0
    code[(code == _DONE) & bad_traj] = _BAD_OUTPUT
    return cols, traj, code


def _in_batch(code):
    """Per trajectory: the batch settled it (finished, or diverged) rather than handing it over."""
    return (code == _DONE) | (code == _DIVERGED)


def _fall_back(code, errors, cols, solver, lists, P, A0s, poff, rows, points_per_strain, fallback):
    """Settle the trajectories the batch did not finish, filling ``errors`` and ``cols`` in place.

    A diverged trajectory gets its ``FabricDivergence`` (at the time the batch saw it);
    each one handed over is integrated alone by ``model.simulate`` with ``fallback``
    (``method``, ``rtol``, ``atol``, ``max_steps``), its rows overwriting the batch's,
    or its error recorded. Trajectories that already have an error are left alone.
    """
    in_batch = _in_batch(code)
    start = np.concatenate([[0], np.cumsum(rows)[:-1]])
    for i in np.flatnonzero(code == _DIVERGED):
        if errors[i] is None:
            k, s_k, a_k, b_k = solver.where[i]
            seg = lists["histories"][i].segments[int(k) - poff[i]]
            errors[i] = FabricDivergence(_time_at(seg, s_k), a_k, b_k)
    for i in np.flatnonzero(~in_batch):
        if errors[i] is not None:
            continue
        if lists["alpha_spline"][i] is not None:
            errors[i] = RuntimeError(f"free-form alphas: the batch could not finish this trajectory "
                                     f"({FALLBACK_REASONS.get(code[i], code[i])}) and simulate has no spline law")
            continue
        try:
            tab = simulate(P[i], lists["histories"][i], model=lists["model"][i], A0=A0s[i],
                           method=fallback["method"], rtol=fallback["rtol"], atol=fallback["atol"],
                           friction=lists["friction"][i], strain_eval=lists["strain_eval"][i],
                           t_eval=lists["t_eval"][i], points_per_strain=points_per_strain,
                           max_steps=fallback["max_steps"])
        except (ValueError, FloatingPointError, RuntimeError) as exc:
            errors[i] = exc
            continue
        sl = slice(start[i], start[i] + rows[i])
        for c in COLUMNS:
            cols[c][sl] = tab[c].to_numpy()


def _batch_result(cols, traj, rows, code, errors, steps, n):
    """The ``BatchResult``: the table without the failed trajectories' rows, the status, the errors."""
    solver_name = np.where(_in_batch(code), "batched", "simulate").astype(object)
    reason = np.array([FALLBACK_REASONS.get(c, "") for c in code], dtype=object)
    failed = np.array([e is not None for e in errors])
    if failed.any():
        keep = ~failed[traj]
        cols = {c: v[keep] for c, v in cols.items()}
    table = pd.DataFrame(cols, columns=["trajectory"] + COLUMNS, copy=False)   # no 2D block copy
    kept_rows = np.where(failed, 0, rows)
    stop = np.cumsum(kept_rows)
    status = pd.DataFrame({
        "trajectory": np.arange(n),
        "status": [_status_word(e) for e in errors],
        "solver": solver_name, "fallback_reason": reason, "steps": steps,
        "message": ["" if e is None else str(e) for e in errors],
    })
    return BatchResult(table, status, errors, stop - kept_rows, stop)


def _time_at(seg, s):
    """Time at which a simple-shear segment (or a rest) has gone through the path strain ``s``."""
    if not isinstance(seg, ShearSegment):
        return seg.t0
    if seg.kind == "constant":
        return seg.t0 + s / abs(seg.p[0])
    tt = np.linspace(seg.t0, seg.t1, 2001)
    return float(np.interp(s, np.abs(seg.strain(tt)), tt))


def _status_word(err):
    if err is None:
        return "ok"
    if isinstance(err, PoleError):
        return "pole"
    if isinstance(err, FabricDivergence):
        return "diverged"
    return "failed"
