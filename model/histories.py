r"""Deformation histories: the velocity gradient L(t) as a chain of segments.

A :class:`History` is a contiguous chain of segments. Inside a segment the
direction of :math:`D'` does not flip and :math:`|D'|` vanishes at most at the
segment's ends (or everywhere: a rest, or a rigid rotation). Zero crossings of
the shear rate are therefore always segment boundaries, located exactly by the
constructors, and the integrator restarts there: X, undefined where
:math:`|D'| = 0`, is never evaluated across a sign change.

Constructors (durations in the arbitrary time unit; strains dimensionless):

- :func:`steady_shear`, :func:`heaviside`, :func:`sinusoidal`, :func:`tabulated`:
  simple shear ``v_x = gammadot(t) y``;
- :func:`rest`, :func:`pure_shear`, :func:`rigid_rotation`,
  :func:`velocity_gradient`: any 2D L(t);
- :func:`concatenate` (or ``h1 + h2``) chains histories;
  :func:`superpose_rotation` views a history from a frame that spins.

Time and strain: ``strain(t)`` is the signed accumulated shear strain
:math:`\int \dot\gamma\, dt`, with :math:`\dot\gamma` the signed equivalent shear
rate :math:`\sqrt2 |D'| \mathrm{sign}(D'_{xy})` (exactly gammadot in simple shear).
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.integrate import quad

from .kinematics import SQRT2, equivalent_shear_rate, rotate_deviator, split_velocity_gradient

# --------------------------------------------------------------------------- segments


@dataclass(frozen=True)
class Segment:
    """Base class: one piece ``[t0, t1]`` of a history.

    Subclasses implement ``kin(t) -> (d1, d2, w)`` (plain floats, called by the
    right-hand side) and ``strain(t)`` (strain accumulated since ``t0``).
    """

    t0: float
    t1: float

    is_rest = False  # D' == 0 throughout (a rest or a rigid rotation)

    def shifted(self, dt: float) -> "Segment":
        return replace(self, t0=self.t0 + dt, t1=self.t1 + dt)

    def gammadot(self, t):
        """Signed equivalent shear rate at times ``t`` (array)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        d = np.array([self.kin(float(ti))[:2] for ti in t]).reshape(-1, 2)
        return equivalent_shear_rate(d[:, 0], d[:, 1])

    def strain(self, t):
        """Strain accumulated from ``t0`` to each of ``t`` (default: quadrature)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        f = lambda s: float(self.gammadot(s)[0])  # noqa: E731
        return np.array([quad(f, self.t0, ti, limit=200)[0] if ti > self.t0 else 0.0 for ti in t])

    def direction(self):
        """Unit direction ``(n1, n2)`` of D' inside the segment (one-sided limit), or None for a rest."""
        if self.is_rest:
            return None
        for frac in (0.5, 1e-6, 1.0 - 1e-6, 0.25, 0.75):
            d1, d2, _ = self.kin(self.t0 + frac * (self.t1 - self.t0))
            n = math.sqrt(2.0 * (d1 * d1 + d2 * d2))
            if n > 0.0:
                return d1 / n, d2 / n
        return None

    def start_direction(self):
        """Direction of D' just after ``t0`` (used to check the mirrored X at a reversal)."""
        return self.direction()


