r"""A release's published tables against a recomputation from the release (docs/data-release.md).

A release keeps, in ``published/``, tables its campaign's run wrote (the claims,
the calibration's parameter table, ...). Recomputed from the release alone
(no YADE), the code gives the same verdicts and nearly the same numbers: a
change of its float path, and the free-form fit's scatter from run to run
(below), move them in the last digits. ``compare`` holds a recomputation to
the published tables:

- rows are matched by their key columns (``TABLE_KEYS``); every published row
  and column must be in the recomputation (a missing one is named), while rows
  and columns the recomputation adds are not compared;
- text must be equal, the numbers inside it excepted (``verdict`` and every
  word must match exactly);
- a cell that is an integer (a count: seeds, runs, rows) must be equal;
- any other number :math:`a` (published) and :math:`b` (recomputed), as printed
  (a number inside text too: the claims print rounded values there),
  must satisfy

  .. math:: |a - b| \le r \max(|a|, |b|) + \tfrac12 (u_a + u_b)

  with :math:`r` = ``RTOL`` and :math:`u` the unit of a number's last printed
  digit (the tables print 6 or 8 significant digits, the claims' text 3): the
  exact values lie within :math:`r` of each other, whatever the rounding.

``RTOL`` = 1e-2. The route-2 fits stop on scipy's tolerances (ODE rtol 1e-6,
least squares' ``ftol``), but the free-form fit behind claims 9 and 10 stops on
its budget of model evaluations, not on a tolerance, and its end point is not
even reproducible: the same code on the same machine, from the same release,
gave claim 10's estimate -29.3209 and -29.3295 in two runs (2.9e-4 apart) and
its alpha2 bend 148.79 and 149.09 (2.0e-3), while the calibration's parameters
moved by 1e-7 (data/bulk-decide, commit fb93132; published: -29.3067). ``RTOL``
is five times the largest of these, so the check does not fail on that
scatter; the verdicts and counts are compared exactly, and a change beyond 1 %
is a change of results: regenerate ``published/`` (``republish``) in the commit
that makes it, saying why.
"""
from __future__ import annotations

import datetime
import io
import math
import re
import shutil
from pathlib import Path

import pandas as pd
import yaml

from .release import MANIFEST, PUBLISHED_DIR, carry_over, checksum_problems, git_output, read_manifest, sha256
from .series import DEMInputError

#: Relative tolerance for numbers that are not integers (module docstring).
RTOL = 1e-2
#: Key columns of each table a release publishes; another table is keyed by its first column.
TABLE_KEYS = {
    "paper_claims.csv": ("claim_id",),
    "plan.csv": ("claim_id",),
    "power.csv": ("claim_id", "quantity", "window", "effect_choice"),
    "reversal_design.csv": ("protocol",),
    "params_table.csv": ("block", "parameter", "route"),
}
#: A number as the tables print it (an integer, a decimal, an exponent; inf and nan).
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?|inf|nan)")


def last_digit_unit(text: str) -> float:
    """The unit of a printed number's last digit: ``"29.3067"`` -> 1e-4, ``"198"`` -> 1, ``"2.87e+06"`` -> 1e4."""
    mantissa, _, exponent = text.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def numbers_agree(a: str, b: str, rtol: float = RTOL) -> bool:
    """Two printed numbers agree within ``rtol`` beyond the rounding of their last printed digits."""
    x, y = float(a), float(b)
    if math.isnan(x) or math.isnan(y) or math.isinf(x) or math.isinf(y):
        return (math.isnan(x) and math.isnan(y)) or x == y
    return abs(x - y) <= rtol * max(abs(x), abs(y)) + 0.5 * (last_digit_unit(a) + last_digit_unit(b))


def is_integer(text: str) -> bool:
    """A cell holding an integer alone (a count)."""
    return re.fullmatch(r"[-+]?\d+", text.strip()) is not None


def cells_agree(a: str, b: str, rtol: float = RTOL) -> bool:
    """Two table cells agree: counts equal, numbers within ``rtol``, the text between numbers equal."""
    if is_integer(a) and is_integer(b):
        return int(a) == int(b)
    if NUMBER.fullmatch(a.strip()) and NUMBER.fullmatch(b.strip()):
        return numbers_agree(a.strip(), b.strip(), rtol)
    words_a, words_b = NUMBER.split(a), NUMBER.split(b)
    nums_a, nums_b = NUMBER.findall(a), NUMBER.findall(b)
    return words_a == words_b and len(nums_a) == len(nums_b) and all(
        numbers_agree(x, y, rtol) for x, y in zip(nums_a, nums_b))


