"""Claim 3 (theta_A passes through 90 degrees) and the one rule for the passage that compare and claims share.

Constructed crossings with a known axis: clear through 90, clear through 0/180, and unclear (a fabric so
weak at the crossing that its noise hides the sign of A_xx); and model-made runs through the comparison,
whose claims.csv must name the same axis as the claims stage for every run.
"""
import numpy as np
import pandas as pd
import pytest

from claims.inputs import dem_curves
from claims.table import Bootstrap, dem_passages, passage_row
from dem_contract.passage import passage
from tests.helpers import comparison_for_truth

S = np.linspace(0.0, 0.5, 251)


def fabric(theta_deg, norm):
    """A_xx, A_xy of a fabric of |A| = ``norm`` along theta (A_xx = |A| cos 2theta / sqrt2)."""
    t = np.radians(2.0 * np.asarray(theta_deg, float))
    return norm * np.cos(t) / np.sqrt(2.0), norm * np.sin(t) / np.sqrt(2.0)


def run(kind_of_crossing, rng, noise=0.002):
    """One reversal: theta_A from 125 degrees to its mirror through 90 ("90"), through 180 ("0/180"), or
    through 90 with |A| nearly 0 where A_xy changes sign ("unclear")."""
    stop = {"90": 55.0, "unclear": 55.0, "0/180": 235.0}[kind_of_crossing]
    theta = np.linspace(125.0, stop, S.size)
    norm = 0.1 * np.ones_like(S)
    if kind_of_crossing == "unclear":      # the fabric isotropic within the noise as it turns (strain 0.15-0.35)
        norm = 0.1 * np.clip((np.abs(S - 0.25) - 0.1) / 0.15, 0.0, 1.0)
    a, b = fabric(theta, norm)
    return pd.DataFrame({"s_rev": S, "A_xx": a + rng.normal(0, noise, S.size), "A_xy": b + rng.normal(0, noise, S.size),
                         "kind": "heaviside"})


def dem_of(plan, seed=0):
    """{(case, group, protocol): curve} from {case: [axis of each run, ...]}."""
    rng = np.random.default_rng(seed)
    return {(case, "p1_I0.001", f"r{k}"): run(ax, rng) for case, axes in plan.items() for k, ax in enumerate(axes)}


@pytest.mark.parametrize("axis", ["90", "0/180", "unclear"])
def test_constructed_crossings_are_classified_as_built(axis):
    d = run(axis, np.random.default_rng(1))
    assert passage(d["s_rev"], d["A_xx"], d["A_xy"], noisy=True)["axis"] == axis


def test_runs_clearly_through_90_reproduce_claim_3():
    row = passage_row(dem_of({f"s{k}": ["90", "90"] for k in range(4)}), Bootstrap(1000))
    assert row["verdict"] == "reproduced" and row["high"] < 0 and row["n"] == 4
    assert "clear runs 8 of 8" in row["detail"]


def test_unclear_runs_count_neither_way():
    clear = passage_row(dem_of({f"s{k}": ["90", "90"] for k in range(4)}), Bootstrap(1000))
    mixed = passage_row(dem_of({f"s{k}": ["90", "90", "unclear"] for k in range(4)}), Bootstrap(1000))
    assert mixed["verdict"] == clear["verdict"] == "reproduced"
    assert "unclear: 4" in mixed["detail"] and "clear runs 8 of 12" in mixed["detail"]
    only_unclear = passage_row(dem_of({f"s{k}": ["unclear", "unclear"] for k in range(4)}), Bootstrap(1000))
    assert only_unclear["verdict"] != "contradicted"      # no run against the paper: never contradicted


def test_one_run_clearly_through_the_horizontal_contradicts_always():
    plan = {f"s{k}": ["90", "90"] for k in range(4)}
    plan["s0"] = ["90", "0/180"]
    row = passage_row(dem_of(plan), Bootstrap(1000))
    assert row["verdict"] == "contradicted" and "through 0/180: 1" in row["detail"]
    assert row["estimate"] < 0      # the mean still leans to 90: the counter-example decides "always"


def test_runs_through_the_horizontal_give_a_positive_statistic():
    row = passage_row(dem_of({f"s{k}": ["0/180", "0/180"] for k in range(3)}), Bootstrap(1000))
    assert row["verdict"] == "contradicted" and row["low"] > 0


# --------------------------------------------------------------------------- one home: compare and claims agree


@pytest.mark.parametrize("truth", ["model1", "model2"])
def test_compare_and_claims_name_the_same_passage_for_every_run(tmp_path, truth):
    dirs, c = comparison_for_truth(tmp_path, truth)
    dem = dem_curves(c.predictions)
    claims_axes = {(case, proto): p["axis"] for (case, _, proto), p in dem_passages(dem).items()}
    rows = c.claims[(c.claims["level"] == "seed") & (c.claims["source"] == "dem")]
    compare_axes = {(r.case, r.protocol): r.theta_passage for r in rows.itertuples()}
    assert compare_axes == claims_axes and len(claims_axes) == 8
    # the same rule on the models' curves in both places
    model_rows = c.claims[(c.claims["level"] == "seed") & (c.claims["source"] == "model2")]
    pred = c.predictions[c.predictions["source"] == "model2"]
    for r in model_rows.itertuples():
        m = pred[(pred["case"] == r.case) & (pred["protocol"] == r.protocol)].sort_values("s_rev")
        assert r.theta_passage == passage(m["s_rev"], m["A_xx"], m["A_xy"], noisy=False)["axis"]
