"""Verdicts a referee accepts (issue 32): model error apart from DEM noise, one level, one row per figure,
"always" without a multiple-testing trap, adequacy beside the comparison.

Model-made data with a known truth and the contract's noise: a DEM run is the truth plus serially
correlated noise of one 500-disk run's size (``dem_contract.synthetic.FABRIC_NOISE`` per fabric
component, correlated over ``tests.helpers.NOISE_LENGTH`` of strain), sampled as the DEM samples
(``dem_contract.synthetic.strain_grid``: fine after the reversal, coarse after); model curves are the
truth or the truth off by a known amount. The rows come from ``claims.table``'s functions on curves in
the layout of ``predictions.csv``. Coverage studies over many draws are behind ``heavy``; the fast
tests use a few draws each.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from claims import margins, stats, table
from claims.inputs import runs as run_curves
from dem_contract import fabric_angle_deg
from dem_contract.synthetic import FABRIC_NOISE, strain_grid
from tests.helpers import NOISE_LENGTH

S = strain_grid(0.3, 0.0005, 0.15, 0.005)      # the DEM's sampling after a reversal
GROUP = "p100000_I0.001"


def ar1(rng, shape, s, sd=FABRIC_NOISE, length=NOISE_LENGTH):
    """Gaussian noise of s.d. ``sd`` correlated over ``length`` of strain along the last axis (AR(1) on ``s``)."""
    e = np.empty((*shape, s.size))
    e[..., 0] = rng.normal(0.0, sd, shape)
    r = np.exp(-np.diff(s) / length)
    for i in range(1, s.size):
        e[..., i] = r[i - 1] * e[..., i - 1] + np.sqrt(1.0 - r[i - 1] ** 2) * rng.normal(0.0, sd, shape)
    return e


def truth(s):
    """The true |A| after a reversal: a fall from 0.1 to a minimum near s = 0.04 and a recovery."""
    return 0.1 - 0.06 * (s / 0.04) * np.exp(1.0 - s / 0.04)


def frame(case, protocol, kind, source, norm):
    a = -np.asarray(norm) / np.sqrt(2.0)          # theta_A = 90 degrees: A_xy = 0, |A| = sqrt2 |A_xx|
    b = np.zeros_like(a)
    return pd.DataFrame(dict(set="fold", case=case, group=GROUP, seed=int(case.rsplit("s", 1)[1]), protocol=protocol,
                             source=source, s_rev=S, A_xx=a, A_xy=b, A_norm=np.asarray(norm),
                             theta_A=fabric_angle_deg(a, b), mu=0.3, in_sample=False, kind=kind))


def campaign(rng, seeds, offsets: dict, draws=1):
    """``draws`` campaigns of ``seeds`` seeds, each one step reversal and one sinusoidal reversal (same truth),
    models the truth plus ``offsets[model]`` (a constant, or a callable of s). Returns a list of runs dicts."""
    noise = ar1(rng, (draws, seeds, 2), S)
    out = []
    for k in range(draws):
        rows = []
        for i in range(seeds):
            case = f"{GROUP}_s{i + 1}"
            for j, (proto, kind) in enumerate((("heaviside", "heaviside"), ("sinusoidal", "sinusoidal"))):
                rows.append(frame(case, proto, kind, "dem", truth(S) + noise[k, i, j]))
                for m, off in offsets.items():
                    rows.append(frame(case, proto, kind, m, truth(S) + (off(S) if callable(off) else off)))
        out.append(run_curves(pd.concat(rows, ignore_index=True)))
    return out


def rows_of(runs, n_resamples=400):
    """Claim 4's rows (per figure and pooled) of one campaign."""
    scores, missing = table.early_scores(runs, table.dem_of(runs), "A_norm", table.EARLY_A)
    rows = table.model_error_rows(scores, missing, "4", table.CLAIM4, "test", "|A|", table.EARLY_A,
                                  table.Bootstrap(n_resamples))
    return {r["claim_id"]: r for r in rows}


def band_margin():
    """The margin (f sigma)^2 of |A| for this noise (the DEM's |A| is the truth plus noise of s.d. FABRIC_NOISE)."""
    return (margins.BAND_FRACTION * FABRIC_NOISE) ** 2


# --------------------------------------------------------------------------- model error, not DEM noise


def test_the_noise_floor_is_the_seed_to_seed_variance_and_a_perfect_model_scores_about_zero():
    (runs,) = campaign(np.random.default_rng(1), 12, {"model1": 0.0, "model2": 0.0})
    scores, _ = table.early_scores(runs, table.dem_of(runs), "A_norm", table.EARLY_A)
    floor = np.mean([r["floor"] for r in scores])
    assert floor == pytest.approx(FABRIC_NOISE ** 2, rel=0.35)
    b2 = np.mean([r["mse"]["model1"] - r["floor"] for r in scores])      # the perfect model's squared error
    assert abs(b2) < 0.25 * floor