@dataclass(frozen=True)
class ShearSegment(Segment):
    r"""Simple shear with a rate profile of one sign.

    ``kind`` is ``"constant"`` (``p = (g,)``), ``"cos_down"`` (``p = (U, T)``:
    :math:`\dot\gamma = U \cos(\pi\tau/T)` for :math:`\tau = t - t_0 \in [0, T/2]`),
    ``"cos_up"`` (``p = (U, T)``: :math:`\dot\gamma = -U \sin(\pi\tau/T)` on
    :math:`[0, T/2]`) or ``"table"`` (``p = (tau, g)``: piecewise linear, one sign).
    """

    kind: str = "constant"
    p: tuple = (1.0,)
    sign: float = 1.0

    def rate(self, t: float) -> float:
        tau = t - self.t0
        k = self.kind
        if k == "constant":
            return self.p[0]
        if k == "cos_down":
            U, T = self.p
            return U * math.sin(math.pi * (0.5 * T - tau) / T)
        if k == "cos_up":
            U, T = self.p
            return -U * math.sin(math.pi * tau / T)
        taus, gs = self.p
        i = min(max(bisect.bisect_right(taus, tau) - 1, 0), len(taus) - 2)
        w = (tau - taus[i]) / (taus[i + 1] - taus[i])
        return gs[i] + w * (gs[i + 1] - gs[i])

    def kin(self, t: float):
        g = 0.5 * self.rate(t)
        return 0.0, g, g

    def gammadot(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        tau = t - self.t0
        k = self.kind
        if k == "constant":
            return np.full_like(t, self.p[0])
        if k == "cos_down":
            U, T = self.p
            return U * np.sin(np.pi * (0.5 * T - tau) / T)
        if k == "cos_up":
            U, T = self.p
            return -U * np.sin(np.pi * tau / T)
        return np.interp(tau, self.p[0], self.p[1])

    def strain(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        tau = np.clip(t - self.t0, 0.0, self.t1 - self.t0)
        k = self.kind
        if k == "constant":
            return self.p[0] * tau
        if k == "cos_down":
            U, T = self.p
            return U * T / np.pi * np.sin(np.pi * tau / T)
        if k == "cos_up":
            U, T = self.p
            return -U * T / np.pi * (1.0 - np.cos(np.pi * tau / T))
        taus, gs = np.asarray(self.p[0]), np.asarray(self.p[1])
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (gs[1:] + gs[:-1]) * np.diff(taus))])
        i = np.clip(np.searchsorted(taus, tau, side="right") - 1, 0, len(taus) - 2)
        dt = tau - taus[i]
        slope = (gs[i + 1] - gs[i]) / (taus[i + 1] - taus[i])
        return cum[i] + gs[i] * dt + 0.5 * slope * dt**2

    def direction(self):
        return 0.0, self.sign / SQRT2


@dataclass(frozen=True)
class GradientSegment(Segment):
    """Any velocity gradient: a constant 2x2 array ``L`` or a callable ``L(t_local)``."""

    L: object = None

    def __post_init__(self):
        if not callable(self.L):
            d1, d2, w = split_velocity_gradient(self.L)
            object.__setattr__(self, "_const", (float(d1), float(d2), float(w)))
            object.__setattr__(self, "is_rest", d1 == 0.0 and d2 == 0.0)
        else:
            object.__setattr__(self, "_const", None)

    def kin(self, t: float):
        if self._const is not None:
            return self._const
        d1, d2, w = split_velocity_gradient(self.L(t - self.t0))
        return float(d1), float(d2), float(w)

    def strain(self, t):
        if self._const is None:
            return super().strain(t)
        t = np.atleast_1d(np.asarray(t, dtype=float))
        tau = np.clip(t - self.t0, 0.0, self.t1 - self.t0)
        return float(equivalent_shear_rate(*self._const[:2])) * tau


@dataclass(frozen=True)
class RotatedSegment(Segment):
    r"""A segment seen from a frame turning at the rate ``omega``.

    With :math:`Q(t)` the rotation by :math:`\phi = \phi_0 + \omega (t - t_0)`,
    :math:`L^* = Q L Q^T + \dot Q Q^T`: :math:`D'^* = Q D' Q^T` and
    :math:`w^* = w - \omega`. An objective model then gives :math:`A^* = Q A Q^T`.
    """

    base: Segment = None
    omega: float = 0.0
    phi0: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "is_rest", self.base.is_rest)

    def shifted(self, dt):
        return replace(self, t0=self.t0 + dt, t1=self.t1 + dt, base=self.base)

    def angle(self, t):
        return self.phi0 + self.omega * (np.asarray(t, dtype=float) - self.t0)

    def kin(self, t: float):
        d1, d2, w = self.base.kin(self.base.t0 + (t - self.t0))
        r1, r2 = rotate_deviator(d1, d2, self.phi0 + self.omega * (t - self.t0))
        return r1, r2, w - self.omega

    def strain(self, t):
        # |D'| is invariant; the sign convention (sign of D'_xy) is not, so integrate.
        return super().strain(t)

    def direction(self):
        # The direction turns with the frame; a constant limit does not exist.
        return Segment.direction(self)


