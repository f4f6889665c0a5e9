"""Reflex controller: sensor delays, gait-state transitions, reflex laws, layout, JSON I/O."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.reflex.controller import (
    CONTROLLER_STATE_SIZE,
    EARLY_STANCE,
    LANDING,
    LATE_STANCE,
    LIFTOFF,
    R_DELAY,
    SWING,
    T_DOF_POS,
    T_DOF_VEL,
    T_FORCE,
    T_LENGTH,
    compute_excitations,
    controller_layout,
    delayed,
    history_length,
    push_sensors,
    read_parameters,
    update_gait_states,
    write_parameters,
)
from bladelab.runner import build_runner


@pytest.fixture(scope="module")
def able():
    return build_runner("able")


@pytest.fixture(scope="module")
def amputee():
    return build_runner("amputee", blade="Cat6")


def test_delay_returns_the_value_from_d_steps_ago():
    nm, nq = 1, 2
    mp = np.array([[1000.0, 0.1, 0.2, 0.0, 0.04, 1.0, 0.6, 10.0]])
    hist = np.zeros((6, 3 * nm + 2 * nq))
    cs = np.zeros(CONTROLLER_STATE_SIZE)
    for k in range(10):
        ms = np.array([[0.1, 0.1 * (1 + k), 0.0, 10.0 * k]])  # L = 1 + k, F = k/100
        push_sensors(hist, cs, ms, mp, np.array([k, -k], float), np.zeros(2))
        for d in range(0, min(k, 4) + 1):
            assert delayed(hist, cs, 0, d) == pytest.approx(1 + k - d)
            assert delayed(hist, cs, 2, d) == pytest.approx((k - d) / 100)
            assert delayed(hist, cs, 3 * nm + 1, d) == pytest.approx(-(k - d))


def test_delay_before_history_is_filled_gives_the_first_sample():
    mp = np.array([[1000.0, 0.1, 0.2, 0.0, 0.04, 1.0, 0.6, 10.0]])
    hist = np.zeros((5, 3 + 2))
    cs = np.zeros(CONTROLLER_STATE_SIZE)
    push_sensors(hist, cs, np.array([[0.1, 0.07, 0.0, 0.0]]), mp, np.array([0.3]), np.zeros(1))
    assert delayed(hist, cs, 0, 3) == pytest.approx(0.7)
    assert delayed(hist, cs, 3, 3) == pytest.approx(0.3)


def _crec(fz_left, fz_right, x_left, x_right):
    # two contacts: leg 0 and leg 1; columns Fx, Fz, px, pz, vx, vz, depth
    crec = np.zeros((2, 7))
    crec[0, 1], crec[1, 1] = fz_left, fz_right
    crec[0, 2], crec[1, 2] = x_left, x_right
    cp = np.zeros((2, 8))
    cp[0, 6], cp[1, 6] = 0, 1
    return crec, cp


def test_gait_state_machine_walks_through_the_cycle():
    bw, thr, leg_len = 800.0, np.array([0.2, 0.2, 0.0, 0.0]), 1.0
    qpos = np.zeros(3)  # pelvis x = 0
    cs = np.array([SWING, SWING, 0, 0], float)

    def step(fl, fr, xl, xr):
        return update_gait_states(cs, *_crec(fl, fr, xl, xr), qpos, 0, bw, thr, leg_len)

    step(0, 0, 0.3, -0.3)  # left foot ahead, no contact: landing
    assert cs[0] == LANDING and cs[1] == SWING
    step(400, 0, 0.3, -0.3)  # load 0.5 BW > 0.2: early stance
    assert cs[0] == EARLY_STANCE
    step(100, 0, 0.1, -0.3)  # load 0.125 BW < 0.2: contact lost -> swing
    assert cs[0] == SWING
    step(400, 0, 0.2, -0.2)
    assert cs[0] == EARLY_STANCE
    step(400, 0, -0.05, 0.1)  # foot behind the pelvis: late stance
    assert cs[0] == LATE_STANCE
    step(400, 400, -0.2, 0.3)  # other leg lands: liftoff (double support)
    assert cs[0] == LIFTOFF and cs[1] == EARLY_STANCE
    step(0, 400, -0.3, 0.2)
    assert cs[0] == SWING


def test_an_unloading_running_leg_lifts_off_before_it_leaves_the_ground():
    # liftoff_load_margin_<side> (our addition): a running leg in late stance goes to Liftoff
    # when its load falls below its stance threshold plus the margin, without double
    # support; 0 (the default) never
    bw, leg_len = 800.0, 1.0
    qpos = np.zeros(3)
    for liftoff, want in ((0.0, LATE_STANCE), (0.5, LATE_STANCE), (0.7, LIFTOFF)):
        thr = np.array([0.2, 0.2, liftoff, 0.0])
        cs = np.array([LATE_STANCE, SWING, 0, 0], float)
        update_gait_states(cs, *_crec(1600, 0, -0.2, -0.3), qpos, 0, bw, thr, leg_len)
        assert cs[0] == LATE_STANCE  # 2 BW: still pushing
        update_gait_states(cs, *_crec(640, 0, -0.3, -0.2), qpos, 0, bw, thr, leg_len)
        # 0.8 BW, the other leg in the air: below 0.2 + 0.7 BW, not below 0.2 + 0.5
        assert cs[0] == want and cs[1] == SWING
        update_gait_states(cs, *_crec(0, 0, -0.4, -0.1), qpos, 0, bw, thr, leg_len)
        assert cs[0] == SWING
    layout = controller_layout(build_runner("able"))
    assert layout.x0[layout.index("liftoff_load_margin_l")] == 0.0


def test_warm_start_digest_is_unchanged_by_parameters_added_at_their_defaults(amputee):
    # task folders store the digest of their warm start; the liftoff margins (added later)
    # at their defaults leave it as the layout without them would have computed it
    import hashlib

    from bladelab.predict.reflex.controller import parameter_digest

    layout = controller_layout(amputee)
    x = layout.x0 + 0.01 * np.arange(layout.size)
    added = [layout.index(f"liftoff_load_margin_{s}") for s in ("l", "r")]
    x[added] = layout.x0[added]
    older = np.delete(x, added).astype("<f8").tobytes()
    assert parameter_digest(x, layout) == hashlib.sha256(older).hexdigest()
    x[added[1]] = 0.7  # a warm start that uses one is another warm start
    moved = np.delete(x, added[:1]).astype("<f8").tobytes()
    assert parameter_digest(x, layout) == hashlib.sha256(moved).hexdigest()
    assert parameter_digest(x) == hashlib.sha256(x.astype("<f8").tobytes()).hexdigest()


def test_reflex_laws_by_hand():
    # one muscle, one dof: every kind of term, with delays
    table = np.array(
        [
            # kind, target, leg, mask, source, delay, gain idx, offset idx, offset const
            [T_LENGTH, 0, 0, 0b00011, 0, 2, 0, 1, 0.0],
            [T_FORCE, 0, 0, 0b00011, 0, 1, 2, -1, 0.0],
            [T_DOF_POS, 0, 0, 0b11100, 0, 0, 3, -1, -0.105],
            [T_DOF_VEL, 0, 0, 0b11100, 0, 0, 4, -1, 0.0],
        ]
    )
    p = np.array([2.0, 0.9, 0.5, 1.5, 0.3])
    mp = np.array([[1000.0, 0.1, 0.2, 0.0, 0.04, 1.0, 0.6, 10.0]])
    hist = np.zeros((4, 3 + 2))
    cs = np.array([EARLY_STANCE, SWING, 0, 0], float)
    lengths = [0.10, 0.11, 0.12]
    forces = [100.0, 200.0, 300.0]
    for ln, f in zip(lengths, forces, strict=True):
        push_sensors(hist, cs, np.array([[0.1, ln, 0.0, f]]), mp, np.array([-0.2]), np.array([0.4]))
    u = np.zeros(1)
    compute_excitations(u, table, p, hist, cs, 1, 1)
    # stance: KL*(L(t-2) - L0) + KF*F(t-1) = 2*(1.0 - 0.9) + 0.5*0.2
    assert u[0] == pytest.approx(2 * 0.1 + 0.5 * 0.2)
    cs[0] = SWING
    compute_excitations(u, table, p, hist, cs, 1, 1)
    # swing: KP*(P0 - q) - KV*qd = 1.5*(-0.105 + 0.2) - 0.3*0.4, clipped at 0
    assert u[0] == pytest.approx(max(1.5 * 0.095 - 0.12, 0.0))
    p[3] = 10.0
    compute_excitations(u, table, p, hist, cs, 1, 1)
    assert u[0] == pytest.approx(10 * 0.095 - 0.12)
    p[3] = 100.0
    compute_excitations(u, table, p, hist, cs, 1, 1)
    assert u[0] == 1.0  # clipped


def test_layout_ports_scone_values_and_is_asymmetric(able, amputee):
    la, lp = controller_layout(able), controller_layout(amputee)
    assert len(set(la.names)) == la.size
    # SCONE H0918GaitRS2Hfd4.par, column best
    assert la.x0[la.index("S00011.vasti_l.KF")] == pytest.approx(0.82139952)
    assert la.x0[la.index("S00011.vasti_r.KF")] == pytest.approx(0.82139952)
    assert la.x0[la.index("S11100.iliopsoas_l-hamstrings.KL")] == pytest.approx(-2.8426204)
    assert la.x0[la.index("stance_load_threshold_l")] == pytest.approx(0.28168695)
    # the prosthetic leg has no shank muscles, so no reflex to or from them
    assert not [
        n for n in lp.names if "_r" in n and any(m in n for m in ("soleus", "gastroc", "tib_ant"))
    ]
    assert "S11111.soleus_l.KF" in lp.names and "S11111.soleus_r.KF" in la.names
    assert la.size > lp.size
    # delays: ankle reflexes 35 ms -> 70 steps of 0.5 ms
    t = la.table_for(5e-4)
    assert set(np.unique(t[:, R_DELAY])) <= {0, 20, 30, 40, 70, 100}


def test_early_swing_knee_flexion_offset_acts_in_swing_only(amputee):
    # S01000.bifemsh_<side>.C0 (our addition): on in Swing, off in every other state; the
    # prosthetic side has it too (bifemsh is a thigh muscle)
    layout = controller_layout(amputee)
    table = layout.table_for(5e-4)
    muscles = list(amputee.muscle_names)
    nm, nq = len(muscles), len(amputee.dof_names)
    hist = np.zeros((history_length(layout, 5e-4), 3 * nm + 2 * nq))
    for side, leg in (("l", 0), ("r", 1)):
        p = np.zeros(layout.size)
        p[layout.index(f"S01000.bifemsh_{side}.C0")] = 0.37
        target = muscles.index(f"bifemsh_{side}")
        for state in (EARLY_STANCE, LATE_STANCE, LIFTOFF, SWING, LANDING):
            cs = np.array([EARLY_STANCE, EARLY_STANCE, 0, 1], float)
            cs[leg] = state
            u = np.zeros(nm)
            compute_excitations(u, table, p, hist, cs, nm, nq)
            assert u[target] == (0.37 if state == SWING else 0.0), (side, state)
            assert np.count_nonzero(u) == (1 if state == SWING else 0)


def _sensor_setup(model, dt: float):
    """The amputee's layout, its table at ``dt`` [s], muscle names, muscle and dof counts, the
    pelvis_tx index, an empty sensor history, controller state and muscle state."""
    layout = controller_layout(model)
    muscles, dofs = list(model.muscle_names), list(model.dof_names)
    nm, nq = len(muscles), len(dofs)
    hist = np.zeros((history_length(layout, dt), 3 * nm + 2 * nq))
    ms = np.zeros((nm, 4))
    ms[:, 1] = 0.1
    return (layout, layout.table_for(dt), muscles, nm, nq, dofs.index("pelvis_tx"), hist,
            np.zeros(CONTROLLER_STATE_SIZE), ms)


def test_swing_leg_placement_sees_the_delayed_forward_speed(amputee):
    # S11100.<hip muscle>_<side>-pelvis_tx.KV·(V0 − v(t − 50 ms)) (our addition): in Liftoff,
    # Swing and Landing only, on the pelvis's forward velocity 50 ms ago; gain 0 by default
    layout, table, muscles, nm, nq, ix, hist, cs, ms = _sensor_setup(amputee, 1e-3)
    assert layout.x0[layout.index("S11100.iliopsoas_r-pelvis_tx.KV")] == 0.0
    mp = amputee.muscle_params
    qvel = np.zeros(nq)
    for k in range(60):  # forward speed 3.0 m/s until 50 steps ago, 4.0 m/s since
        qvel[ix] = 3.0 if k < 10 else 4.0
        push_sensors(hist, cs, ms, mp, np.zeros(nq), qvel)
    for side, leg in (("l", 0), ("r", 1)):
        for muscle in ("iliopsoas", "glut_max"):
            p = np.zeros(layout.size)
            p[layout.index(f"S11100.{muscle}_{side}-pelvis_tx.KV")] = -0.5
            p[layout.index(f"S11100.{muscle}_{side}-pelvis_tx.V0")] = 3.4
            target = muscles.index(f"{muscle}_{side}")
            for state in (EARLY_STANCE, LATE_STANCE, LIFTOFF, SWING, LANDING):
                cs[:2] = EARLY_STANCE
                cs[leg] = state
                u = np.zeros(nm)
                compute_excitations(u, table, p, hist, cs, nm, nq)
                swinging = state in (LIFTOFF, SWING, LANDING)
                # -0.5·(3.4 − 3.0) < 0 is clipped; the 4.0 m/s of 49 steps ago is not seen yet
                assert u[target] == 0.0 and np.count_nonzero(u) == 0
                p[layout.index(f"S11100.{muscle}_{side}-pelvis_tx.V0")] = 2.8
                compute_excitations(u, table, p, hist, cs, nm, nq)
                assert u[target] == pytest.approx(0.1 if swinging else 0.0), (side, muscle, state)
                p[layout.index(f"S11100.{muscle}_{side}-pelvis_tx.V0")] = 3.4


def test_swing_leg_placement_on_the_mean_speed_of_the_last_stride(amputee):
    # S11100.<hip muscle>_<side>-pelvis_tx.KS·(S0 − mean forward speed over SPEED_WINDOW,
    # ending 50 ms ago), from the pelvis's position; off until the history holds the window
    from bladelab.predict.reflex.controller import SPEED_WINDOW

    dt = 1e-3
    layout, table, muscles, nm, nq, ix, hist, cs, ms = _sensor_setup(amputee, dt)
    nh = len(hist)
    assert nh == round((0.05 + SPEED_WINDOW) / dt) + 2
    cs[0] = SWING
    p = np.zeros(layout.size)
    p[layout.index("S11100.iliopsoas_l-pelvis_tx.KS")] = -2.0
    p[layout.index("S11100.iliopsoas_l-pelvis_tx.S0")] = 3.0
    target = muscles.index("iliopsoas_l")
    q, qd = np.zeros(nq), np.zeros(nq)

    def step(x, v):
        q[ix], qd[ix] = x, v
        push_sensors(hist, cs, ms, amputee.muscle_params, q, qd)
        u = np.zeros(nm)
        compute_excitations(u, table, p, hist, cs, nm, nq)
        return u[target]

    # until the history holds the window and the delay, the term is off
    assert step(0.0, 3.4) == 0.0
    assert step(3.4 * (nh - 3) * dt, 3.4) == 0.0
    # 3.4 m/s on average but a velocity sensor swinging by ±0.3 m/s within the stride: once the
    # window is full the term sees the mean only
    for k in range(1, 2 * nh):
        u = step(3.4 * k * dt, 3.4 + 0.3 * math.sin(2 * math.pi * k * dt / SPEED_WINDOW))
    assert u == pytest.approx(-2.0 * (3.0 - 3.4), rel=1e-9)
    # a runner 0.1 m/s faster for the whole window and the delay: 0.2 more excitation
    x = 3.4 * (2 * nh - 1) * dt
    for _ in range(nh):
        x += 3.5 * dt
        u = step(x, 3.5)
    assert u == pytest.approx(-2.0 * (3.0 - 3.5), rel=1e-9)
    cs[0] = EARLY_STANCE  # swing reflexes only
    assert step(x + 3.5 * dt, 3.5) == 0.0


def test_mean_speed_reflexes_with_a_run_up_act_from_the_start(amputee):
    # cs[4] = 1 (ObjectiveSettings.run_up): before the window is full, the positions before the
    # first sample are the first sample's moved back at its velocity; the stance leg's hip
    # muscles have the same term in EarlyStance/LateStance
    dt = 1e-3
    layout, table, muscles, nm, nq, ix, hist, cs, ms = _sensor_setup(amputee, dt)
    cs[0], cs[1], cs[4] = SWING, EARLY_STANCE, 1.0
    p = np.zeros(layout.size)
    for name, gain, s0 in (("S11100.iliopsoas_l", -1.0, 3.0), ("S00011.glut_max_r", 1.5, 3.8)):
        p[layout.index(f"{name}-pelvis_tx.KS")] = gain
        p[layout.index(f"{name}-pelvis_tx.S0")] = s0
    swing, stance = muscles.index("iliopsoas_l"), muscles.index("glut_max_r")
    q, qd = np.zeros(nq), np.zeros(nq)
    u = np.zeros(nm)
    q[ix], qd[ix] = 5.0, 3.6  # the start: 3.6 m/s
    push_sensors(hist, cs, ms, amputee.muscle_params, q, qd)
    compute_excitations(u, table, p, hist, cs, nm, nq)
    assert u[swing] == pytest.approx(-1.0 * (3.0 - 3.6), rel=1e-9)
    assert u[stance] == pytest.approx(1.5 * (3.8 - 3.6), rel=1e-9)
    # 0.2 s later at 3.1 m/s: the window ending 50 ms ago holds 0.15 s at 3.1 and 0.55 s of
    # run-up at 3.6 m/s
    for k in range(1, 201):
        q[ix], qd[ix] = 5.0 + 3.1 * k * dt, 3.1
        push_sensors(hist, cs, ms, amputee.muscle_params, q, qd)
    compute_excitations(u, table, p, hist, cs, nm, nq)
    v = (0.15 * 3.1 + 0.55 * 3.6) / 0.7
    assert u[swing] == pytest.approx(-1.0 * (3.0 - v), rel=1e-9)
    assert u[stance] == pytest.approx(1.5 * (3.8 - v), rel=1e-9)
    cs[4] = 0.0  # without a run-up: off until the window is full
    compute_excitations(u, table, p, hist, cs, nm, nq)
    assert u[swing] == 0.0 and u[stance] == 0.0


def test_parameter_json_roundtrip_and_errors(tmp_path, able, amputee):
    la = controller_layout(able)
    x = la.x0 + 0.01
    path = write_parameters(tmp_path / "p.json", la, x, speed_m_per_s=3.5)
    np.testing.assert_allclose(read_parameters(path, la), x)
    lp = controller_layout(amputee)
    with pytest.raises(InputFileError, match="able model"):
        read_parameters(path, lp)
    # warm start of the amputee from the able-bodied solution: shared names carried over
    xt = read_parameters(path, lp, transfer=True)
    assert xt[lp.index("S00011.vasti_r.KF")] == pytest.approx(x[la.index("S00011.vasti_r.KF")])
    assert xt[lp.index("S11111.soleus_l.KF")] == pytest.approx(x[la.index("S11111.soleus_l.KF")])
    (tmp_path / "bad.json").write_text(json.dumps({"parameters": {"nope.KL": 1.0}}))
    with pytest.raises(SpecError, match="nope.KL"):
        read_parameters(tmp_path / "bad.json", la)
    (tmp_path / "broken.json").write_text("{")
    with pytest.raises(InputFileError, match="JSON"):
        read_parameters(tmp_path / "broken.json", la)
    with pytest.raises(InputFileError, match="not found"):
        read_parameters(tmp_path / "missing.json", la)
