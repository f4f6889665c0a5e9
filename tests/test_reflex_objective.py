"""Objective of seed 001 eq. 2.4–2.9 and the closed-loop simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.predict.reflex.controller import controller_layout
from bladelab.predict.reflex.objective import ObjectiveSettings, _evaluate, simulate_controlled
from bladelab.runner import build_runner


@pytest.fixture(scope="module")
def able():
    model = build_runner("able")
    return model, controller_layout(model)


def _td(times, speed, legs=None, struck=(), strike_bw=1.0):
    """Steps (time [s], pelvis x [m], leg, strike peak [BW]) at a constant speed, legs
    alternating; the steps in ``struck`` are struck with a peak of ``strike_bw``."""
    legs = [i % 2 for i in range(len(times))] if legs is None else legs
    return np.array([[t, speed * t, leg, strike_bw if i in struck else 0.0]
                     for i, (t, leg) in enumerate(zip(times, legs, strict=True))])


def test_gait_measure_by_hand():
    s = ObjectiveSettings(speed=3.5, speed_tolerance=0.1, duration=10.0)
    acc = np.zeros(4)
    # steps every 0.35 s at exactly 3.5 m/s up to 9.8 s: every step counts fully
    ev = _evaluate(s, acc, _td(np.arange(1, 29) * 0.35, 3.5), 10.0, 35.0, False, 80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0 - 9.8 / 10.0)
    # steps at 3.0 m/s: Psi = 3.4 - 3.0 = 0.4, each step weighs 0.6
    ev = _evaluate(s, acc, _td(np.arange(1, 29) * 0.35, 3.0), 10.0, 30.0, False, 80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0 - 0.6 * 9.8 / 10.0)
    # too fast by more than 1 m/s: no credit
    ev = _evaluate(s, acc, _td([0.5, 1.0], 5.0), 1.0, 5.0, True, 80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0)
    assert ev.cost == pytest.approx(100.0 * 1.0)


def test_gait_measure_gives_no_credit_to_a_gallop():
    s = ObjectiveSettings(speed=3.5, speed_tolerance=0.1, duration=10.0)
    acc = np.zeros(4)
    times = np.arange(1, 29) * 0.35  # 28 steps at 3.5 m/s
    gallop = [(0, 1, 1)[i % 3] for i in range(28)]  # left, right, right, left, right, right...
    # hand count: steps 3, 6, ..., 27 (1-based) repeat the leg before them: 9 steps of 0.35 s
    ev = _evaluate(s, acc, _td(times, 3.5, gallop), 10.0, 35.0, False, 80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0 - (9.8 - 9 * 0.35) / 10.0)
    # a step during which the other foot struck the ground with 1 BW (strike_limit_bw) or
    # more earns nothing either (2 of 28)
    ev = _evaluate(s, acc, _td(times, 3.5, struck=(4, 10)), 10.0, 35.0, False, 80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0 - (9.8 - 2 * 0.35) / 10.0)
    ev = _evaluate(s, acc, _td(times, 3.5, struck=(4, 10), strike_bw=1.7), 10.0, 35.0, False,
                   80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0 - (9.8 - 2 * 0.35) / 10.0)
    # a lighter strike (0.25 BW) costs a quarter of the step's credit
    ev = _evaluate(s, acc, _td(times, 3.5, struck=(4, 10), strike_bw=0.25), 10.0, 35.0, False,
                   80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0 - (9.8 - 2 * 0.25 * 0.35) / 10.0)
    # strike_limit_bw = 0: any strike cancels the step's credit
    strict = ObjectiveSettings(speed=3.5, duration=10.0, strike_limit_bw=0.0)
    ev = _evaluate(strict, acc, _td(times, 3.5, struck=(4, 10), strike_bw=0.25), 10.0, 35.0,
                   False, 80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0 - (9.8 - 2 * 0.35) / 10.0)
    # the seed's measure counts every step
    seed = ObjectiveSettings(speed=3.5, duration=10.0, alternating_steps=False)
    ev = _evaluate(seed, acc, _td(times, 3.5, gallop), 10.0, 35.0, False, 80.0, 0.0)
    assert ev.j_gait == pytest.approx(1.0 - 9.8 / 10.0)


def test_cost_terms_and_weights_by_hand():
    s = ObjectiveSettings(speed=3.5, duration=2.0)
    # energy 1600 J, 80 kg, 7 m: J_cot = 1600/(80*7); penalties accumulated as integral * s
    acc = np.array([1600.0, 30.0, 4.0, 0.0])
    ev = _evaluate(s, acc, np.zeros((0, 4)), 2.0, 7.0, False, 80.0, 0.0)
    assert ev.j_cot == pytest.approx(1600 / 560)
    assert ev.j_inj == pytest.approx(15.0)
    assert ev.j_lean == pytest.approx(2.0)
    assert ev.j_gait == pytest.approx(1.0)
    assert ev.cost == pytest.approx(0.1 * 1600 / 560 + 100.0 + 0.1 * 15 + 0.1 * 2)


def test_simulation_is_deterministic_and_stops_when_fallen(able):
    model, layout = able
    s = ObjectiveSettings(duration=3.0)
    e1, res = simulate_controlled(model, layout.x0, layout=layout, settings=s, record_every=1)
    e2, _ = simulate_controlled(model, layout.x0, layout=layout, settings=s)
    assert e1 == e2
    # SCONE's walking parameters do not run at 3.5 m/s: the model falls, the run stops early
    assert e1.fell and e1.duration < 3.0 and res.fell
    assert res.time[-1] == pytest.approx(e1.duration)
    assert res.qpos[-1, model.dof("pelvis_tz")] < 0.6 * model.stand_qpos[model.dof("pelvis_tz")]
    assert e1.j_gait > 1.0 - e1.duration / 3.0 - 1e-9


def test_lean_penalty_recomputed_from_recorded_states(able):
    model, layout = able
    s = ObjectiveSettings(duration=0.5, squared_penalty=0.5)
    ev, res = simulate_controlled(model, layout.x0, layout=layout, settings=s, record_every=1)
    tilt = np.degrees(res.qpos[:, model.dof("pelvis_tilt")])
    err = np.where(tilt < -16.0, -16.0 - tilt, np.where(tilt > -2.0, tilt + 2.0, 0.0))
    expected = np.sum(err + 0.5 * err**2) * s.dt / ev.duration
    assert expected > 0
    assert ev.j_lean == pytest.approx(expected, rel=1e-9)
    # distance and speed from the recorded pelvis
    x = res.qpos[:, model.dof("pelvis_tx")]
    assert ev.distance == pytest.approx(x[-1] - x[0])
    assert math.isfinite(ev.j_cot) and ev.j_cot > 0


def test_wrong_parameter_count_is_an_error(able):
    from bladelab.errors import SimulationError

    model, layout = able
    with pytest.raises(SimulationError, match="controller parameters"):
        simulate_controlled(model, layout.x0[:-1], layout=layout)


def test_online_steps_match_the_offline_count_and_scone_rules():
    # the objective's online step count (runner.closed_loop) and runner.analyses.step_touchdowns
    # (offline) agree on a force record with a bounce, a scuff and alternating stances
    from bladelab.predict.reflex.closed_loop import STEP_STATE_SIZE, _count_touchdowns
    from bladelab.runner.analyses import step_touchdowns

    dt, bw = 2.5e-4, 700.0
    t = np.arange(0.0, 2.0, dt)
    force = np.zeros((len(t), 2))
    for leg, a, b, f in ((0, 0.10, 0.30, 1800.0), (1, 0.45, 0.62, 1800.0),
                         (0, 0.80, 1.0, 1800.0), (1, 1.15, 1.35, 1800.0),
                         (1, 1.42, 1.45, 300.0),  # a scuff 0.27 s after the last step
                         (0, 1.50, 1.52, 50.0),  # a touch below 0.1 BW (70 N)
                         (0, 1.60, 1.80, 1800.0)):
        force[(t >= a) & (t < b), leg] = f
    force[(t >= 0.15) & (t < 0.17), 0] = 0.0  # a bounce: back 70 ms after the step
    # the swinging right foot strikes at 0.86 s, its force rising to 1200 N at 0.93 s, after
    # the 0.1 s window: the peak counts to the end of the strike
    strike = (t >= 0.86) & (t < 0.94)
    force[strike, 1] = np.minimum(500.0 + 1e4 * (t[strike] - 0.86), 1200.0)
    cp = np.zeros((2, 13))
    cp[1, 6] = 1.0  # contact 0 on the left leg, contact 1 on the right
    crec = np.zeros((2, 7))
    steps = np.zeros(STEP_STATE_SIZE)
    steps[2], steps[3] = -1e9, -1.0
    acc, td = np.zeros(4), np.zeros((50, 4))
    for k in range(len(t)):
        crec[:, 1] = force[k - 1] if k else 0.0  # the previous step's forces, as in the loop
        _count_touchdowns(t[k], 3.5 * t[k], crec, cp, bw, steps, acc, td)
    online = td[: int(acc[3])]
    offline = np.array(step_touchdowns(t, force, bw), dtype=float)
    np.testing.assert_allclose(online[:, 0], offline[:, 0], atol=1e-12)
    np.testing.assert_array_equal(online[:, 2], offline[:, 1])
    np.testing.assert_allclose(online[:, 3], offline[:, 2], rtol=1e-12)
    # by hand: the bounce (back within 0.1 s) and the 50 N touch are not steps, the scuff is;
    # the strike 60 ms after the left step at 0.8 s marks that step with its peak
    assert online[:, 2].tolist() == [0, 1, 0, 1, 1, 0]
    peak = force[strike, 1].max()
    assert peak > 1150.0
    np.testing.assert_allclose(online[:, 3], [0, 0, peak / bw, 0, 0, 0], rtol=1e-12)
    np.testing.assert_allclose(online[:, 0], [0.1, 0.45, 0.8, 1.15, 1.42, 1.6], atol=2 * dt)
    np.testing.assert_allclose(online[:, 1], 3.5 * online[:, 0])


def test_initial_speed_sets_the_starting_state_not_the_target(able):
    # the run starts moving at initial_speed (default: the prescribed speed); the gait measure
    # still judges the steps against the prescribed speed
    model, layout = able
    ix = model.dof("pelvis_tx")
    firsts = {}
    for v0 in (None, 3.0):
        s = ObjectiveSettings(speed=4.0, duration=0.05, initial_speed=v0)
        ev, res = simulate_controlled(model, layout.x0, layout=layout, settings=s, record_every=1)
        firsts[v0] = res.qvel[0, ix]
    assert firsts[None] == pytest.approx(4.0, abs=0.02)
    assert firsts[3.0] == pytest.approx(3.0, abs=0.02)


def test_a_push_changes_the_forward_speed_at_its_step_and_nothing_before(able):
    # ObjectiveSettings.push = (time [s], relative change): the pelvis's forward velocity is
    # multiplied by 1 + change at that instant; the run is the unpushed one until then
    model, layout = able
    ix = model.dof("pelvis_tx")
    plain = ObjectiveSettings(duration=0.4, dt=1e-3, integrator="implicit")
    pushed = ObjectiveSettings(duration=0.4, dt=1e-3, integrator="implicit", push=(0.2, 0.05))
    _, a = simulate_controlled(model, layout.x0, layout=layout, settings=plain, record_every=1)
    _, b = simulate_controlled(model, layout.x0, layout=layout, settings=pushed, record_every=1)
    k = int(np.searchsorted(a.time, 0.2 - 1e-9))
    assert a.time[k] == pytest.approx(0.2)
    np.testing.assert_array_equal(a.qvel[:k], b.qvel[:k])
    np.testing.assert_array_equal(a.qpos[:k + 1], b.qpos[:k + 1])
    assert b.qvel[k, ix] == pytest.approx(1.05 * a.qvel[k, ix], rel=1e-12)
    others = np.arange(a.qvel.shape[1]) != ix
    np.testing.assert_array_equal(a.qvel[k, others], b.qvel[k, others])
    # afterwards the pushed body is ahead by about the extra speed times the time since
    dx = b.qpos[k + 50, ix] - a.qpos[k + 50, ix]
    assert dx == pytest.approx(0.05 * a.qvel[k, ix] * 0.05, rel=0.3)
    # a push of zero is no push
    zero = ObjectiveSettings(duration=0.4, dt=1e-3, integrator="implicit", push=(0.2, 0.0))
    _, c = simulate_controlled(model, layout.x0, layout=layout, settings=zero, record_every=1)
    np.testing.assert_array_equal(a.qpos, c.qpos)


@pytest.mark.parametrize("push", [(11.0, 0.05), (1.0, 0.6), (-1.0, 0.05)])
def test_a_push_outside_the_run_is_refused(push):
    from bladelab.errors import SpecError

    with pytest.raises(SpecError, match="push"):
        ObjectiveSettings(duration=10.0, push=push)


def test_pushed_copies_need_room_for_the_push():
    from bladelab.errors import SpecError

    with pytest.raises(SpecError, match="robust_push"):
        ObjectiveSettings(duration=4.0, robust_push=0.02)
    s = ObjectiveSettings(duration=10.0, robust_push=0.02, push=(5.0, -0.02))
    assert ObjectiveSettings.from_dict(s.to_dict()) == s


def test_the_power_balance_can_leave_out_a_push(able):
    # a push adds kinetic energy without external work: one spike in the residual, which
    # skip_times leaves out (verify_solution does for its pushed runs)
    from bladelab.runner.analyses import power_balance_residual_pct

    model, layout = able
    kw = {"duration": 0.4, "dt": 1e-3, "integrator": "implicit"}
    _, plain = simulate_controlled(model, layout.x0, layout=layout,
                                   settings=ObjectiveSettings(**kw), record_every=2)
    _, pushed = simulate_controlled(model, layout.x0, layout=layout,
                                    settings=ObjectiveSettings(**kw, push=(0.2, 0.05)),
                                    record_every=2)
    base = power_balance_residual_pct(plain)
    assert power_balance_residual_pct(pushed) > 3 * base
    assert power_balance_residual_pct(pushed, skip_times=(0.2,)) < 1.5 * base
    # leaving out the same samples of the unpushed run changes it little
    assert power_balance_residual_pct(plain, skip_times=(0.2,)) == pytest.approx(base, rel=0.2)


def test_the_closed_loop_sees_the_mean_speed_placement_once_its_window_is_full():
    # the compiled loop runs the controller's current terms (a stale cached loop once ran an
    # older formula: bladelab.numba_cache); the mean-speed placement is off until the history
    # holds its window and delay, then acts
    from pathlib import Path

    import bladelab.predict.reflex.controller as ctl
    from bladelab.predict.reflex.controller import SPEED_WINDOW, VES_DELAY, read_parameters

    model = build_runner("able")
    layout = controller_layout(model)
    shipped = Path(ctl.__file__).resolve().parents[2] / "data/runner/reflex-starts/able-3.5.json"
    x = read_parameters(shipped, layout)
    s = ObjectiveSettings(duration=1.2)
    _, a = simulate_controlled(model, x, layout=layout, settings=s, record_every=4)
    x[layout.index("S11100.glut_max_l-pelvis_tx.KS")] = 1.0
    x[layout.index("S11100.glut_max_l-pelvis_tx.S0")] = 0.0  # -3.5 m/s·1: glut_max off
    _, b = simulate_controlled(model, x, layout=layout, settings=s, record_every=4)
    on = SPEED_WINDOW + VES_DELAY
    before = a.time < on - 1e-3
    np.testing.assert_array_equal(a.qpos[before], b.qpos[before])
    assert not np.array_equal(a.qpos[~before], b.qpos[~before])
    gmax = list(model.muscle_names).index("glut_max_l")
    # the left glut_max's excitation is the first to change, after the window is full
    changed = a.time[a.excitation[:, gmax] != b.excitation[:, gmax]]
    assert len(changed) and changed[0] >= on - 1e-3
