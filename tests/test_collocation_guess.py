"""Initial guesses of a periodic stride (template, measured trial, forward simulation)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bladelab.datasets import measured_running_trial, measured_static_trial
from bladelab.errors import SpecError
from bladelab.predict.collocation.guess import (
    guess_from_reflex,
    guess_from_trial,
    template_guess,
)
from bladelab.runner import build_runner
from bladelab.runner.layout import CP_BLADE, CP_LEG
from bladelab.runner.model import contact_heights

SOLUTIONS = Path(__file__).resolve().parents[1] / "src/bladelab/data/runner/reflex-starts"


@pytest.fixture(scope="module")
def able():
    return build_runner("able")


def _check_periodic(model, g, speed):
    assert g.speed == pytest.approx(speed, rel=1e-9)
    # periodic: the last node is the first one period later (pelvis advanced by the stride)
    advance = np.zeros(g.q.shape[1])
    advance[model.dof("pelvis_tx")] = speed * g.period
    np.testing.assert_allclose(g.q[-1], g.q[0] + advance, atol=1e-9)
    np.testing.assert_allclose(g.qd[-1], g.qd[0], atol=1e-9)


def _check_stride(model, g, speed):
    _check_periodic(model, g, speed)
    # the pelvis is placed so that the lowest contact point touches the ground at every node
    lowest = np.array([contact_heights(model, q).min() for q in g.q])
    np.testing.assert_allclose(lowest, 0.0, atol=1e-9)


def _leg_heights(model, g):
    """Lowest contact point of each leg [m] at every node, shape (n + 1, 2)."""
    legs = model.contact_params[:, CP_LEG]
    return np.array([[contact_heights(model, q)[legs == leg].min() for leg in (0, 1)]
                     for q in g.q])


@pytest.mark.parametrize("kind", ["able", "amputee", "transfemoral"])
def test_template_runs_forwards_on_its_stance_feet(kind):
    """The template's kinematic stances are its force pattern's: the loaded foot is on the
    ground while its hip extends; between the stances the runner flies, no foot in the ground."""
    model = build_runner(kind)
    g = template_guess(model, speed=4.0, n=40)
    _check_periodic(model, g, 4.0)
    heights = _leg_heights(model, g)
    f = g.vertical_grf_bw[:-1]
    phase = np.arange(40) / 40
    for leg, start, side in ((0, 0.0, "l"), (1, 0.5, "r")):
        stance = (np.mod(phase - start, 1.0) < 0.3) & (f > 0)
        assert stance.sum() >= 8
        np.testing.assert_allclose(heights[:-1][stance, leg], 0.0, atol=1e-9)
        hip = g.q[:-1, model.dof(f"hip_flexion_{side}")][stance]
        assert hip[-1] < hip[0] - np.radians(30)  # the stance hip extends: running forwards
    flight = f == 0
    assert flight.sum() >= 4
    assert heights[:-1][flight].min() > -1e-9
    assert (g.q[:-1, model.dof("pelvis_tz")][flight].max()
            > g.q[:-1, model.dof("pelvis_tz")][~flight].max())


def test_the_able_template_moves_its_toes_as_their_hinge_would():
    """On a body with toe hinges the able runner's template extends the toes through each
    stance (the toe tip rising towards the ball's height as the heel rises) and lets them fall
    back in swing at the hinge's own time constant D/K; the stance foot stays on or just above
    the ground (the pelvis is not moved for the toes)."""
    model = build_runner("able", body="human")
    n, speed = 50, 3.5
    g = template_guess(model, speed=speed, n=n)
    _check_periodic(model, g, speed)
    hinge = model.params.toe_hinge
    decay = np.exp(-g.period / n * hinge.stiffness_Nm_per_rad / hinge.damping_Nms_per_rad)
    heights = _leg_heights(model, g)
    f = g.vertical_grf_bw[:-1]
    phase = np.arange(n) / n
    for leg, start, side in ((0, 0.0, "l"), (1, 0.5, "r")):
        toes = g.q[:-1, model.dof(f"mtp_angle_{side}")]
        stance = (np.mod(phase - start, 1.0) < 0.3) & (f > 0)
        assert toes.min() >= 0.0  # never flexed
        peak = int(np.argmax(toes))
        assert np.radians(5.0) < toes[peak] < np.radians(30.0)
        assert stance[(peak - 1) % n] or stance[peak]  # the peak at toe-off
        swing = [(peak + i) % n for i in range(1, 20)]
        ratio = toes[swing[1:]] / toes[swing[:-1]]
        np.testing.assert_allclose(ratio, decay, rtol=1e-9)  # the hinge's own lag in swing
        assert heights[:-1][stance, leg].min() > -1e-9
        assert heights[:-1][stance, leg].max() < 0.012
    neutral = template_guess(model, speed=speed, n=n, toes="neutral")
    assert not neutral.q[:, model.dof("mtp_angle_l")].any()
    amputee = build_runner("amputee", body="human")  # its intact foot's toes stay at neutral
    assert not template_guess(amputee, speed=4.0, n=n).q[:, amputee.dof("mtp_angle_l")].any()
    with pytest.raises(SpecError, match="toes"):
        template_guess(model, toes="flat")


def test_template_is_people_running(able):
    g = template_guess(able, speed=4.0, n=40)
    assert g.q.shape == (41, 10) and 0.6 < g.period < 0.8
    # swing knee flexion of running (> 80°), a nearly straight knee at touch-down, and the
    # legs half a period apart
    knee = -np.degrees(g.q[:, able.dof("knee_angle_l")])
    assert knee.max() > 80 and knee[0] < 25
    right = -np.degrees(g.q[:, able.dof("knee_angle_r")])
    np.testing.assert_allclose(np.roll(right[:-1], -20), knee[:-1], atol=1e-9)
    with pytest.raises(SpecError, match="speed"):
        template_guess(able, speed=0.0)
    # its force pattern: alternating half-sine stances carrying one body weight on average,
    # shorter and higher when faster
    f = g.vertical_grf_bw
    assert f.shape == (41,) and np.trapezoid(f, dx=1 / 40) == pytest.approx(1.0, rel=0.02)
    assert f[0] == 0.0 and f[20] == 0.0 and f[5] > 2.2 and f[25] > 2.2
    slower = template_guess(able, speed=3.0, n=40)
    assert slower.period > g.period and slower.vertical_grf_bw.max() < f.max()


def test_resampling_keeps_the_stride(able):
    g = template_guess(able, speed=3.5, n=50)
    back = g.resample(100).resample(50)
    assert np.abs(back.q - g.q).max() < 1e-3
    assert back.speed == pytest.approx(3.5)
    faster = g.with_speed(4.5)
    assert faster.speed == pytest.approx(4.5) and faster.period == g.period
    np.testing.assert_allclose(g.resample(100).vertical_grf_bw[::2], g.vertical_grf_bw,
                               atol=1e-12)


def test_guess_from_the_fukuchi_trial(able):
    g = guess_from_trial(able, measured_running_trial(),
                         static=measured_static_trial(), speed=3.5, n=50)
    _check_stride(able, g, 3.5)
    # 3.5 m/s treadmill running: stride ~0.70 s (the force platforms' touch-downs); knee
    # nearly straight at touch-down, flexed > 90° in swing
    assert 0.65 < g.period < 0.75 and "41 left-leg cycles" in g.source
    knee = -np.degrees(g.q[:, able.dof("knee_angle_l")])
    assert knee[0] < 25 and knee.max() > 90
    # the measured force, in body weights: mean 1 over the stride, peaks 2.3–2.6 BW, two
    # stances with flight between them
    f = g.vertical_grf_bw
    assert np.trapezoid(f, dx=1 / 50) == pytest.approx(1.0, rel=0.02)
    assert 2.3 < f.max() < 2.7 and (f < 0.05).sum() > 10
    # the horizontal force: no net impulse over a stride at the treadmill's constant speed;
    # each stance brakes first (negative) and propels last; none in flight
    fx = g.horizontal_grf_bw
    assert fx.shape == f.shape and abs(np.mean(fx[:-1])) < 0.02
    stance = f > 0.3
    first = np.flatnonzero(stance & ~np.roll(stance, 1))
    last = np.flatnonzero(stance & ~np.roll(stance, -1))
    assert len(first) == len(last) == 2
    for a, b in zip(first, last, strict=True):
        assert fx[a + 1: a + 4].mean() < -0.1 and fx[b - 3: b].mean() > 0.1
    assert np.abs(fx[f < 0.01]).max() < 0.02
    np.testing.assert_allclose(g.resample(100).horizontal_grf_bw[:-1:2], fx[:-1], atol=1e-12)
    with pytest.raises(SpecError, match="running speed"):
        guess_from_trial(able, measured_running_trial())


def test_guess_from_a_reflex_start():
    g = guess_from_reflex(SOLUTIONS / "able-3.5.json", n=30, duration=3.0)
    assert g.q.shape == (31, 10) and g.activation.shape == (31, 24)
    assert abs(g.speed - 3.5) < 0.2 and 0.6 < g.period < 0.85
    assert g.activation.min() >= 0.01 - 1e-12 and g.activation.max() <= 1.0
    assert g.tendon_force.min() >= 0.0 and g.tendon_force.max() < 2.0
    assert np.trapezoid(g.vertical_grf_bw, dx=1 / 30) == pytest.approx(1.0, rel=0.05)


def test_a_seed_body_guess_starts_the_toe_body(able):
    """A guess of seed 001's body (named columns) on the toe body: every coordinate and muscle
    kept by name, the toe hinges neutral; a guess of the other model kind is refused."""
    toes = build_runner("able", body="toes")
    g = template_guess(able, speed=3.5, n=20)
    n = g.q.shape[0]
    rng = np.random.default_rng(3)
    act, ft = rng.uniform(0.02, 0.5, (n, 24)), rng.uniform(0.01, 1.0, (n, 24))
    named = g.__class__(**{**g.__dict__, "activation": act, "tendon_force": ft,
                           "dof_names": able.dof_names, "muscle_names": able.muscle_names})
    on = named.on_model(toes)
    assert on.q.shape == (n, len(toes.dof_names)) and on.dof_names is None
    for j, name in enumerate(toes.dof_names):
        if name.startswith("mtp_angle"):
            assert not on.q[:, j].any() and not on.qd[:, j].any()
        else:
            np.testing.assert_array_equal(on.q[:, j], g.q[:, able.dof(name)])
            np.testing.assert_array_equal(on.qd[:, j], g.qd[:, able.dof(name)])
    np.testing.assert_array_equal(on.activation, act)  # same muscles, same order
    np.testing.assert_array_equal(on.tendon_force, ft)
    assert named.on_model(able).q is g.q  # already the model's own columns
    with pytest.raises(SpecError, match="not in the amputee model"):
        named.on_model(build_runner("amputee"))
    with pytest.raises(SpecError, match="coordinates"):
        g.on_model(toes)  # unnamed columns of another model


def test_the_transfemoral_template_keeps_the_passive_knee_straight_in_stance():
    """The prosthetic knee cannot be driven: the template holds it at 5° through its stance
    (the right leg lands half a stride after the left) and flexes it in swing only."""
    from bladelab.predict.collocation.guess import template_guess
    from bladelab.runner import build_runner

    runner = build_runner("transfemoral")
    g = template_guess(runner, speed=5.0, n=40)
    knee = -np.degrees(g.q[:, runner.dof("knee_angle_r")])  # flexion positive
    phase = np.mod(np.linspace(0.0, 1.0, 41) + 0.5, 1.0)  # of the right leg
    assert np.allclose(knee[phase < 0.35], 5.0)
    assert 60.0 < knee.max() < 66.0 and abs(phase[np.argmax(knee)] - 0.675) < 0.03
    intact = -np.degrees(g.q[:, runner.dof("knee_angle_l")])
    assert intact.max() > 90.0  # the intact knee keeps the running template


def test_a_sphere_stride_starts_a_multilink_blade_at_its_static_deflection():
    from bladelab.design.blade_generator import generate_blade
    from bladelab.predict.collocation.stride_guess import StrideGuess, deflected_blade

    sphere = build_runner("transfemoral")
    runner = build_runner("transfemoral", blade_model=generate_blade(
        {"stiffness_kN_per_m": 25.0}).model)
    blade = runner.contact_params[:, CP_BLADE] == 1
    joints = [runner.dof(f"blade_joint{i}") for i in range(5)]
    from bladelab.runner.model import _standing_pose

    q = np.tile(_standing_pose(sphere), (3, 1))
    q[:, sphere.dof("pelvis_tz")] += [0.0, -0.06, 0.2]  # standing, 6 cm lower, in the air
    g = StrideGuess("test", 0.5, q, np.zeros_like(q), dof_names=sphere.dof_names,
                    muscle_names=sphere.muscle_names).on_model(runner)
    undeformed = np.array([contact_heights(runner, np.where(
        np.isin(np.arange(g.q.shape[1]), joints), 0.0, row))[blade].min() for row in g.q])
    deformed = np.array([contact_heights(runner, row)[blade].min() for row in g.q])
    assert undeformed[1] < -0.05  # the undeformed links would meet the ground 5+ cm deep
    assert deformed[1] == pytest.approx(-0.01, abs=1e-4)  # the deflected blade: 1 cm
    assert np.all(g.q[2, joints] == 0.0) and np.any(g.q[1, joints] != 0.0)  # none in the air
    assert np.array_equal(deflected_blade(sphere, q), q)  # no multi-link blade: unchanged
