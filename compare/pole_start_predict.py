r"""Model 1 with its pole at each run's start ("model1_start") against the DEM, beside Models 1 and 2.

The variant (``model.pole_start``; fitted by ``calibrate.pole_start_fit``) is
Model 1 with, for each run, :math:`X_c = \max(X_{rev}, 0) + \delta`:
:math:`X_{rev}` is the model's mirrored X at the run's reversal, from the same
start fabric ``A0`` and imposed history as Models 1 and 2 (``compare.dem``,
``compare.predict``, called as they are):

- a run whose history starts reversed (a step): the mirrored X of ``A0``;
- a run that first keeps shearing forward (a half cosine): Model 1 integrated
  over that forward strain, up to the zero of the rate (X < 0 there, so the
  pole plays no part), then mirrored.

The prediction itself is ``compare.predict.predict`` with that X_c, so the
variant is scored exactly as the others. Outputs are separate files beside the
comparison's (``pole_start_predictions.csv``, ``pole_start_errors.csv``: the
variant's rows in the layout of ``predictions.csv`` and ``errors.csv``, source
``model1_start``), so the tables of Models 1 and 2 are unchanged.

Command line::

    python -m compare.pole_start_predict --dem results/dem/<case> ... --fit results/calibration/<set>/pole_start.yaml \
        --set <set> --protocols heaviside sinusoidal [--train-cases ...] [--train-protocols ...] \
        --out results/compare/<set>
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from model import simulate
from model.pole_start import far_pole, forward_history, load, mirrored_x, with_pole

from .comparison import CURVE_COLUMNS, seed_rows, tags_last, model_steady, transient_groups
from .dem import canonical
from .predict import Prediction, imposed_history, predict

MODEL = "model1_start"


def forward_strain(history) -> tuple:
    """(strain sheared before the rate first changes sign, the sign it starts with) of a tabulated history.

    The rate is piecewise linear between the history's breakpoints, so its zero is
    interpolated linearly inside the segment where it changes sign; 0 when the rate
    never changes sign (the run starts reversed).
    """
    bp = history.breakpoints
    r = np.concatenate([[history.segments[0].gammadot(np.array([bp[0]]))[0]], history.gammadot(bp[1:])])
    sign0 = float(np.sign(r[0]))
    change = np.nonzero(np.sign(r[1:]) != sign0)[0]
    if sign0 == 0.0 or not change.size:
        return 0.0, sign0
    i = int(change[0])
    t_zero = bp[i] + (bp[i + 1] - bp[i]) * r[i] / (r[i] - r[i + 1])
    return float(abs(history.strain(t_zero)[0])), sign0


def reversal_x(rev, params) -> float:
    """The model's mirrored X at ``rev``'s reversal (module docstring), from ``rev.A0`` on its imposed history."""
    history, _, _ = imposed_history(rev)
    s_before, sign0 = forward_strain(history)
    if s_before <= 0.0:
        return mirrored_x(rev.A0[1], sign0)
    sim = simulate(far_pole(params), forward_history(s_before, sign0), model="model1", A0=rev.A0, friction="eq2",
                   t_eval=np.array([s_before]))
    return mirrored_x(float(sim["A_xy"].iloc[-1]), -sign0)


def predict_start(rev, params, delta: float):
    """``compare.predict.predict`` of Model 1 with X_c = max(X_rev, 0) + delta on ``rev``; model named ``MODEL``."""
    try:
        x_rev = reversal_x(rev, params)
    except (ValueError, FloatingPointError) as exc:
        status = f"{type(exc).__name__}: the forward part before the reversal: {exc}".replace("\n", " ")
        return Prediction(rev.label, rev.protocol, MODEL, "eq2", None, status, 0, float("nan"))
    return replace(predict(rev, with_pole(params, x_rev, delta), "model1"), model=MODEL)


def run(case_dirs, fit_path, protocols, set_name="all", train_cases=None, train_protocols=None):
    """The variant on every case and protocol: (predictions, errors) in the layout of ``compare.comparison.run``.

    Only the variant's rows: ``source`` / ``model`` = ``model1_start``, seed level.
    """
    params, delta = load(fit_path)
    labels = [str(getattr(d, "name", d)).rstrip("/").split("/")[-1] for d in case_dirs]
    train_cases = set(labels if train_cases is None else train_cases)
    train_protocols = set(protocols if train_protocols is None else train_protocols)
    pred_rows, err_rows, steady = [], [], {}
    for protocol, key, revs in transient_groups(case_dirs, protocols):
        preds = [predict_start(r, params, delta) for r in revs]
        sign = -1 if np.median(revs[0].data["gammadot"].to_numpy()[-5:]) < 0 else 1
        steady.setdefault(sign, model_steady(params, "model1", "eq2", sign))
        preds = [replace(p, table=canonical(r, p.table)) for r, p in zip(revs, preds)]
        revs = [replace(r, data=canonical(r)) for r in revs]
        tags = dict(kind=revs[0].kind, reversal=revs[0].reversal, direction=revs[0].direction)
        for r, p in zip(revs, preds):
            base = dict(set=set_name, level="seed", case=r.label, group=r.group, protocol=key,
                        in_sample=r.label in train_cases and protocol in train_protocols)
            curves, errors, _ = seed_rows(r, {MODEL: p}, base, {MODEL: steady[sign]}, 1)
            pred_rows += [c.assign(**tags) for c in curves if c["source"].iloc[0] == MODEL]
            err_rows += [dict(e, **tags) for e in errors]
    preds = (pd.concat(pred_rows, ignore_index=True) if pred_rows   # every run failed: the header alone
             else pd.DataFrame(columns=["set", "case", "group", "seed", "protocol", "source", *CURVE_COLUMNS,
                                        "kind", "reversal", "direction"]))
    return preds, tags_last(pd.DataFrame(err_rows))


def main(argv=None) -> int:
    from .cli import protocol_name
    from .dem import DEMInputError

    ap = argparse.ArgumentParser(prog="python -m compare.pole_start_predict", description=__doc__.split("\n\n")[0])
    ap.add_argument("--dem", nargs="+", required=True, help="DEM case directories results/dem/<label>")
    ap.add_argument("--fit", required=True, help="pole_start.yaml of the calibration set (calibrate.pole_start_fit)")
    ap.add_argument("--set", default="all")
    ap.add_argument("--protocols", nargs="+", default=["heaviside", "sinusoidal"], type=protocol_name)
    ap.add_argument("--train-cases", nargs="*", default=None)
    ap.add_argument("--train-protocols", nargs="*", default=None)
    ap.add_argument("--out", required=True, help="output directory (the set's comparison folder)")
    args = ap.parse_args(argv)
    try:
        preds, errors = run(args.dem, args.fit, args.protocols, args.set, args.train_cases, args.train_protocols)
    except (DEMInputError, ValueError) as exc:
        print(f"compare.pole_start_predict: error: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    preds.to_csv(out / "pole_start_predictions.csv", index=False)
    errors.to_csv(out / "pole_start_errors.csv", index=False)
    bad = errors[errors["status"] != "ok"]
    for _, r in bad.iterrows():
        print(f"warning: {MODEL} on {r['case']} ({r['protocol']}): {r['status']}", file=sys.stderr)
    print(f"compare.pole_start_predict: set {args.set}, {len(args.dem)} case(s) -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
