"""Command line of the bulk-vs-walls study: ``python -m dem_study.bulk_cli estimate|analyse ...``.

``estimate`` prints the estimated cost of every cell of ``accuracy.bulk_vs_walls``
(``bulk_cells.estimate``); ``cost`` tables the measured cost of finished cases
(``bulk_cost``); ``analyse`` builds ``bulk_vs_walls.csv`` and its
figure from finished runs (dem_study/README.md, "Bulk against walls").
"""
from __future__ import annotations

import argparse
import sys

import yaml

import pandas as pd

from . import bulk_cells, bulk_cost, grid
from .analysis import StudyInputError
from .cli import _read_yaml


def estimate(args) -> int:
    config = _read_yaml(args.configfile[0], "config file (--configfile)")
    for extra in args.configfile[1:]:   # merged as Snakemake merges several --configfile
        config = _merge(config, _read_yaml(extra, "config file (--configfile)"))
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
          f"about {grid.makespan(est['est_core_s'], args.cores) / 3600:.2f} h on {args.cores} cores")
    return 0


def cost(args) -> int:
    cases = pd.read_csv(args.cases)
    table = bulk_cost.cost_table(cases, args.bulk_dir)
    table.to_csv(args.out, index=False, float_format="%.6g")
    print(table[["case", "N", "cpu_time_s", "wall_time_s"]].to_string())
    print(f"{len(table)} cases: {table['core_hours'].sum():.3f} core-hours")
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
    args = p.parse_args(argv)
    try:
        return args.func(args)
    except (StudyInputError, ValueError, yaml.YAMLError) as err:
        print(f"dem_study.bulk_cli {args.command}: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
