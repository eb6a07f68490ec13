"""The engines' figure: each engine's seed-mean transient after the reversal with its +-SE band."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .bulk import AXIAL, TRANSIENT  # noqa: E402
from .bulk_figures import break_at_wraps  # noqa: E402

LABELS = {"mu": r"friction $\mu = \sigma_{xy}/p$ (-)", "A_norm": r"fabric anisotropy $|A|$ (-)",
          "theta_A_deg": r"fabric angle $\theta_A$ (deg)"}
ENGINE_LABELS = {"yade": "YADE", "lammps": "LAMMPS"}


def transients(curves: dict, seeds: dict, stage: str, early_strain: float, path) -> None:
    """One panel per transient quantity (mu, |A|, theta_A) against the strain since the reversal:
    per engine the seed mean (line) and +- one standard error (band); the compared window, the
    first ``early_strain``, shaded. ``curves``: engine -> ``bulk.mean_curves`` table; ``seeds``:
    engine -> number of seeds (in the legend)."""
    fig, axes = plt.subplots(1, len(TRANSIENT), figsize=(4.2 * len(TRANSIENT), 3.6), constrained_layout=True)
    for ax, q in zip(axes, TRANSIENT):
        ax.axvspan(0.0, early_strain, color="0.9", lw=0, zorder=0)
        for k, (engine, c) in enumerate(curves.items()):
            x, y, se = (c[col].to_numpy() for col in ("strain_since_reversal", q, f"{q}_se"))
            if q in AXIAL:
                x, y, se = break_at_wraps(x, y, se)
            label = f"{ENGINE_LABELS.get(engine, engine)} ({seeds[engine]} seeds)"
            ax.plot(x, y, color=f"C{k}", lw=1.6, label=label)
            ax.fill_between(x, y - se, y + se, color=f"C{k}", alpha=0.25, lw=0)
        ax.set_xlabel("shear strain since the reversal (-)")
        ax.set_ylabel(LABELS[q])
        ax.set_xlim(left=0.0)
    axes[0].legend(fontsize=8, title=f"{stage}; seed mean +- SE", title_fontsize=8)
    axes[-1].text(early_strain, 0.02, f"compared: first {early_strain:g} ", transform=axes[-1].get_xaxis_transform(),
                  va="bottom", ha="right", fontsize=7, color="0.4")
    fig.savefig(path, dpi=130)
    plt.close(fig)
