r"""Claim 4 for Model 1 as the paper configured it: the pole at each run's start ("model1_start").

The paper puts Eq. 6's pole at the start of the reversal (X_c = 0.0827, just
above the mirrored steady X). ``calibrate.pole_start`` fits that configuration
(X_c = max(X_rev, 0) + delta per run) and ``compare.pole_start`` predicts
every run with it. This table scores it on claim 4's statistic, the RMSE of
|A| over the first ``EARLY_A`` strain after the reversal, out of sample,
paired on each run and averaged per seed, exactly as the claims table does
for Model 1 against Model 2 (``claims.table.early_error_row``):

- ``4-start-m1``: the variant minus Model 1 (X_c fitted freely);
- ``4-start-m2``: the variant minus Model 2.

Negative is the variant better; the verdicts and the margin (5 % of the DEM's
fall of |A|) are the claims table's. The table is its own file,
``results/claims/pole_start.csv`` (columns of ``paper_claims.csv``), so the
claims table itself is unchanged.

Command line::

    python -m claims.pole_start --compare results/compare [--sets all heaviside_only] \
        --out results/claims/pole_start.csv [--resamples 2000]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from dem_contract import DEMInputError

from . import inputs, stats
from .table import COLUMNS, EARLY_A, Bootstrap, early_error_row

MODEL = "model1_start"
NAMES = {MODEL: "Model 1 (pole at start)", "model1": "Model 1", "model2": "Model 2"}


def read_variant(compare_dir, sets=None) -> pd.DataFrame:
    """Every set's ``predictions.csv`` with its ``pole_start_predictions.csv`` rows added, ``in_sample`` flagged.

    Sets without a ``pole_start_predictions.csv`` are left out.
    """
    compare_dir = Path(compare_dir)
    sets = [s for s in (sets or inputs.comparison_sets(compare_dir))
            if (compare_dir / s / "pole_start_predictions.csv").is_file()]
    if not sets:
        raise DEMInputError(f"{compare_dir}: no <set>/pole_start_predictions.csv (run python -m compare.pole_start)")
    base = inputs.read_comparison(compare_dir, sets)
    frames = [base]
    for name in sets:
        pred = inputs.read_csv(compare_dir / name / "pole_start_predictions.csv", inputs.PREDICTION_COLUMNS,
                                "the pole-at-start variant's curves")
        err = inputs.read_csv(compare_dir / name / "pole_start_errors.csv", inputs.ERROR_COLUMNS,
                               "the pole-at-start variant's errors")
        flags = (err[err["level"] == "seed"].drop_duplicates(["case", "protocol"])
                 .set_index(["case", "protocol"])["in_sample"].astype(bool))
        key = pd.MultiIndex.from_frame(pred[["case", "protocol"]])
        pred["in_sample"] = flags.reindex(key).fillna(True).to_numpy(bool)
        pred["set"] = name
        frames.append(pred)
    return pd.concat(frames, ignore_index=True)


def _paired(runs: dict, first: str, second: str) -> dict:
    """``runs`` with ``first`` as "model1" and ``second`` as "model2" (what ``early_error_row`` pairs)."""
    out = {}
    for key, cur in runs.items():
        pair = {"dem": cur["dem"]} if "dem" in cur else {}
        if first in cur:
            pair["model1"] = cur[first]
        if second in cur:
            pair["model2"] = cur[second]
        out[key] = pair
    return out


def _renamed(row: dict, first: str, second: str) -> dict:
    """``early_error_row``'s texts with the two models' names."""
    for col in ("statistic", "detail"):
        row[col] = (row[col].replace("Model 1", "\x01").replace("Model 2", "\x02")
                    .replace("\x01", NAMES[first]).replace("\x02", NAMES[second]))
    return row


def variant_rows(pred: pd.DataFrame, n_resamples=stats.N_RESAMPLES, seed=0) -> pd.DataFrame:
    """The two rows of the module docstring, in the columns of the claims table."""
    boot = Bootstrap(n_resamples, seed)
    runs = inputs.runs(pred)
    rows = []
    for cid, other in (("4-start-m1", "model1"), ("4-start-m2", "model2")):
        row = early_error_row(_paired(runs, MODEL, other), cid,
                              f"Model 1 with its pole at each run's start captures the fall of |A| just after the "
                              f"reversal better than {NAMES[other]}", "the paper, Sec. 3.3 (X_c = 0.0827) and Sec. 4",
                              "A_norm", "|A|", EARLY_A, boot)
        rows.append(_renamed(row, MODEL, other))
    return pd.DataFrame(rows, columns=COLUMNS)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m claims.pole_start", description=__doc__.split("\n\n")[0])
    ap.add_argument("--compare", required=True, help="the comparison folder, results/compare")
    ap.add_argument("--sets", nargs="*", default=None, help="calibration sets (default: every one with the variant)")
    ap.add_argument("--resamples", type=int, default=stats.N_RESAMPLES)
    ap.add_argument("--out", required=True, help="CSV to write")
    args = ap.parse_args(argv)
    try:
        table = variant_rows(read_variant(args.compare, args.sets), args.resamples)
    except (DEMInputError, ValueError) as exc:
        print(f"claims.pole_start: error: {exc}", file=sys.stderr)
        return 2
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.out, index=False)
    for _, r in table.iterrows():
        print(f"{r['claim_id']}: {r['estimate']:+.4g} [{r['low']:+.4g}, {r['high']:+.4g}] -> {r['verdict']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
