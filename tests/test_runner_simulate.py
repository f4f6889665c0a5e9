"""Runner simulation: muscle model, drop test, blade statics, power balance, contact kinematics."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from bladelab.errors import SimulationError
from bladelab.runner import build_runner, power_balance, power_balance_residual_pct, simulate_runner
from bladelab.runner.muscle import (
    equilibrium_fiber_length,
    force_length,
    force_velocity,
    muscle_step,
    tendon_force_of_state,
)

G = 9.81


@pytest.fixture(scope="module")
def amputee():
    return build_runner("amputee")


# ---------------------------------------------------------------- muscle


def test_isometric_maximal_force_is_fmax_cos_pennation():
    """At l_ce = l_opt, a = 1, v = 0 the tendon carries Fmax·cos α0 (hand-derived MTU length)."""
    fmax, l_opt, l_ts, penn = 3000.0, 0.06, 0.39, 0.3
    # tendon strain for Fmax·cos α0 with f_t = (ε/0.04)²
    strain = 0.04 * math.sqrt(math.cos(penn))
    l_mtu = l_opt * math.cos(penn) + l_ts * (1 + strain)
    l_ce = equilibrium_fiber_length(l_mtu, 1.0, l_opt, l_ts, penn)
    assert l_ce == pytest.approx(l_opt, rel=1e-4)
    assert tendon_force_of_state(l_mtu, l_ce, fmax, l_opt, l_ts, penn) == pytest.approx(
        fmax * math.cos(penn), rel=1e-3
    )
    mp = np.array([[fmax, l_opt, l_ts, penn, 0.04, 1.0, 0.6, 10.0]])
    ms = np.array([[1.0, l_ce, 0.0, 0.0]])
    for _ in range(200):  # held isometric: stays in equilibrium
        muscle_step(mp, ms, np.array([l_mtu]), np.array([1.0]), 5e-4)
    assert ms[0, 3] == pytest.approx(fmax * math.cos(penn), rel=1e-3)
    assert abs(ms[0, 2]) < 1e-6


def test_active_strength_scales_the_active_force_only():
    """With active strength 2.5, activation 0.4 holds the fibre at l_opt against the same
    tendon force as activation 1 at strength 1; the passive and tendon curves are unchanged
    (an inactive, stretched muscle carries the same force at either strength)."""
    fmax, l_opt, l_ts, penn, strength = 3000.0, 0.06, 0.39, 0.3, 2.5
    strain = 0.04 * math.sqrt(math.cos(penn))
    l_mtu = l_opt * math.cos(penn) + l_ts * (1 + strain)
    l_ce = equilibrium_fiber_length(l_mtu, 1.0 / strength, l_opt, l_ts, penn, 0.04, strength)
    assert l_ce == pytest.approx(l_opt, rel=1e-4)
    forces = []
    for s in (1.0, strength):
        mp = np.array([[fmax, l_opt, l_ts, penn, 0.04, s, 0.6, 10.0]])
        ms = np.array([[0.4, l_ce, 0.0, 0.0]])
        for _ in range(400):
            muscle_step(mp, ms, np.array([l_mtu]), np.array([0.4]), 5e-4)
        forces.append(ms[0, 3])
    assert forces[1] == pytest.approx(fmax * math.cos(penn), rel=1e-3)  # 2.5 x 0.4 = 1
    assert forces[0] < 0.6 * forces[1]
    stretched = l_opt * 1.3 * math.cos(penn) + l_ts  # a slack-ish tendon, fibre stretched
    passive = [equilibrium_fiber_length(stretched, 0.01, l_opt, l_ts, penn, 0.04, s)
               for s in (1.0, 50.0)]
    assert passive[1] < passive[0]  # stronger active part at a = 0.01: shorter fibre
    assert equilibrium_fiber_length(stretched, 0.0, l_opt, l_ts, penn, 0.04, 50.0) == (
        pytest.approx(equilibrium_fiber_length(stretched, 0.0, l_opt, l_ts, penn, 0.04, 1.0)))


def test_force_velocity_shape():
    assert force_velocity(0.0) == 1.0
    assert force_velocity(-1.0) == 0.0
    assert force_velocity(-0.5) < 0.3  # Hill: (1 - 0.5)/(1 + 2) = 1/6
    assert force_velocity(-0.5) == pytest.approx(1 / 6)
    assert force_velocity(10.0) == pytest.approx(1.5, abs=0.01)


def test_activation_dynamics_first_order():
    """u = 1 from a = 0.01: a(t) = 1 − 0.99·exp(−100 t) (rate 100 /s), Euler-discretised."""
    mp = np.array([[1000.0, 0.1, 0.2, 0.0, 0.04, 1.0, 0.6, 10.0]])
    ms = np.array([[0.01, 0.1, 0.0, 0.0]])
    dt = 1e-4
    for _ in range(200):
        muscle_step(mp, ms, np.array([0.3]), np.array([1.0]), dt)
    assert ms[0, 0] == pytest.approx(1 - 0.99 * math.exp(-100 * 0.02), rel=2e-3)


def test_a_shortening_fibre_is_in_equilibrium_at_its_own_maximum_velocity():
    """MTU shortening at 3 l_opt/s for 60 ms: at the end the tendon force equals the fibre's
    (a·f_l·f_v(ṽ) + f_p + β·ṽ)·Fmax with ṽ = v_ce/(v_max·l_opt) of the muscle's own v_max
    column; twice the maximum velocity, more force at the same shortening speed."""
    fmax, l_opt, l_ts, penn = 3000.0, 0.1, 0.2, 0.0
    l_mtu = l_opt + l_ts * 1.04
    l_ce = equilibrium_fiber_length(l_mtu, 1.0, l_opt, l_ts, penn)
    dt, speed = 1e-4, 0.3
    forces = []
    for vmax in (10.0, 20.0):
        mp = np.array([[fmax, l_opt, l_ts, penn, 0.04, 1.0, 0.6, vmax]])
        ms = np.array([[1.0, l_ce, 0.0, 0.0]])
        length = l_mtu
        for _ in range(600):
            length -= speed * dt
            muscle_step(mp, ms, np.array([length]), np.array([1.0]), dt)
        v_norm = ms[0, 2] / (vmax * l_opt)
        ln = ms[0, 1] / l_opt
        fibre = (force_length(ln) * force_velocity(v_norm) + 0.1 * v_norm) * fmax
        tendon = tendon_force_of_state(length, ms[0, 1], fmax, l_opt, l_ts, penn)
        assert ms[0, 2] == pytest.approx(-speed, rel=0.05)  # steady: the fibre takes the speed
        assert tendon == pytest.approx(fibre, rel=1e-3)
        forces.append(tendon)
    assert forces[1] > 1.5 * forces[0]


def test_quick_release_shortens_fibre_with_a_compliant_tendon():
    """A sudden MTU shortening unloads the tendon first; the fibre then shortens (v_ce < 0)."""
    fmax, l_opt, l_ts, penn = 3000.0, 0.1, 0.2, 0.0
    l_mtu = l_opt + l_ts * 1.04
    l_ce = equilibrium_fiber_length(l_mtu, 1.0, l_opt, l_ts, penn)
    mp = np.array([[fmax, l_opt, l_ts, penn, 0.04, 1.0, 0.6, 10.0]])
    ms = np.array([[1.0, l_ce, 0.0, 0.0]])
    muscle_step(mp, ms, np.array([l_mtu - 0.004]), np.array([1.0]), 5e-4)
    f_after = tendon_force_of_state(l_mtu - 0.004, ms[0, 1], fmax, l_opt, l_ts, penn)
    assert f_after < 0.7 * fmax  # tendon unloaded by the release (compliant, not rigid)
    assert ms[0, 2] < 0  # and the fibre shortens to reload it


# ---------------------------------------------------------------- simulation


def test_contact_point_velocity_matches_mujoco_jacobian(amputee):
    """The kernel's contact-point velocity equals J·q̇ from mj_jac at the same point."""
    rng = np.random.default_rng(3)
    res = simulate_runner(amputee, duration=0.02, record_every=1, initial_speed=1.0)
    m = amputee.mj_model
    d = mujoco.MjData(m)
    for i in rng.integers(0, len(res.time), 5):
        d.qpos[:] = res.qpos[i]
        d.qvel[:] = res.qvel[i]
        mujoco.mj_forward(m, d)
        for c, row in enumerate(amputee.contact_params):
            p = d.site_xpos[int(row[0])] - np.array([0.0, 0.0, row[2]])
            jac = np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jac, None, p, int(row[1]))
            v = jac @ d.qvel
            assert res.contacts[i, c, 4] == pytest.approx(v[0], abs=1e-9)
            assert res.contacts[i, c, 5] == pytest.approx(v[2], abs=1e-9)