# --------------------------------------------------------------------------- history


class History:
    """A contiguous chain of segments starting at t = 0.

    Attributes
    ----------
    segments : tuple of Segment
    t_end : float
    """

    def __init__(self, segments):
        segs = tuple(segments)
        if not segs:
            raise ValueError("a history needs at least one segment")
        t = 0.0
        for s in segs:
            if abs(s.t0 - t) > 1e-12 * max(1.0, abs(t)) or not s.t1 > s.t0:
                raise ValueError(f"segments must be contiguous from t = 0 with positive durations (at t = {t})")
            t = s.t1
        self.segments = segs
        self.t_end = t
        # strain at the start of each segment
        s0 = [0.0]
        for s in segs[:-1]:
            s0.append(s0[-1] + float(s.strain(s.t1)[0]))
        self.strain0 = np.array(s0)

    def __add__(self, other: "History") -> "History":
        return concatenate(self, other)

    def __repr__(self):
        kinds = ", ".join(f"{type(s).__name__}[{s.t0:g},{s.t1:g}]" for s in self.segments)
        return f"History({kinds})"

    @property
    def breakpoints(self) -> np.ndarray:
        """Segment boundaries, from 0 to t_end."""
        return np.array([0.0] + [s.t1 for s in self.segments])

    def segment_index(self, t) -> np.ndarray:
        """Index of the segment holding each time (a boundary belongs to the segment on its left)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        ends = self.breakpoints[1:-1]
        return np.searchsorted(ends, t, side="left")

    def _per_segment(self, t, value) -> np.ndarray:
        """``value(i, segment, t_i)`` evaluated segment by segment at times ``t``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        idx = self.segment_index(t)
        out = np.empty_like(t)
        for i in np.unique(idx):
            m = idx == i
            out[m] = value(i, self.segments[i], t[m])
        return out

    def gammadot(self, t) -> np.ndarray:
        """Signed equivalent shear rate at times ``t`` (left limit at boundaries)."""
        return self._per_segment(t, lambda i, seg, ti: seg.gammadot(ti))

    def strain(self, t) -> np.ndarray:
        """Signed accumulated strain at times ``t``."""
        return self._per_segment(t, lambda i, seg, ti: self.strain0[i] + seg.strain(ti))

    def times_at_strains(self, strains) -> np.ndarray:
        """Times at which the history passes through ``strains``, in order.

        Each value is searched forward from the time found for the previous
        one, so a list made of monotone pieces that follows the path (e.g. 0..3
        then 3..0 for a Heaviside reversal at strain 3) maps one-to-one.
        Raises ValueError for a strain the remaining path never reaches.
        """
        from scipy.optimize import brentq

        targets = np.asarray(strains, dtype=float).ravel()
        if not np.all(np.isfinite(targets)):
            raise ValueError("strain_eval must be finite")
        span = float(np.max(np.abs(self.strain(self.breakpoints)))) if len(self.segments) else 1.0
        tol = 1e-9 * max(1.0, span)
        # sample path: a few points per segment (strain is monotone inside a segment)
        knots = []
        for s in self.segments:
            knots.append(np.linspace(s.t0, s.t1, 9))
        T = np.unique(np.concatenate(knots))
        S = self.strain(T)
        out = np.empty_like(targets)
        k, t_cur, s_cur = 0, 0.0, float(S[0])
        for j, target in enumerate(targets):
            found = False
            while k < len(T) - 1:
                lo_t, lo_s = max(T[k], t_cur), (s_cur if t_cur > T[k] else S[k])
                hi_t, hi_s = T[k + 1], S[k + 1]
                if abs(lo_s - target) <= tol:
                    t_found = lo_t
                elif abs(hi_s - target) <= tol:
                    t_found = hi_t
                elif (lo_s - target) * (hi_s - target) < 0.0:
                    f = lambda tt: float(self.strain(tt)[0]) - target  # noqa: E731
                    t_found = brentq(f, lo_t, hi_t, xtol=1e-14 * max(1.0, hi_t), rtol=1e-15)
                else:
                    k += 1
                    continue
                found = True
                break
            if not found:
                raise ValueError(
                    f"strain_eval[{j}] = {target:g} is not reached by the history after "
                    f"t = {t_cur:g} (strain {s_cur:g}); give strains in the order the path visits them"
                )
            out[j] = t_found
            t_cur, s_cur = t_found, float(self.strain(t_found)[0])
        return out


