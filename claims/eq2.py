r"""Eq. 2 against the paper as curves, and what the data say about the paper's k5 (issue 32, item 8).

Comparing Eq. 2's coefficients one by one with the paper's (X0, k1, k3, k5) is
misleading: they are correlated, and a coefficient "not set by the data" (k5
at its bound 0) can still change mu where the data are. So this module
compares curves, over the X range the data visit:

- ``curves``: mu(X) of Eq. 2 fitted to each seed's reversal samples (the
  signed form ``model.laws.stress_ratio_eq2``, as the calibration fits it,
  ``calibrate.fits.fit_eq2``), its mean over seeds with the 90 % Student t
  band at each X (the table's level, ``claims.stats``), the calibration's
  fit of set ``all`` and the paper's curve (X0 0.028, k1 2.7, k3 20, k5 9e4),
  on a grid over the 1st-99th percentile of the X visited; ``paper_inside``
  says where the paper's curve lies inside the band;
- ``k5_profile``: for k5 held at each value of ``K5_GRID`` (0 to 1e6, the
  paper's 9e4 among them) and X0, k1, k3 refitted per seed, the RMS scatter
  of mu about the curve over that of the free fit, mean over seeds with its
  90 % t interval: the profile of k5 on the scale of claim 2b (Eq. 2
  captures mu(X) when within ``table.EQ2_MARGIN`` - 1 = 10 % of the best
  curve's scatter), and mu's change at the largest X visited.

``python -m claims`` writes both to ``eq2_vs_paper.csv`` (``section`` curve
or k5_profile) and draws ``eq2_vs_paper.png``.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from calibrate.fits import EQ2_BOUNDS, fit_eq2
from model import friction_eq2
from model.laws import stress_ratio_eq2

from . import stats

PAPER = dict(X0=0.028, k1=2.7, k3=20.0, k5=9.0e4)
K5_GRID = (0.0, 1e3, 1e4, 3e4, 9e4, 3e5, 1e6)
N_GRID = 60
COLUMNS = ["section", "X", "k5", "value", "low", "high", "fit_all", "paper", "paper_inside", "mu_change_at_X_hi",
           "n"]


def _signed(samples: pd.DataFrame):
    """(X, signed stress ratio g sigma_xy/p) of a case's reversal samples: g = sign(gammadot) = sign(X A_xy)."""
    X = samples["X"].to_numpy(float)
    g = np.sign(X) * np.sign(samples["A_xy"].to_numpy(float))
    tau = g * samples["stress_ratio"].to_numpy(float)
    ok = np.isfinite(X) & np.isfinite(tau) & (g != 0)
    return X[ok], tau[ok]


def fit_seed(samples: pd.DataFrame) -> dict:
    """Eq. 2 fitted to one seed's samples (``calibrate.fits.fit_eq2``, no steady-state term): X0, k1, k3, k5."""
    X, tau = _signed(samples)
    sd = float(np.std(tau)) or 1.0
    return fit_eq2(X, tau, sd, {"X": 0.0, "mu": 0.0, "se_mu": 1.0}, steady_weight=0.0).values


def fit_fixed_k5(samples: pd.DataFrame, k5: float, start: dict) -> tuple:
    """X0, k1, k3 refitted with k5 held; returns (values, RMS of the signed residual)."""
    X, tau = _signed(samples)
    scale = np.array([0.01, 1.0, 10.0])
    lo, hi = (np.array(b[:3]) / scale for b in zip(*EQ2_BOUNDS))

    def res(p):
        X0, k1, k3 = p * scale
        return stress_ratio_eq2(X, X0, k1, k3, k5) - tau

    best = None
    for s0 in (np.array([start["X0"], start["k1"], start["k3"]]), np.array([0.03, 2.0, 0.0])):
        sol = least_squares(res, np.clip(s0 / scale, lo + 1e-9, hi - 1e-9), bounds=(lo, hi), x_scale="jac")
        if best is None or sol.cost < best.cost:
            best = sol
    X0, k1, k3 = best.x * scale
    return dict(X0=X0, k1=k1, k3=k3, k5=k5), float(np.sqrt(np.mean(best.fun ** 2)))


def _band(values):
    """Mean over seeds and its 90 % t band, per column of ``values`` (seeds x points)."""
    v = np.asarray(values, float)
    n = v.shape[0]
    mean = v.mean(axis=0)
    half = stats.t_quantile(n) * v.std(axis=0, ddof=1) / math.sqrt(n) if n >= 2 else np.full(v.shape[1], np.nan)
    return mean, mean - half, mean + half


