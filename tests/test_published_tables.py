"""A recomputation from a release against the tables it published (dem_contract.published, docs/data-release.md).

On copies of data/bulk-decide's own published tables: the rows and columns of
published/ are compared (a missing row is named), verdicts and counts exactly,
numbers to ``RTOL`` beyond their printed rounding; ``republish`` replaces the
tables and their manifest entries so that the release still verifies.
"""
import shutil
from pathlib import Path

import pandas as pd
import pytest
import yaml

from dem_contract import published, release
from tests.helpers import run_main

ROOT = Path(__file__).resolve().parents[1]
DECIDE = ROOT / "data" / "bulk-decide"
CLAIMS = DECIDE / "published" / "paper_claims.csv"

pytestmark = pytest.mark.skipif(not DECIDE.is_dir(), reason="the deciding campaign's release is not in data/")


def recomputed(tmp_path, edit=None) -> Path:
    """A results folder holding every published table where the recomputation writes it, ``edit`` applied
    to the claims table (a function of its text frame that changes it in place or returns a new one)."""
    results = tmp_path / "results"
    for table, where in published.published_tables(DECIDE, results).items():
        where.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(table, where)
    if edit:
        path = results / "claims" / "paper_claims.csv"
        claims = pd.read_csv(path, dtype=str, keep_default_na=False)
        changed = edit(claims)
        claims = claims if changed is None else changed
        claims.to_csv(path, index=False)
    return results


def scale(claim, column, factor):
    def edit(claims):
        row = claims["claim_id"] == claim
        claims.loc[row, column] = f"{float(claims.loc[row, column].iloc[0]) * factor:.6g}"
    return edit


def test_a_missing_recomputed_table_is_named_and_a_table_agrees_with_itself(tmp_path):
    problems = published.compare(DECIDE, tmp_path / "nothing")
    assert len(problems) == len(release.read_manifest(DECIDE)["published"])
    assert all(": missing (published: " in p for p in problems)
    assert published.compare_table(CLAIMS, CLAIMS) == []


@pytest.mark.parametrize("edit, agree", [(scale("10", "estimate", 1 + published.RTOL / 2), True),
                                         (scale("10", "estimate", 1 + 2 * published.RTOL), False),
                                         (scale("4-step", "n", 2), False)],
                         ids=["half the tolerance", "twice the tolerance", "a count doubled"])
def test_numbers_agree_to_the_tolerance_and_counts_exactly(tmp_path, edit, agree):
    results = recomputed(tmp_path, edit)
    problems = published.compare(DECIDE, results)
    assert (problems == []) is agree, problems


def test_a_changed_verdict_is_named_with_its_row_and_column(tmp_path):
    def flip(claims):
        claims.loc[claims["claim_id"] == "2a", "verdict"] = "contradicted"
    problems = published.compare(DECIDE, recomputed(tmp_path, flip))
    assert len(problems) == 1 and "row claim_id=2a, column verdict: 'contradicted', published" in problems[0]


def test_a_published_row_missing_from_the_recomputation_is_named_and_an_added_row_is_not_compared(tmp_path):
    """Rows are matched by claim_id: a recomputation may add claims, never lose a published one."""
    def drop_10_add_11(claims):
        added = claims.iloc[:1].assign(claim_id="11")
        return pd.concat([claims[claims["claim_id"] != "10"], added], ignore_index=True)
    problems = published.compare(DECIDE, recomputed(tmp_path, drop_10_add_11))
    assert problems == [f"{tmp_path / 'results' / 'claims' / 'paper_claims.csv'}: published row claim_id=10 missing"]


def test_republishing_a_recomputation_that_agrees_writes_nothing(tmp_path):
    copy = tmp_path / "bulk-decide"
    shutil.copytree(DECIDE, copy)
    results = recomputed(tmp_path)
    done = run_main("dem_contract.__main__", ["republish", "--release", copy, "--results", results, "--reason", "x"])
    assert done.returncode == 0 and "nothing written" in done.stdout
    assert (copy / "manifest.yaml").read_bytes() == (DECIDE / "manifest.yaml").read_bytes()


def test_numbers_in_text_agree_across_their_rounding():
    """Claim 10's text printed 198 from the published run and 197 from the recomputation (3 digits of 197.5)."""
    assert published.cells_agree("149 [101, 198]; X_hi = 0.09245", "149 [101, 197]; X_hi = 0.09245")
    assert not published.cells_agree("149 [101, 198]", "149 [101, 190]")
    assert not published.cells_agree("reproduced", "inconclusive")


def test_republish_replaces_the_tables_and_the_release_still_verifies(tmp_path):
    """The sanctioned way to regenerate published/: new tables, their sha256 in the manifest, and why."""
    copy = tmp_path / "bulk-decide"
    shutil.copytree(DECIDE, copy)
    results = recomputed(tmp_path, scale("10", "estimate", 1.5))
    done = run_main("dem_contract.__main__", ["republish", "--release", copy, "--results", results,
                                              "--reason", "a test"])
    assert done.returncode == 0, done.stderr
    assert release.checksum_problems(copy) == []
    assert (copy / "published" / "paper_claims.csv").read_bytes() == \
        (results / "claims" / "paper_claims.csv").read_bytes()
    manifest = yaml.safe_load((copy / "manifest.yaml").read_text())
    assert manifest["republished"][-1]["reason"] == "a test" and manifest["republished"][-1]["tables"] == [
        "paper_claims.csv"]                                   # the one table that changed; the others keep their bytes
    old_text, new_text = (DECIDE / "manifest.yaml").read_text(), (copy / "manifest.yaml").read_text()
    for key in ("seeds", "regenerate", "cases"):            # every other block as it was written, comments included
        assert release.manifest_blocks(new_text)[key] == release.manifest_blocks(old_text)[key]
    assert "# Every seed planned, run and excluded" in new_text
    assert run_main("dem_contract.__main__", ["published", "--release", copy, "--results", results]).returncode == 0
    assert run_main("dem_contract.__main__", ["published", "--release", DECIDE, "--results", results]).returncode == 1
