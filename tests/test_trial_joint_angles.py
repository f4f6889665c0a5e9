"""Sagittal joint angles from markers and the leg of each stance, on the real Fukuchi trial."""

from __future__ import annotations

import dataclasses

import ezc3d
import numpy as np
import pytest

from bladelab.errors import DataError, InputFileError, SpecError
from bladelab.trial import combined_grf, detect_stances
from bladelab.trial.joint_angles import (
    JointMarkerMap,
    load_joint_marker_map,
    sagittal_angles,
    stance_legs,
)
from conftest import FUKUCHI_RUN as RUN
from conftest import FUKUCHI_STATIC as STATIC


@pytest.fixture(scope="module")
def trials(fukuchi_trials):
    return fukuchi_trials


def _raw_sagittal(path, names):
    """Marker coordinates straight from the file with ezc3d: (frames, 2) of (forward, up).

    The Fukuchi files have x forward and y up (a treadmill lab frame), so the sagittal plane is
    the file's x–y plane."""
    c = ezc3d.c3d(str(path))
    labels = c["parameters"]["POINT"]["LABELS"]["value"]
    pts = c["data"]["points"]
    xyz = np.mean([pts[:3, labels.index(n), :].T for n in names], axis=0) / 1000.0
    return xyz[:, [0, 1]]


def _hand_knee(path, side):
    """Knee flexion by hand: the angle between the thigh and shank cluster axes in the sagittal
    plane from the dot product (arccos), signed by the 2-D cross product."""
    s = side
    thigh = (_raw_sagittal(path, [f"{s}.Thigh.Bottom.Lateral", f"{s}.Thigh.Bottom.Medial"])
             - _raw_sagittal(path, [f"{s}.Thigh.Top.Lateral", f"{s}.Thigh.Top.Medial"]))
    shank = (_raw_sagittal(path, [f"{s}.Shank.Bottom.Lateral", f"{s}.Shank.Bottom.Medial"])
             - _raw_sagittal(path, [f"{s}.Shank.Top.Lateral", f"{s}.Shank.Top.Medial"]))
    dot = np.sum(thigh * shank, axis=1)
    norm = np.linalg.norm(thigh, axis=1) * np.linalg.norm(shank, axis=1)
    cross = shank[:, 0] * thigh[:, 1] - shank[:, 1] * thigh[:, 0]  # shank -> thigh, counter-clockwise
    return np.sign(cross) * np.arccos(np.clip(dot / norm, -1.0, 1.0))


def test_knee_angle_equals_hand_computation(trials):
    """Unfiltered module angle = hand vector maths on the raw file coordinates, minus the
    static trial's mean (a few frames across the trial, both legs)."""
    run, static = trials
    ja = sagittal_angles(run, static=static, cutoff_hz=None)
    frames = [37, 512, 1999, 4321]
    for side, s in (("right", "R"), ("left", "L")):
        raw = _hand_knee(RUN, s)
        offset = float(np.mean(_hand_knee(STATIC, s)))
        assert ja.offsets[f"knee_{side}"] == pytest.approx(offset, abs=1e-9)
        np.testing.assert_allclose(ja.angles[f"knee_{side}"][frames], raw[frames] - offset,
                                   atol=1e-9)
    # flexion is positive: the running knee spends most of the cycle flexed
    assert np.median(ja.angles["knee_right"]) > np.radians(20)


def test_static_trial_reads_zero(trials):
    _, static = trials
    ja = sagittal_angles(static, static=static, cutoff_hz=None)
    for name, a in ja.angles.items():
        assert abs(np.mean(a)) < 1e-12, name


def test_filter_changes_little(trials):
    """The 20 Hz marker filter removes noise, not the motion (3.5 m/s running)."""
    run, static = trials
    raw = sagittal_angles(run, static=static, cutoff_hz=None).angles["knee_right"]
    filt = sagittal_angles(run, static=static).angles["knee_right"]
    assert np.degrees(np.sqrt(np.mean((raw - filt) ** 2))) < 1.5


def test_stance_legs_alternate_and_match_the_grounded_foot(trials):
    """Running alternates legs; at mid-stance the stance foot is the lower one (its heel is
    on the belt, the other foot swings), and right stances lie to the right (lab y is left)."""
    run, _ = trials
    stances = detect_stances(run)
    legs = stance_legs(run, stances)
    assert all(a != b for a, b in zip(legs[:-1], legs[1:], strict=True))
    cop_y = {"left": [], "right": []}
    for ev, leg in zip(stances, legs, strict=True):
        frame = int(round(0.5 * (ev.start_s + ev.end_s) * run.marker_rate))
        heel = {s: run.marker(f"{s[0].upper()}.Heel.Bottom")[frame, 2] for s in ("left", "right")}
        other = "left" if leg == "right" else "right"
        assert heel[leg] < heel[other], ev.index
        _, cop = combined_grf(run, ev.plates)
        cop_y[leg].append(cop[(ev.start_sample + ev.end_sample) // 2, 1])
    assert np.mean(cop_y["right"]) < np.mean(cop_y["left"])


def test_missing_marker_names_file_and_marker(trials):
    run, _ = trials
    markers = dict(run.markers)
    del markers["R.Shank.Top.Medial"]
    broken = dataclasses.replace(run, markers=markers)
    with pytest.raises(DataError) as info:
        sagittal_angles(broken)
    msg = str(info.value)
    assert "R.Shank.Top.Medial" in msg and "RBDS001runT35.c3d" in msg and "shank_proximal" in msg


def test_marker_map_yaml(tmp_path):
    path = tmp_path / "map.yaml"
    path.write_text("side_prefix: {left: LT, right: RT}\n"
                    "right:\n  shank_distal: [CLAMP_ANT, CLAMP_POST]\n  contact: BLADE_TIP\n")
    m = load_joint_marker_map(path)
    assert m.names("shank_distal", "right") == ("CLAMP_ANT", "CLAMP_POST")
    assert m.names("contact", "right") == ("BLADE_TIP",)
    assert m.names("shank_distal", "left") == ("LT.Shank.Bottom.Lateral", "LT.Shank.Bottom.Medial")
    assert m.names("pelvis_anterior") == JointMarkerMap().pelvis_anterior
    path.write_text("right:\n  knee: [X]\n")
    with pytest.raises(SpecError, match="knee"):
        load_joint_marker_map(path)
    path.write_text("thigh: [X]\n")
    with pytest.raises(SpecError):
        load_joint_marker_map(path)
    with pytest.raises(InputFileError):
        load_joint_marker_map(tmp_path / "none.yaml")


def test_side_without_foot_markers_has_no_ankle(trials):
    """An amputee's prosthetic side: no foot roles, contact from other markers."""
    run, static = trials
    m = JointMarkerMap(right={"foot_anterior": (), "foot_posterior": (),
                              "contact": ("R.Shank.Bottom.Lateral",)})
    ja = sagittal_angles(run, markers=m, static=static)
    assert "ankle_right" not in ja.angles and "ankle_left" in ja.angles
    full = sagittal_angles(run, static=static)
    np.testing.assert_allclose(ja.angles["knee_right"], full.angles["knee_right"])