# --------------------------------------------------------------------------- constructors


def _positive(name, value, allow_zero=False):
    v = float(value)
    ok = math.isfinite(v) and (v >= 0.0 if allow_zero else v > 0.0)
    if not ok:
        rng = "[0, inf)" if allow_zero else "(0, inf)"
        raise ValueError(f"'{name}' = {value!r} is outside the allowed range {rng}")
    return v


def _rate(name, value):
    v = float(value)
    if not (math.isfinite(v) and v != 0.0):
        raise ValueError(f"'{name}' = {value!r} must be finite and non-zero")
    return v


def steady_shear(strain, gammadot=1.0) -> History:
    """Simple shear at constant ``gammadot`` for ``strain`` (> 0) units of strain magnitude."""
    g = _rate("gammadot", gammadot)
    T = _positive("strain", strain) / abs(g)
    return History([ShearSegment(0.0, T, "constant", (g,), math.copysign(1.0, g))])


def heaviside(strain_before, strain_after, gammadot=1.0) -> History:
    """Shear at ``gammadot`` for ``strain_before``, then at ``-gammadot`` for ``strain_after``."""
    return steady_shear(strain_before, gammadot) + steady_shear(strain_after, -_rate("gammadot", gammadot))


def sinusoidal(strain_before, transition_strain, strain_after, gammadot=1.0) -> History:
    r"""Shear at ``U = gammadot``, a half cosine from +U to -U, then -U.

    The transition lasts :math:`T = ` ``transition_strain / |U|`` in time:
    :math:`\dot\gamma = U\cos(\pi \tau / T)`, :math:`0 \le \tau \le T`; it is split at
    its zero crossing :math:`\tau = T/2` so the integrator restarts there. Its net
    strain is zero (it goes forward by ``U T/pi`` and back). ``strain_before`` and
    ``strain_after`` may be 0.
    """
    U = _rate("gammadot", gammadot)
    T = _positive("transition_strain", transition_strain) / abs(U)
    sb = _positive("strain_before", strain_before, allow_zero=True)
    sa = _positive("strain_after", strain_after, allow_zero=True)
    sgn = math.copysign(1.0, U)
    segs = []
    t = 0.0
    if sb > 0:
        segs.append(ShearSegment(0.0, sb / abs(U), "constant", (U,), sgn))
        t = sb / abs(U)
    segs.append(ShearSegment(t, t + 0.5 * T, "cos_down", (U, T), sgn))
    segs.append(ShearSegment(t + 0.5 * T, t + T, "cos_up", (U, T), -sgn))
    t += T
    if sa > 0:
        segs.append(ShearSegment(t, t + sa / abs(U), "constant", (-U,), -sgn))
    return History(segs)


def rest(duration) -> History:
    """No deformation and no spin for ``duration``: A is frozen (Eq. 4 gives dA/dt = 0)."""
    return velocity_gradient(np.zeros((2, 2)), duration)


def pure_shear(rate, duration) -> History:
    """Pure shear ``L = [[rate, 0], [0, -rate]]`` (stretch along x for rate > 0)."""
    r = _rate("rate", rate)
    return velocity_gradient([[r, 0.0], [0.0, -r]], duration)


