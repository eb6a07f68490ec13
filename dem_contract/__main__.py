"""Command line of the DEM contract: ``import`` external runs; ``release``, ``verify``, ``restore`` a data release.

``import`` writes external DEM runs (minimal CSVs and a metadata YAML,
docs/own-dem-data.md) into the contract's layout (docs/data-contract.md) and
reads them back through the contract's reader. ``release`` writes a finished
campaign's DEM cases as a data release (docs/data-release.md), ``verify``
checks a release's checksums and reads every case back, ``restore`` writes one
released case into a results folder as a finished case (after the checksums).
``published`` compares a recomputation from a release with the tables the
release published, ``republish`` replaces those tables by a recomputation's.
Bad input exits with status 2 and a message naming the file (and key or row);
a release that fails ``verify``, or a recomputation that differs from the
published tables, exits with status 1.
"""
from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from . import published, release
from .importer import import_cases, summary
from .series import DEMInputError


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m dem_contract", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    imp = sub.add_parser("import", help="minimal CSVs + metadata YAML -> <out>/<label>/ in the contract's layout")
    imp.add_argument("--meta", required=True, help="the metadata YAML (docs/own-dem-data.md); run files are "
                                                   "relative to its folder")
    imp.add_argument("--out", required=True, help="the DEM folder to write, e.g. results/dem")
    rel = sub.add_parser("release", help="finished DEM cases -> a data release folder data/<name>/")
    rel.add_argument("--cases", nargs="+", required=True,
                     help="finished case folders: <results>/dem/<case> or <results>/accuracy/bulk/<cell>_s<seed>")
    rel.add_argument("--config", required=True, nargs="+",
                     help="the campaign's config file(s) as run, in the order of --configfile")
    rel.add_argument("--out", required=True, help="the release folder to write, e.g. data/<campaign>")
    rel.add_argument("--states", action="store_true",
                     help="also release each case's pre-shear state (preshear.final.yade.gz; LAMMPS: .final.lammps)")
    rel.add_argument("--published", nargs="+", default=[], metavar="TABLE",
                     help="tables the campaign's run wrote from these cases (e.g. <results>/claims/paper_claims.csv), "
                          "kept in published/ to compare a recomputation with")
    rel.add_argument("--compression", choices=sorted(release.COMPRESSIONS), default="gz",
                     help="the series' compression: gz (.csv.gz, the default) or xz (.csv.xz, lzma preset 9e: "
                          "about 15 %% fewer bytes); both lossless, equal data give equal bytes")
    rel.add_argument("--run-commit", metavar="SHA",
                     help="the commit whose code ran the DEM, when releasing from a later one (an ancestor of HEAD): "
                          "dem_code_commit is then the last change of the DEM's code at or before it")
    rel.add_argument("--carry-from", metavar="MANIFEST",
                     help="remaking a release: a copy of its old manifest.yaml; the blocks this command does not "
                          "write (seeds, republished, ...) and the published tables' provenance are carried over, "
                          "and a 'remade' entry compares every kept file's sha256 with it")
    rel.add_argument("--reason", help="with --carry-from: why the release is remade (kept in the manifest)")
    ver = sub.add_parser("verify", help="check releases' checksums and read every released case back")
    ver.add_argument("releases", nargs="+", help="release folders, e.g. data/*/")
    res = sub.add_parser("restore", help="one released case -> <out> as a finished DEM case")
    res.add_argument("--release", required=True, help="the release folder")
    res.add_argument("--case", required=True, help="the case's label")
    res.add_argument("--out", required=True, help="the case folder to write, e.g. results/dem/<case>")
    pub = sub.add_parser("published", help="a recomputation from a release against the tables it published")
    pub.add_argument("--release", required=True, help="the release folder, e.g. data/bulk-decide")
    pub.add_argument("--results", required=True, help="the results folder of the recomputation")
    rep = sub.add_parser("republish", help="replace a release's published tables by a recomputation's")
    rep.add_argument("--release", required=True, help="the release folder, e.g. data/bulk-decide")
    rep.add_argument("--results", required=True, help="the results folder of the recomputation")
    rep.add_argument("--reason", required=True, help="why the tables changed (kept in the manifest)")
    return ap


def run(args) -> int:
    """One sub-command; returns the exit status."""
    if args.command == "import":
        cases = import_cases(args.meta, args.out)
        print(f"dem_contract import: {len(cases)} case(s) written and read back")
        print(summary(cases))
    elif args.command == "release":
        command = "python -m dem_contract release " + shlex.join(
            sys.argv[2:] if sys.argv[1:2] == ["release"] else
            ["--cases", *args.cases, "--config", *args.config, "--out", args.out]
            + (["--states"] if args.states else [])
            + (["--published", *args.published] if args.published else [])
            + (["--compression", args.compression] if args.compression != "gz" else [])
            + (["--run-commit", args.run_commit] if args.run_commit else [])
            + (["--carry-from", args.carry_from] if args.carry_from else [])
            + (["--reason", args.reason] if args.reason else []))
        out = release.make_release(args.cases, args.out, args.config, command, args.states,
                                   published=args.published, compression=args.compression,
                                   run_commit=args.run_commit, carry_from=args.carry_from, reason=args.reason)
        manifest = release.read_manifest(out)
        print(f"dem_contract release: {len(manifest['cases'])} case(s) in {out}, "
              f"{manifest['total_bytes'] / 1e6:.3f} MB; all releases beside it: "
              f"{release.release_bytes(Path(out).parent) / 1e6:.3f} MB (budget 20 MB in the repository)")
        if args.carry_from:
            files = manifest["remade"][-1]["files"]
            print(f"dem_contract release: against {args.carry_from}: {files['kept_with_equal_sha256']} file(s) kept "
                  f"with equal sha256, {len(files['changed'])} changed, {len(files['dropped'])} dropped, "
                  f"{len(files['added'])} added; {files['bytes_before'] / 1e6:.3f} MB -> "
                  f"{files['bytes_after'] / 1e6:.3f} MB")
            for what in ("changed", "dropped", "added"):
                for name in files[what]:
                    print(f"  {what}: {name}")
            return 1 if files["changed"] else 0
    elif args.command == "verify":
        bad = 0
        for folder in args.releases:
            problems = release.verify(folder)
            bad += len(problems)
            print(f"dem_contract verify: {folder}: " + ("ok" if not problems else f"{len(problems)} problem(s)"))
            for problem in problems:
                print(f"  {problem}")
        return 1 if bad else 0
    elif args.command == "published":
        problems = published.compare(args.release, args.results)
        print(f"dem_contract published: {args.results} against {args.release}/published: "
              + ("agree" if not problems else f"{len(problems)} difference(s)")
              + f" (verdicts and counts exactly, numbers to a relative {published.RTOL:g})")
        for problem in problems:
            print(f"  {problem}")
        return 1 if problems else 0
    elif args.command == "republish":
        command = "python -m dem_contract " + shlex.join(sys.argv[1:]) if sys.argv[1:2] == ["republish"] else \
            f"python -m dem_contract republish --release {args.release} --results {args.results}"
        tables = published.republish(args.release, args.results, command, args.reason)
        print(f"dem_contract republish: {', '.join(p.name for p in tables)} in {args.release}/published, "
              f"from {args.results}" if tables else
              f"dem_contract republish: every table of {args.release}/published agrees with {args.results}: "
              "nothing written")
    else:
        out = release.restore_case(args.release, args.case, args.out)
        print(f"dem_contract restore: {args.case} from {args.release} -> {out}")
    return 0


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return run(args)
    except DEMInputError as exc:
        print(f"dem_contract {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"dem_contract {args.command}: error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
