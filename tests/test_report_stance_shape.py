"""The shape of a predicted stance beside the measured runner's (bladelab.report.stance_shape)."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.report.stance_shape import (
    StanceShape,
    knee_flexion_deg,
    stance_knees,
    stance_peak_places,
)


def test_where_each_stance_peaks_counts_a_stance_across_the_period_s_end():
    force = np.zeros(40)
    force[5:15] = [1, 2, 3, 4, 5, 4, 3, 2, 1, 0.5]  # peaks at its 5th node of 10: 40 %
    force[[36, 37, 38, 39, 0, 1, 2, 3]] = [1, 2, 2.5, 3, 2, 1.5, 1, 0.5]  # wraps: 3 of 8, 37.5 %
    assert sorted(stance_peak_places(force, 0.1)) == pytest.approx([37.5, 40.0])
    assert stance_peak_places(np.zeros(10), 0.1) == []


def test_each_stance_s_knee_landing_and_deepest_flexion_wrap_around_the_period():
    force = np.zeros(40)
    force[5:15] = 1.0
    force[[36, 37, 38, 39, 0, 1, 2, 3]] = 1.0  # a stance across the period's end
    knee = np.zeros(40)
    knee[5:15] = [30, 40, 50, 45, 40, 35, 30, 25, 20, 15]  # lands at 30, deepest at 2 of 10
    knee[[36, 37, 38, 39, 0, 1, 2, 3]] = [12, 20, 30, 40, 44, 35, 25, 15]  # 4 of 8: 50 %
    got = sorted(stance_knees(force, knee, 0.5))
    assert got == [pytest.approx((12.0, 50.0)), pytest.approx((30.0, 20.0))]
    assert stance_knees(np.zeros(10), np.zeros(10), 0.5) == []


def test_knee_flexion_is_positive_flexed_and_none_without_the_knee():
    q = np.array([[0.1, -0.5], [0.2, -1.0]])
    np.testing.assert_allclose(knee_flexion_deg(q, ("hip_flexion_l", "knee_angle_l"), "l"),
                               np.degrees([0.5, 1.0]))
    assert knee_flexion_deg(q, ("hip_flexion_l", "knee_angle_l"), "r") is None


def _shape(peaks=(26.0, 27.0), knees=((31.0, 33.0), (30.0, 32.0))):
    return StanceShape(("left", "right"), peaks, knees, (35.0, 38.0), ((14.0, 45.0), (16.0, 44.0)))


def test_the_shape_s_table_puts_each_stance_beside_the_measured_runner_s_range():
    table = _shape().table()
    assert list(table["measure"]) == [
        "vertical force peak, left leg's stance", "vertical force peak, right leg's stance",
        "knee flexion at touch-down, left leg's stance",
        "knee flexion at touch-down, right leg's stance",
        "deepest stance knee flexion, left leg's stance",
        "deepest stance knee flexion, right leg's stance"]
    assert list(table["this stride"]) == [26.0, 27.0, 31.0, 30.0, 33.0, 32.0]
    assert list(table["the measured runner"]) == ["35–38"] * 2 + ["14–16"] * 2 + ["44–45"] * 2
    assert list(table["unit"]) == ["% of the stance"] * 2 + ["deg"] * 2 + ["% of the stance"] * 2
    # without the measured knees only the force's rows
    bare = StanceShape(("left",), (26.0,), ((31.0, 33.0),), (35.0,), ())
    assert list(bare.table()["the measured runner"]) == ["35"]


def test_force_peak_and_deepest_knee_count_as_together_within_the_agreement():
    assert _shape().together  # 26 vs 33 and 27 vs 32: within 10 % of the stance
    assert not _shape(peaks=(10.0, 27.0)).together
    assert "brings the peak earlier" in _shape().caption_text()
    assert "brings the peak earlier" not in _shape(peaks=(10.0, 27.0)).caption_text()
    text = _shape().summary_text()
    assert "peaks at 26, 27 % of the stance (the measured runner's 35–38 %)" in text
    assert "lands 31, 30° flexed (the measured runner's 14–16°)" in text
