"""Figures of the DEM resolution study: error against cost, transients, mu(I)."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from .analysis import DEFAULT_TOLERANCE, QUANTITIES  # noqa: E402

LABELS = {"mu": r"$\mu$", "A_norm": r"$|A|$", "theta_A_deg": r"$\theta_A$ (deg)"}
MARKERS = dict(zip(["kappa", "inertial_number", "H_over_d", "dt_over_tc", "fine_interval", "coarse_interval"],
                   "osD^vP"))


def error_against_cost(table: pd.DataFrame, path, tolerance: dict | None = None):
    """|deviation from the finest value of each axis| against shear wall time per unit strain."""
    tol = {**DEFAULT_TOLERANCE, **(tolerance or {})}
    rows = table[table["axis"] != "seed"]
    fig, axes = plt.subplots(2, 3, figsize=(12, 7), sharex=True)
    for j, q in enumerate(QUANTITIES):
        for i, (key, title) in enumerate([(q, f"steady {LABELS[q]}"), (f"transient_{q}", f"transient {LABELS[q]} (RMS)")]):
            ax = axes[i, j]
            for axis, g in rows.groupby("axis", sort=False):
                g = g[~g["finest"]]
                ax.scatter(g["wall_time_per_strain_s"], np.abs(g[f"d_{key}"]), marker=MARKERS.get(axis, "o"),
                           label=axis)
                for x, y, v in zip(g["wall_time_per_strain_s"], np.abs(g[f"d_{key}"]), g["value"]):
                    ax.annotate(f"{v:g}", (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
            spread = table[f"seed_spread_{key}"].iloc[0]
            if np.isfinite(spread):
                ax.axhline(spread, color="grey", ls="--", lw=1, label="seed spread")
            ax.axhline(tol[key], color="k", ls=":", lw=1, label="tolerance")
            ax.set_xscale("log")
            ax.set_title(f"deviation of {title}", fontsize=10)
            if i == 1:
                ax.set_xlabel("wall time per unit strain (s, one thread)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("DEM settings: deviation from the finest value of each axis against cost")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def transients(table: pd.DataFrame, curves: dict, path):
    """The Heaviside transients of every value of every axis (strain since the reversal)."""
    axes_names = [a for a in table["axis"].unique() if a != "seed"] + ["seed"]
    fig, axes = plt.subplots(len(axes_names), 3, figsize=(12, 2.4 * len(axes_names)), squeeze=False, sharex=True)
    for i, axis in enumerate(axes_names):
        g = table[table["axis"] == axis]
        for row in g.to_dict("records"):
            c = curves[row["point"]]
            style = dict(lw=2.0, color="k") if row.get("finest") is True else dict(lw=1.0)
            for j, q in enumerate(QUANTITIES):
                axes[i, j].plot(c["strain_since_reversal"], c[q], label=f"{row['value']:g}", **style)
        for j, q in enumerate(QUANTITIES):
            axes[i, j].set_ylabel(LABELS[q])
        axes[i, 0].set_title(axis, fontsize=9, loc="left")
        axes[i, 2].legend(fontsize=6, ncol=2)
    for j in range(3):
        axes[-1, j].set_xlabel("strain since the reversal")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def mu_of_I(table: pd.DataFrame, path):
    """Steady mu against achieved I, the line mu_c + b I and the campaign's I."""
    data, camp = table[table["kind"] == "data"], table[table["kind"] == "campaign"]
    mu_c, b, tol = table["mu_c"].iloc[0], table["b"].iloc[0], table["quasi_static_tolerance"].iloc[0]
    fig, ax = plt.subplots(figsize=(6, 4.2))
    ax.scatter(data["inertial_number_achieved"], data["mu_steady"], label="DEM (steady pre-shear)")
    I = np.linspace(0, max(data["inertial_number_achieved"].max(), camp["inertial_number"].max()) * 1.1, 50)
    ax.plot(I, mu_c + b * I, "k-", label=rf"$\mu_c + bI$: $\mu_c$ = {mu_c:.3f}, b = {b:.3g}")
    ax.fill_between(I, mu_c, mu_c * (1 + tol), color="grey", alpha=0.2,
                    label=rf"quasi-static: $(\mu-\mu_c)/\mu_c \leq$ {tol:g}")
    ax.scatter(camp["inertial_number"], camp["mu_fit"], marker="*", s=120, color="C3", zorder=3,
               label="campaign I (fit)")
    ax.set_xlabel("inertial number I (achieved)")
    ax.set_ylabel(r"steady $\mu$")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
