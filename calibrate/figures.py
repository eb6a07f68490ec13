"""Figures from our own data, as in the paper: Fig. 2a, 2b, 3a, 3b, and the fitted curves against the DEM."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dem_contract import fabric_angle_deg, fabric_norm  # noqa: E402
from model.laws import alpha_model1, alpha_model2, friction_eq2, friction_quadratic, stress_ratio_eq2  # noqa: E402

PROTO_COLORS = {"heaviside": "tab:blue", "sinusoidal": "tab:orange", "preshear": "tab:gray"}


def fig2a(samples, path):
    """sigma_xy/p against A_xy (raw samples of every seed, per protocol)."""
    fig, ax = plt.subplots(figsize=(5, 4))
    for proto, d in samples.groupby("protocol"):
        ax.plot(d["b_raw"], d["sigma_xy_over_p"], ".", ms=2, alpha=0.4, color=PROTO_COLORS.get(proto), label=proto)
    ax.set_xlabel(r"$A_{xy}$")
    ax.set_ylabel(r"$\sigma_{xy}/p$")
    ax.set_title("Fig. 2a: shear stress against fabric (DEM)")
    ax.legend(markerscale=4)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def _binned_means(X, y, nbins):
    edges = np.linspace(np.min(X), np.max(X), nbins + 1)
    idx = np.digitize(X, edges) - 1
    rows = [(X[m].mean(), y[m].mean(), y[m].std(ddof=1) / np.sqrt(m.sum()))
            for m in (idx == k for k in range(nbins)) if m.sum() >= 3]
    return np.array(rows).T if rows else np.empty((3, 0))


def fig2b(X, tau, eq2: dict, quad: dict, path, nbins=30):
    """Fig. 2b, both ways: mu = |sigma_xy|/p against X (the paper's, left) and the signed ratio (right).

    ``tau`` is the signed ratio g sigma_xy/p of the kept samples; both laws are
    drawn as fitted (to tau): Eq. 2 as mu(X) on the left, as its signed form
    ``stress_ratio_eq2`` on the right; the quadratic law as |tau| and tau.
    """
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    x = np.linspace(np.min(X), np.max(X), 300)
    quad_tau = friction_quadratic(x, **quad)
    panels = ((np.abs(tau), friction_eq2(x, **eq2), np.abs(quad_tau),
               r"$\mu = |\sigma_{xy}|/p$", "Fig. 2b: friction against X (as in the paper)"),
              (tau, stress_ratio_eq2(x, **eq2), quad_tau,
               r"$\tau = \mathrm{sign}(\dot\gamma)\,\sigma_{xy}/p$", "signed stress ratio (the data fitted)"))
    for ax, (y, eq2_line, quad_line, ylabel, title) in zip(axes, panels):
        ax.plot(X, y, ".", ms=2, color="0.75", label="DEM samples")
        xm, ym, ye = _binned_means(X, y, nbins)
        ax.errorbar(xm, ym, ye, fmt="o", ms=3, color="k", label="DEM binned mean")
        ax.plot(x, eq2_line, "r-", label="Eq. 2 fit")
        ax.plot(x, quad_line, "b--", label="quadratic law [15] fit")
        ax.axvline(eq2["X0"], color="r", lw=0.6, ls=":")
        ax.set_xlabel(r"$X = A:D'/|D'|$")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10)
    axes[1].axhline(0.0, color="0.5", lw=0.6)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def fig3(bins, which, m1: dict, m2: dict, path, free=None):
    """alpha1 (which=1) or alpha2 (which=2) against X: back-solved bins and the Model 1 / Model 2 fits.

    ``m1`` and ``m2`` map a route label to the block's values. ``free`` (optional,
    ``freeform.curves_for_figure``): the free-form fit, drawn with its band of
    +-t_{n-1} jackknife standard errors over the n seeds (``free["t"]``).
    """
    col = f"alpha{which}"
    fig, ax = plt.subplots(figsize=(5.5, 4))
    lo_col, hi_col = f"{col}_low", f"{col}_high"
    for used, style in ((True, dict(fmt="o", color="k", label="back-solve, used bins")),
                        (False, dict(fmt="o", mfc="none", color="0.6", label="back-solve, left out (cond./count)"))):
        d = bins[bins["used"] == used]
        if not len(d):
            continue
        if lo_col in d and np.isfinite(d[lo_col]).any():
            err = np.vstack([d[col] - d[lo_col], d[hi_col] - d[col]]).clip(min=0)
        else:
            err = d[f"se_{col}"]
        ax.errorbar(d["X_mean"], d[col], err, ms=4, capsize=2, **style)
    xmin, xmax = float(bins["X_lo"].min()), float(bins["X_hi"].max())
    colors = iter(["tab:red", "tab:purple", "tab:blue", "tab:cyan"])
    for label, v in m1.items():
        x = np.linspace(xmin, min(xmax, v["X_c"] * 0.999), 400)
        ax.plot(x, alpha_model1(x, **v)[which - 1], "-", color=next(colors), label=f"Model 1 ({label})")
    for label, v in m2.items():
        x = np.linspace(xmin, xmax, 100)
        ax.plot(x, np.broadcast_to(alpha_model2(x, **v)[which - 1], x.shape), "--", color=next(colors),
                label=f"Model 2 ({label})")
    if free is not None:
        y, se = free[col], free[f"se{which}"]
        ax.plot(free["X"], y, "-", lw=2, color="tab:green", label=free["label"])
        if np.isfinite(se).any():
            k = free["t"]
            ax.fill_between(free["X"], y - k * se, y + k * se, color="tab:green", alpha=0.2, lw=0)
    used = bins[bins["used"]]
    if len(used):
        lo, hi = np.nanpercentile(used[col], [2, 98])
        pad = 0.5 * (hi - lo) + 1.0
        ax.set_ylim(lo - pad, hi + pad)
    ax.set_xlabel(r"$X = A:D'/|D'|$ (dimensionless)")
    ax.set_ylabel(rf"$\alpha_{which}$ (dimensionless)")
    ax.set_title(f"Fig. 3{'ab'[which - 1]}: " + rf"$\alpha_{which}$ against X")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def fig_curves(replays, predictions: dict, path):
    """|A|, theta_A and mu against path strain: DEM ensemble (every seed) and the models.

    ``predictions`` maps a label to {replay label: (n, 3) array of a, b, signed mu}.
    """
    protos = sorted({r.label.split("/")[-1] for r in replays})
    fig, axes = plt.subplots(3, len(protos), figsize=(4.5 * len(protos), 8), squeeze=False, sharex="col")
    for j, proto in enumerate(protos):
        reps = [r for r in replays if r.label.endswith(proto)]
        for r in reps:
            axes[0, j].plot(r.s, fabric_norm(r.a, r.b), ".", ms=2, color="0.7")
            axes[1, j].plot(r.s, fabric_angle_deg(r.a, r.b), ".", ms=2, color="0.7")
            axes[2, j].plot(r.s, r.mu, ".", ms=2, color="0.7")
        for (label, pred), style in zip(predictions.items(), ("r-", "b--", "m-.", "c:")):
            m = pred.get(reps[0].label)
            if m is None:
                continue
            axes[0, j].plot(reps[0].s, fabric_norm(m[:, 0], m[:, 1]), style, label=label)
            axes[1, j].plot(reps[0].s, fabric_angle_deg(m[:, 0], m[:, 1]), style)
            axes[2, j].plot(reps[0].s, m[:, 2], style)
        axes[0, j].set_title(proto)
        axes[0, j].set_ylabel(r"$|A|$")
        axes[1, j].set_ylabel(r"$\theta_A$ (deg)")
        axes[2, j].set_ylabel(r"$\mathrm{sign}(\dot\gamma)\sigma_{xy}/p$")
        axes[2, j].set_xlabel("path strain since the run start")
        axes[0, j].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_profiles(prof, prof_iv, path):
    """Each profiled parameter: objective minus its minimum against the parameter, with the interval's threshold.

    One panel per (model, parameter) of ``prof`` (``profiles.profile``): the
    re-fitted points (crosses where no re-fit could be integrated), the
    threshold line of the 95 % profile interval and the interval's ends
    (``prof_iv``, ``profiles.intervals``). Model 1's c1 and c2 span decades:
    their axis is |value| on a log scale.
    """
    keys = list(dict.fromkeys(zip(prof["model"], prof["parameter"]))) if len(prof) else []
    n = max(len(keys), 1)
    ncol = min(3, n)
    nrow = int(np.ceil(n / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.2 * nrow), squeeze=False)
    for ax in axes.flat[len(keys):]:
        ax.axis("off")
    if not keys:
        axes[0, 0].text(0.5, 0.5, "no profiles (--profile-points 0)", ha="center", va="center")
    for ax, (model, name) in zip(axes.flat, keys):
        p = prof[(prof["model"] == model) & (prof["parameter"] == name)].sort_values("value")
        logx = model == "model1" and name in ("c1", "c2")
        x = np.abs(p["value"].to_numpy(float)) if logx else p["value"].to_numpy(float)
        d = p["delta"].to_numpy(float)
        thr = float(p["threshold"].iloc[0])
        ok = np.isfinite(d)
        ax.plot(x[ok], np.maximum(d[ok], thr * 1e-3), "o-", ms=3, color="tab:blue", label="re-fitted")
        if (~ok).any():
            ax.plot(x[~ok], np.full((~ok).sum(), thr), "x", color="tab:red", label="cannot be integrated")
        ax.axhline(thr, color="k", ls="--", lw=1, label="95 % threshold")
        iv = prof_iv[(prof_iv["model"] == model) & (prof_iv["parameter"] == name)]
        if len(iv):
            for end in (iv["low"].iloc[0], iv["high"].iloc[0]):
                if np.isfinite(end):
                    ax.axvline(abs(end) if logx else end, color="tab:green", lw=1)
            ax.set_title(f"{model} {name}: {'identified' if iv['identified'].iloc[0] else 'not identified'}",
                         fontsize=9)
        ax.set_yscale("log")
        if logx:
            ax.set_xscale("log")
        ax.set_xlabel(f"|{name}|" if logx else name)
        ax.set_ylabel("objective - minimum")
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
