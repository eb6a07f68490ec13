"""The claims table as a figure (a forest plot) and as a Markdown section for the README."""
from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import power as pw  # noqa: E402
from .table import EARLY_A  # noqa: E402
from .stats import VERDICTS, verdict_counts  # noqa: E402

COLOURS = {"reproduced": "tab:green", "contradicted": "tab:red", "negligible": "tab:blue", "inconclusive": "0.45",
           "both fail": "tab:purple"}
RULE = ("One level: every interval is the 90 % interval of its statistic, every verdict a one-sided test at 5 % "
        "read off it. A claim is **reproduced** when the interval lies entirely on the paper's side of the null "
        "value (no effect), **contradicted** when it lies entirely on the other side, **negligible** when it lies "
        "inside null +- its margin, the smallest effect that would matter (declared in `claims/margins.py`, "
        "reasons in `docs/model.md`: the two one-sided tests of equivalence at 5 %); \"reproduced, negligible\" "
        "is a real effect too small to matter. **Inconclusive** otherwise (the interval contains the null, or too "
        "few seeds to compute it). A comparison of two models reads **both fail** when each lies outside the "
        "DEM's ensemble band on the row's statistic (column adequacy). Claims 4, 7 and 9 are scored on the model "
        "error (each run's MSE less the DEM's noise floor, measured from the seed-to-seed scatter; the floor "
        "cancels from the paired difference), one row per figure (step reversals: Fig. 4; the sinusoidal "
        "reversal: Fig. 5) and a pooled row as a secondary line. \"theta_A always passes through 90 degrees\" is "
        "also contradicted by a run that crosses the horizontal at family-wise 5 % over the runs (Holm). "
        "Intervals are over seeds, pooled across ensembles (percentile bootstrap, widened to the Student t "
        "interval where wider); model comparisons are out of sample (a calibration set scored on the runs it "
        "was not fitted on) and paired on each run.")


