"""Segmentation: the geometric error against the circular-segment formula, choice of N,
self-intersection detection."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.blade.profile import Profile, ProfileElement, profile_from_elements
from bladelab.blade.segmentation import segment_profile, segmentation_error
from bladelab.errors import ModelError


def _arc_error_mm(radius: float, piece: float) -> float:
    """Area between an arc piece and its chord per unit arc length [mm], circle geometry."""
    theta = piece / radius
    area = 0.5 * radius**2 * (theta - math.sin(theta))
    return area / piece * 1e3


def _fine_arc(radius: float, angle: float) -> Profile:
    # Points every 0.5 mm on the circle: the polyline's error matches the circle's within ~1e-4.
    return profile_from_elements([ProfileElement(radius * angle, angle)])


def test_straight_profile_has_zero_error_and_one_segment():
    p = Profile(np.array([[0.0, 0.0], [0.0, -0.2], [0.0, -0.4]]))
    seg = segment_profile(p, max_error_mm2_per_mm=0.01)
    assert seg.n == 1
    assert seg.error == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("n", [4, 8, 16])
def test_arc_error_matches_circular_segment_area(n):
    r, angle = 0.12, math.radians(150)
    seg = segment_profile(_fine_arc(r, angle), n_segments=n)
    expected = _arc_error_mm(r, r * angle / n)
    assert seg.error == pytest.approx(expected, rel=2e-3)
    # A pure arc: every piece has the same error, and the mean equals the worst.
    np.testing.assert_allclose(seg.segment_errors, expected, rtol=2e-3)
    assert seg.mean_error == pytest.approx(seg.error, rel=1e-3)
    # Segment end points lie on the circle (centre at (r, 0)) at equal arc spacing.
    np.testing.assert_allclose(np.hypot(seg.points[:, 0] - r, seg.points[:, 1]), r, atol=1e-6)
    np.testing.assert_allclose(seg.chord_lengths, 2 * r * math.sin(angle / n / 2), rtol=1e-5)


def test_worst_segment_vs_mean_with_a_straight_part():
    r, angle, line = 0.1, math.radians(90), 0.3
    prof = profile_from_elements([ProfileElement(line), ProfileElement(r * angle, angle)])
    n = 8  # 0.3/((0.3+0.157)/8) is not an integer: one piece straddles line and arc
    seg = segment_profile(prof, n_segments=n)
    piece = prof.length / n
    # The pieces fully on the arc have the circle's error; fully straight ones have none.
    on_arc = seg.breaks[:-1] >= line
    straight = seg.breaks[1:] <= line
    np.testing.assert_allclose(seg.segment_errors[on_arc], _arc_error_mm(r, piece), rtol=2e-3)
    np.testing.assert_allclose(seg.segment_errors[straight], 0.0, atol=1e-9)
    # Mean = total area / total length, smaller than the worst segment.
    areas = seg.segment_errors * piece
    assert seg.mean_error == pytest.approx(areas.sum() / prof.length, rel=1e-9)
    assert seg.mean_error < seg.error


def test_smallest_n_below_threshold():
    r, angle = 0.15, math.radians(200)
    prof = _fine_arc(r, angle)
    length = r * angle
    for threshold in (0.5, 1.0, 2.0):
        # Independent reference: the circle formula, N = 1, 2, ...
        n_ref = next(n for n in range(1, 100) if _arc_error_mm(r, length / n) <= threshold)
        seg = segment_profile(prof, max_error_mm2_per_mm=threshold)
        assert seg.n == n_ref
        assert seg.error <= threshold
        assert segmentation_error(prof, seg.n - 1) > threshold
        assert seg.threshold == threshold


def test_error_falls_as_one_over_n_squared():
    prof = _fine_arc(0.1, math.radians(120))
    e8, e16 = segmentation_error(prof, 8), segmentation_error(prof, 16)
    assert e8 / e16 == pytest.approx(4.0, rel=0.01)


def test_s_curve_chord_crossing_counts_both_sides():
    # An S: the chord of one piece crosses the profile; the area is the sum of both lobes.
    r = 0.05
    prof = profile_from_elements([ProfileElement(r * math.pi / 2, math.pi / 2),
                                  ProfileElement(r * math.pi / 2, -math.pi / 2)])
    seg = segment_profile(prof, n_segments=1)
    # The chord (0,0)-(2r,-2r) contains each quarter arc's own chord, so the area is two
    # circular segments of 90 deg, one on each side: no cancellation between the lobes.
    lobe = 0.5 * r**2 * (math.pi / 2 - 1.0)
    assert seg.error == pytest.approx(2 * lobe / prof.length * 1e3, rel=2e-3)


def test_self_intersecting_segmentation_is_detected():
    # An inward spiral (simple curve) whose coarse chords cut across the inner turns.
    t = np.linspace(0.0, 1.0, 2000)
    rad = 0.1 * (1.0 - 0.5 * t)
    ang = 4.0 * math.pi * t
    prof = Profile(np.stack([rad * np.cos(ang), rad * np.sin(ang)], axis=1))
    bad = [n for n in range(2, 12)
           if _crosses(segment_profile(prof, n_segments=n, check_intersections=False).points)]
    assert bad, "test geometry should produce a crossing for some N"
    with pytest.raises(ModelError, match="intersects itself"):
        segment_profile(prof, n_segments=bad[0])


def _crosses(points: np.ndarray) -> bool:
    """Brute-force proper-crossing test, independent of the module's implementation."""
    def ccw(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    n = len(points) - 1
    for i in range(n):
        for j in range(i + 2, n):
            a, b, c, d = points[i], points[i + 1], points[j], points[j + 1]
            if ccw(a, b, c) * ccw(a, b, d) < 0 and ccw(c, d, a) * ccw(c, d, b) < 0:
                return True
    return False


def test_bad_arguments():
    prof = _fine_arc(0.1, 1.0)
    with pytest.raises(ModelError, match="positive"):
        segment_profile(prof, max_error_mm2_per_mm=0.0)
    with pytest.raises(ModelError, match="positive integer"):
        segment_profile(prof, n_segments=0)
    with pytest.raises(ModelError, match="no segmentation"):
        segment_profile(prof, max_error_mm2_per_mm=1e-6, max_segments=5)


def test_to_dict_units():
    seg = segment_profile(_fine_arc(0.1, 1.0), n_segments=3)
    d = seg.to_dict()
    assert d["n_segments"] == 3
    assert len(d["points_x_m"]) == 4
    assert d["error_mm2_per_mm"] == pytest.approx(seg.error)
