r"""Conditioning-aware back-solve of Eq. 4 for alpha1, alpha2 against X.

Equations
---------
With :math:`A = [[a, b], [b, -a]]`, path strain :math:`s` (:math:`ds = |\dot\gamma| dt`)
and :math:`g = \mathrm{sign}\,\dot\gamma`, Eq. 4 in simple shear reads (docs/model.md, Eq. 4)

.. math::
    \frac{da}{ds} = \frac{\alpha_2 a}{\sqrt2} + g b, \qquad
    \frac{db}{ds} = \frac{\alpha_1 g}{2} + \frac{\alpha_2 b}{\sqrt2} - g a,

so each sample gives two linear equations :math:`M (\alpha_1, \alpha_2)^T = r`:

.. math::
    M = \begin{pmatrix} 0 & a/\sqrt2 \\ g/2 & b/\sqrt2 \end{pmatrix}, \qquad
    r = \begin{pmatrix} da/ds - g b \\ db/ds + g a \end{pmatrix},
    \qquad \det M = -\frac{g a}{2\sqrt2}.

A pointwise solve divides by :math:`a` = A_xx, which is close to zero all
through steady shear; and since :math:`b = g X/\sqrt2`, every b-row of one X
is the same equation :math:`\alpha_1 + X \alpha_2 = 2(g\, db/ds + a)`: only
samples with a sizeable :math:`|a|` separate alpha1 from alpha2.

Rules (stated, settable)
------------------------
* Samples: keep those with :math:`|\dot\gamma| \ge` ``rate_min`` times the
  run's median rate (near-zero :math:`|D'|`, where X is undefined and the DEM
  is not quasi-static) and at least ``skip`` strain after a reversal (the
  smoother's edge, see ``smoothing``).
* Bins of X (width ``bin_width``): stack every kept sample of the bin and of
  every seed into one weighted least-squares problem (row weights: the inverse
  noise of r from ``smoothing``). Its condition number is that of the
  weighted design matrix with unit-norm columns. A bin is *used* (fitted,
  drawn filled) if it has at least ``min_samples`` samples and condition
  number at most ``cond_max``; other bins are reported, flagged, never fitted.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

SQRT2 = np.sqrt(2.0)


@dataclass(frozen=True)
class BacksolveSettings:
    rate_min: float = 0.2
    skip: float = 0.005
    bin_width: float = 0.005
    min_samples: int = 20
    cond_max: float = 30.0

    def as_dict(self) -> dict:
        return asdict(self)


def equations(a, b, da, db, g):
    """Per-sample ``M`` (n, 2, 2) and ``r`` (n, 2) of the module Notes."""
    a, b, da, db, g = (np.asarray(v, dtype=float) for v in (a, b, da, db, g))
    n = a.shape[0]
    M = np.zeros((n, 2, 2))
    M[:, 0, 1] = a / SQRT2
    M[:, 1, 0] = g / 2.0
    M[:, 1, 1] = b / SQRT2
    r = np.stack([da - g * b, db + g * a], axis=1)
    return M, r


def pointwise(a, b, da, db, g):
    """Naive per-sample solve of the 2x2 system (for comparison only): alpha1, alpha2, det M."""
    M, r = equations(a, b, da, db, g)
    det = np.linalg.det(M)
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha2 = r[:, 0] / M[:, 0, 1]
        alpha1 = (r[:, 1] - M[:, 1, 1] * alpha2) / M[:, 1, 0]
    return alpha1, alpha2, det


def select(samples: pd.DataFrame, settings: BacksolveSettings = BacksolveSettings()) -> np.ndarray:
    """Boolean mask of the samples the back-solve keeps (see module Rules)."""
    return ((samples["rate_frac"].to_numpy() >= settings.rate_min)
            & (samples["s_piece"].to_numpy() >= settings.skip)).astype(bool)


def row_sigma(samples: pd.DataFrame):
    """Noise of the two right-hand sides: sd(da - g b), sd(db + g a)."""
    s1 = np.sqrt(samples["sd_da"].to_numpy() ** 2 + samples["sd_b"].to_numpy() ** 2)
    s2 = np.sqrt(samples["sd_db"].to_numpy() ** 2 + samples["sd_a"].to_numpy() ** 2)
    floor = 1e-12
    return np.maximum(s1, floor), np.maximum(s2, floor)


def stacked_solve(M, r, s1, s2):
    """Weighted least squares of all rows of the samples given.

    Returns
    -------
    alpha : (2,)
    cov : (2, 2)  covariance, scaled by the reduced chi-square when it exceeds 1... see Notes
    cond : float  condition number of the weighted design matrix with unit-norm columns
    chi2 : float  reduced chi-square

    Notes
    -----
    ``cov = max(chi2_red, 1) (G^T G)^-1`` with ``G`` the weighted design matrix:
    the stated noise is a floor, extra scatter widens the error bars.
    """
    G = np.concatenate([M[:, 0, :] / s1[:, None], M[:, 1, :] / s2[:, None]])
    y = np.concatenate([r[:, 0] / s1, r[:, 1] / s2])
    norms = np.linalg.norm(G, axis=0)
    if np.any(norms == 0):
        return np.full(2, np.nan), np.full((2, 2), np.nan), np.inf, np.nan
    sv = np.linalg.svd(G / norms, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else np.inf
    alpha, *_ = np.linalg.lstsq(G, y, rcond=None)
    dof = max(len(y) - 2, 1)
    chi2 = float(np.sum((G @ alpha - y) ** 2) / dof)
    with np.errstate(all="ignore"):
        try:
            cov = np.linalg.inv(G.T @ G) * max(chi2, 1.0)
        except np.linalg.LinAlgError:
            cov = np.full((2, 2), np.inf)
    return alpha, cov, cond, chi2


def bin_edges(X, width):
    lo = np.floor(np.min(X) / width) * width
    hi = np.ceil(np.max(X) / width) * width
    return np.arange(lo, hi + 0.5 * width, width)


BIN_COLUMNS = ["X_lo", "X_hi", "X_mean", "n_samples", "n_seeds", "alpha1", "alpha2", "se_alpha1", "se_alpha2",
               "cov12", "cond", "chi2_red", "used"]


def binned(samples: pd.DataFrame, settings: BacksolveSettings = BacksolveSettings(), edges=None) -> pd.DataFrame:
    """Back-solve alpha1, alpha2 per bin of X over every kept sample of every seed.

    Parameters
    ----------
    samples : DataFrame from ``smoothing.smooth_cases``
    settings : BacksolveSettings
    edges : array, optional
        Bin edges; default ``bin_width`` wide over the kept samples' X.

    Returns
    -------
    DataFrame with ``BIN_COLUMNS``; ``used`` follows the module Rules.
    """
    keep = select(samples, settings)
    d = samples[keep]
    if len(d) == 0:
        return pd.DataFrame(columns=BIN_COLUMNS)
    X = d["X"].to_numpy()
    if edges is None:
        edges = bin_edges(X, settings.bin_width)
    M, r = equations(d["a"], d["b"], d["da"], d["db"], d["g"])
    s1, s2 = row_sigma(d)
    idx = np.digitize(X, edges) - 1
    seeds = (d["group"] + "/" + d["seed"]).to_numpy()
    rows = []
    for k in range(len(edges) - 1):
        m = idx == k
        n = int(m.sum())
        if n == 0:
            continue
        if n >= 2:
            alpha, cov, cond, chi2 = stacked_solve(M[m], r[m], s1[m], s2[m])
        else:
            alpha, cov, cond, chi2 = np.full(2, np.nan), np.full((2, 2), np.nan), np.inf, np.nan
        used = bool(n >= settings.min_samples and np.isfinite(cond) and cond <= settings.cond_max)
        rows.append([edges[k], edges[k + 1], float(X[m].mean()), n, len(set(seeds[m])), alpha[0], alpha[1],
                     float(np.sqrt(cov[0, 0])), float(np.sqrt(cov[1, 1])), float(cov[0, 1]), cond, chi2, used])
    return pd.DataFrame(rows, columns=BIN_COLUMNS)
