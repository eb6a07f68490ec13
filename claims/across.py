r"""The same claims decided on two campaigns (two engines, or two cells), side by side.

``python -m claims across --table yade=<paper_claims.csv> --table lammps=<paper_claims.csv> --out <folder>``
writes ``claims_across.csv`` and ``claims_across.md``: one row per claim id the two tables share,
each table's estimate, 90 % interval and verdict, and

- ``same_verdict``: whether the two verdicts are the same; a row where they differ is reported
  as **engine-dependent** (``dependent_word``: cell-dependent for two cells);
- the difference of the two estimates and its Welch t,

  .. math:: t = \frac{\hat\theta_1 - \hat\theta_2}{\sqrt{s_1^2/n_1 + s_2^2/n_2}}, \qquad
            \nu = \frac{(s_1^2/n_1 + s_2^2/n_2)^2}{\frac{(s_1^2/n_1)^2}{n_1 - 1} + \frac{(s_2^2/n_2)^2}{n_2 - 1}}

  (``sd`` and ``n`` of each row: its seed-to-seed s.d., ``ddof = 1``, and seeds, claims.table), with
  a two-sided p-value from Student's t with the Welch-Satterthwaite degrees of freedom nu
  (``scipy.stats.ttest_ind_from_stats(..., equal_var=False)``: the seed counts are small, 5-10 a
  side, where the normal distribution would overstate a difference), and ``estimates_differ`` at
  family-wise 10 % over the rows (two-sided, ``FAMILY_ALPHA``: the table's one level, 5 % a side;
  Holm, ``stats.holm``): a verdict can differ between the campaigns while their estimates agree
  within seed noise (the two intervals straddle a null or a margin), which is a different finding
  from estimates that differ.

Rows without a finite ``sd`` or ``n`` < 2 in either table get no t and are left out of the Holm
family. Data never executes: labels are checked to be plain words.
"""
from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats as sps

from .stats import ALPHA, holm

#: Columns a claims table must hold to be set beside another.
NEEDED = ("claim_id", "estimate", "low", "high", "sd", "n", "verdict")
#: The estimates' difference is tested two-sided at the table's one level (90 % intervals: 5 % a side), family-wise.
FAMILY_ALPHA = 2 * ALPHA
LABEL = re.compile(r"^[A-Za-z][A-Za-z0-9_.-]{0,39}$")


def read_table(path) -> pd.DataFrame:
    """A claims table (``paper_claims.csv``) with the columns ``NEEDED``; ValueError naming what is missing."""
    table = pd.read_csv(path)
    missing = [c for c in NEEDED if c not in table.columns]
    if missing:
        raise ValueError(f"{path}: not a claims table (missing columns {', '.join(missing)})")
    return table


def across(first: pd.DataFrame, second: pd.DataFrame, labels=("yade", "lammps")) -> pd.DataFrame:
    """One row per shared claim id: both tables' estimate, interval and verdict, the Welch t of their difference.

    Parameters
    ----------
    first, second : DataFrame
        Claims tables (``read_table``), e.g. the same campaign run by two engines.
    labels : pair of str
        The two campaigns' names, used as column prefixes.

    Returns
    -------
    DataFrame
        ``claim_id``, ``<label>_estimate``, ``_low``, ``_high``, ``_n``, ``_verdict`` for each label,
        ``same_verdict``, ``difference`` (first - second), Welch's ``t``, its degrees of freedom ``df``,
        ``p`` (two-sided), ``estimates_differ`` (Holm at family-wise ``FAMILY_ALPHA`` over the rows with a t),
        in the first table's row order.
    """
    a, b = labels
    keep = ["claim_id", "estimate", "low", "high", "sd", "n", "verdict"]
    merged = first[keep].merge(second[keep], on="claim_id", suffixes=(f"_{a}", f"_{b}"), how="inner", sort=False)
    se2 = merged[f"sd_{a}"] ** 2 / merged[f"n_{a}"] + merged[f"sd_{b}"] ** 2 / merged[f"n_{b}"]
    ok = (merged[f"n_{a}"] >= 2) & (merged[f"n_{b}"] >= 2) & np.isfinite(se2) & (se2 > 0)
    merged["same_verdict"] = merged[f"verdict_{a}"] == merged[f"verdict_{b}"]
    merged["difference"] = merged[f"estimate_{a}"] - merged[f"estimate_{b}"]
    merged["t"], merged["df"], merged["p"] = math.nan, math.nan, math.nan
    differ = np.zeros(len(merged), dtype=bool)
    if ok.any():
        (ea, sa, na), (eb, sb, nb) = ([merged.loc[ok, f"{c}_{lab}"].to_numpy(float) for c in ("estimate", "sd", "n")]
                                      for lab in (a, b))
        welch = sps.ttest_ind_from_stats(ea, sa, na, eb, sb, nb, equal_var=False)
        va, vb = sa ** 2 / na, sb ** 2 / nb     # scipy's result does not carry its Welch-Satterthwaite df
        merged.loc[ok, "t"], merged.loc[ok, "p"] = welch.statistic, welch.pvalue
        merged.loc[ok, "df"] = (va + vb) ** 2 / (va ** 2 / (na - 1) + vb ** 2 / (nb - 1))
        differ[ok.to_numpy()] = holm(welch.pvalue, alpha=FAMILY_ALPHA)
    merged["estimates_differ"] = differ
    return merged.drop(columns=[f"sd_{a}", f"sd_{b}"])


