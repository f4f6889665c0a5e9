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
    leg_energy,
    leg_stiffness,
    simulate_runner,
    spatiotemporal,
    summary,
    swing_contacts,
)
from bladelab.runner.analyses import blade_energy, joint_moments, stances
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


def test_leg_stiffness_hand_derived(amputee):
    """K_leg = F_peak / (Δy + L0(1 − cos θ)), θ = asin(v·t_c / 2L0) (seed 001 eq. 2.19–2.21)."""
    res = _synthetic(amputee, stances=STANCES, drop=0.04, peak=2000.0)
    ks = leg_stiffness(res, threshold_n=1.0)
    assert len(ks) == 5
    row = ks[ks.leg == "intact"].iloc[0]
    # joints fixed: the COM dips with the pelvis (minus the first 1 ms of the dip, before the
    # first sample above threshold)
    assert row.delta_y == pytest.approx(0.04, abs=1e-3)
    assert row.F_peak == pytest.approx(2000.0, rel=1e-3)
    l0 = row.L0
    assert 0.85 < l0 < 1.0  # hip height of a 1.80 m athlete
    prosth = ks[ks.leg == "prosthetic"].iloc[0].L0
    assert prosth - l0 == pytest.approx(0.03, abs=1e-6)  # 3 cm longer prosthetic leg
    tc = row.contact_time
    theta = math.asin(3.0 * tc / (2 * l0))
    assert row.K_leg == pytest.approx(2000.0 / (0.04 + l0 * (1 - math.cos(theta))), rel=0.02)


def test_leg_energy_of_a_loop(amputee):
    """COM dips 4 cm and rises back under a half-sine force: stored = generated = ∫F dy."""
    res = _synthetic(amputee, stances=STANCES, drop=0.04, peak=2000.0)
    en = leg_energy(res, threshold_n=1.0)
    row = en.iloc[0]
    # F = P·sin(s), y = −D·sin(s): ∫ over descent of F·dy = P·D·∫0^{π/2} sin·cos ds = P·D/2
    assert row.E_stored == pytest.approx(2000.0 * 0.04 / 2, rel=0.01)
    assert row.E_generated == pytest.approx(2000.0 * 0.04 / 2, rel=0.01)
    assert row.recoil_pct == pytest.approx(100.0, abs=1.0)


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


def test_strikes_never_count_as_stances(amputee):
    # the swinging intact foot strikes the ground (40 ms, 1 kN) just after each prosthetic
    # touch-down: leg stiffness and leg energy see the same stances as without the strikes
    strikes = [(0, 0.42, 0.46), (0, 1.02, 1.06)]
    clean = _synthetic(amputee, stances=STANCES, drop=0.04)
    struck = _synthetic(amputee, stances=[*STANCES, *strikes], drop=0.04)
    struck.qpos[:] = clean.qpos  # the same motion: only the forces differ
    st = stances(struck)
    assert list(st.leg) == ["intact", "prosthetic", "intact", "prosthetic", "intact"]
    np.testing.assert_allclose(st.touchdown_s, [0.1, 0.4, 0.7, 1.0, 1.3], atol=2e-3)
    assert (st.contact_time_s > 0.19).all()
    for analysis in (leg_energy, leg_stiffness):
        a, b = analysis(clean), analysis(struck)
        assert len(a) == len(b) == 5
        np.testing.assert_allclose(a.select_dtypes("number"), b.select_dtypes("number"))
    # every stance is complete: a contact cut by the start or end of the record is left out
    cut = _synthetic(amputee, stances=[(0, -0.1, 0.05), *STANCES, (1, 1.95, 2.2)])
    assert len(stances(cut)) == 5


def test_joint_moments_times_speed_are_the_joint_powers(amputee):
    res = simulate_runner(amputee, duration=0.2, excitations=0.1, initial_state="gait",
                          initial_speed=2.0, fall_height=-math.inf)
    mom = joint_moments(res).pivot(index="time", columns="joint", values="moment_Nm")
    pw = joint_powers(res).pivot(index="time", columns="joint", values="power")
    for joint in ("hip_flexion_l", "knee_angle_r", "socket_angle_r"):
        qd = res.qvel[:, amputee.dof(joint)]
        np.testing.assert_allclose(mom[joint].to_numpy() * qd, pw[joint].to_numpy())


