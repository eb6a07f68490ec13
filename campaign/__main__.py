"""python -m campaign estimate|status --configfile FILE [FILE ...] [--cores N]: a campaign's DEM, priced or followed.

- ``estimate``: every DEM stage of every case with its disks, steps and projected one-thread
  seconds, the throughput it was priced at, and the totals (``campaign.price``): what the
  pre-flight check sums up in one line before any job.
- ``status``: a running or stopped campaign's cases done, running (each stage's progress and ETA)
  and waiting, core-hours spent and left, the ETA of its DEM, and where a stopped stage resumes
  (``campaign.status``). Read only.

Later files override earlier ones, as with ``snakemake --configfile a.yaml b.yaml``; the schema's
defaults are filled in as the Snakefile fills them. Exit 0, or 2 naming a config that cannot be read.
"""
from __future__ import annotations

import argparse
import sys

from dem_contract import DEMInputError
from dem_contract.release import merge_config

from .configfile import ConfigProblem, load_configfile
from .price import duration, plural, price, price_lines
from .schema_defaults import with_defaults
from .status import campaign_status, status_lines

DEFAULT_CORES = 2


def read_config(paths) -> dict:
    """The config files merged (later ones over earlier ones), with the schema's defaults."""
    config = {}
    for path in paths:
        config = merge_config(config, load_configfile(path))
    return with_defaults(config)


def estimate(config: dict, cores: int) -> list[str]:
    """The per-stage table, the throughput it used and the totals."""
    p = price(config, cores)
    table = p.table.assign(core_s=p.table["core_s"].round(1))
    lines = [table.to_string(index=False), f"throughput: {p.throughput.source}"]
    if p.throughput.measured:
        lines.append(f"  (the documented figure x {p.throughput.factor:.3g})")
    lines.append(f"total: {p.core_s / 3600:.3g} core-hours; about {duration(p.wall_s)} on {plural(cores, 'core')}; "
                 f"{duration(p.cluster_s)} on a cluster with one core per job")
    lines.append("against the quick preset: " + "; ".join(text for ratio, text in p.drivers if ratio > 1.0)
                 if any(ratio > 1.0 for ratio, _ in p.drivers) else "against the quick preset: no setting costlier")
    return lines + price_lines(p)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m campaign", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name, text in (("estimate", "every DEM stage's projected cost, and the totals, before the run"),
                       ("status", "a running or stopped campaign: done, running, waiting, core-hours, ETA")):
        c = sub.add_parser(name, help=text)
        c.add_argument("--configfile", nargs="+", required=True, help="the campaign's config file(s)")
        c.add_argument("--cores", type=int, default=DEFAULT_CORES,
                       help=f"cores the DEM jobs run on (snakemake -j; default {DEFAULT_CORES})")
    args = parser.parse_args(argv)
    if args.cores < 1:
        parser.error(f"--cores {args.cores}: must be at least 1")
    try:
        config = read_config(args.configfile)
        lines = (estimate(config, args.cores) if args.command == "estimate"
                 else status_lines(campaign_status(config, args.cores)))
    except (ConfigProblem, DEMInputError, OSError) as exc:
        print(exc, file=sys.stderr)
        return 2
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
