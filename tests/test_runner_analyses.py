"""Runner analyses on synthetic results with hand-derived answers, and on a real simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.runner import (
    build_runner,
    gait_events,
    joint_angles,
    joint_powers,
    simulate_runner,
    spatiotemporal,
    summary,
    swing_contacts,
)
from bladelab.runner.analyses import joint_moments
from bladelab.runner.simulate import RunnerResult


@pytest.fixture(scope="module")
def amputee():
    return build_runner("amputee")


def _synthetic(model, *, stances, duration=2.0, dt=1e-3, speed=3.0, drop=0.0, peak=2000.0):
    """A result whose pelvis moves forward at ``speed`` (joints fixed at 0) with half-sine
    vertical GRFs on the given (leg, start, end) stances; the pelvis dips by ``drop`` as a
    half-sine during each stance."""
    t = np.arange(0.0, duration + dt / 2, dt)
    n = len(t)
    nq = model.mj_model.nq
    qpos = np.zeros((n, nq))
    qvel = np.zeros((n, nq))
    qpos[:, 0] = speed * t
    qvel[:, 0] = speed
    qpos[:, 1] = 1.0
    nc = len(model.contact_names)
    contacts = np.zeros((n, nc, 7))
    legs = model.contact_params[:, 6]
    for leg, t0, t1 in stances:
        on = (t > t0) & (t < t1)
        shape = np.sin(math.pi * (t[on] - t0) / (t1 - t0))
        cols = np.flatnonzero(legs == leg)
        contacts[np.ix_(on, cols, [1])] = (peak * shape / len(cols))[:, None, None]
        qpos[on, 1] -= drop * shape
    nm = len(model.muscle_names)
    return RunnerResult(
        model=model,
        time=t,
        qpos=qpos,
        qvel=qvel,
        muscles=np.zeros((n, nm, 4)),
        mtu=np.zeros((n, nm, 2)),
        excitation=np.zeros((n, nm)),
        contacts=contacts,
        ligament=np.zeros((n, nq)),
        dt=dt,
        fell=False,
        requested_duration=duration,
    )


# intact stances 0.1-0.3, 0.7-0.9, 1.3-1.5; prosthetic 0.4-0.6, 1.0-1.2
STANCES = [(0, 0.1, 0.3), (1, 0.4, 0.6), (0, 0.7, 0.9), (1, 1.0, 1.2), (0, 1.3, 1.5)]


def test_gait_events_and_spatiotemporal(amputee):
    res = _synthetic(amputee, stances=STANCES)
    ev = gait_events(res, threshold_n=1.0)
    td = ev[(ev.leg == "intact") & (ev.event == "touchdown")].time.to_numpy()
    np.testing.assert_allclose(td, [0.1, 0.7, 1.3], atol=2e-3)
    st = spatiotemporal(res, threshold_n=1.0).set_index(["leg", "variable"]).value
    # hand-derived: stride 0.6, contact 0.2, step 0.3, flight 0.1, swing 0.4
    for leg in ("intact", "prosthetic"):
        assert st[(leg, "stride_time")] == pytest.approx(0.6, abs=3e-3)
        assert st[(leg, "contact_time")] == pytest.approx(0.2, abs=3e-3)
        assert st[(leg, "step_time")] == pytest.approx(0.3, abs=3e-3)
        assert st[(leg, "flight_time")] == pytest.approx(0.1, abs=3e-3)
        assert st[(leg, "swing_time")] == pytest.approx(0.4, abs=3e-3)


def test_bounces_and_brief_touches_do_not_change_the_gait_events(amputee):
    # a 10 ms bounce inside the first intact stance and a 10 ms touch of the swinging intact
    # foot at 0.5 s: the same strides and contact times as without them
    stances = [*STANCES, (0, 0.5, 0.51)]
    res = _synthetic(amputee, stances=stances)
    fz = res.contacts[:, :, 1]
    legs = amputee.contact_params[:, 6]
    gap = (res.time > 0.18) & (res.time < 0.19)
    fz[np.ix_(gap, np.flatnonzero(legs == 0))] = 0.0
    ev = gait_events(res, threshold_n=1.0)
    td = ev[(ev.leg == "intact") & (ev.event == "touchdown")].time.to_numpy()
    np.testing.assert_allclose(td, [0.1, 0.7, 1.3], atol=2e-3)
    st = spatiotemporal(res, threshold_n=1.0).set_index(["leg", "variable"]).value
    assert st[("intact", "contact_time")] == pytest.approx(0.2, abs=3e-3)
    assert st[("intact", "stride_time")] == pytest.approx(0.6, abs=3e-3)
    # without the cleaning the bounce and the touch are events of their own
    raw = gait_events(res, threshold_n=1.0, min_gap_s=0.0, min_contact_s=0.0, steps_only=False)
    assert len(raw[raw.leg == "intact"]) == len(ev[ev.leg == "intact"]) + 4


def test_a_swinging_foot_striking_the_ground_is_not_a_stance(amputee):
    # the intact foot strikes the ground (40 ms, 1 kN) 20 ms after each prosthetic touch-down:
    # not a step (SCONE: within 0.1 s of the last step), so not a stance but a swing contact
    strikes = [(0, 0.42, 0.46), (0, 1.02, 1.06)]
    res = _synthetic(amputee, stances=[*STANCES, *strikes], peak=2000.0)
    ev = gait_events(res, threshold_n=1.0)
    td = ev[(ev.leg == "intact") & (ev.event == "touchdown")].time.to_numpy()
    np.testing.assert_allclose(td, [0.1, 0.7, 1.3], atol=2e-3)
    st = spatiotemporal(res, threshold_n=1.0).set_index(["leg", "variable"]).value
    assert st[("intact", "stride_time")] == pytest.approx(0.6, abs=3e-3)
    sc = swing_contacts(res, threshold_n=1.0)
    np.testing.assert_allclose(sc.start, [0.42, 1.02], atol=2e-3)
    assert (sc.leg == "intact").all() and sc.peak_N.min() > 900.0
    assert len(gait_events(res, threshold_n=1.0, steps_only=False)) == len(ev) + 4


def test_analyses_on_a_simulation(amputee):
    res = simulate_runner(
        amputee,
        duration=0.5,
        excitations=0.1,
        initial_state="gait",
        initial_speed=2.0,
        fall_height=-math.inf,
    )
    ang = joint_angles(res)
    assert set(ang.joint) >= {"hip_flexion_l", "knee_angle_l", "socket_angle_r", "pelvis_tilt"}
    pw = joint_powers(res)
    assert set(pw.joint) >= {"hip_flexion_l", "knee_angle_r", "ankle_angle_l", "blade_r"}
    assert np.isfinite(pw.power).all()
    s = summary(res)
    for key in (
        "fell",
        "duration_s",
        "mean_speed_mps",
        "contact_time_intact_s",
        "contact_time_prosthetic_s",
        "power_balance_residual_pct",
    ):
        assert key in s
    assert s["duration_s"] == pytest.approx(0.5)
    assert s["power_balance_residual_pct"] < 2.0
    grf = res.leg_grf()
    assert set(grf.leg) == {"intact", "prosthetic"}
    bw = amputee.body_weight
    np.testing.assert_allclose(grf.Fz_bw, grf.Fz / bw)


def test_joint_moments_times_speed_are_the_joint_powers(amputee):
    res = simulate_runner(amputee, duration=0.2, excitations=0.1, initial_state="gait",
                          initial_speed=2.0, fall_height=-math.inf)
    mom = joint_moments(res).pivot(index="time", columns="joint", values="moment_Nm")
    pw = joint_powers(res).pivot(index="time", columns="joint", values="power")
    for joint in ("hip_flexion_l", "knee_angle_r", "socket_angle_r"):
        qd = res.qvel[:, amputee.dof(joint)]
        np.testing.assert_allclose(mom[joint].to_numpy() * qd, pw[joint].to_numpy())