def eq2_table(dem_cases, fit_all: dict | None = None) -> pd.DataFrame:
    """The ``curve`` and ``k5_profile`` sections of the module docstring (``COLUMNS``)."""
    cases = [c for c in dem_cases if len(c.samples) >= 20]
    if len(cases) < 2:
        return pd.DataFrame(columns=COLUMNS)
    fits = [fit_seed(c.samples) for c in cases]
    X_all = np.concatenate([_signed(c.samples)[0] for c in cases])
    lo_x, hi_x = np.percentile(X_all, [1, 99])
    grid = np.linspace(lo_x, hi_x, N_GRID)
    mu = [friction_eq2(grid, **f) for f in fits]
    mean, low, high = _band(mu)
    paper = friction_eq2(grid, **PAPER)
    allfit = friction_eq2(grid, **fit_all) if fit_all else np.full(grid.size, np.nan)
    rows = [dict(section="curve", X=x, k5=math.nan, value=m, low=lo, high=hi, fit_all=a, paper=p,
                 paper_inside=bool(lo <= p <= hi), mu_change_at_X_hi=math.nan, n=len(cases))
            for x, m, lo, hi, a, p in zip(grid, mean, low, high, allfit, paper)]
    free_rms = [_fit_rms(c.samples, f) for c, f in zip(cases, fits)]
    for k5 in K5_GRID:
        fixed = [fit_fixed_k5(c.samples, k5, f) for c, f in zip(cases, fits)]
        ratio = [r / r0 for (_, r), r0 in zip(fixed, free_rms)]
        est, lo, hi, n = stats.mean_interval(ratio)
        change = float(np.mean([friction_eq2(hi_x, **p) - friction_eq2(hi_x, **f) for (p, _), f in zip(fixed, fits)]))
        rows.append(dict(section="k5_profile", X=hi_x, k5=k5, value=est, low=lo, high=hi, fit_all=math.nan,
                         paper=math.nan, paper_inside=False, mu_change_at_X_hi=change, n=n))
    return pd.DataFrame(rows, columns=COLUMNS)


def _fit_rms(samples, values) -> float:
    X, tau = _signed(samples)
    return float(np.sqrt(np.mean((stress_ratio_eq2(X, **values) - tau) ** 2)))


def summary(tab: pd.DataFrame, eq2_margin: float) -> str:
    """One paragraph: where the paper's curve leaves the band, and the k5 profile at the paper's 9e4."""
    if tab.empty:
        return "Eq. 2 against the paper: not computed (fewer than 2 seeds with reversal samples)."
    cur = tab[tab["section"] == "curve"]
    outside = cur[~cur["paper_inside"].astype(bool)]
    gap = float((cur["paper"] - cur["value"]).abs().max())
    prof = tab[tab["section"] == "k5_profile"].set_index("k5")
    at = prof.loc[PAPER["k5"]]
    verdict = ("within" if at["high"] < eq2_margin else "beyond" if at["low"] > eq2_margin else "not decided against")
    return (f"Eq. 2 against the paper, as curves over the X visited ({cur['X'].min():.3g} to {cur['X'].max():.3g}): "
            f"the paper's mu(X) lies outside the 90 % band over seeds of the fitted curve on "
            f"{len(outside)} of {len(cur)} grid points (largest |paper - fit| {gap:.3g}); with k5 held at the "
            f"paper's 9e4 (X0, k1, k3 refitted per seed) mu's scatter is {at['value']:.3g} [{at['low']:.3g}, "
            f"{at['high']:.3g}] times the free fit's, {verdict} the 10 % of claim 2b's margin, and mu at the "
            f"largest X changes by {at['mu_change_at_X_hi']:+.3g}.")


def figure(tab: pd.DataFrame, path) -> None:
    """mu(X): the fit's band, the set-all fit and the paper's curve; and the k5 profile."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    cur = tab[tab["section"] == "curve"]
    if len(cur):
        a.fill_between(cur["X"], cur["low"], cur["high"], color="0.8", lw=0, label="Eq. 2 per seed: 90 % t band")
        a.plot(cur["X"], cur["value"], "k-", lw=1.2, label="Eq. 2, mean over seeds")
        if np.isfinite(cur["fit_all"]).any():
            a.plot(cur["X"], cur["fit_all"], "b--", lw=1.0, label="Eq. 2, calibration set all")
        a.plot(cur["X"], cur["paper"], "r-", lw=1.2, label="the paper's Eq. 2")
        a.set_xlabel("X (over the 1st-99th percentile visited)")
        a.set_ylabel(r"$\mu$")
        a.legend(fontsize=7)
    prof = tab[tab["section"] == "k5_profile"]
    if len(prof):
        x = np.where(prof["k5"] > 0, prof["k5"], np.nan)
        b.errorbar(x, prof["value"], [prof["value"] - prof["low"], prof["high"] - prof["value"]], fmt="o-",
                   capsize=3)
        b.axvline(PAPER["k5"], color="r", lw=0.8, ls="--", label="the paper's k5")
        b.axhline(1.1, color="k", lw=0.8, ls=":", label="claim 2b's 10 %")
        b.set_xscale("log")
        b.set_xlabel("k5 held (X0, k1, k3 refitted per seed)")
        b.set_ylabel("scatter of mu over the free fit's (90 % t)")
        b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