def read_text_table(path) -> pd.DataFrame:
    """A CSV table with every cell as its text (empty cells as ``""``), so numbers keep their printed digits."""
    path = Path(path)
    try:
        return pd.read_csv(io.StringIO(path.read_text()), dtype=str, keep_default_na=False)
    except (OSError, UnicodeDecodeError, pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise DEMInputError(f"{path}: not a readable CSV table ({exc})") from None


def compare_table(published, recomputed, keys=None, rtol: float = RTOL) -> list:
    """Every difference of a recomputed table from the published one (empty: they agree).

    Parameters
    ----------
    published, recomputed : str or Path
        The two CSV files.
    keys : sequence of str, optional
        The columns that identify a row (default ``TABLE_KEYS`` by the file's
        name, else its first column).
    rtol : float

    Returns
    -------
    list of str
        One line per problem: the recomputed file missing, a published column
        or row missing from it, a key that is not unique, or a cell that
        differs (named by row key and column, with both values).
    """
    published, recomputed = Path(published), Path(recomputed)
    if not recomputed.is_file():
        return [f"{recomputed}: missing (published: {published})"]
    pub, rec = read_text_table(published), read_text_table(recomputed)
    keys = list(keys or TABLE_KEYS.get(published.name, pub.columns[:1]))
    missing = [c for c in pub.columns if c not in rec.columns]
    if missing:
        return [f"{recomputed}: column(s) {missing} of {published} missing"]
    for name, table in ((published, pub), (recomputed, rec)):
        if table.duplicated(keys).any():
            return [f"{name}: rows not unique by {keys}"]
    rec = rec.set_index(keys)
    problems = []
    for _, row in pub.iterrows():
        key = tuple(row[k] for k in keys) if len(keys) > 1 else row[keys[0]]
        label = ", ".join(f"{k}={row[k]}" for k in keys)
        if key not in rec.index:
            problems.append(f"{recomputed}: published row {label} missing")
            continue
        other = rec.loc[key]
        for col in pub.columns:
            if col not in keys and not cells_agree(row[col], other[col], rtol):
                problems.append(f"{recomputed}: row {label}, column {col}: {other[col]!r}, published "
                                f"{row[col]!r}")
    return problems


def published_tables(release, results) -> dict:
    """Published table (Path in ``release/published/``) -> the same table under the results folder ``results``.

    The manifest's ``published`` names where each table was under the campaign's
    ``results_dir``; the recomputation writes it at the same place under ``results``.
    """
    manifest = read_manifest(release)
    base = Path(str(manifest["config"].get("results_dir", "results")))
    out = {}
    for name, source in (manifest.get("published") or {}).items():
        try:
            inside = Path(source).relative_to(base)
        except ValueError:
            raise DEMInputError(f"{Path(release) / 'manifest.yaml'}: published {name} came from {source}, not "
                                f"from the campaign's results_dir {base}") from None
        out[Path(release) / PUBLISHED_DIR / name] = Path(results) / inside
    return out


def compare(release, results, rtol: float = RTOL) -> list:
    """Every difference between a release's published tables and a recomputation in ``results``."""
    problems = []
    for published, recomputed in published_tables(release, results).items():
        problems += compare_table(published, recomputed, rtol=rtol)
    return problems


def republish(release, results, command: str, reason: str) -> list:
    """Replace a release's published tables by a recomputation's, and their entries in the manifest.

    The tables are not the release's data: when the code that makes them
    changes (legitimately: a new claim, a float path), they are regenerated
    from the release, and the manifest records when, from which commit, by
    which command and why (``republished``), and their new sha256 and size.
    The rest of the release is checked first and left as it is: the manifest's
    other blocks are carried over verbatim, comments included
    (``release.carry_over``).

    Returns
    -------
    list of Path
        The tables written: those that differ from their recomputation (``compare_table``); the
        others keep their bytes, and with none differing nothing is written.

    Raises
    ------
    DEMInputError
        The release does not match its manifest, or a recomputed table is missing.
    """
    release = Path(release)
    problems = checksum_problems(release)
    if problems:
        raise DEMInputError(f"{release}: differs from its manifest, not republished:\n  " + "\n  ".join(problems))
    tables = published_tables(release, results)
    for recomputed in tables.values():
        if not recomputed.is_file():
            raise DEMInputError(f"{recomputed}: missing (a table the release publishes)")
    # a table that agrees with its recomputation (numbers to RTOL) keeps its bytes: only what changed is replaced
    tables = {pub: rec for pub, rec in tables.items() if compare_table(pub, rec)}
    if not tables:
        return []
    old_text = (release / MANIFEST).read_text()
    manifest = read_manifest(release)
    for published, recomputed in tables.items():
        shutil.copyfile(recomputed, published)
        manifest["files"][str(published.relative_to(release))] = {"sha256": sha256(published),
                                                                   "bytes": published.stat().st_size}
    manifest["total_bytes"] = sum(f["bytes"] for f in manifest["files"].values())
    commit = git_output("rev-parse", "HEAD", cwd=Path(__file__).resolve().parents[1])
    manifest.setdefault("republished", []).append({
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "code_commit": commit, "command": command, "reason": reason, "tables": sorted(p.name for p in tables)})
    # only these blocks are written anew; every other one is carried over as it was written, comments included
    rewritten = ("files", "total_bytes", "republished")
    (release / MANIFEST).write_text(carry_over({k: v for k, v in manifest.items() if k in rewritten}, old_text,
                                               [k for k in manifest if k not in rewritten]))
    return list(tables)


__all__ = ["RTOL", "TABLE_KEYS", "last_digit_unit", "numbers_agree", "is_integer", "cells_agree", "compare_table",
           "published_tables", "compare", "republish"]
