r"""The quantities every stage derives from a DEM time series, each defined once.

Every consumer of the DEM files (the campaign summary, the calibration, the
comparison, the DEM study) takes these numbers from here, so two tables that
report the same quantity of the same run agree (docs/data-contract.md).

- ``steady_window`` / ``steady_values``: the steady state of a pre-shear, the
  mean over the last half of its strain path.
- ``fabric_norm`` / ``fabric_angle_deg``: |A| and theta_A of
  :math:`A = [[A_{xx}, A_{xy}], [A_{xy}, -A_{xx}]]`. They are the model's own
  (``model.laws``, the lowest layer that needs them; ``model`` never imports
  ``dem_contract``) and are re-exported here so DEM readers find them in one
  place.
- ``axial_mean``: the mean of axial angles (period 180 degrees), e.g. theta_A
  over seeds, across the 0/180 wrap.
- ``angle_difference``: the difference of two axial angles in (-90, 90].
- ``reversal_indices``: where the sign of the shear rate flips, ignoring noise.
- ``pre_reversal_state``: the state a reversal starts from (over the end of
  the leg before it: the mean of a steady pre-shear, the end of a line fitted
  to a moving transient).
- ``reversal_times`` / ``split_transients``: the reversals of a run (one, or
  several for a reversal schedule) and the run split into transients, one per
  reversal, each with the state just before it.
- ``reversal_kinds``: each reversal's kind (a Heaviside step or a half-cosine
  transition), direction (-1 against the pre-shear, +1 back along it) and
  transition strain.
- ``mirror_reversal``: a +1 reversal reflected (x -> -x) into the frame of the
  -1 ones.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.stats import circmean

from model.laws import fabric_angle_deg, fabric_norm

from .series import DEMInputError

__all__ = ["STEADY_FRACTION", "STEADY_COLUMNS", "PRE_REVERSAL_WINDOW", "MIN_PRE_REVERSAL_SAMPLES",
           "REVERSAL_DEAD_BAND", "REVERSAL_MIN_RUN", "steady_window", "steady_values", "fabric_norm",
           "fabric_angle_deg", "axial_mean", "angle_difference", "reversal_indices", "pre_reversal_state",
           "Transient", "reversal_times", "split_transients", "REVERSAL_KINDS", "reversal_kinds",
           "MIRRORED_COLUMNS", "mirror_reversal"]

#: Last fraction of a pre-shear's strain path taken as its steady state.
STEADY_FRACTION = 0.5
#: Columns averaged by ``steady_values`` when the series has them.
STEADY_COLUMNS = ("A_xx", "A_xy", "mu", "phi", "Z", "inertial_number")


def steady_window(strain, fraction: float = STEADY_FRACTION, last_strain: float | None = None) -> np.ndarray:
    r"""The samples of a pre-shear that make its steady state.

    With the strain path travelled since the first sample,
    :math:`s_i = |\gamma_i - \gamma_0|`, a sample belongs to the window when

    .. math:: s_i \ge (1 - f)\, s_{\mathrm{end}}

    (``fraction`` :math:`f`, default the last half of the strain), or, when
    ``last_strain`` :math:`w` is given, :math:`s_i \ge s_{\mathrm{end}} - w`
    (the DEM study's ``accuracy.steady_window``, configured as a strain).

    Parameters
    ----------
    strain : array_like
        The pre-shear's ``strain`` column, in time order (monotone: a
        pre-shear does not reverse).
    fraction : float
        Last fraction of the strain path, in (0, 1].
    last_strain : float, optional
        Last strain path instead of a fraction (> 0).

    Returns
    -------
    numpy.ndarray of bool
        True for the samples in the window.
    """
    strain = np.asarray(strain, dtype=float)
    s = np.abs(strain - strain[0])
    if last_strain is not None:
        if not last_strain > 0:
            raise ValueError(f"steady_window: last_strain = {last_strain!r} must be positive")
        return s >= s[-1] - last_strain
    if not 0 < fraction <= 1:
        raise ValueError(f"steady_window: fraction = {fraction!r} must lie in (0, 1]")
    return s >= (1.0 - fraction) * s[-1]


def steady_values(pre, fraction: float = STEADY_FRACTION, last_strain: float | None = None) -> dict:
    r"""Steady values of one pre-shear: window means, and |A|, theta_A of the mean fabric.

    Over the samples of ``steady_window``, each column of ``STEADY_COLUMNS``
    that ``pre`` has is averaged; the fabric's norm and angle are those of the
    mean tensor (the fabric of the pooled contacts, not the mean of per-sample
    norms):

    .. math::
        |A| = \sqrt{2 (\bar a^2 + \bar b^2)}, \qquad
        \theta_A = \tfrac12 \operatorname{atan2}(\bar b, \bar a) \bmod 180^\circ

    with :math:`\bar a, \bar b` the window means of ``A_xx``, ``A_xy``.

    Parameters
    ----------
    pre : pandas.DataFrame
        The pre-shear (``strain``, ``A_xx``, ``A_xy``; ``mu``, ``phi``, ``Z``,
        ``inertial_number`` when present).
    fraction, last_strain : float
        The window, see ``steady_window``.

    Returns
    -------
    dict
        The means under their column names, ``A_norm``, ``theta_A`` (degrees in
        [0, 180)) and ``n_samples`` (samples in the window).
    """
    win = steady_window(pre["strain"].to_numpy(), fraction, last_strain)
    out = {c: float(np.mean(pre[c].to_numpy()[win])) for c in STEADY_COLUMNS if c in pre}
    out["A_norm"] = float(fabric_norm(out["A_xx"], out["A_xy"]))
    out["theta_A"] = float(fabric_angle_deg(out["A_xx"], out["A_xy"]))
    out["n_samples"] = int(win.sum())
    return out


def axial_mean(theta_deg, axis=None):
    r"""Circular mean of axial angles in degrees (period 180), in [0, 180).

    An axial angle and the same angle plus 180 degrees are one direction, so
    the doubled angles are averaged on the circle
    (``scipy.stats.circmean``) and the mean halved:

    .. math:: \bar\theta = \tfrac12 \operatorname{atan2}\Big(\sum_i \sin 2\theta_i,\ \sum_i \cos 2\theta_i\Big) \bmod 180^\circ

    The mean of 179 and 1 degrees is 0 (not 90).

    Parameters
    ----------
    theta_deg : array_like
        Angles in degrees (any range).
    axis : int, optional
        Axis to average over (default: all values).
    """
    doubled = np.radians(2.0 * np.asarray(theta_deg, dtype=float))
    return np.mod(np.degrees(circmean(doubled, high=2 * np.pi, low=0.0, axis=axis)) / 2.0, 180.0)


def angle_difference(a, b):
    r"""Signed difference :math:`a - b` of axial angles in degrees, in (-90, 90].

    .. math:: \Delta = \big((a - b + 90) \bmod 180\big) - 90, \quad \text{then } -90 \mapsto 90

    so that 179 and 1 degrees differ by -2 (and 1 and 179 by +2).
    """
    d = np.mod(np.asarray(a, float) - np.asarray(b, float) + 90.0, 180.0) - 90.0
    return np.where(d == -90.0, 90.0, d)


#: Rates below this fraction of the median |gammadot| have no sign (``reversal_indices``).
REVERSAL_DEAD_BAND = 0.1
#: Samples of one sign in a row that a new direction needs (``reversal_indices``).
REVERSAL_MIN_RUN = 3


def reversal_indices(gammadot, dead_band: float = REVERSAL_DEAD_BAND, min_run: int = REVERSAL_MIN_RUN) -> np.ndarray:
    r"""Where the shear rate reverses: the first sample of each new direction.

    Noise must neither make nor hide a reversal. A sample has the sign of its
    rate when :math:`|\dot\gamma_i| > d \cdot \mathrm{median}_j |\dot\gamma_j|`
    (``dead_band`` :math:`d`) and none otherwise (it is at rest, or noise about
    zero). The direction is the sign of the first ``min_run`` signed samples in
    a row; it reverses at the first sample of a run of ``min_run`` signed
    samples in a row of the other sign (shorter runs are noise). Rests between
    two directions do not count: a rate that stops and resumes in the same
    direction is not a reversal.

    Parameters
    ----------
    gammadot : array_like
        The ``gammadot`` column, in time order (one run, or runs joined).
    dead_band : float
        Fraction of the median rate below which a sample has no sign, in [0, 1).
    min_run : int
        Samples of one sign in a row that make a direction (>= 1).

    Returns
    -------
    numpy.ndarray of int
        Indices of the first sample of each new direction (empty: no reversal).
    """
    g = np.asarray(gammadot, dtype=float)
    if not 0 <= dead_band < 1 or min_run < 1:
        raise ValueError(f"reversal_indices: dead_band = {dead_band!r} must lie in [0, 1) and min_run = {min_run!r} be >= 1")
    sign = np.where(np.abs(g) > dead_band * np.median(np.abs(g)), np.sign(g), 0.0)
    signed = np.nonzero(sign)[0]
    sg = sign[signed]
    # runs of one sign among the signed samples: their starts, lengths and signs
    starts = np.concatenate([[0], np.nonzero(sg[1:] != sg[:-1])[0] + 1]) if sg.size else np.array([], int)
    lengths = np.diff(np.append(starts, sg.size))
    out, current = [], 0.0
    for k, n in zip(starts, lengths):
        if n < min_run:
            continue
        if current != 0.0 and sg[k] != current:
            out.append(int(signed[k]))
        current = sg[k]
    return np.array(out, dtype=int)


#: Strain before a reversal over which the state at the reversal is estimated (``pre_reversal_state``).
PRE_REVERSAL_WINDOW = 0.1
#: Fewest samples in that estimate (the last ones are taken if the window holds fewer).
MIN_PRE_REVERSAL_SAMPLES = 10


#: How ``pre_reversal_state`` estimates the state at a reversal from the window before it.
PRE_REVERSAL_ESTIMATES = ("mean", "line")


def pre_reversal_state(pre, window: float = PRE_REVERSAL_WINDOW, estimate: str = "mean"):
    r"""The DEM state at a reversal, estimated over the end of the leg before it.

    Over the samples within ``window`` of strain before the leg's last sample
    (at least ``MIN_PRE_REVERSAL_SAMPLES``), each of :math:`y = A_{xx}, A_{xy}, \mu`
    is estimated at the reversal by

    - ``estimate="mean"``: the window's mean. Right for a leg that is steady at
      its end (a pre-shear: the calibration checks it for drift), where it has
      the smallest variance.
    - ``estimate="line"``: a straight line fitted (least squares) in the strain
      :math:`s_i = |\gamma_{\mathrm{end}} - \gamma_i| \le w` travelled back from the
      last sample, :math:`y_i \approx \hat y + c\, s_i`, taken at the reversal,
      :math:`\hat y`. Right for a leg that still moves (the transient before a
      schedule's later reversal), where a mean lags behind the state at the
      reversal, by more the faster the fabric moves and the more samples the
      window holds early on (sampling is fine just after the previous reversal).

    ``split_transients`` takes the mean for the first reversal and the line for
    the later ones. Measured on model-made double reversals (back after 0.15
    strain) with the contract's noise, 12 seeds (tests/test_reversal_start_state.py):
    at the second reversal the bias of |A| against the noise-free state at the
    reversal falls from 0.015 (mean) to below 0.001 (line), its RMS error from
    0.015 to 0.006; on the steady pre-shear (sampled every 0.01 strain) the line
    would double the mean's RMS error (0.004 -> 0.009), which is why it keeps the
    mean.

    Parameters
    ----------
    pre : pandas.DataFrame
        The leg before the reversal (``strain``, ``gammadot``, ``A_xx``, ``A_xy``, ``mu``):
        the pre-shear, or the transient before a later reversal.
    window : float
        Strain before the reversal over which the state is estimated.
    estimate : {"mean", "line"}
        The estimator (above).

    Returns
    -------
    dict
        ``A_xx``, ``A_xy``, ``mu`` (the state at the reversal), ``gammadot`` (the
        median rate of the last tenth of the run), its sign ``gammadot_sign``
        (0 if the run does not move) and ``X`` :math:`= \sqrt2 A_{xy}\,\mathrm{sign}(\dot\gamma)`
        (docs/model.md); a reversal starts from :math:`-X`, the *mirrored* X.
    """
    if estimate not in PRE_REVERSAL_ESTIMATES:
        raise ValueError(f"pre_reversal_state: estimate = {estimate!r} is not one of {PRE_REVERSAL_ESTIMATES}")
    n = len(pre)
    rate = float(np.median(pre["gammadot"].to_numpy()[-max(MIN_PRE_REVERSAL_SAMPLES, n // 10):]))
    g = float(np.sign(rate))
    s = pre["strain"].to_numpy(dtype=float)
    back = np.abs(s[-1] - s)            # strain back from the last sample (the leg has one direction near its end)
    win = back <= window
    if win.sum() < MIN_PRE_REVERSAL_SAMPLES:
        win = np.zeros(n, bool)
        win[-MIN_PRE_REVERSAL_SAMPLES:] = True
    a, b, mu = (_line_at_end(back[win], pre[c].to_numpy(dtype=float)[win]) if estimate == "line"
                else float(pre[c].to_numpy(dtype=float)[win].mean()) for c in ("A_xx", "A_xy", "mu"))
    return {"A_xx": a, "A_xy": b, "mu": mu, "gammadot": rate, "gammadot_sign": g, "X": float(np.sqrt(2.0) * b * g)}


def _line_at_end(back, y) -> float:
    """Intercept at ``back = 0`` of the least-squares line through (back, y); the mean where back does not vary."""
    if len(y) < 3 or np.ptp(back) <= 0:
        return float(np.mean(y))
    return float(np.polynomial.polynomial.polyfit(back, y, 1)[0])


def reversal_times(meta: dict):
    """The start times of a run's reversals that its sidecar states, or None.

    ``reversals`` (a reversal schedule: one entry per reversal, each with ``t``), else
    ``reversal_t`` (heaviside, sinusoidal: one reversal), else None (detect them).
    """
    if meta.get("reversals"):
        return [float(r["t"]) for r in meta["reversals"]], [float(r["strain"]) for r in meta["reversals"]]
    if "reversal_t" in meta:
        strain = meta.get("reversal_strain")
        return [float(meta["reversal_t"])], [None if strain is None else float(strain)]
    return None


@dataclass
class Transient:
    """One reversal of a run and what follows it, up to the next reversal.

    Attributes
    ----------
    index : int
        The reversal's number in the run, from 1.
    n_reversals : int
        Reversals in the run.
    data : pandas.DataFrame
        The run's rows from the reversal's start to the next reversal (index reset).
    t0, strain0 : float
        Time and strain at which the reversal starts.
    initial : dict
        ``pre_reversal_state`` of the leg before the reversal (the pre-shear, or the
        previous transient): ``A_xx, A_xy, mu, gammadot, gammadot_sign, X``.
    sign : float
        Sign of the shear rate after the reversal (``-initial["gammadot_sign"]``).
    """

    index: int
    n_reversals: int
    data: pd.DataFrame
    t0: float
    strain0: float
    initial: dict
    sign: float
    meta: dict = field(default_factory=dict)


def split_transients(pre, run, meta=None, window: float = PRE_REVERSAL_WINDOW, what: str = "run",
                     min_samples: int = 1) -> list:
    r"""Split a reversal run into transients, one per reversal.

    The reversals start at the times the sidecar ``meta`` states (``reversal_times``);
    without them they are detected on the pre-shear's rate followed by the run's
    (``reversal_indices``): the first reversal at the run's first row when it
    reverses the pre-shear, a later one at the last row before its new direction.

    Transient :math:`k` holds the run's rows with :math:`t_k \le t < t_{k+1}` (to the
    end for the last): a row at :math:`t_{k+1}` itself is the state just before that
    reversal and closes transient :math:`k`; only the run's first row, when it lies at
    the run's first reversal, opens a transient. Its initial state is
    ``pre_reversal_state`` over the last ``window`` strain of the leg before
    :math:`t_k`: the pre-shear for the first reversal (followed by the run's rows
    before it, if the run first keeps the pre-shear's direction), transient
    :math:`k-1` for the others (the pre-shear's mean, a transient's fitted line at its
    end: ``pre_reversal_state``). A single-reversal run (heaviside, sinusoidal) gives
    one transient: the whole run from ``reversal_t`` on, started from the end of the
    pre-shear.

    Parameters
    ----------
    pre, run : pandas.DataFrame
        The pre-shear and the reversal run (``t``, ``strain``, ``gammadot``, ``A_xx``,
        ``A_xy``, ``mu``), each in time order.
    meta : dict, optional
        The run's sidecar (``reversals`` or ``reversal_t``, ``reversal_strain``).
    window : float
        Strain over which the state at a reversal is estimated (``pre_reversal_state``).
    what : str
        The run's name in error messages (its file).
    min_samples : int
        Fewest rows a transient must hold.

    Returns
    -------
    list of Transient

    Raises
    ------
    DEMInputError
        A stated reversal time outside [end of the pre-shear, end of the run], times
        not increasing, a run whose rate never opposes the pre-shear's, a sidecar
        that lists more than one reversal where the rate reverses a different
        number of times, or a transient with fewer than ``min_samples`` rows.
    """
    t = run["t"].to_numpy(dtype=float)
    g_all = np.concatenate([pre["gammadot"].to_numpy(dtype=float), run["gammadot"].to_numpy(dtype=float)])
    found = reversal_indices(g_all)
    if found.size == 0:
        raise DEMInputError(f"{what}: the rate never opposes the pre-shear's "
                         f"(for {REVERSAL_MIN_RUN} samples in a row): no reversal in this run")
    stated = reversal_times(meta or {})
    n_pre = len(pre)
    if stated is None:
        starts, strains = [], []
        for i in found:
            if i <= n_pre:   # at the junction: the run's first row (the pre-shear ends just before it)
                starts.append(float(t[0]))
                strains.append(float(run["strain"].iloc[0]))
            else:
                starts.append(float(t[i - n_pre - 1]))
                strains.append(float(run["strain"].iloc[i - n_pre - 1]))
    else:
        starts, strains = stated
        t_pre_end = float(pre["t"].iloc[-1])
        for k, tk in enumerate(starts):
            tol = 1e-9 * max(1.0, abs(tk))
            if not (t_pre_end - tol <= tk <= t[-1]):
                raise DEMInputError(f"{what}: sidecar reversal time {tk} (reversal {k + 1}) lies outside "
                                 f"[end of pre-shear {t_pre_end}, end of run {t[-1]}]")
        if np.any(np.diff(starts) <= 0):
            raise DEMInputError(f"{what}: sidecar reversal times {starts} do not increase")
        if len(starts) > 1 and len(starts) != found.size:
            raise DEMInputError(f"{what}: the sidecar lists {len(starts)} reversals, the rate reverses "
                             f"{found.size} time(s) (for {REVERSAL_MIN_RUN} samples in a row)")
        strains = [float(run["strain"].iloc[int(np.searchsorted(t, tk - 1e-9 * max(1.0, abs(tk))))])
                   if sk is None else sk for tk, sk in zip(starts, strains)]
    # row ranges: transient k = [lo_k, lo_{k+1}); a row at t_k opens k only if it is the run's first row
    lo = []
    for k, tk in enumerate(starts):
        tol = 1e-9 * max(1.0, abs(tk))
        first = int(np.searchsorted(t, tk - tol))      # first row with t >= t_k
        if 0 < first < len(t) and abs(t[first] - tk) <= tol:
            first += 1   # the state just before the reversal, inside the run: it closes the leg before
        lo.append(first)
    lo.append(len(t))
    # the leg before the first reversal: the pre-shear, and the run's rows before it if any
    history = pre if lo[0] == 0 else pd.concat([pre, run.iloc[: lo[0]]], ignore_index=True)
    out = []
    for k in range(len(starts)):
        data = run.iloc[lo[k]: lo[k + 1]].reset_index(drop=True)
        if len(data) < min_samples:
            raise DEMInputError(f"{what}: only {len(data)} samples after reversal {k + 1} (t = {starts[k]}), "
                             f"at least {min_samples} are needed")
        leg = history if k == 0 else out[-1].data
        # the pre-shear is steady at its end (its mean); a later leg is a transient still moving (the line's end)
        initial = pre_reversal_state(leg, window, "mean" if k == 0 else "line")
        out.append(Transient(index=k + 1, n_reversals=len(starts), data=data, t0=float(starts[k]),
                             strain0=float(strains[k]), initial=initial, sign=-initial["gammadot_sign"]))
    return out


#: A reversal's kind: a step of the rate, or a half-cosine transition (docs/scene.md).
REVERSAL_KINDS = ("heaviside", "sinusoidal")
#: The sidecar's ``transition`` -> the reversal's kind.
TRANSITION_KINDS = {"heaviside": "heaviside", "half_cosine": "sinusoidal"}


def _kind_of(entry: dict, what: str, k: int) -> dict:
    """One reversal's ``{kind, direction, transition_strain}`` from a sidecar entry (``reversals`` or ``segments``)."""
    transition = entry.get("transition", "heaviside")
    if transition not in TRANSITION_KINDS:
        raise DEMInputError(f"{what}: reversal {k}: transition {transition!r} is not one of "
                            f"{', '.join(TRANSITION_KINDS)}")
    direction = entry.get("direction")
    if direction not in (-1, 1):
        raise DEMInputError(f"{what}: reversal {k}: direction {direction!r} is not -1 or +1")
    ts = entry.get("transition_strain")
    if transition == "half_cosine" and not (isinstance(ts, (int, float)) and ts > 0):
        raise DEMInputError(f"{what}: reversal {k}: a half cosine needs a positive transition_strain (got {ts!r})")
    return {"kind": TRANSITION_KINDS[transition], "direction": int(direction),
            "transition_strain": float(ts) if transition == "half_cosine" else None}


def reversal_kinds(meta: dict | None, protocol: str, what: str = "run") -> list:
    r"""Each reversal of a run: its kind, its direction and its transition strain.

    The kind is ``"heaviside"`` (the rate steps from one direction to the other) or
    ``"sinusoidal"`` (it turns through a half cosine over ``transition_strain``,
    :math:`\dot\gamma(t) = \dot\gamma_0 [\tfrac{a+b}2 + \tfrac{a-b}2 \cos(\pi (t - t_k)/T)]`
    from direction :math:`a` to :math:`b`, docs/scene.md). The direction is that of
    the shear after the reversal relative to the pre-shear's: -1 against it, +1 back
    along it. They come, in order of preference, from

    1. the sidecar's ``reversals`` (a schedule: one entry per reversal, with
       ``direction``, ``transition`` and, for a half cosine, ``transition_strain``);
    2. its ``segments`` (the expanded schedule): a reversal at every segment whose
       direction differs from the one before it (the pre-shear's, +1, before the first);
    3. the protocol's name for the classic runs: ``heaviside`` is one step against the
       pre-shear, ``sinusoidal`` one half cosine against it (its transition strain from
       the sidecar's scene, ``scene.sinusoidal.transition_strain``, when present).

    Parameters
    ----------
    meta : dict or None
        The run's sidecar (``series.read_sidecar``).
    protocol : str
        The run's protocol (its file's stem).
    what : str
        The run's name in error messages (its file).

    Returns
    -------
    list of dict
        ``{"kind", "direction", "transition_strain"}`` per reversal, in order
        (``transition_strain`` None for a step).

    Raises
    ------
    DEMInputError
        A schedule whose sidecar states neither ``reversals`` nor ``segments`` (its
        reversals' kinds cannot be known), or an entry with an unknown transition, a
        direction other than -1/+1, or a half cosine without a positive transition strain.
    """
    meta = meta or {}
    if meta.get("reversals"):
        return [_kind_of(r, what, k + 1) for k, r in enumerate(meta["reversals"])]
    if meta.get("segments"):
        out, prev = [], 1
        for seg in meta["segments"]:
            if seg.get("direction") != prev:
                out.append(_kind_of(seg, what, len(out) + 1))
                prev = seg.get("direction")
        return out
    if protocol == "heaviside":
        return [{"kind": "heaviside", "direction": -1, "transition_strain": None}]
    if protocol == "sinusoidal":
        ts = (meta.get("scene") or {}).get("sinusoidal", {}).get("transition_strain")
        return [{"kind": "sinusoidal", "direction": -1, "transition_strain": None if ts is None else float(ts)}]
    raise DEMInputError(f"{what}: the sidecar lists neither 'reversals' nor 'segments', so the kind of the "
                        f"reversals of schedule {protocol!r} is unknown (heaviside and sinusoidal runs need none)")


#: Columns an x -> -x reflection changes sign of (``mirror_reversal``).
MIRRORED_COLUMNS = ("strain", "gammadot", "U_top", "U_bottom", "A_xy", "sigma_xy", "sigma_xy_bulk")


def mirror_reversal(data: pd.DataFrame) -> pd.DataFrame:
    r"""A run reflected through x -> -x: a +1 reversal in the frame of the -1 ones.

    A reversal back along the pre-shear (direction +1) is the mirror image of one
    against it: under the reflection :math:`x \mapsto -x` the fabric
    :math:`A = [[a, b], [b, -a]]` becomes :math:`[[a, -b], [-b, -a]]`, every
    x-velocity and the shear stress change sign, and so

    .. math::
        A_{xy} \mapsto -A_{xy}, \quad \theta_A \mapsto (180^\circ - \theta_A) \bmod 180^\circ,
        \quad \dot\gamma, \gamma, \sigma_{xy}, U \mapsto -\dot\gamma, -\gamma, -\sigma_{xy}, -U

    while :math:`A_{xx}`, :math:`|A|`, :math:`\mu = |\sigma_{xy}|/p`, p, the strain
    travelled ``s_rev`` and :math:`X = \sqrt2 A_{xy} \operatorname{sign}\dot\gamma`
    are unchanged. Applying it twice gives the run back.

    Parameters
    ----------
    data : pandas.DataFrame
        Rows of a run (any of ``MIRRORED_COLUMNS`` and ``theta_A``; other columns are kept).

    Returns
    -------
    pandas.DataFrame
        A reflected copy.
    """
    out = data.copy()
    for c in MIRRORED_COLUMNS:
        if c in out:
            out[c] = -out[c]
    if "theta_A" in out:
        out["theta_A"] = np.mod(180.0 - out["theta_A"].to_numpy(dtype=float), 180.0)
    return out
