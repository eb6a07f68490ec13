"""Command line of the bulk-vs-walls study: ``python -m dem_study.bulk_cli estimate|analyse ...``.

``estimate`` prints the estimated cost of every cell of ``accuracy.bulk_vs_walls``
(``bulk_cells.estimate``); ``cost`` tables the measured cost of finished cases
(``bulk_cost``); ``analyse`` builds ``bulk_vs_walls.csv`` and its
figure from finished runs (dem_study/README.md, "Bulk against walls").
"""
from __future__ import annotations

import argparse
import json
import sys

import yaml

import pandas as pd

from campaign.schedule import makespan
from dem_contract import DEMInputError
from dem_contract.tables import read_table

from . import bulk, bulk_cells, bulk_cost, bulk_figures
from .analysis import StudyInputError, strain_edges
from .cli import read_yaml


def estimate(args) -> int:
    config = read_yaml(args.configfile[0], "config file (--configfile)")
    for extra in args.configfile[1:]:   # merged as Snakemake merges several --configfile
        config = _merge(config, read_yaml(extra, "config file (--configfile)"))
    if not isinstance(config, dict) or "bulk_vs_walls" not in (config.get("accuracy") or {}):
        raise StudyInputError(f"{' '.join(args.configfile)}: missing block 'accuracy.bulk_vs_walls'")
    try:
        problems = bulk_cells.problems(config)
        if problems:
            raise StudyInputError("\n".join(problems))
        est = bulk_cells.estimate(config)
    except KeyError as exc:
        raise StudyInputError(f"{' '.join(args.configfile)}: missing key {exc}") from None
    per_cell = est.groupby("cell", sort=False).agg(kind=("kind", "first"), H_over_d=("H_over_d", "first"),
                                                   W_over_d=("W_over_d", "first"), N=("N", "first"),
                                                   seeds=("seed", "size"), est_core_s=("est_core_s", "sum"))
    per_cell["core_h"] = per_cell["est_core_s"] / 3600
    print(per_cell.drop(columns="est_core_s").to_string(float_format=lambda x: f"{x:.3g}"))
    total = est["est_core_s"].sum()
    print(f"{len(est)} DEM cases: {total / 3600:.2f} core-hours; "
          f"about {makespan(est['est_core_s'], args.cores) / 3600:.2f} h on {args.cores} cores")
    return 0


def cost(args) -> int:
    try:  # a cut or ragged table is refused by line
        cases = read_table(args.cases, what="the cases table")
    except DEMInputError as exc:
        raise StudyInputError(str(exc)) from None
    table = bulk_cost.cost_table(cases, args.bulk_dir)
    table.to_csv(args.out, index=False, float_format="%.6g")
    print(table[["case", "N", "cpu_time_s", "wall_time_s"]].to_string())
    print(f"{len(table)} cases: {table['core_hours'].sum():.3f} core-hours")
    return 0


def analyse(args) -> int:
    try:  # a cut or ragged table is refused by line
        cases = read_table(args.cases, what="the cases table")
    except DEMInputError as exc:
        raise StudyInputError(str(exc)) from None
    need = {"case", "cell", "seed", "kind", "H_over_d", "W_over_d"} - set(cases.columns)
    if need:
        raise StudyInputError(f"{args.cases}: missing columns {', '.join(sorted(need))} "
                              "(the table of bulk_study_cases)")
    edges = strain_edges(args.heaviside_strain, args.transient_bin)
    table, cells, curves = bulk.analyse(cases, args.bulk_dir, args.steady_window, edges, args.early_strain,
                                        args.references, args.tall_reference, args.match_se)
    table.to_csv(args.out_table, index=False, float_format="%.6g")
    summary = bulk.verdict(table, args.references, args.tall_reference, args.match_se)
    if args.out_summary:
        with open(args.out_summary, "w") as fh:
            json.dump(summary, fh, indent=2)
            fh.write("\n")
    cells = cells.merge(table.drop_duplicates("cell")[["cell", *[c for c in table if c.startswith(
        ("info_ratio_", "core_hours_to_tall_se_"))]]], on="cell")
    bulk_figures.bulk_vs_walls(cells, curves, args.references, args.tall_reference, args.out_figure, args.match_se)
    with pd.option_context("display.width", 200, "display.max_columns", 30):
        print(table[["cell", "reference", "N", "core_hours_per_seed", "mu", "A_norm", "theta_A_deg", "match",
                     "failing"]].to_string())
        print(cells[["cell", "N", "early_se_A_norm", "early_se_theta_A_deg",
                     *[c for c in cells if c.startswith(("info_ratio_", "core_hours_to_tall_se_"))]]].to_string())
    matching = ", ".join(summary["matching_every_reference"]) or "none"
    print(f"matching every reference within {args.match_se:g} SE: {matching}; best: {summary['best']} "
          f"(information per core-hour {summary['best_info_ratio']} x the tall cell's)")
    return 0


def _merge(base, extra):
    if isinstance(base, dict) and isinstance(extra, dict):
        return {**base, **{k: _merge(base.get(k), v) if k in base else v for k, v in extra.items()}}
    return extra


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m dem_study.bulk_cli", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)
    e = sub.add_parser("estimate", help="estimated run time of the study's DEM cases, per cell")
    e.add_argument("--configfile", required=True, nargs="+",
                   help="config file(s), merged in order as Snakemake does")
    e.add_argument("--cores", type=int, default=2)
    e.set_defaults(func=estimate)
    c = sub.add_parser("cost", help="CPU and wall time of every case, from the sidecars")
    c.add_argument("--cases", required=True, help="the study's cases table (bulk_study_cases), CSV")
    c.add_argument("--bulk-dir", required=True, help="folder holding one folder per case")
    c.add_argument("--out", required=True, help="output CSV")
    c.set_defaults(func=cost)
    a = sub.add_parser("analyse", help="bulk_vs_walls.csv and its figure from the finished cases")
    a.add_argument("--cases", required=True, help="the study's cases table (bulk_study_cases), CSV")
    a.add_argument("--bulk-dir", required=True, help="folder holding one folder per case")
    a.add_argument("--out-table", required=True, help="output CSV (bulk_vs_walls.csv)")
    a.add_argument("--out-figure", required=True, help="output figure (bulk_vs_walls.png)")
    a.add_argument("--out-summary", help="output JSON: the cells matching every reference and the best of them")
    a.add_argument("--references", nargs="+", required=True, help="the reference cells (W = 4H wall cells)")
    a.add_argument("--tall-reference", help="the paper's cell: denominator of the information ratio")
    a.add_argument("--steady-window", type=float, default=1.0, help="pre-shear strain averaged for steady values")
    a.add_argument("--heaviside-strain", type=float, required=True, help="strain after the reversal")
    a.add_argument("--transient-bin", type=float, default=0.01, help="strain bin of the transient curves")
    a.add_argument("--early-strain", type=float, default=0.1, help="strain after the reversal of the information")
    a.add_argument("--match-se", type=float, default=2.0, help="combined standard errors of a match")
    a.set_defaults(func=analyse)
    args = p.parse_args(argv)
    try:
        return args.func(args)
    except (StudyInputError, ValueError, yaml.YAMLError) as err:
        print(f"dem_study.bulk_cli {args.command}: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
