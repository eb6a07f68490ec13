r"""Claim 4 for Model 1 as the paper configured it: the pole at each run's start ("model1_start").

The paper puts Eq. 6's pole at the start of the reversal (X_c = 0.0827, just
above the mirrored steady X). ``calibrate.pole_start_fit`` fits that configuration
(X_c = max(X_rev, 0) + delta per run) and ``compare.pole_start_predict`` predicts
every run with it. The claims table scores it as the paper's Model 1 against
Model 2 (rows ``4-start-step`` and ``4-start-sin``, given the variant's
predictions: ``python -m claims --pole-start``). This table scores it on
claim 4's statistic against both models, per figure, exactly as the claims
table does (``claims.table.model_error_rows``: the difference of squared
model errors of |A| over the first ``EARLY_A`` strain after the reversal, out
of sample, paired on each run, averaged per seed):

- ``4-start-m1-step``, ``-sin``: the variant minus Model 1 (X_c fitted freely);
- ``4-start-m2-step``, ``-sin``: the variant minus Model 2 (the claims table's
  ``4-start-*`` rows).

Negative is the variant better; the verdicts, adequacy and margins are the
claims table's. The file is ``results/claims/pole_start.csv`` (columns of
``paper_claims.csv``).

Command line::

    python -m claims.pole_start_claim --compare results/compare [--sets all heaviside_only] \
        --out results/claims/pole_start.csv [--resamples 2000]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from dem_contract import DEMInputError

from . import inputs, stats
from .table import CLAIM4_START, COLUMNS, EARLY_A, MODEL_START, Bootstrap, early_scores, model_error_rows

MODEL = MODEL_START


def read_variant(compare_dir, sets=None) -> pd.DataFrame:
    """Every set's ``predictions.csv`` with its ``pole_start_predictions.csv`` rows added, ``in_sample`` flagged.

    Sets without a ``pole_start_predictions.csv`` are left out.
    """
    compare_dir = Path(compare_dir)
    sets = [s for s in (sets or inputs.comparison_sets(compare_dir))
            if (compare_dir / s / "pole_start_predictions.csv").is_file()]
    if not sets:
        raise DEMInputError(f"{compare_dir}: no <set>/pole_start_predictions.csv (run python -m compare.pole_start_predict)")
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


def variant_rows(pred: pd.DataFrame, n_resamples=stats.N_RESAMPLES, seed=0) -> pd.DataFrame:
    """The rows of the module docstring, in the columns of the claims table."""
    from .inputs import dem_curves
    boot = Bootstrap(n_resamples, seed)
    runs, dem = inputs.runs(pred), dem_curves(pred)
    rows = []
    for cid, other in (("4-start-m1", "model1"), ("4-start-m2", "model2")):
        rows += model_error_rows(*early_scores(runs, dem, "A_norm", EARLY_A, (MODEL, other)), cid,
                                 CLAIM4_START.replace("Model 2", {"model1": "Model 1 (X_c fitted)",
                                                                  "model2": "Model 2"}[other]),
                                 "the paper, Sec. 3.3 (X_c = 0.0827) and Sec. 4", "|A|", EARLY_A, boot,
                                 (MODEL, other), pooled=False)
    return pd.DataFrame(rows, columns=COLUMNS)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m claims.pole_start_claim", description=__doc__.split("\n\n")[0])
    ap.add_argument("--compare", required=True, help="the comparison folder, results/compare")
    ap.add_argument("--sets", nargs="*", default=None, help="calibration sets (default: every one with the variant)")
    ap.add_argument("--resamples", type=int, default=stats.N_RESAMPLES)
    ap.add_argument("--out", required=True, help="CSV to write")
    args = ap.parse_args(argv)
    try:
        table = variant_rows(read_variant(args.compare, args.sets), args.resamples)
    except (DEMInputError, ValueError) as exc:
        print(f"claims.pole_start_claim: error: {exc}", file=sys.stderr)
        return 2
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.out, index=False)
    for _, r in table.iterrows():
        print(f"{r['claim_id']}: {r['estimate']:+.4g} [{r['low']:+.4g}, {r['high']:+.4g}] -> {r['verdict']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