def _blade_loop(amputee, *, dissipation):
    """One prosthetic stance whose blade sphere compresses as a half-sine (peak 50 mm, 0.2 s)
    under the Hunt–Crossley force k·δ^1.5·(1 + 1.5·c·δ̇)."""
    res = _synthetic(amputee, stances=[(0, 0.1, 0.3), (1, 0.4, 0.6), (0, 0.7, 0.9)])
    b = int(np.flatnonzero(amputee.contact_params[:, 7] == 1)[0])
    k = amputee.contact_params[b, 3]
    t = res.time
    on = (t > 0.4) & (t < 0.6)
    depth = np.where(on, 0.05 * np.sin(math.pi * (t - 0.4) / 0.2), 0.0)
    rate = np.gradient(depth, t)
    force = np.where(on, k * depth**1.5 * np.clip(1 + 1.5 * dissipation * rate, 0, None), 0.0)
    res.contacts[:, b, 1] = force
    res.contacts[:, b, 6] = depth
    return res, depth, force


def test_blade_energy_of_elastic_and_dissipative_loops(amputee):
    elastic, depth, force = _blade_loop(amputee, dissipation=0.0)
    row = blade_energy(elastic).iloc[0]
    stored = np.trapezoid(np.where(np.gradient(depth) > 0, force, 0.0), depth)
    assert row.E_stored_J == pytest.approx(stored, rel=1e-3)
    assert row.recoil_pct == pytest.approx(100.0, abs=0.05)
    lossy, depth, force = _blade_loop(amputee, dissipation=0.2)
    row = blade_energy(lossy).iloc[0]
    # stored − returned = ∮F·dδ = ∫ 1.5·c·k·δ^1.5·δ̇² dt, the Hunt–Crossley dissipation
    cp = amputee.contact_params[int(np.flatnonzero(amputee.contact_params[:, 7] == 1)[0])]
    rate = np.gradient(depth, lossy.time)
    lost = np.trapezoid(1.5 * 0.2 * cp[3] * depth**1.5 * rate**2, lossy.time)
    assert row.hysteresis_J == pytest.approx(lost, rel=0.02)
    assert 60.0 < row.recoil_pct < 99.0
    # the seed's bookkeeping (compression from the force by eq. 2.3) cannot see the loss
    assert blade_energy(lossy, compression="hertz").recoil_pct.iloc[0] == pytest.approx(
        100.0, abs=0.05)
    assert blade_energy(_synthetic(build_runner("able"), stances=STANCES)).empty


def test_blade_energy_counts_each_stance_once_under_a_smooth_contact_law(amputee):
    """A smooth law (the collocation model's) pushes with a small force above the ground too:
    each stance's window is where the blade penetrates, not where its force is above 0."""
    res = _synthetic(amputee, stances=STANCES)
    b = int(np.flatnonzero(amputee.contact_params[:, 7] == 1)[0])
    k = amputee.contact_params[b, 3]
    t = res.time
    depth = np.zeros_like(t)
    for t0, t1 in ((0.4, 0.6), (1.0, 1.2)):
        on = (t > t0) & (t < t1)
        depth[on] = 0.05 * np.sin(math.pi * (t[on] - t0) / (t1 - t0))
    res.contacts[:, b, 1] = k * depth**1.5 + 0.1  # 0.1 N above the ground
    res.contacts[:, b, 6] = depth
    e = blade_energy(res)
    one = k * 0.05**2.5 / 2.5  # ∫k·δ^1.5 dδ up to the peak [J]
    assert len(e) == 2
    np.testing.assert_allclose(e.E_stored_J, one, rtol=1e-3)
    np.testing.assert_allclose(e.E_returned_J, one, rtol=1e-3)
