"""Profiles: parametric elements against circle geometry, CSV import and its errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.blade.profile import (
    Profile,
    ProfileElement,
    find_self_intersections,
    profile_from_elements,
    read_profile_csv,
)
from bladelab.errors import DataError, InputFileError, ModelError


def test_straight_line_goes_down_the_pylon_axis():
    p = profile_from_elements([ProfileElement(0.3)])
    np.testing.assert_allclose(p.points[-1], [0.0, -0.3], atol=1e-15)
    assert p.length == pytest.approx(0.3)
    assert p.height == pytest.approx(0.3)


def test_quarter_arc_matches_circle_geometry():
    r = 0.1
    # Going down, a positive turn of 90 deg bends forward (+x): centre at (r, 0).
    p = profile_from_elements([ProfileElement(r * math.pi / 2, math.pi / 2)])
    np.testing.assert_allclose(p.points[-1], [r, -r], atol=1e-12)
    dist = np.hypot(p.points[:, 0] - r, p.points[:, 1])
    np.testing.assert_allclose(dist, r, atol=1e-12)
    # The polyline is made of chords, slightly shorter than the arc.
    assert p.length == pytest.approx(r * math.pi / 2, rel=1e-5)
    assert p.lowest_point[1] == pytest.approx(-r)
    assert p.toe_length == pytest.approx(r)


def test_negative_turn_bends_backward():
    p = profile_from_elements([ProfileElement(0.1, -math.pi / 2)])
    assert p.points[-1, 0] < -0.05
    assert np.all(p.points[:, 0] <= 1e-15)


def test_line_then_arc_heading_continues():
    p = profile_from_elements([ProfileElement(0.1), ProfileElement(0.05 * math.pi, math.pi)],
                              start_heading=-math.pi / 2)
    # U-turn of radius 0.05 after 0.1 m down: ends at (0.1, -0.1), heading up.
    np.testing.assert_allclose(p.points[-1], [0.1, -0.1], atol=1e-12)
    assert p.height == pytest.approx(0.15, abs=1e-6)


def test_bad_element_and_profile():
    with pytest.raises(ModelError, match="length must be positive"):
        profile_from_elements([ProfileElement(-0.1)])
    with pytest.raises(ModelError, match="at least two points"):
        Profile(np.array([[0.0, 0.0]]))
    with pytest.raises(ModelError, match="repeated"):
        Profile(np.array([[0.0, 0.0], [0.0, 0.0], [0.0, -1.0]]))


def test_csv_in_m_and_mm_agree(tmp_path):
    pts = np.array([[0.0, 0.0], [0.01, -0.2], [0.05, -0.4], [0.2, -0.42]])
    a = tmp_path / "m.csv"
    a.write_text("# from CAD\nx_m,z_m\n" + "\n".join(f"{x},{z}" for x, z in pts) + "\n")
    b = tmp_path / "mm.csv"
    b.write_text("x_mm, z_mm\n" + "\n".join(f"{x * 1e3},{z * 1e3}" for x, z in pts) + "\n")
    pa, pb = read_profile_csv(a), read_profile_csv(b)
    np.testing.assert_allclose(pa.points, pts)
    np.testing.assert_allclose(pb.points, pts)
    assert pa.name == "m.csv"


@pytest.mark.parametrize(
    ("text", "error", "match"),
    [
        ("x,z\n0,0\n0,-1\n", InputFileError, "missing columns"),
        ("x_m,z_m\n0,0\n", DataError, "at least two points"),
        ("x_m,z_m\n0,0\nabc,-1\n", DataError, "non-numeric"),
        ("x_m,z_m\n0,0\n0,\n", DataError, "missing value"),
        ("x_m,z_m\n0,0\n0,-0.1\n0,-0.1\n0.1,-0.2\n", DataError, "same point"),
        # a figure eight
        ("x_m,z_m\n0,0\n0.1,-0.1\n0.1,0\n0,-0.1\n", DataError, "intersects itself"),
    ],
)
def test_csv_errors_name_the_file(tmp_path, text, error, match):
    f = tmp_path / "bad.csv"
    f.write_text(text)
    with pytest.raises(error, match=match) as info:
        read_profile_csv(f)
    assert "bad.csv" in str(info.value)


def test_csv_missing_file(tmp_path):
    with pytest.raises(InputFileError, match="not found"):
        read_profile_csv(tmp_path / "none.csv")


def test_self_intersections():
    simple = np.array([[0, 0], [0, -1], [1, -1], [1, 0]], float)
    assert find_self_intersections(simple) == []
    cross = np.array([[0, 0], [1, -1], [1, 0], [0, -1]], float)
    assert find_self_intersections(cross) == [(0, 2)]
    fold = np.array([[0, 0], [0, -1], [0, -0.5]], float)
    assert find_self_intersections(fold) == [(0, 1)]
    touch = np.array([[0, 0], [0, -1], [1, -1], [0, -0.5]], float)  # ends on piece 0
    assert (0, 2) in find_self_intersections(touch)
