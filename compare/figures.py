r"""Figures: Fig. 4 / Fig. 5 of the paper (DEM band, Model 1, Model 2) and the sensitivity band.

Abscissa everywhere: the strain travelled since the reversal, ``s_rev`` (see
``dem``); theta_A in degrees; |A| and mu dimensionless. Angle lines are broken
where they wrap between 0 and 180 degrees instead of drawing a vertical jump.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROWS = (("A_norm", r"$|A|$"), ("theta_A", r"$\theta_A$ (deg)"), ("mu", r"$\mu = |\sigma_{xy}|/p$"))
STYLE = {"model1": dict(color="C3", lw=1.6, label="Model 1 (Eq. 6, Eq. 2)"),
         "model2": dict(color="C0", lw=1.6, ls="--", label="Model 2 ([15])")}
XLABEL = r"strain since reversal $\int|\dot\gamma|\,dt$"


def _broken(theta):
    """theta with NaN inserted where it wraps (|jump| > 90 deg), for plotting."""
    th = np.asarray(theta, float).copy()
    jump = np.abs(np.diff(th)) > 90.0
    th[1:][jump] = np.nan
    return th


def _plot_panel(ax, ens, q, models, zoom=None):
    s = ens["s_rev"].to_numpy()
    m = s <= zoom if zoom else slice(None)
    y = ens[f"dem_{q}"].to_numpy()
    sd = ens[f"dem_{q}_std"].to_numpy()
    ax.fill_between(s[m], (y - sd)[m], (y + sd)[m], color="0.75", lw=0, label=r"DEM $\pm$1 s.d. over seeds")
    ax.plot(s[m], (_broken(y) if q == "theta_A" else y)[m], color="k", lw=1.0, label="DEM, mean over seeds")
    for model in models:
        col = f"{model}_{q}"
        if col in ens and np.isfinite(ens[col]).any():
            v = ens[col].to_numpy()
            ax.plot(s[m], (_broken(v) if q == "theta_A" else v)[m], **STYLE[model])


def reversal_figure(ensembles, kind, path, models=("model1", "model2"), zoom=0.1, title=""):
    """Fig. 4 (Heaviside) or Fig. 5 (sinusoidal): |A|, theta_A, mu against strain.

    One pair of columns (whole run, zoom) per ensemble of reversals of that kind:
    the classic run of each (pressure, I) group and every reversal of that kind of
    a schedule, a +1 one already reflected into the frame of the -1 ones
    (``comparison.run``).

    Parameters
    ----------
    ensembles : dict
        (group, key) -> DataFrame of ``comparison.ensemble_curves``, whose ``attrs`` name
        its ``kind`` and ``direction`` (without them: the key is the kind).
    kind : {"heaviside", "sinusoidal"}
    path : path
        PNG to write.
    zoom : float
        Strain range of the inset on the start of the reversal (the paper's Fig. 4c).

    Returns
    -------
    list of (group, key)
        The ensembles drawn, in order.
    """
    keys = [(g, p) for (g, p), ens in ensembles.items() if ens.attrs.get("kind", p) == kind]
    if not keys:
        raise ValueError(f"no DEM reversal of kind {kind!r} to draw (none of the compared protocols has one)")
    ncol = 2 * len(keys)
    fig, axes = plt.subplots(3, ncol, figsize=(max(8.0, 6.8 * len(keys)), 9.0), squeeze=False,
                             gridspec_kw=dict(width_ratios=[2.2, 1.0] * len(keys)))
    for j, (g, p) in enumerate(keys):
        ens = ensembles[(g, p)]
        n_ok = ens.attrs.get("n_ok", {})
        for k, z in enumerate((None, zoom)):
            col = 2 * j + k
            for i, (q, label) in enumerate(ROWS):
                ax = axes[i, col]
                _plot_panel(ax, ens, q, models, zoom=z)
                if q == "theta_A":
                    ax.axhline(90.0, color="0.5", lw=0.6, ls=":")
                    ax.set_ylim(0, 180)
                    ax.set_yticks([0, 45, 90, 135, 180])
                else:
                    ax.set_ylim(bottom=0)
                if z:
                    ax.set_xlim(0, z)
                if col == 0:
                    ax.set_ylabel(label)
                if i < 2:
                    ax.tick_params(labelbottom=False)
            axes[-1, col].set_xlabel(XLABEL if z is None else f"zoom: first {z:g} strain")
        n_seeds = ens.attrs.get("n_seeds", 0)
        notes = [f"{STYLE[m]['label'].split(' (')[0]} on {n} of {n_seeds} seeds"
                 for m, n in n_ok.items() if n < n_seeds]
        name = g if p == kind else f"{g}, {p}" + (" (+1, mirrored)" if ens.attrs.get("direction", -1) > 0 else "")
        axes[0, 2 * j].set_title(f"{name} ({n_seeds} seeds)" + (f"; {'; '.join(notes)} (see errors.csv)" if notes else ""),
                                 fontsize=9, loc="left")
        axes[0, 2 * j + 1].set_title("start of the reversal", fontsize=9)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=2, frameon=False, fontsize=9, bbox_to_anchor=(0.5, 0.965))
    fig.suptitle(title, y=0.995, fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.91))
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return keys


def sensitivity_figure(bands, path):
    """Envelopes of the predictions under the parameter perturbations.

    Parameters
    ----------
    bands : dict
        (protocol, model) -> dict with ``s_rev``, ``dem`` (DataFrame of the DEM
        run: ``A_norm, theta_A, mu``), ``nominal`` (DataFrame) and
        ``envelopes``: kind -> (low DataFrame, high DataFrame, n_runs, n_failed).
    path : path
    """
    keys = list(bands)
    fig, axes = plt.subplots(3, len(keys), figsize=(4.2 * len(keys) + 0.6, 9.0), squeeze=False, sharex="col")
    shades = {"interval": ("C2", 0.25), "5%": ("C1", 0.35), "1%": ("C3", 0.6)}
    for j, key in enumerate(keys):
        b = bands[key]
        s = b["s_rev"]
        for i, (q, label) in enumerate(ROWS):
            ax = axes[i, j]
            ax.plot(s, b["dem"][q].to_numpy() if q != "theta_A" else _broken(b["dem"][q]), ".", ms=2,
                    color="0.55", label="DEM (this seed)")
            for kind, (lo, hi, n, nf) in b["envelopes"].items():
                if n - nf <= 0:
                    continue
                color, alpha = shades.get(kind, ("C4", 0.3))
                ax.fill_between(s, lo[q], hi[q], color=color, alpha=alpha, lw=0,
                                label=f"one parameter at {kind}" + (f" ({nf} of {n} failed)" if nf else ""))
            if b["nominal"] is not None:
                v = b["nominal"][q].to_numpy()
                ax.plot(s, _broken(v) if q == "theta_A" else v, color="k", lw=1.2, label="fitted parameters")
            if q == "theta_A":
                ax.set_ylim(0, 180)
                ax.set_yticks([0, 45, 90, 135, 180])
            if j == 0:
                ax.set_ylabel(label)
        protocol, model = key
        axes[0, j].set_title(f"{STYLE[model]['label']}\n{protocol} ({b['case']})", fontsize=9)
        axes[0, j].legend(fontsize=7, loc="upper right")
        axes[-1, j].set_xlabel(XLABEL)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