def _runner(kind: str):
    """``able``, ``amputee``, ``able-toes`` (the toe body: toe segment, compliant Achilles) or
    ``able-human-arch`` (the human body with a midtarsal hinge and its arch spring)."""
    if kind == "able-toes":
        return build_runner("able", body="toes")
    if kind == "able-human-arch":
        from bladelab.runner.params import ArchSpring, default_runner_params

        return build_runner(default_runner_params("able", body="human").model_copy(
            update={"arch": ArchSpring()}))
    return build_runner(kind)


def _integrator(kind: str) -> str:
    """The human body's toe dampers need the Newmark scheme (the explicit one refuses them)."""
    return "newmark" if kind.startswith("able-human") else "explicit"


def test_explicit_scheme_refuses_the_human_toes_damper():
    """The human body's toes (2 N·m·s/rad on about 1.5·10⁻⁴ kg·m²): an explicit run at the
    default step is refused with the joint and the remedy named; at a step short enough, or
    with the Newmark scheme, it runs."""
    human = build_runner("able", body="human")
    with pytest.raises(SimulationError, match="mtp_angle") as err:
        simulate_runner(human, duration=0.01)
    assert "newmark" in err.value.hint
    limit = float(err.value.hint.rsplit("at most ", 1)[1].split()[0])
    assert 4e-5 < limit < 1e-4
    short = simulate_runner(human, duration=0.01, dt=0.9 * limit)
    assert short.duration == pytest.approx(0.01, abs=limit) and np.isfinite(short.qvel).all()
    assert simulate_runner(human, duration=0.01, integrator="newmark").duration > 0


