"""Command line of the DEM contract: ``python -m dem_contract import --meta case.yaml --out results/dem``.

``import`` writes external DEM runs (minimal CSVs and a metadata YAML,
docs/own-dem-data.md) into the contract's layout (docs/data-contract.md) and
reads them back through the contract's reader. Bad input exits with status 2
and a message naming the file (and key or row).
"""
from __future__ import annotations

import argparse
import sys

from .importer import import_cases, summary
from .series import DEMInputError


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m dem_contract", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    imp = sub.add_parser("import", help="minimal CSVs + metadata YAML -> <out>/<label>/ in the contract's layout")
    imp.add_argument("--meta", required=True, help="the metadata YAML (docs/own-dem-data.md); run files are "
                                                   "relative to its folder")
    imp.add_argument("--out", required=True, help="the DEM folder to write, e.g. results/dem")
    return ap


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        cases = import_cases(args.meta, args.out)
    except DEMInputError as exc:
        print(f"dem_contract import: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"dem_contract import: error: {exc.filename or args.out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    print(f"dem_contract import: {len(cases)} case(s) written and read back")
    print(summary(cases))
    return 0


if __name__ == "__main__":
    sys.exit(main())
