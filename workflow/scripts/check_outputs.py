"""Check that every output Snakemake planned exists, is non-empty and up to date,
and (with --results) that no rule wrote a file it did not declare.

Usage: python check_outputs.py SUMMARY_TSV [EXTRA_FILE ...] [--results RESULTS_DIR]
SUMMARY_TSV is the output of `snakemake --summary`; EXTRA_FILEs are expected too
(e.g. the report). Under RESULTS_DIR every file must be a planned output, an
EXTRA_FILE, the summary, or a log or benchmark (logs/, benchmarks/).
"""
import argparse
import csv
import sys
from pathlib import Path

NOT_OUTPUTS = ("logs", "benchmarks")  # declared per rule as log: and benchmark:, not listed by --summary


def undeclared(results: Path, declared: set[Path]) -> list[Path]:
    """Files under ``results`` that no rule declares."""
    return sorted(p for p in results.rglob("*")
                  if p.is_file() and p.resolve() not in declared
                  and p.relative_to(results).parts[0] not in NOT_OUTPUTS)


def main(summary: str, extra: list[str], results: str | None = None) -> int:
    with open(summary) as fh:
        rows = list(csv.DictReader(fh, delimiter="\t"))
    problems = []
    for row in rows:
        path = Path(row["output_file"])
        if not path.is_file():
            problems.append(f"missing: {path}")
        elif path.stat().st_size == 0:
            problems.append(f"empty: {path}")
        elif row.get("status", "ok") != "ok":
            problems.append(f"{row['status']}: {path}")
    for name in extra:
        if not Path(name).is_file() or Path(name).stat().st_size == 0:
            problems.append(f"missing or empty: {name}")
    if results is not None:
        declared = {Path(p).resolve() for p in [summary, *extra, *(row["output_file"] for row in rows)]}
        problems += [f"written but not declared by any rule: {p}" for p in undeclared(Path(results), declared)]
    print(f"{len(rows)} planned outputs checked, {len(problems)} problems")
    for line in problems:
        print("  " + line)
    if not rows:
        print("no outputs listed: the summary is empty")
        return 1
    return 1 if problems else 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("summary")
    parser.add_argument("extra", nargs="*")
    parser.add_argument("--results", help="results folder: every file in it must be declared")
    args = parser.parse_args()
    sys.exit(main(args.summary, args.extra, args.results))