def dependent_word(labels) -> str:
    """'engine-dependent' for two engines (yade, lammps), else '<a>/<b>-dependent'."""
    return "engine-dependent" if set(labels) == {"yade", "lammps"} else f"{labels[0]}/{labels[1]}-dependent"


def markdown(table: pd.DataFrame, labels=("yade", "lammps")) -> str:
    """The side-by-side table as Markdown: estimate [90 % interval] and verdict per campaign, Welch's t, the reading."""
    a, b = labels
    word = dependent_word(labels)

    def cell(r, lab):
        return (f"{r[f'estimate_{lab}']:.3g} [{r[f'low_{lab}']:.3g}, {r[f'high_{lab}']:.3g}] "
                f"(n {r[f'n_{lab}']:.0f}): **{r[f'verdict_{lab}']}**")

    lines = [f"| claim | {a} | {b} | Welch t of the difference (df) | reading |", "|---|---|---|---|---|"]
    for _, r in table.iterrows():
        t = ("-" if not np.isfinite(r["t"]) else f"{r['t']:+.2f} ({r['df']:.0f})"
             + (" (differ, Holm)" if r["estimates_differ"] else ""))
        if r["same_verdict"]:
            reading = "same verdict"
        elif not np.isfinite(r["t"]):
            reading = f"{word} verdict; too few seeds for a t"
        elif r["estimates_differ"]:
            reading = f"{word}: the estimates differ"
        else:
            reading = f"{word} verdict; the estimates agree within seed noise"
        lines.append(f"| {r['claim_id']} | {cell(r, a)} | {cell(r, b)} | {t} | {reading} |")
    n_dep = int((~table["same_verdict"]).sum())
    n_diff = int(table["estimates_differ"].sum())
    lines += ["", f"{len(table)} rows; {n_dep} with verdicts that differ ({word}); {n_diff} whose estimates differ at "
                  f"family-wise {FAMILY_ALPHA:.0%} (Welch's t, Holm over the {int(np.isfinite(table['t']).sum())} rows with a t)."]
    return "\n".join(lines) + "\n"


def parse_table_arg(text: str):
    """``LABEL=PATH`` -> (label, Path); ValueError for a bad label (a plain word: letters, digits, _ . -)."""
    label, sep, path = text.partition("=")
    if not (sep and path):
        raise ValueError(f"--table {text!r}: expected LABEL=paper_claims.csv, e.g. yade=results/claims/paper_claims.csv")
    if not LABEL.match(label):
        raise ValueError(f"--table {text!r}: the label must be a plain word (letters, digits, _ . -; at most 40)")
    return label, Path(path)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m claims across",
                                 description="Two claims tables side by side: verdicts, and whether the estimates differ.")
    ap.add_argument("--table", action="append", required=True, metavar="LABEL=CSV",
                    help="a claims table with its label; give it twice (the first is the reference)")
    ap.add_argument("--out", required=True, help="folder for claims_across.csv and claims_across.md")
    args = ap.parse_args(argv)
    try:
        if len(args.table) != 2:
            raise ValueError(f"--table given {len(args.table)} times: give it exactly twice")
        (la, pa), (lb, pb) = map(parse_table_arg, args.table)
        if la == lb:
            raise ValueError(f"--table: the two labels are both {la!r}")
        table = across(read_table(pa), read_table(pb), (la, lb))
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        table.to_csv(out / "claims_across.csv", index=False, float_format="%.6g")
        (out / "claims_across.md").write_text(markdown(table, (la, lb)))
    except (ValueError, OSError) as exc:
        print(f"claims across: error: {exc}", file=sys.stderr)
        return 2
    print(f"claims across: {len(table)} rows, {int((~table['same_verdict']).sum())} verdicts differ -> {out}")
    return 0
