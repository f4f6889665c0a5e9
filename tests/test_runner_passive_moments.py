"""Passive joint moments of the runner's muscles against people's (Riener & Edrich 1999)."""

from __future__ import annotations

import math

import pytest

from bladelab.runner import build_runner
from bladelab.runner.passive_moments import (
    leg_muscle_forces,
    passive_flexion_moment,
    riener_edrich_hip_moment,
    riener_edrich_knee_moment,
)


def test_riener_edrich_formulas_at_hand_computed_poses():
    """Typed from the paper's fit (degrees): knee at 90° flexion, hip and ankle at 0°, and the
    hip at 20° of extension with a straight knee."""
    knee = math.exp(1.800 - 0.0352 * 90) - math.exp(-3.971 + 0.0495 * 90) - 4.820
    assert riener_edrich_knee_moment(90, 0) == pytest.approx(knee + math.exp(2.220 - 135.0))
    assert riener_edrich_knee_moment(90, 0) == pytest.approx(-6.19, abs=0.01)
    assert riener_edrich_hip_moment(0, -20) == pytest.approx(
        math.exp(1.4655 + 1.5) - math.exp(1.3403 - 0.61) + 8.072)


def test_human_body_passive_knee_and_flexed_hip_moments_are_people_s():
    """The human body's passive knee moment at 60–90° of flexion and the hip's at 60° of
    flexion are within 5 N·m of people's; seed 001's body resists 90° of knee flexion with ten
    times people's moment (the reason the human body's passive curve is softer)."""
    human = build_runner("able", body="human")
    for knee, hip in ((60, 0), (90, 0), (90, 30)):
        model = passive_flexion_moment(human, "knee", knee_deg=knee, hip_deg=hip)
        assert model == pytest.approx(riener_edrich_knee_moment(knee, hip), abs=5.0), (knee, hip)
    hip_model = passive_flexion_moment(human, "hip", knee_deg=0, hip_deg=60)
    assert hip_model == pytest.approx(riener_edrich_hip_moment(0, 60), abs=5.0)
    seed = build_runner("able")
    assert passive_flexion_moment(seed, "knee", knee_deg=90, hip_deg=0) < 8 * (
        riener_edrich_knee_moment(90, 0))


def test_passive_flexion_moment_refuses_another_joint():
    with pytest.raises(ValueError, match="joint must be 'knee' or 'hip'"):
        passive_flexion_moment(build_runner("able"), "ankle", knee_deg=0, hip_deg=0)


def test_leg_muscle_forces_act_on_the_joints_they_cross():
    """On the knee at 45° of flexion: the hip-only muscles act not at all, the vasti extend it
    (knee_angle = −flexion, so a positive generalised force), more at full activation than
    passive; the monoarticular knee flexor flexes it."""
    runner = build_runner("able", body="human")
    q = runner.stand_qpos.copy()
    q[runner.dof("knee_angle_l")] = math.radians(-45.0)
    passive = leg_muscle_forces(runner, "knee_angle_l", q, activation=0.0)
    active = leg_muscle_forces(runner, "knee_angle_l", q, activation=1.0)
    assert abs(active["glut_max"]) < 1e-6 and abs(active["iliopsoas"]) < 1e-6
    assert active["vasti"] > passive["vasti"] >= 0.0 and active["vasti"] > 100.0
    assert active["bifemsh"] < 0.0
