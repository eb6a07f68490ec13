"""python -m preflight check CONFIGFILE [CONFIGFILE ...] [--cores N]: the workflow's pre-flight check, alone.

Later files override earlier ones, as with ``snakemake --configfile a.yaml b.yaml``.
Exit 0 when the campaign may start, with its price on ``--cores`` (``preflight.price``) after
"ok"; 2 with one line per problem otherwise.
"""
import argparse
import sys

from snakemake.utils import update_config

from campaign.configfile import ConfigProblem, load_configfile
from campaign.schema_defaults import with_defaults

from .checks import check
from .price import DEFAULT_CORES, price_text


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m preflight", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    c = sub.add_parser("check", help="check config files as the Snakefile does before any job")
    c.add_argument("configfiles", nargs="+")
    c.add_argument("--cores", type=int, default=DEFAULT_CORES,
                   help=f"cores the campaign's DEM jobs run on, for its price (snakemake -j; default {DEFAULT_CORES})")
    args = parser.parse_args(argv)
    config = {}
    try:
        for path in args.configfiles:
            update_config(config, load_configfile(path))
    except ConfigProblem as exc:
        print(exc, file=sys.stderr)
        return 2
    problems = check(config, args.configfiles)
    if problems:
        print("\n".join(problems), file=sys.stderr)
        return 2
    print(f"{', '.join(args.configfiles)}: ok")
    print(price_text(with_defaults(config), max(args.cores, 1)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
