"""When the seeds of one cell agree (a settled cell), by hand."""

from __future__ import annotations

import math

import pytest

from bladelab.predict.reflex.agreement import seed_agreement


def test_three_seeds_within_2_percent_and_5_cm_per_s_settle_a_cell():
    a = seed_agreement([60.0, 61.1, 60.5], [3.50, 3.54, 3.46])
    assert a.agreeing == (True, True, True) and a.settled
    assert a.cost_spread_pct == pytest.approx(100 * 1.1 / 60)
    assert a.speed_spread_m_per_s == pytest.approx(0.08)  # spread over all, not to the best
    assert "settled" in a.describe() and "not settled" not in a.describe()


@pytest.mark.parametrize(("costs", "speeds", "agreeing"), [
    ([60.0, 61.3, 60.5], [3.5, 3.5, 3.5], (True, False, True)),      # 2.2 % above the best
    ([60.0, 60.1, 60.5], [3.5, 3.56, 3.5], (True, False, True)),     # 0.06 m/s off the best
    ([60.0, math.nan, 60.5], [3.5, 3.5, 3.5], (True, False, True)),  # a seed without a cost
])
def test_a_seed_off_the_best_leaves_the_cell_unsettled(costs, speeds, agreeing):
    a = seed_agreement(costs, speeds)
    assert a.agreeing == agreeing and not a.settled
    assert "2 of 3 seeds" in a.describe() and "not settled" in a.describe()


def test_a_worse_fourth_seed_does_not_unsettle_three_that_agree():
    a = seed_agreement([66.0, 70.8, 65.5, 66.4], [3.33, 3.26, 3.34, 3.31])
    assert a.agreeing == (True, False, True, True) and a.settled


def test_one_seed_alone_is_never_settled_and_bad_input_is_refused():
    assert not seed_agreement([60.0], [3.5]).settled
    with pytest.raises(ValueError):
        seed_agreement([60.0, 61.0], [3.5])
