"""Claim 5's interval is at least as wide as its run counts allow (claims.table.turn_count_interval):
a difference of two fractions of runs, often all zero, has a zero-width per-seed bootstrap interval
whatever the number of runs; the exact binomial bound of the counts does not."""
import math

import pytest

from claims import margins, stats
from claims.table import turn_count_interval


def test_no_opposite_turn_in_n_runs_is_bounded_by_the_closed_form_of_clopper_pearson():
    # k = 0 of n: the upper bound at two-sided level L is 1 - ((1 - L) / 2) ** (1 / n); each fraction at
    # 1 - 0.10 / 2 = 95 % (Bonferroni over the two), so (1 - 0.95) / 2 = 0.025
    for n in (1, 2, 10, 80):
        lo, hi = turn_count_interval(0, 0, n)
        assert hi == pytest.approx(1 - 0.025 ** (1 / n)) and lo == pytest.approx(-hi)


def test_two_clear_runs_without_an_opposite_turn_leave_claim_5_inconclusive():
    lo, hi = turn_count_interval(0, 0, 2)
    assert stats.verdict(lo, hi, 0.0, ">", margins.TURN_FRACTION) == "inconclusive"


def test_eighty_clear_runs_without_an_opposite_turn_make_it_negligible():
    lo, hi = turn_count_interval(0, 0, 80)
    assert stats.verdict(lo, hi, 0.0, ">", margins.TURN_FRACTION) == "negligible"


def test_model_2_turning_wrong_in_half_the_runs_reproduces_the_claim_and_no_runs_give_no_interval():
    lo, hi = turn_count_interval(20, 0, 40)
    assert 0 < lo < 0.5 < hi and stats.verdict(lo, hi, 0.0, ">", margins.TURN_FRACTION) == "reproduced"
    assert all(math.isnan(x) for x in turn_count_interval(0, 0, 0))
