"""The planner (python -m claims plan): seeds and core-hours that decide the undecided claims.

Its power formulas against closed forms and against the table's own decision rule on drawn per-seed
values (the stated power reached within its binomial interval), its table and command line on a claims
table, and, with YADE, that extending ``seeds:`` reruns no finished seed.
"""
import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats as st

from claims import plan, power, stats
from claims.cli import main
from dem_contract.synthetic import write_ensemble
from model import default_params


def test_tost_power_approaches_the_normal_closed_form():
    # large n: P = Phi((m - d)/se - z95) + Phi((m + d)/se - z95) - 1
    n, sd, d, m = 400, 1.0, 0.02, 0.15
    se = sd / math.sqrt(n)
    z = st.norm.ppf(0.95)
    closed = st.norm.cdf((m - d) / se - z) + st.norm.cdf((m + d) / se - z) - 1
    assert plan.power_tost(n, sd, d, m) == pytest.approx(closed, abs=0.01)


def test_tost_seeds_are_the_first_count_reaching_the_power():
    n = plan.seeds_tost(1.0, 0.1, 0.5)
    assert plan.power_tost(n, 1.0, 0.1, 0.5) >= 0.8 > plan.power_tost(n - 1, 1.0, 0.1, 0.5)
    assert plan.seeds_tost(1.0, 0.5, 0.5) == math.inf          # an effect as large as the margin is never negligible
    assert math.isnan(plan.seeds_tost(float("nan"), 0.0, 0.5))


def claims_rows(**over):
    base = dict(claim="c", estimate=-0.5, null=0.0, paper_side="<", margin=float("nan"), sd=1.0, n=3,
                verdict="inconclusive")
    return {**base, **over}


def test_plan_lists_only_undecided_claims_with_the_cheaper_way_to_decide_them():
    table = pd.DataFrame([
        dict(claims_rows(claim_id="4")),                                          # Model 1 better by 0.5 s.d.
        dict(claims_rows(claim_id="7", estimate=0.05, margin=0.5)),               # tiny effect, margin 0.5 s.d.
        dict(claims_rows(claim_id="8", estimate=140.0, null=135.0, sd=4.0)),      # the wrong side of the null
        dict(claims_rows(claim_id="1a", verdict="reproduced")),
        dict(claims_rows(claim_id="5", verdict="negligible")),
        dict(claims_rows(claim_id="2b", sd=float("nan"), estimate=float("nan"))),
    ])
    p = plan.plan_table(table, seed_cpu_s=3600.0, ensembles=2).set_index("claim_id")
    assert list(p.index) == ["4", "7", "8", "2b"]
    assert p.loc["4", "outcome"] == "reproduced" and p.loc["4", "seeds_needed"] == power.seeds_needed(1.0, -0.5)
    assert p.loc["4", "cases_to_add"] == p.loc["4", "seeds_needed"] - 3
    assert p.loc["4", "config_seeds_to_add"] == math.ceil(p.loc["4", "cases_to_add"] / 2)
    assert p.loc["4", "core_hours"] == pytest.approx(p.loc["4", "cases_to_add"])       # one core-hour a case
    assert p.loc["4", "wall_hours_2_cores"] == pytest.approx(p.loc["4", "core_hours"] / 2)
    assert p.loc["4", "wall_hours_cluster"] == pytest.approx(1.0)                      # one case's chain
    assert p.loc["7", "outcome"] == "negligible" and p.loc["7", "seeds_needed"] == plan.seeds_tost(1.0, 0.05, 0.5)
    assert p.loc["7", "seeds_sided"] > p.loc["7", "seeds_needed"]
    assert p.loc["8", "outcome"] == "contradicted"
    assert p.loc["2b", "outcome"] == "unknown" and "no seed-to-seed s.d." in p.loc["2b", "note"]
    unknown = plan.plan_table(table, seed_cpu_s=float("nan")).set_index("claim_id")
    assert unknown.loc["4", "core_hours"] == "unknown"                  # a cost not measured is named, not NaN
    assert unknown.loc["4", "wall_hours_2_cores"] == unknown.loc["4", "wall_hours_cluster"] == "unknown"


@pytest.mark.parametrize("delta, margin, outcome", [(-0.5, float("nan"), "reproduced"), (0.0, 0.6, "negligible")])
def test_planned_seeds_reach_the_stated_power_under_the_tables_own_rule(delta, margin, outcome):
    """Per-seed values drawn at the planned count, decided by claims.stats as the table does: the share of
    realisations reaching the outcome is 80 % within its binomial interval."""
    row = dict(claims_rows(claim_id="x", estimate=delta, margin=margin))
    n = int(plan.plan_table(pd.DataFrame([row]), float("nan")).loc[0, "seeds_needed"])
    rng = np.random.default_rng(7)
    hits, reps = 0, 300
    for k in range(reps):
        v = rng.normal(delta, 1.0, n)
        _, lo, hi, _ = stats.mean_interval(v, n_resamples=400, seed=k)       # the one 90 % interval
        hits += outcome in stats.verdict(lo, hi, 0.0, "<", margin)
    _, lo, hi, _ = stats.clopper_pearson(hits, reps)
    assert lo <= 0.8 <= hi, (n, hits / reps)


def test_command_line_writes_the_plan_and_names_an_unmeasured_cost(tmp_path):
    dirs = write_ensemble(tmp_path / "dem", default_params(), seeds=(1, 2), preshear_strain=0.3,
                          reversal_strain=0.2, coarse=0.01)
    pd.DataFrame([dict(claims_rows(claim_id="4"))]).to_csv(tmp_path / "paper_claims.csv", index=False)
    assert main(["plan", "--table", str(tmp_path / "paper_claims.csv"), "--dem", *map(str, dirs),
                 "--out", str(tmp_path / "plan.csv")]) == 0
    p = pd.read_csv(tmp_path / "plan.csv", dtype={"claim_id": str})
    assert p.loc[0, "claim_id"] == "4" and p.loc[0, "core_hours"] == "unknown"   # model-made: no CPU time


def test_command_line_names_a_table_without_margins_and_exits_2(tmp_path, capsys):
    pd.DataFrame([dict(claim_id="4", estimate=0.1)]).to_csv(tmp_path / "old.csv", index=False)
    assert main(["plan", "--table", str(tmp_path / "old.csv"), "--dem", str(tmp_path), "--out",
                 str(tmp_path / "p.csv")]) == 2
    assert "old.csv: column(s) null, paper_side, margin, sd, n, verdict missing" in capsys.readouterr().err


def test_power_paragraph_names_an_unmeasured_cost_unknown():
    from claims import report
    row = dict(claim_id="4", quantity="|A|", effect_choice="measured", effect=-0.002, sd_per_seed=0.003,
               disks_per_seed=500.0, transients_per_seed=2.0, seeds_needed=20.0, particles=1e4,
               core_hours=float("nan"), power_measured=0.3, seeds_measured=4, window=0.1, transients=40.0)
    text = report.power_section(pd.DataFrame([row]), [], dict(name="m", seeds=4, disks=500.0, transients=2.0),
                                dict(measured=0.01, ratio=1.0))
    assert "unknown core-hours" in text and "nan" not in text