@pytest.mark.parametrize("body", ["seed001", "toes", "human"])
def test_default_integrator_is_explicit_exactly_where_the_explicit_step_is_allowed(body):
    """``integrator_for`` and the reflex route's ``body_integrator`` pick the explicit scheme
    where an explicit run at the default step is accepted, and Newmark where it is refused
    (one rule, the dampers' step limit, for every body)."""
    from bladelab.predict.reflex.named_runs import body_integrator
    from bladelab.runner import integrator_for
    from bladelab.runner.implicit_setup import explicit_step_limit
    from bladelab.runner.model import DEFAULT_DT

    runner = build_runner("amputee", body=body)
    try:
        simulate_runner(runner, duration=0.005)
        explicit_runs = True
    except SimulationError:
        explicit_runs = False
    assert explicit_runs == (explicit_step_limit(runner) >= DEFAULT_DT)
    chosen = "explicit" if explicit_runs else "newmark"
    assert integrator_for(runner)[0] == chosen
    assert body_integrator("amputee", body) == chosen
    assert body_integrator("able", body, "implicit") == "implicit"


@pytest.mark.parametrize("kind,mass", [("able", 83.47), ("amputee", 81.43), ("able-toes", 83.47),
                                       ("able-human-arch", 75.0)])
def test_passive_drop_comes_to_rest_with_body_weight(kind, mass):
    """Dropped 5 cm with the joints held: static vertical GRF = m·g within 1 %."""
    runner = _runner(kind)
    res = simulate_runner(runner, duration=1.5, hold_pose=True, drop_height=0.05, record_every=5,
                          integrator=_integrator(kind))
    assert not res.fell
    fz = res.contacts[:, :, 1].sum(axis=1)
    assert fz[: len(fz) // 10].max() > 1.5 * mass * G  # the landing impact happened
    last = res.time > 1.3
    assert np.mean(fz[last]) == pytest.approx(mass * G, rel=0.01)
    assert np.ptp(fz[last]) < 0.01 * mass * G  # at rest
    assert abs(res.qvel[-1, 1]) < 1e-3


@pytest.mark.parametrize("category,k_cat", [("Cat4", 21.2e3), ("Cat7", 33.3e3)])
def test_blade_static_compression_in_simulation(category, k_cat):
    """Standing on the blade alone (intact hip flexed, joints held): the compression at rest is
    the Hertz value at body weight, δ = 1.5·m·g/K_cat for a tangent stiffness K_cat."""
    runner = build_runner("amputee", blade=category)
    state = {"hip_flexion_l": 0.6, "knee_angle_l": -0.6, "knee_angle_r": 0.0, "hip_flexion_r": 0.0}
    # the blade's low dissipation (0.2 s/m) lets the bounce ring for a few seconds
    res = simulate_runner(
        runner, duration=5.0, hold_pose=True, initial_state=state, drop_height=0.01, record_every=10
    )
    blade = runner.contact_names.index("blade_r")
    assert res.contacts[-50:, :blade, 1].max() == 0.0  # intact foot in the air
    fz = res.contacts[-50:, blade, 1]
    assert np.mean(fz) == pytest.approx(81.43 * G, rel=0.01)
    depth = np.mean(res.contacts[-50:, blade, 6])
    assert depth == pytest.approx(1.5 * 81.43 * G / k_cat, rel=0.02)


@pytest.mark.parametrize(
    "kind,u", [("amputee", 0.05), ("amputee", 0.4), ("able", 0.2), ("able-toes", 0.2),
               ("able-human-arch", 0.2)]
)
def test_power_balance_with_ground_contact(kind, u):
    """2 s, constant excitations, feet/blade on the ground throughout: the RMS residual of
    P_external − P_kinetic is under 2 % of the peak kinetic power. The model collapses (no
    controller), so the fall stop is switched off to keep the full 2 s."""
    runner = _runner(kind)
    res = simulate_runner(
        runner, duration=2.0, excitations=u, record_every=1, fall_height=-math.inf,
        integrator=_integrator(kind)
    )
    assert res.duration == pytest.approx(2.0)
    fz = res.contacts[:, :, 1].sum(axis=1)
    assert (fz > 0).mean() > 0.5  # ground contact during most of the simulation
    pb = power_balance(res)
    assert pb.kinetic.abs().max() > 100.0  # something happens
    assert abs(pb.muscle).max() > 10.0 and abs(pb.contact).max() > 10.0
    assert power_balance_residual_pct(res) < 2.0
    # energy: the integral of the external power equals the kinetic energy change; the gap is
    # the first-order integrator's error (∝ dt: 2.2 % of the kinetic-energy range at 0.5 ms,
    # 0.5 % at 0.1 ms, measured)
    from bladelab.runner.analyses import forward_pass

    ek = forward_pass(res)["ek"]
    work = np.trapezoid(pb.external, pb.time)
    assert work == pytest.approx(ek[-1] - ek[0], abs=0.05 * np.ptp(ek))


def test_bad_simulation_inputs(amputee):
    from bladelab.errors import BladelabError

    with pytest.raises(BladelabError):
        simulate_runner(amputee, duration=-1.0)
    with pytest.raises(BladelabError):
        simulate_runner(amputee, duration=0.1, initial_state="fly")
    with pytest.raises(BladelabError, match="21"):
        simulate_runner(amputee, duration=0.1, excitations=[0.1, 0.2])
    with pytest.raises(BladelabError, match=r"\[0, 1\]"):
        simulate_runner(amputee, duration=0.1, excitations=1.5)
    with pytest.raises(BladelabError, match="dt"):
        simulate_runner(amputee, duration=0.1, dt=0.01)


def test_controller_is_called_with_states(amputee):
    calls = []

    def controller(t, state):
        calls.append((t, state.muscles.shape, state.contacts.shape))
        return np.full(len(amputee.muscle_names), 0.2)

    res = simulate_runner(amputee, controller=controller, duration=0.01, dt=5e-4, control_interval=2)
    # 20 steps of 0.5 ms, a call every 2 steps, plus the call at t = 0
    assert len(calls) == 11 and calls[0][1] == (21, 4) and calls[0][2] == (3, 7)
    assert np.allclose(res.excitation[-1], 0.2)


def test_muscle_paths_match_mujoco_spatial_tendons(amputee):
    """bladelab's path lengths/velocities and muscle generalized forces equal MuJoCo's spatial
    tendons (the analysis model) at random states."""
    from bladelab.runner.kernel import path_kinematics

    rng = np.random.default_rng(7)
    ma = amputee.mj_analysis_model
    ms_ = amputee.mj_model
    da, ds = mujoco.MjData(ma), mujoco.MjData(ms_)
    path, pstart = amputee.path_points, amputee.path_start
    nm = len(amputee.muscle_names)
    for _ in range(5):
        q = amputee.stand_qpos + rng.normal(0, 0.3, ma.nq)
        v = rng.normal(0, 2.0, ma.nv)
        force = rng.uniform(0, 2000, nm)
        for d in (da, ds):
            d.qpos[:], d.qvel[:] = q, v
        da.ctrl[:] = -force
        mujoco.mj_forward(ma, da)
        mujoco.mj_forward(ms_, ds)
        mtu = np.zeros((nm, 2))
        seg_u = np.zeros((path.shape[0], 3))
        path_kinematics(ds.site_xpos, ds.cvel, ds.subtree_com[1].copy(), path, pstart, mtu, seg_u)
        np.testing.assert_allclose(mtu[:, 0], da.ten_length, rtol=1e-12)
        np.testing.assert_allclose(mtu[:, 1], da.ten_velocity, rtol=1e-9, atol=1e-12)
        # generalized force of the point-force pairs = MuJoCo's tendon actuator force
        qfrc = np.zeros(ms_.nv)
        for i in range(nm):
            for k in range(pstart[i], pstart[i + 1] - 1):
                f = force[i] * seg_u[k]
                for row, sign in ((path[k], 1.0), (path[k + 1], -1.0)):
                    mujoco.mj_applyFT(
                        ms_,
                        ds,
                        sign * f,
                        np.zeros(3),
                        ds.site_xpos[row[0]].copy(),
                        int(row[1]),
                        qfrc,
                    )
        np.testing.assert_allclose(qfrc, da.qfrc_actuator, rtol=1e-9, atol=1e-9)