def rigid_rotation(omega, duration) -> History:
    """Rigid rotation at the angular velocity ``omega`` (counter-clockwise > 0): ``L = [[0, -omega], [omega, 0]]``."""
    w = float(omega)
    return velocity_gradient([[0.0, -w], [w, 0.0]], duration)


def velocity_gradient(L, duration, breakpoints=()) -> History:
    """A general 2D history: ``L`` a constant 2x2 array or a callable ``L(t)``.

    For a callable, list in ``breakpoints`` every time in ``(0, duration)`` where
    D' vanishes or changes direction abruptly (the integrator restarts there).
    """
    T = _positive("duration", duration)
    if not callable(L):
        split_velocity_gradient(L)  # validates
        return History([GradientSegment(0.0, T, np.array(L, dtype=float))])
    cuts = sorted(float(b) for b in breakpoints)
    if any(not (0.0 < b < T) for b in cuts):
        raise ValueError(f"breakpoints must lie in (0, {T:g}), got {cuts}")
    edges = [0.0] + cuts + [T]
    segs = []
    for a, b in zip(edges[:-1], edges[1:]):
        segs.append(GradientSegment(a, b, (lambda tl, a=a: L(a + tl))))
    return History(segs)


def tabulated(t, gammadot) -> History:
    """Simple shear with a piecewise-linear ``gammadot(t)`` (e.g. a DEM run's imposed history).

    ``t`` must increase strictly; the history starts at ``t[0]``, shifted to 0. The table is cut at every zero crossing of the rate
    (located exactly on the linear pieces) and intervals where the rate is zero
    at both ends become rests.
    """
    t = np.asarray(t, dtype=float).ravel()
    g = np.asarray(gammadot, dtype=float).ravel()
    if t.size != g.size or t.size < 2:
        raise ValueError("tabulated: t and gammadot need the same length, at least 2")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(g))):
        raise ValueError("tabulated: t and gammadot must be finite")
    if np.any(np.diff(t) <= 0):
        raise ValueError("tabulated: t must increase strictly")
    t = t - t[0]
    # insert the exact zero crossings
    tt, gg = [t[0]], [g[0]]
    for i in range(len(t) - 1):
        if g[i] * g[i + 1] < 0.0:
            tz = t[i] - g[i] * (t[i + 1] - t[i]) / (g[i + 1] - g[i])
            tt.append(tz)
            gg.append(0.0)
        tt.append(t[i + 1])
        gg.append(g[i + 1])
    tt, gg = np.array(tt), np.array(gg)
    # sign of each interval: +1, -1, or 0 (rest: zero at both ends)
    sig = np.where(np.maximum(gg[:-1], gg[1:]) > 0.0, 1.0, np.where(np.minimum(gg[:-1], gg[1:]) < 0.0, -1.0, 0.0))
    segs = []
    i = 0
    while i < len(sig):
        j = i
        while j + 1 < len(sig) and sig[j + 1] == sig[i]:
            j += 1
        if sig[i] == 0.0:
            segs.append(GradientSegment(tt[i], tt[j + 1], np.zeros((2, 2))))
        else:
            taus = tuple(float(x) for x in tt[i:j + 2] - tt[i])
            rates = tuple(float(x) for x in gg[i:j + 2])
            segs.append(ShearSegment(tt[i], tt[j + 1], "table", (taus, rates), float(sig[i])))
        i = j + 1
    return History(segs)


def concatenate(*histories: History) -> History:
    """Chain histories in time."""
    segs, t = [], 0.0
    for h in histories:
        for s in h.segments:
            segs.append(s.shifted(t))
        t += h.t_end
    return History(segs)


def superpose_rotation(history: History, omega: float) -> History:
    """The same history seen from a frame turning at ``omega`` (rad per time unit).

    The frame angle is ``omega * t`` from t = 0. An objective model gives the
    fabric ``Q(t) A(t) Q(t)^T`` (see :class:`RotatedSegment`).
    """
    w = float(omega)
    return History([RotatedSegment(s.t0, s.t1, s, w, w * s.t0) for s in history.segments])
