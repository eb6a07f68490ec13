"""The bulk-vs-walls figure: steady values against disks N with the reference bands, the
Heaviside transients overlaid, and the information per core-hour against the tall cell's."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402

from .bulk import AXIAL, INFORMATION, STEADY, TRANSIENT  # noqa: E402

LABELS = {"mu": r"$\mu$", "A_norm": r"$|A|$", "theta_A_deg": r"$\theta_A$ (deg)", "phi": r"$\phi$", "Z": "Z"}
MARKERS = {"walls": "s", "periodic": "o"}


def break_at_wraps(x, y, *more):
    """Axial angles in [0, 180) with a gap (NaN) where they wrap through 0/180 (a step over 90 deg)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    cut = np.flatnonzero(np.abs(np.diff(y)) > 90) + 1
    out = [np.insert(x, cut, np.nan), np.insert(y, cut, np.nan)]
    out += [np.insert(np.asarray(v, float), cut, np.nan) for v in more]
    return out


def bulk_vs_walls(cells, curves, references, tall, path, match_se: float = 2.0):
    """Row 1: each steady quantity against N (log), seed mean +- SE, each reference's band of
    +- ``match_se`` SE. Row 2: the seed-mean transients of every cell (references bold), and
    the information per core-hour over the tall reference's (log)."""
    fig, axes = plt.subplots(2, len(STEADY), figsize=(4 * len(STEADY), 7.5), constrained_layout=True)
    colours = {cell: f"C{i % 10}" for i, cell in enumerate(cells["cell"])}
    for ax, q in zip(axes[0], STEADY):
        for _, r in cells.iterrows():
            ax.errorbar(r["N"], r[q], yerr=r[f"{q}_se"], marker=MARKERS.get(r["kind"], "o"),
                        color=colours[r["cell"]], ls="none", capsize=3, label=r["cell"])
        for ref in references:
            r = cells.set_index("cell").loc[ref]
            ax.axhspan(r[q] - match_se * r[f"{q}_se"], r[q] + match_se * r[f"{q}_se"],
                       color=colours[ref], alpha=0.15, lw=0)
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("disks N")
        ax.set_ylabel(LABELS[q])
    axes[0][0].legend(fontsize=7)
    for ax, q in zip(axes[1], TRANSIENT):
        for cell, c in curves.items():
            x, y, se = c["strain_since_reversal"].to_numpy(), c[q].to_numpy(), c[f"{q}_se"].to_numpy()
            if q in AXIAL:
                x, y, se = break_at_wraps(x, y, se)
            ax.plot(x, y, color=colours[cell], lw=2.2 if cell in references else 1.0, label=cell)
            if cell in references:
                ax.fill_between(x, y - se, y + se, color=colours[cell], alpha=0.2, lw=0)
        ax.set_xlabel("strain since the reversal")
        ax.set_ylabel(LABELS[q])
    ax = axes[1][len(TRANSIENT)]
    if tall and f"info_ratio_{INFORMATION[0]}" in cells:
        x = np.arange(len(cells))
        for k, q in enumerate(INFORMATION):
            ax.bar(x + (k - 0.5) * 0.4, cells[f"info_ratio_{q}"], width=0.4, label=LABELS[q])
        ax.axhline(1.0, color="k", lw=0.8)
        ax.axhline(10.0, color="k", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.set_xticks(x, cells["cell"], rotation=60, ha="right", fontsize=7)
        ax.set_ylabel(f"information per core-hour / {tall}'s")
        ax.legend(fontsize=7)
    else:
        ax.axis("off")
    for ax in axes[1][len(TRANSIENT) + 1:]:
        ax.axis("off")
    fig.savefig(path, dpi=120)
    plt.close(fig)