def forest_plot(table, path) -> None:
    """One panel per claim: its estimate and 90 % interval against the null line, coloured by verdict."""
    n = len(table)
    fig, axes = plt.subplots(n, 1, figsize=(8.5, 1.05 * n + 0.9), squeeze=False)
    for ax, (_, r) in zip(axes[:, 0], table.iterrows()):
        colour = COLOURS.get(str(r["verdict"]).split(",")[0], "k")
        ax.axvline(r["null"], color="k", lw=0.8, ls="--")
        margin = r.get("margin", math.nan)
        has_margin = isinstance(margin, (int, float)) and math.isfinite(margin)
        if has_margin:     # the band of effects too small to matter
            ax.axvspan(r["null"] - margin, r["null"] + margin, color="tab:blue", alpha=0.12, lw=0)
        if np.isfinite(r["estimate"]):
            lo = r["low"] if np.isfinite(r["low"]) else r["estimate"]
            hi = r["high"] if np.isfinite(r["high"]) else r["estimate"]
            ax.errorbar([r["estimate"]], [0], xerr=[[r["estimate"] - lo], [hi - r["estimate"]]], fmt="o",
                        color=colour, capsize=4, lw=1.6)
            span = [v for v in (lo, hi, r["null"], r["estimate"]) if np.isfinite(v)]
            if has_margin:
                span += [r["null"] - margin, r["null"] + margin]
            pad = 0.15 * (max(span) - min(span) or abs(r["null"]) or 1.0)
            ax.set_xlim(min(span) - pad, max(span) + pad)
        else:
            ax.text(0.5, 0.5, "not computed", transform=ax.transAxes, ha="center", va="center", color=colour)
            ax.set_xticks([])
        ax.set_yticks([])
        side = "paper: " + ("above" if r["paper_side"] == ">" else "below") + f" {r['null']:g}"
        ax.set_ylabel(f"claim {r['claim_id']}", rotation=0, ha="right", va="center")
        ax.set_title(f"{_short(r['claim'])}: {r['verdict']} (n = {r['n']})", fontsize=8, loc="left",
                     color=colour)
        band = f"; shaded: null +- margin {margin:.2g}" if has_margin else ""
        ax.set_xlabel(f"{r['unit']} ({side}; dashed: null{band})", fontsize=7, labelpad=1)
        ax.tick_params(labelsize=7)
    fig.suptitle("The paper's claims: estimate and 90 % interval per claim, and the margin that matters",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def _short(text, width=80):
    return text if len(text) <= width else text[: width - 3] + "..."


def _num(x):
    return "" if not (isinstance(x, (int, float)) and math.isfinite(x)) else f"{x:.3g}"


def _adequacy(row) -> str:
    """The row's adequacy cell ('' where the claim compares no two models)."""
    a = str(row.get("adequacy", ""))
    return "" if a == "nan" else a.replace("|", "\\|")


def markdown_section(table, title="The paper's claims, decided", source="") -> str:
    """A Markdown section: the decision rule, a summary line and one table row per claim."""
    counts = verdict_counts(table["verdict"])
    lines = [f"## {title}", "",
             "Generated by `python -m claims` from the comparison's curves and the DEM series"
             + (f" ({source})" if source else "") + "; do not edit by hand.", "", RULE, "",
             "Summary: " + ", ".join(f"{counts[v]} {v}" for v in VERDICTS) + ".", "",
             "| id | claim (source) | statistic | estimate [90 % interval] | null | margin | test | n | adequacy "
             "| verdict |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in table.iterrows():
        interval = f"{_num(r['estimate'])} [{_num(r['low'])}, {_num(r['high'])}] {r['unit']}"
        margin = f"+-{_num(r['margin'])}" if _num(r.get("margin", math.nan)) else "none"
        cell = lambda s: str(s).replace("|", "\\|")  # noqa: E731  (|A| stays |A| in a Markdown table)
        lines.append(f"| {r['claim_id']} | {cell(r['claim'])} ({cell(r['source'])}) | {cell(r['statistic'])}"
                     f"{'; ' + cell(r['detail']) if str(r['detail']) not in ('', 'nan') else ''} | {cell(interval)} | "
                     f"{r['paper_side']} {_num(r['null'])} | {margin} | {cell(r['test'])} | {r['n']} "
                     f"{cell(r['n_unit'])} | {_adequacy(r)} | "
                     f"**{r['verdict']}** |")
    return "\n".join(lines) + "\n"


def _n(x):
    return "no finite number" if not np.isfinite(x) else f"{x:,.0f}"


def _cost(x, fmt: str) -> str:
    """A DEM cost (disks, core-hours) formatted, or ``claims.power.UNKNOWN`` when the sidecars do not record it."""
    if np.isnan(x):
        return pw.UNKNOWN
    return format(x, fmt) if np.isfinite(x) else "no finite number of"


def power_section(power, presets: list, campaign: dict, noise: dict) -> str:
    """The README's power paragraph: seeds needed per claim and effect (``claims.power``), and each preset's reach.

    Parameters
    ----------
    power : DataFrame
        ``claims.power.power_table``.
    presets : list of dict
        ``claims.power.preset_from_config`` (name, seeds, disks, transients).
    campaign : dict
        The measured campaign as a preset (``claims.power.campaign_preset``).
    noise : dict
        ``claims.power.fabric_noise_check``.
    """
    lines = ["### Power: how much DEM decides Model 1 against Model 2", "",
             f"From the seed-to-seed s.d. of the paired differences (every comparison row of claims 4, 4-start and "
             f"7, per figure), the seeds needed for the 90 % interval to exclude 0 (one-sided 5 %) with "
             f"{pw.POWER:.0%} power (noncentral t; `power.csv`). Assumed: the per-seed s.d. "
             f"falls as N^-1/2 in disks and k^-1/2 in scored transients per seed; the fabric's per-sample noise in "
             f"the steady pre-shear is {noise['measured']:.4f}, " + (
                 f"{noise['ratio']:.2f} times that of independent contacts (1/sqrt(8 n_c)): contact-sampling "
                 f"noise, which falls as N^-1/2" if np.isfinite(noise["ratio"]) else
                 "against independent contacts unknown (the data hold no contact counts, n_contacts)") +
             ". Minimal effect: the row's margin.", ""]
    for _, r in power.iterrows():
        lines.append(f"- claim {r['claim_id']} ({r['quantity']}), {r['effect_choice']} effect {r['effect']:.2g} "
                     f"(s.d. per seed {r['sd_per_seed']:.2g} at {_cost(r['disks_per_seed'], '.0f')} disks, "
                     f"{r['transients_per_seed']:g} transients per seed): {_n(r['seeds_needed'])} seeds, "
                     f"{_n(r['particles']) if np.isfinite(r['disks_per_seed']) else pw.UNKNOWN} disk-seeds, "
                     f"{_cost(r['core_hours'], '.2g')} core-hours at this campaign's "
                     f"settings (power now {r['power_measured']:.2f}).")
    lines.append("")
    for p in [campaign, *presets]:
        verdicts = []
        for _, r in power.iterrows():
            x = pw.reach(r, p["seeds"], p["disks"], p["transients"])
            verdicts.append(f"claim {r['claim_id']} {r['effect_choice']}: {'yes' if x['reached'] else 'no'} "
                            f"({_n(x['seeds_needed'])} seeds needed, power {x['power']:.2f})")
        lines.append(f"- the {p['name']} preset ({p['seeds']} seeds x {_cost(p['disks'], '.0f')} disks x "
                     f"{p['transients']:g} scored transients): " + "; ".join(verdicts) + ".")
    lines.append("- a preset of S seeds x N disks x k scored transients reaches a row when S >= the seeds needed at "
                 "s.d. x sqrt(N0 k0 / (N k)) (N0, k0: this campaign's). A measured effect of the wrong sign "
                 "(positive) is reached as 'contradicted', not 'reproduced'. The s.d. is that of these data: "
                 "where the two models nearly coincide (a measured effect near 0) it understates the spread a "
                 "pole that acts brings (README, \"The paper's claims\").")
    return "\n".join(lines) + "\n"


def design_section(design) -> str:
    """The README's reversal-design paragraph: claim 4's per-seed s.d., cost and information per core-hour per protocol.

    Parameters
    ----------
    design : DataFrame
        ``claims.design.design_table``.
    """
    lines = ["### The reversal design: information on claim 4 per core-hour", "",
             "Per reversal protocol, over the seeds: claim 4's paired difference (squared model error of |A| over "
             f"the first {EARLY_A:g} strain, MSE of Model 1 minus MSE of Model 2, out of sample) averaged over the "
             "protocol's reversals "
             "of a seed; its s.d. over seeds (90 % chi-square interval); the CPU hours of a seed of that design "
             "alone (packing, pre-shear, the protocol's run); information per core-hour 1/(s.d.^2 x hours), "
             "relative to the best; the design effect (1: a seed's reversals as good as independent ones); |A| at "
             "the reversal over the steady |A| (`reversal_design.csv`, `claims/design.py`).", "",
             "| protocol | seeds | reversals per seed | mean difference [90 % t] | s.d. per seed [90 %] | "
             "CPU h per seed | relative information | design effect | |A| at reversal / steady |",
             "|---|---|---|---|---|---|---|---|---|"]
    for _, r in design.iterrows():
        lines.append(f"| {r['protocol']} | {r['seeds']} | {_num(r['reversals_per_seed'])} | {_num(r['mean_difference'])} "
                     f"[{_num(r['mean_lo'])}, {_num(r['mean_hi'])}] | {_num(r['sd_per_seed'])} "
                     f"[{_num(r['sd_lo'])}, {_num(r['sd_hi'])}] | {_num(r['cpu_hours_per_seed'])} | "
                     f"{_num(r['relative_information'])} | {_num(r['design_effect'])} | "
                     f"{_num(r['A_at_reversal_over_steady'])} |")
    return "\n".join(lines) + "\n"
