"""Check that every output Snakemake planned exists, is non-empty and up to date.

Usage: python check_outputs.py SUMMARY_TSV [EXTRA_FILE ...]
SUMMARY_TSV is the output of `snakemake --summary`.
"""
import csv
import sys
from pathlib import Path


def main(summary: str, extra: list[str]) -> int:
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
    print(f"{len(rows)} planned outputs checked, {len(problems)} problems")
    for line in problems:
        print("  " + line)
    if not rows:
        print("no outputs listed: the summary is empty")
        return 1
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2:]))