def test_a_perfect_model_against_a_null_model_with_an_effect_of_twice_the_margin_reads_reproduced():
    m = band_margin()
    (runs,) = campaign(np.random.default_rng(2), 10, {"model1": 0.0, "model2": np.sqrt(2.0 * m)})
    rows = rows_of(runs)
    for cid in ("4-step", "4-sin", "4-pooled"):
        assert rows[cid]["estimate"] == pytest.approx(-2.0 * m, rel=0.5)
        assert rows[cid]["margin"] == pytest.approx(m, rel=0.35)
        assert rows[cid]["verdict"] == "reproduced", (cid, rows[cid]["low"], rows[cid]["high"], rows[cid]["margin"])


def test_two_models_both_exactly_right_read_negligible():
    # two integrations of the truth that differ at the 1e-6 level
    (runs,) = campaign(np.random.default_rng(3), 5, {"model1": 0.0, "model2": lambda s: 1e-6 * np.sin(40 * s)})
    for cid, r in rows_of(runs).items():
        assert r["verdict"] == "negligible", cid
        assert r["adequacy"].startswith("Model 1 within; Model 2 within"), cid


def never_negligible(draws, seed):
    # "misses by twice the margin": its curve is off by 2 sqrt(m), a squared model error of 4 m
    m = band_margin()
    campaigns = campaign(np.random.default_rng(seed), 5, {"model1": 0.0, "model2": 2.0 * np.sqrt(m)}, draws=draws)
    verdicts = [r["verdict"] for runs in campaigns for r in rows_of(runs, 200).values()]
    assert len(verdicts) == 3 * draws and not any("negligible" in v for v in verdicts)


def test_a_perfect_model_is_never_negligible_against_a_model_that_misses_by_twice_the_margin():
    never_negligible(12, seed=4)


@pytest.mark.heavy
def test_a_perfect_model_is_never_negligible_in_400_draws():
    never_negligible(400, seed=11)


def test_the_rmse_difference_could_call_a_perfect_model_negligible_and_the_model_error_does_not():
    """The deciding campaign's case (issue 32): against a DEM noise of 0.0145, a Model 2 of RMSE 0.018 leaves a
    perfect model at most 0.0037 of RMSE to gain, under the 0.0042 margin of the old rule; on the model-error
    scale the perfect model gains Model 2's whole squared error."""
    noise, rmse2 = 0.0145, 0.0182
    gain = rmse2 - noise                                  # the most a perfect model can gain in RMSE
    assert gain < 0.0042
    b2_model2 = rmse2 ** 2 - noise ** 2                   # what it gains on the model-error scale
    assert b2_model2 > 4 * (margins.BAND_FRACTION * noise) ** 2 / 2


@pytest.mark.heavy
def test_a_null_effect_reads_reproduced_in_at_most_5_percent_of_draws():
    """Both models equally wrong (off by +c and -c: the same squared model error), 400 draws of 5 seeds.

    Each seed's difference is then -4 c times its window's mean noise: normal, so the t interval's 5 % is
    exact and the bootstrap only widens it; the three rows' rates are held to it at 99 % (binomial).
    The rates, printed with -s: .venv/bin/python -m pytest -q -s -m heavy tests/test_claims_referee.py -k null"""
    m = band_margin()
    c = np.sqrt(m)
    draws = campaign(np.random.default_rng(5), 5, {"model1": c, "model2": -c}, draws=400)
    verdicts = [rows_of(runs, 200) for runs in draws]
    for cid in ("4-step", "4-sin", "4-pooled"):
        hits = sum(v[cid]["verdict"].startswith("reproduced") for v in verdicts)
        print(f"\nclaim 4 under no effect, row {cid}: reproduced in {hits} of {len(verdicts)} draws")
        _, lo, _, _ = stats.clopper_pearson(hits, len(verdicts), level=0.99)
        assert lo <= 0.05, (cid, hits)


def test_a_null_effect_rarely_reads_reproduced():
    """The fast version of the coverage study: 20 draws, at most 3 reproduced (5 % is 1 of 20)."""
    m = band_margin()
    draws = campaign(np.random.default_rng(6), 5, {"model1": np.sqrt(m), "model2": -np.sqrt(m)}, draws=20)
    hits = sum(rows_of(runs, 200)["4-pooled"]["verdict"].startswith("reproduced") for runs in draws)
    assert hits <= 3


# --------------------------------------------------------------------------- one level


def test_one_level_an_interval_on_one_side_inside_the_margin_is_reproduced_negligible():
    assert stats.verdict(-0.0038, -0.0005, 0.0, "<", 0.0042) == "reproduced, negligible"
    assert stats.LEVEL == 0.90 and stats.ALPHA == 0.05


