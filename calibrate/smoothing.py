r"""Smoothing and differentiation of the fabric in strain (Savitzky-Golay).

Method (the rule the calibration states)
----------------------------------------
* Work in the *path strain* :math:`s` (:math:`ds = |d\gamma|`): Eq. 4 is rate
  independent, so the fabric is a function of :math:`s` and of the sign
  :math:`g` of the shear rate only, and the derivative
  :math:`dA/ds = (dA/dt)/|\dot\gamma|` carries no rate.
* Cut each run into *pieces* of one sign of :math:`\dot\gamma` (samples with
  :math:`\dot\gamma = 0` belong to none). A reversal makes :math:`dA/ds` jump,
  so no filter window ever straddles one.
* In each piece, interpolate linearly onto a uniform grid of spacing
  ``h = fine_window / (fine_points - 1)`` and apply
  ``scipy.signal.savgol_filter`` (polynomial order ``order``, ``mode="interp"``)
  for the value and the first derivative; read both back at the samples.
  Two windows: ``fine_window`` strain (default 0.011: 11 points of the quick
  preset's 0.001 sampling) for the first ``fine_span`` strain of a piece, where the
  fabric changes fast after a reversal, and ``coarse_window`` (default 0.051)
  beyond, where the sampling is coarse (0.01) and the fabric slow.
* The smoother is linear, so it is built as matrices ``S`` (values) and ``D``
  (derivatives) acting on the raw samples; the noise of each smoothed
  derivative is then exactly :math:`\sigma \|D_{i\cdot}\|` for white sample
  noise :math:`\sigma`, estimated per run and component from the residuals
  :math:`\hat\sigma^2 = \sum_i r_i^2 / \sum_i \|(I - S)_{i\cdot}\|^2`.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd
from scipy.signal import savgol_filter

from .io import DEMInputError, Run

SQRT2 = np.sqrt(2.0)


@dataclass(frozen=True)
class SmoothingSettings:
    """Savitzky-Golay settings in units of path strain (see module docstring)."""

    fine_window: float = 0.011
    coarse_window: float = 0.051
    fine_points: int = 11
    fine_span: float = 0.1
    order: int = 2

    def __post_init__(self):
        if not (self.fine_window > 0 and self.coarse_window >= self.fine_window):
            raise ValueError("need 0 < fine_window <= coarse_window")
        if self.fine_points < self.order + 2 or self.fine_points % 2 == 0:
            raise ValueError(f"fine_points = {self.fine_points} must be odd and >= order + 2")
        if self.order < 1:
            raise ValueError("order must be >= 1 (a derivative is needed)")

    @property
    def grid(self) -> float:
        return self.fine_window / (self.fine_points - 1)

    def as_dict(self) -> dict:
        return {**asdict(self), "grid": self.grid, "filter": "scipy.signal.savgol_filter, mode=interp"}


def pieces(gammadot):
    """Index arrays of the maximal runs of samples with one non-zero sign of the rate."""
    sg = np.sign(np.asarray(gammadot, dtype=float))
    out, start = [], None
    for i, v in enumerate(sg):
        if start is not None and v != sg[start]:
            out.append(np.arange(start, i))
            start = None
        if start is None and v != 0:
            start = i
    if start is not None:
        out.append(np.arange(start, len(sg)))
    return out


def _odd_points(window, h, n_grid, order):
    m = int(round(window / h)) | 1
    m = min(m, n_grid if n_grid % 2 else n_grid - 1)
    return m if m >= order + 2 else 0


def smoothing_operator(s, settings: SmoothingSettings = SmoothingSettings()):
    r"""Matrices ``S``, ``D`` with ``S @ y`` the smoothed values and ``D @ y`` the d/ds of samples ``y``.

    Parameters
    ----------
    s : array, strictly increasing
        Path strain of the samples of one piece.
    settings : SmoothingSettings

    Returns
    -------
    S, D : ndarray (n, n), or (None, None) if the piece is too short to
        differentiate (fewer grid points than ``order + 2``).
    """
    s = np.asarray(s, dtype=float)
    n = len(s)
    h = settings.grid
    if n < settings.order + 2:
        return None, None
    grid = s[0] + h * np.arange(int(np.floor((s[-1] - s[0]) / h + 1e-9)) + 1)
    if grid[-1] < s[-1] - 1e-12:
        grid = np.append(grid, grid[-1] + h)  # extends at most h past the last sample (flat extrapolation)
    # linear interpolation as a matrix: P (n_grid x n)
    j = np.clip(np.searchsorted(s, grid, side="right") - 1, 0, n - 2)
    w = np.clip((grid - s[j]) / (s[j + 1] - s[j]), 0.0, 1.0)
    P = np.zeros((len(grid), n))
    P[np.arange(len(grid)), j] = 1.0 - w
    P[np.arange(len(grid)), j + 1] += w
    # back to the samples: Q (n x n_grid)
    k = np.clip(np.searchsorted(grid, s, side="right") - 1, 0, len(grid) - 2) if len(grid) > 1 else np.zeros(n, int)
    out_S, out_D = np.zeros((n, n)), np.zeros((n, n))
    rel = s - s[0]
    for window, mask in ((settings.fine_window, rel <= settings.fine_span),
                         (settings.coarse_window, rel > settings.fine_span)):
        if not mask.any():
            continue
        m = _odd_points(window, h, len(grid), settings.order)
        if m == 0:
            return None, None
        Gs = savgol_filter(P, m, settings.order, deriv=0, axis=0, mode="interp")
        Gd = savgol_filter(P, m, settings.order, deriv=1, delta=h, axis=0, mode="interp")
        if len(grid) == 1:
            return None, None
        kk = k[mask]
        u = np.clip((s[mask] - grid[kk]) / h, 0.0, 1.0)[:, None]
        out_S[mask] = (1 - u) * Gs[kk] + u * Gs[kk + 1]
        out_D[mask] = (1 - u) * Gd[kk] + u * Gd[kk + 1]
    return out_S, out_D


def _noise(y, S):
    r = y - S @ y
    R = np.eye(len(y)) - S
    denom = float(np.sum(R**2))
    return float(np.sqrt(np.sum(r**2) / denom)) if denom > 0 else np.nan


SAMPLE_COLUMNS = [
    "case", "group", "seed", "protocol", "piece", "s", "s_piece", "strain", "g", "rate_frac",
    "a_raw", "b_raw", "mu", "sigma_xy_over_p", "a", "b", "da", "db", "sd_a", "sd_b", "sd_da", "sd_db", "X",
]


def smooth_run(run: Run, settings: SmoothingSettings = SmoothingSettings()) -> pd.DataFrame:
    r"""Smoothed fabric and its strain derivative at every usable sample of a run.

    Returns
    -------
    pandas.DataFrame
        One row per sample in a piece long enough to differentiate, columns
        ``SAMPLE_COLUMNS``: ``s`` path strain from the file start, ``s_piece``
        from the piece start (the last reversal), ``g`` sign of the rate,
        ``rate_frac`` = |gammadot| / median |gammadot| of the run, ``a, b``
        smoothed A_xx, A_xy, ``da, db`` their d/ds, ``sd_*`` the noise of each,
        ``X = sqrt2 b g``.
    """
    d = run.data
    g_all = d["gammadot"].to_numpy()
    strain = d["strain"].to_numpy()
    s_all = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(strain)))])
    med = float(np.median(np.abs(g_all[g_all != 0]))) if np.any(g_all != 0) else 1.0
    frames = []
    for k, idx in enumerate(pieces(g_all)):
        s = s_all[idx]
        keep = np.concatenate([[True], np.diff(s) > 1e-12 * max(1.0, s[-1])])
        idx, s = idx[keep], s[keep]
        S, D = smoothing_operator(s, settings)
        if S is None:
            continue
        a_raw, b_raw = d["A_xx"].to_numpy()[idx], d["A_xy"].to_numpy()[idx]
        sd_a, sd_b = _noise(a_raw, S), _noise(b_raw, S)
        g = np.sign(g_all[idx])
        Dn = np.sqrt(np.sum(D**2, axis=1))
        Sn = np.sqrt(np.sum(S**2, axis=1))
        b_s = S @ b_raw
        frames.append(pd.DataFrame({
            "case": run.case, "group": run.group, "seed": run.seed, "protocol": run.protocol, "piece": k,
            "s": s, "s_piece": s - s[0], "strain": strain[idx], "g": g,
            "rate_frac": np.abs(g_all[idx]) / med,
            "a_raw": a_raw, "b_raw": b_raw, "mu": d["mu"].to_numpy()[idx],
            "sigma_xy_over_p": (d["sigma_xy"] / d["p"]).to_numpy()[idx],
            "a": S @ a_raw, "b": b_s, "da": D @ a_raw, "db": D @ b_raw,
            "sd_a": sd_a * Sn, "sd_b": sd_b * Sn, "sd_da": sd_a * Dn, "sd_db": sd_b * Dn,
            "X": SQRT2 * b_s * g,
        }, columns=SAMPLE_COLUMNS))
    if not frames:
        raise DEMInputError(f"{run.path}: no piece of one shear direction is long enough to differentiate "
                            f"with a {settings.fine_window} strain window")
    return pd.concat(frames, ignore_index=True)


def smooth_cases(cases, settings: SmoothingSettings = SmoothingSettings(), include_preshear=False) -> pd.DataFrame:
    """``smooth_run`` over every chosen reversal run (and optionally the pre-shear) of every case."""
    frames = []
    for c in cases:
        runs = list(c.runs.values()) + ([c.preshear] if include_preshear else [])
        frames += [smooth_run(r, settings) for r in runs]
    return pd.concat(frames, ignore_index=True)
