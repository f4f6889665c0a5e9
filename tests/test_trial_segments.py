"""Segment lengths from a static trial: a pelvis built around known joint centres, a residual
limb, a missing landmark, and the Fukuchi subject's static trial."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.errors import DataError
from bladelab.trial import Trial, read_c3d
from bladelab.trial.segments import SegmentMarkerMap, segment_lengths
from conftest import FUKUCHI_STATIC as STATIC


def _standing(pw=0.24, pd=0.16, tilt_deg=12.0, thigh=0.42, shank=0.41, frames=5,
              ankle_right=True) -> Trial:
    """Markers of a person standing with the pelvis tilted forward by ``tilt_deg`` about the
    lateral axis and the hip joint centres where Harrington et al.'s regression puts them:
    knee and ankle joint centres straight below them (lab x forward, y left, z up)."""
    t = math.radians(tilt_deg)
    x = np.array([math.cos(t), 0.0, -math.sin(t)])  # anterior, tilted down
    z = np.array([0.0, -1.0, 0.0])  # to the right
    y = np.cross(z, x)  # superior
    origin = np.array([0.1, 0.0, 1.0])  # the ASIS' midpoint
    markers = {"L.ASIS": origin - 0.5 * pw * z, "R.ASIS": origin + 0.5 * pw * z,
               "L.PSIS": origin - pd * x - 0.04 * z, "R.PSIS": origin - pd * x + 0.04 * z}
    ax = (-0.24 * pd * 1000 - 9.9) / 1000
    ay = (-0.30 * pw * 1000 - 10.9) / 1000
    az = (0.33 * pw * 1000 + 7.3) / 1000
    for side, sign in (("L", -1.0), ("R", 1.0)):
        hip = origin + ax * x + ay * y + sign * az * z
        knee = hip - np.array([0.0, 0.0, thigh])
        ankle = knee - np.array([0.0, 0.0, shank])
        markers[f"{side}.Knee"] = knee + sign * 0.05 * z
        markers[f"{side}.Knee.Medial"] = knee - sign * 0.05 * z
        if side == "L" or ankle_right:
            markers[f"{side}.Ankle"] = ankle + sign * 0.035 * z
            markers[f"{side}.Ankle.Medial"] = ankle - sign * 0.035 * z
    rng = np.random.default_rng(0)
    noisy = {k: v + rng.normal(0.0, 1e-4, (frames, 3)) for k, v in markers.items()}
    for v in noisy.values():
        v[-1] = np.nan  # a gap in the last frame: left out of the mean
    return Trial(markers=noisy, marker_rate=100.0)


def test_the_lengths_of_a_standing_person_built_around_known_joint_centres():
    got = segment_lengths(_standing())
    for side in ("left", "right"):
        assert got.thigh_m[side] == pytest.approx(0.42, abs=5e-4)
        assert got.shank_m[side] == pytest.approx(0.41, abs=5e-4)
    assert got.pelvic_width_m == pytest.approx(0.24, abs=5e-4)
    assert got.pelvic_depth_m == pytest.approx(0.16, abs=5e-4)
    # another pelvis tilt and size: the regression follows the pelvis, not the lab
    other = segment_lengths(_standing(pw=0.20, pd=0.19, tilt_deg=-5.0, thigh=0.47))
    assert other.thigh_m["left"] == pytest.approx(0.47, abs=5e-4)


def test_a_residual_limb_has_its_thigh_and_no_shank():
    got = segment_lengths(_standing(ankle_right=False))
    assert got.thigh_m["right"] == pytest.approx(0.42, abs=5e-4)
    assert math.isnan(got.shank_m["right"]) and got.shank_m["left"] == pytest.approx(0.41,
                                                                                     abs=5e-4)


def test_a_missing_pelvis_landmark_is_named():
    trial = _standing()
    del trial.markers["R.PSIS"]
    with pytest.raises(DataError, match="R.PSIS"):
        segment_lengths(trial)
    renamed = SegmentMarkerMap(psis="{side}_PSIS")
    with pytest.raises(DataError, match="L_PSIS"):
        segment_lengths(_standing(), renamed)


def test_the_fukuchi_subject_s_segments():
    """RBDS001 (1.81 m): thighs and shanks within a centimetre of each other side to side, in
    the range of a 1.81 m adult (Winter's ratios 0.245 and 0.246 of the height: 0.44 m)."""
    got = segment_lengths(read_c3d(STATIC))
    for part in (got.thigh_m, got.shank_m):
        assert abs(part["left"] - part["right"]) < 0.01
        assert all(0.38 < v < 0.50 for v in part.values())
    assert 0.18 < got.pelvic_width_m < 0.30
