"""claims.across: two claims tables side by side, on tables the pipeline wrote (data/bulk-decide's published claims)."""
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from claims import across

from helpers import ROOT

PUBLISHED = ROOT / "data" / "bulk-decide" / "published" / "paper_claims.csv"


def test_a_table_beside_itself_has_every_verdict_the_same_and_no_difference():
    t = across.read_table(PUBLISHED)
    out = across.across(t, t)
    assert len(out) == len(t)
    assert out["same_verdict"].all()
    assert not out["estimates_differ"].any()
    assert np.allclose(out["t"].dropna(), 0.0)


def test_a_shifted_estimate_is_flagged_as_differing_after_holm_and_only_that_row():
    t = across.read_table(PUBLISHED)
    row = t.index[t["claim_id"] == "1a"][0]
    shifted = t.copy()
    se = t.loc[row, "sd"] / np.sqrt(t.loc[row, "n"])
    shifted.loc[row, ["estimate", "low", "high"]] += 10 * se      # 10 / sqrt(2) = 7 standard errors of the difference
    out = across.across(t, shifted).set_index("claim_id")
    assert out.loc["1a", "t"] == pytest.approx(-10 / np.sqrt(2))
    assert out.loc["1a", "estimates_differ"]
    assert out["estimates_differ"].sum() == 1


def test_a_small_shift_is_not_flagged_though_it_changes_no_verdict():
    t = across.read_table(PUBLISHED)
    row = t.index[t["claim_id"] == "1a"][0]
    shifted = t.copy()
    shifted.loc[row, "estimate"] += 1.0 * t.loc[row, "sd"] / np.sqrt(t.loc[row, "n"])
    out = across.across(t, shifted).set_index("claim_id")
    assert not out.loc["1a", "estimates_differ"]


def one_row(estimate, sd, n):
    return pd.DataFrame([dict(claim_id="x", estimate=estimate, low=estimate - 1, high=estimate + 1, sd=sd, n=n,
                              verdict="inconclusive")])


def test_a_difference_between_few_seeds_is_judged_on_welchs_t_not_the_normal():
    # 3 seeds a side, equal s.d.: Welch's df = 4. t = 2.0 gives p 0.046 under the normal (a difference at
    # the family's 10 %) but 0.116 under Student's t with 4 df: not a difference.
    sd, n = 1.0, 3
    shift = 2.0 * np.sqrt(2 * sd ** 2 / n)
    out = across.across(one_row(0.0, sd, n), one_row(-shift, sd, n)).iloc[0]
    assert out["t"] == pytest.approx(2.0)
    assert out["df"] == pytest.approx(4.0)
    assert out["p"] == pytest.approx(0.1161, abs=1e-3)
    assert not out["estimates_differ"]
    far = across.across(one_row(0.0, sd, n), one_row(-2.5 * shift, sd, n)).iloc[0]   # t = 5: p 0.0075
    assert far["estimates_differ"]


def test_unequal_spreads_get_the_welch_satterthwaite_degrees_of_freedom():
    a, b = one_row(0.0, 1.0, 10), one_row(1.0, 3.0, 5)
    va, vb = 1.0 / 10, 9.0 / 5
    expected = (va + vb) ** 2 / (va ** 2 / 9 + vb ** 2 / 4)
    assert across.across(a, b).iloc[0]["df"] == pytest.approx(expected)


def test_a_differing_verdict_is_reported_as_engine_dependent(tmp_path):
    t = across.read_table(PUBLISHED)
    other = t.copy()
    other.loc[other["claim_id"] == "8", "verdict"] = "contradicted"
    a, b = tmp_path / "yade.csv", tmp_path / "lammps.csv"
    t.to_csv(a, index=False)
    other.to_csv(b, index=False)
    res = subprocess.run([sys.executable, "-m", "claims", "across", "--table", f"yade={a}", "--table", f"lammps={b}",
                          "--out", str(tmp_path / "out")], cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    md = (tmp_path / "out" / "claims_across.md").read_text()
    line = next(x for x in md.splitlines() if x.startswith("| 8 |"))
    assert "engine-dependent verdict" in line
    table = pd.read_csv(tmp_path / "out" / "claims_across.csv")
    assert (~table["same_verdict"]).sum() == 1


@pytest.mark.parametrize("arg, message", [("yade", "expected LABEL=paper_claims.csv"),
                                          ("$(touch x)=a.csv", "plain word")])
def test_a_bad_table_argument_exits_2_naming_it(tmp_path, arg, message):
    res = subprocess.run([sys.executable, "-m", "claims", "across", "--table", arg, "--table", f"b={PUBLISHED}",
                          "--out", str(tmp_path)], cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 2
    assert message in res.stderr