def test_t_quantiles_for_a_jackknife_of_five_seeds():
    lo, hi = stats.t_interval(-29.3, 1.0, 5)          # 90 %: t_{0.95, 4} = 2.132
    assert hi - lo == pytest.approx(2 * 2.131846786326649)
    lo95, hi95, sd = stats.rescaled_interval(0.0, -2.776445105197793, 2.776445105197793, 5)   # +-t_{0.975,4} s.e.
    assert hi95 == pytest.approx(2.131846786326649) and sd == pytest.approx(np.sqrt(5))


# --------------------------------------------------------------------------- "always" and family-wise error


def fabric(theta_deg, norm):
    t = np.radians(2.0 * np.asarray(theta_deg, float))
    return norm * np.cos(t) / np.sqrt(2.0), norm * np.sin(t) / np.sqrt(2.0)


CROSS = strain_grid(0.3, 0.0005, 0.15, 0.005)


def through_90_at_the_edge(rng, n_runs):
    """``n_runs`` DEM-like runs that all turn through 90 degrees with the fabric isotropic as they cross
    (A_xx exactly 0 where A_xy changes sign: the edge of "through 90", the hardest honest case), with the
    contract's correlated noise at the DEM's sampling. Returns {(case, group, protocol): curve}."""
    theta = 125.0 - 70.0 * np.clip(CROSS / 0.1, 0.0, 1.0)                    # crosses 90 at s = 0.05
    norm = 0.1 * np.clip(np.abs(CROSS - 0.05) / 0.04, 0.0, 1.0)             # |A| = 0 there
    a, b = fabric(theta, norm)
    na, nb = ar1(rng, (n_runs,), CROSS), ar1(rng, (n_runs,), CROSS)
    positions = 10 if n_runs >= 100 else 8
    out = {}
    for k in range(n_runs):
        key = (f"{GROUP}_s{k // positions + 1}", GROUP, f"train_r{k % positions + 1}")
        out[key] = pd.DataFrame({"s_rev": CROSS, "A_xx": a + na[k], "A_xy": b + nb[k], "kind": "heaviside"})
    return out


def contradicted_rate(n_runs, draws, seed):
    rng = np.random.default_rng(seed)
    new = old = 0
    for _ in range(draws):
        dem = through_90_at_the_edge(rng, n_runs)
        passages = table.dem_passages(dem)
        new += any(c["horizontal"] for c in table.crossing_tests(dem, passages).values())
        old += any(p["axis"] == "0/180" for p in passages.values())      # the former rule: one run past 2 s.d.
    return new / draws, old / draws


@pytest.mark.parametrize("n_runs", [40, 400])
def test_every_run_through_90_rarely_reads_contradicted_at_40_or_400_runs(n_runs):
    new, old = contradicted_rate(n_runs, 20 if n_runs == 40 else 4, seed=n_runs)
    assert new <= 0.05 + 1e-12           # 20 draws at 40 runs, 4 at 400: none contradicted
    assert old >= 0.3                    # the former rule contradicted about half the campaigns or more


@pytest.mark.heavy
@pytest.mark.parametrize("n_runs, draws", [(40, 400), (400, 100)])
def test_every_run_through_90_reads_contradicted_in_at_most_5_percent_of_draws(n_runs, draws):
    """The family-wise check (claims.table.crossing_tests). The rates, printed with -s:
    .venv/bin/python -m pytest -q -s -m heavy tests/test_claims_referee.py -k always"""
    new, old = contradicted_rate(n_runs, draws, seed=7 + n_runs)
    print(f"\nclaim 3, every run through 90 degrees at the edge, {n_runs} runs, {draws} draws: contradicted "
          f"{new:.3f} (Holm over runs), {old:.3f} (the former one-run-past-2-s.d. rule)")
    hits = round(new * draws)
    _, lo, _, _ = stats.clopper_pearson(hits, draws, level=0.90)
    assert lo <= 0.05, (n_runs, new)


def test_a_run_clearly_through_the_horizontal_still_contradicts_always():
    rng = np.random.default_rng(8)
    dem = through_90_at_the_edge(rng, 40)
    theta = 125.0 + 110.0 * np.clip(CROSS / 0.1, 0.0, 1.0)           # through 180 with |A| = 0.1
    a, b = fabric(theta, 0.1)
    key = (f"{GROUP}_s1", GROUP, "train_r1")
    dem[key] = pd.DataFrame({"s_rev": CROSS, "A_xx": a + ar1(rng, (), CROSS), "A_xy": b + ar1(rng, (), CROSS),
                             "kind": "heaviside"})
    tests = table.crossing_tests(dem)
    assert tests[key]["horizontal"] and sum(c["horizontal"] for c in tests.values()) == 1


