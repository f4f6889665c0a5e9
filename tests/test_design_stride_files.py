"""Stride file names of design points and the nearest solved designs in a folder."""

from __future__ import annotations

import math

import pytest

from bladelab.design.stride_files import (
    coded_distance,
    point_file_stem,
    point_from_stem,
    stored_neighbours,
)

RANGES = {"stiffness_kN_per_m": (18.0, 32.0), "width_m": (0.05, 0.08)}


def _point(stiffness: float, width: float) -> dict[str, float]:
    return {"stiffness_kN_per_m": stiffness, "width_m": width}


def test_a_point_survives_its_file_name():
    point = _point(18.0, 0.065)
    assert point_from_stem(point_file_stem(point)) == point
    assert point_from_stem("not-a-point") is None


def test_the_coded_distance_counts_each_half_range_as_one():
    centre, corner = _point(25.0, 0.065), _point(32.0, 0.08)
    assert coded_distance(centre, corner, RANGES) == pytest.approx(math.sqrt(2))
    assert coded_distance(centre, _point(18.0, 0.065), RANGES) == pytest.approx(1.0)
    # a factor without a range is measured relative to its value
    assert coded_distance({"x": 2.0}, {"x": 3.0}, {}) == pytest.approx(0.5)
    assert coded_distance(centre, {"width_m": 0.065}, RANGES) == math.inf


def test_the_neighbours_come_nearest_first_without_the_point_itself(tmp_path):
    points = [_point(25.0, 0.065), _point(32.0, 0.08), _point(18.0, 0.065), _point(25.0, 0.07)]
    for p in points:
        (tmp_path / f"{point_file_stem(p)}.json").write_text("{}")
    (tmp_path / f"{point_file_stem(points[1])}.previous.json").write_text("{}")
    (tmp_path / f"{point_file_stem(points[2])}.best_iterate.json").write_text("{}")
    (tmp_path / "notes.json").write_text("{}")
    found = stored_neighbours(tmp_path, points[0], RANGES)
    assert [f.name for f in found] == [f"{point_file_stem(p)}.json"
                                       for p in (points[3], points[2], points[1])]
    assert stored_neighbours(tmp_path / "missing", points[0], RANGES) == []
