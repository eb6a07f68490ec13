r"""Command line of the claims stage.

::

    python -m claims --compare results/compare --dem results/dem/<case> ... [--protocols heaviside sinusoidal ...] \
        [--calibration results/calibration/all/params.yaml] [--sets all heaviside_only ...] \
        [--resamples 2000] [--seed 0] [--preset paper=config/config.yaml ...] [--pole-start] --out results/claims
        # -> paper_claims.csv, paper_claims.png, power.csv, reversal_design.csv, eq2_vs_paper.csv/.png,
        #    README_section.md
        # --pole-start: every set's pole_start_predictions.csv too (python -m compare.pole_start_predict): the rows of
        #   the paper's configuration of Model 1 (4-start-step, 4-start-sin)
    python -m claims plan --table results/claims/paper_claims.csv --dem results/dem/<case> ... \
        [--protocols heaviside sinusoidal ...] --out results/claims/plan.csv
        # -> seeds and core-hours that decide every undecided claim (claims.plan)
    python -m claims across --table yade=<paper_claims.csv> --table lammps=<paper_claims.csv> --out <folder>
        # -> claims_across.csv/.md: two campaigns' verdicts side by side, engine-dependent rows (claims.across)

Bad input (a missing table or column, a bad DEM file) exits with status 2 and
a message naming the file.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from dem_contract import REVERSAL_PROTOCOLS, DEMInputError

from . import across, design, eq2, inputs, plan, pole_start_claim, power, report, table


def build_parser():
    ap = argparse.ArgumentParser(prog="python -m claims", description="The paper's claims as a table with verdicts.")
    ap.add_argument("--compare", required=True, help="the comparison folder results/compare (one sub-folder per set)")
    ap.add_argument("--dem", nargs="+", required=True, help="DEM case directories results/dem/<label>")
    ap.add_argument("--protocols", nargs="+", default=list(REVERSAL_PROTOCOLS),
                    help="the protocols' runs to read from each case: heaviside, sinusoidal and reversal schedules "
                         "(every reversal of each, by its kind; default heaviside sinusoidal)")
    ap.add_argument("--calibration", default=None,
                    help="params.yaml whose Eq. 2 is checked against the collapse (default: <compare>/../calibration/all/params.yaml)")
    ap.add_argument("--freeform", default=None,
                    help="a calibration set's freeform.csv (python -m calibrate --freeform): adds claims 9 and 10")
    ap.add_argument("--sets", nargs="*", default=None, help="calibration sets to read (default: every one found)")
    ap.add_argument("--resamples", type=int, default=2000, help="bootstrap resamples (default 2000)")
    ap.add_argument("--seed", type=int, default=0, help="random seed of the bootstrap")
    ap.add_argument("--preset", nargs="*", default=[], metavar="NAME=CONFIG",
                    help="presets whose power the README section states, e.g. paper=config/config.yaml")
    ap.add_argument("--pole-start", action="store_true",
                    help="read every set's pole_start_predictions.csv too: rows 4-start-* (Model 1 with its pole "
                         "at each reversal's start, the paper's configuration)")
    ap.add_argument("--out", required=True, help="output folder, e.g. results/claims")
    return ap


def _preset(text):
    name, sep, path = text.partition("=")
    if not (sep and name and path):
        raise ValueError(f"--preset {text!r}: expected NAME=CONFIG.yaml, e.g. paper=config/config.yaml")
    return name, path


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["plan"]:
        return plan.main(argv[1:])
    if argv[:1] == ["across"]:
        return across.main(argv[1:])
    args = build_parser().parse_args(argv)
    t0 = time.perf_counter()
    try:
        if args.resamples < 100:
            raise ValueError(f"--resamples = {args.resamples}: must be at least 100")
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        pred = (pole_start_claim.read_variant(args.compare, args.sets) if args.pole_start
                else inputs.read_comparison(args.compare, args.sets))
        dem_cases = [inputs.read_dem_case(d, args.protocols) for d in args.dem]
        params = Path(args.calibration) if args.calibration else Path(args.compare).parent / "calibration" / "all" / "params.yaml"
        ff = inputs.read_freeform(args.freeform) if args.freeform else None
        eq2_all = table.eq2_params(params)
        tab = table.claims_table(pred, dem_cases, eq2_all, args.resamples, args.seed, ff)
        tab.to_csv(out / "paper_claims.csv", index=False, float_format="%.6g")
        report.forest_plot(tab, out / "paper_claims.png")
        runs = inputs.runs(pred)
        pw, cost = power.power_table(runs, args.dem, tab)
        power.with_unknown_costs(pw).to_csv(out / "power.csv", index=False, float_format="%.6g")
        dsg = design.design_table(runs, args.dem, args.protocols, dem_cases)
        dsg.to_csv(out / "reversal_design.csv", index=False, float_format="%.6g")
        presets = [power.preset_from_config(*_preset(p), cost) for p in args.preset]
        section = report.markdown_section(tab, source=f"`{out / 'paper_claims.csv'}`")
        section += "\n" + report.power_section(pw, presets, power.campaign_preset(pw), power.fabric_noise_check(args.dem))
        section += "\n" + report.design_section(dsg)
        curves = eq2.eq2_table(dem_cases, eq2_all)
        curves.to_csv(out / "eq2_vs_paper.csv", index=False, float_format="%.6g")
        eq2.figure(curves, out / "eq2_vs_paper.png")
        section += ("\n### Eq. 2 against the paper\n\n" + eq2.summary(curves, table.EQ2_MARGIN)
                    + " (`eq2_vs_paper.csv`, `eq2_vs_paper.png`, `claims/eq2.py`)\n")
        (out / "README_section.md").write_text(section)
    except (DEMInputError, ValueError) as exc:
        print(f"claims: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"claims: error: {exc.filename or args.out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    counts = tab["verdict"].value_counts().to_dict()
    print(f"claims: {len(tab)} claims -> {out} in {time.perf_counter() - t0:.1f} s: {counts}")
    return 0