# --------------------------------------------------------------------------- adequacy beside the comparison


def sinusoidal_runs(rng, seeds, widths: dict):
    """Sinusoidal reversals whose theta_A turns from 125 to 55 degrees over a width (10-90 %) per source."""
    s = np.linspace(0.0, 0.4, 401)
    rows = []
    for i in range(seeds):
        case = f"{GROUP}_s{i + 1}"
        for source, w in widths.items():
            w_i = w * (1.0 + 0.1 * rng.standard_normal()) if source == "dem" else w
            theta = 90.0 + 35.0 * np.tanh(-(s - 0.1) / (w_i / (2 * np.arctanh(0.8))))
            a, b = fabric(theta, 0.1)
            if source == "dem":
                a, b = a + rng.normal(0, 0.1 * FABRIC_NOISE, s.size), b + rng.normal(0, 0.1 * FABRIC_NOISE, s.size)
            rows.append(pd.DataFrame(dict(set="fold", case=case, group=GROUP, seed=i + 1, protocol="sinusoidal",
                                          source=source, s_rev=s, A_xx=a, A_xy=b, A_norm=np.hypot(a, b) * np.sqrt(2),
                                          theta_A=fabric_angle_deg(a, b), mu=0.3, in_sample=False,
                                          kind="sinusoidal")))
    return run_curves(pd.concat(rows, ignore_index=True))


def test_claim_6_with_both_models_20_times_too_sharp_reads_both_fail():
    runs = sinusoidal_runs(np.random.default_rng(9), 5, {"dem": 0.050, "model1": 0.0025, "model2": 0.0025 / 2})
    row = table.width_row(runs, table.Bootstrap(400))
    assert row["verdict"] == "both fail"
    assert row["adequacy"].startswith("Model 1 outside; Model 2 outside")


def test_claim_6_with_one_model_inside_the_band_is_decided_by_the_comparison():
    runs = sinusoidal_runs(np.random.default_rng(10), 8, {"dem": 0.050, "model1": 0.050, "model2": 0.0025})
    row = table.width_row(runs, table.Bootstrap(400))
    assert row["verdict"] == "reproduced" and "Model 2 outside" in row["adequacy"]
    assert not row["adequacy"].startswith("Model 1 outside")      # one model not outside: the comparison decides


# --------------------------------------------------------------------------- Eq. 2 against the paper as curves


def eq2_cases(rng, params, seeds=4, n=400, noise=0.01):
    """DEM-like reversal samples whose signed stress ratio is Eq. 2 with ``params`` plus noise."""
    from claims.inputs import DemCase
    from model.laws import stress_ratio_eq2
    cases = []
    for i in range(seeds):
        X = rng.uniform(-0.12, 0.09, n)
        g = np.where(rng.random(n) < 0.5, 1.0, -1.0)
        A_xy = X / (np.sqrt(2.0) * g)
        tau = stress_ratio_eq2(X, **params) + rng.normal(0, noise, n)
        samples = pd.DataFrame({"protocol": "heaviside", "kind": "heaviside", "reversal": 1, "X": X,
                                "mu": np.abs(tau), "A_xy": A_xy, "stress_ratio": g * tau})
        cases.append(DemCase(label=f"{GROUP}_s{i + 1}", group=GROUP, steady={}, samples=samples))
    return cases


def test_data_made_by_the_papers_eq2_lie_on_its_curve_and_keep_its_k5():
    from claims import eq2
    tab = eq2.eq2_table(eq2_cases(np.random.default_rng(12), eq2.PAPER))
    cur = tab[tab["section"] == "curve"]
    assert cur["paper_inside"].mean() > 0.5         # a pointwise 90 % band of 4 seeds, one draw
    assert (cur["paper"] - cur["value"]).abs().max() < 0.01
    prof = tab[tab["section"] == "k5_profile"].set_index("k5")
    assert prof.loc[eq2.PAPER["k5"], "value"] < 1.01 < prof.loc[0.0, "value"]      # 9e4 fits, 0 does not


def test_data_made_without_a_fifth_order_term_say_how_much_9e4_costs():
    from claims import eq2
    cases = eq2_cases(np.random.default_rng(13), dict(X0=0.032, k1=2.2, k3=4.0, k5=0.0))
    tab = eq2.eq2_table(cases)
    cur = tab[tab["section"] == "curve"]
    assert cur["paper_inside"].mean() < 0.3 and (cur["paper"] - cur["value"]).abs().max() > 0.03
    prof = tab[tab["section"] == "k5_profile"].set_index("k5")
    assert prof.loc[0.0, "value"] == pytest.approx(1.0, abs=0.01) and prof.loc[eq2.PAPER["k5"], "low"] > 1.02
    assert "times the free fit's" in eq2.summary(tab, table.EQ2_MARGIN)
