"""The runner's linearly implicit schemes (``integrator="implicit"`` and ``"newmark"``): their
pieces against MuJoCo and finite differences, their steps against the explicit one, and their
accuracy at a 1 ms step."""

from __future__ import annotations

import dataclasses
import json
import math

import mujoco
import numpy as np
import pytest

from bladelab.runner import build_runner, power_balance, power_balance_residual_pct, simulate_runner
from bladelab.runner.implicit import dense_mass, implicit_forces, path_jacobian, solve_tree
from bladelab.runner.implicit_setup import implicit_arrays
from bladelab.runner.kernel import forces, mujoco_views, path_kinematics
from bladelab.runner.muscle import equilibrium_fiber_length
from bladelab.runner.simulate import initial_qpos


@pytest.fixture(scope="module")
def amputee():
    return build_runner("amputee")


def _state(model, dt=1e-3, activation=0.3):
    """MjData after ``mj_step1`` at a perturbed gait state (the intact foot 1 cm in the ground),
    and the force arrays of the kernels."""
    m = model.mj_model
    m.opt.timestep = dt
    d = mujoco.MjData(m)
    q, v = initial_qpos(model, "gait")
    d.qpos[:] = q
    d.qpos[model.dof("pelvis_tz")] -= 0.01
    d.qvel[:] = v + 0.3 * np.random.default_rng(0).standard_normal(m.nv)
    mujoco.mj_step1(m, d)
    nm = len(model.muscle_names)
    mp = model.muscle_params
    ms = np.zeros((nm, 4))
    ms[:, 0] = activation
    mtu = np.zeros((nm, 2))
    seg_u = np.zeros((model.path_points.shape[0], 3))
    root = d.subtree_com[1].copy()
    path_kinematics(d.site_xpos, d.cvel, root, model.path_points, model.path_start, mtu, seg_u)
    for i in range(nm):
        ms[i, 1] = equilibrium_fiber_length(mtu[i, 0], ms[i, 0], *mp[i, 1:7])
    cp = model.contact_params
    arrays = (mp, ms, mtu, seg_u, np.full(nm, activation), model.path_points, model.path_start,
              cp, np.zeros((cp.shape[0], 1)), model.joint_params, np.zeros((cp.shape[0], 7)),
              np.zeros(m.nv))
    imp = implicit_arrays(model, m, d, "implicit")
    return m, d, arrays, root, imp


def test_path_jacobian_matches_lengths_and_finite_differences(amputee):
    """Lengths and velocities as path_kinematics (1e-12); ∂l/∂q as central differences of the
    lengths (1e-7 m/rad)."""
    m, d, arrays, root, imp = _state(amputee)
    mtu = np.zeros_like(arrays[2])
    moment = np.zeros((mtu.shape[0], m.nv))
    path_jacobian(d.site_xpos, d.cdof, root, amputee.path_points, amputee.path_start, imp[20],
                  imp[21], imp[32], imp[33], d.qvel, mtu, moment)
    np.testing.assert_allclose(mtu, arrays[2], atol=1e-12)

    def lengths(q):
        dd = mujoco.MjData(m)
        dd.qpos[:] = q
        mujoco.mj_kinematics(m, dd)
        mujoco.mj_comPos(m, dd)
        out = np.zeros_like(mtu)
        path_kinematics(dd.site_xpos, dd.cvel, dd.subtree_com[1].copy(), amputee.path_points,
                        amputee.path_start, out, np.zeros_like(arrays[3]))
        return out[:, 0]

    fd = np.zeros_like(moment)
    for j in range(m.nv):
        qp, qm = d.qpos.copy(), d.qpos.copy()
        qp[j] += 1e-6
        qm[j] -= 1e-6
        fd[:, j] = (lengths(qp) - lengths(qm)) / 2e-6
    assert np.abs(fd).max() > 0.05
    np.testing.assert_allclose(moment, fd, atol=1e-7)


def test_tree_solve_and_dense_mass(amputee):
    """The dense mass matrix equals mj_fullM; the tree elimination solves a non-symmetric
    matrix of M's sparsity as numpy does."""
    m, d, _, _, imp = _state(amputee)
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    dense = np.zeros_like(full)
    dense_mass(d.M, imp[2], imp[3], imp[4], dense)
    np.testing.assert_array_equal(dense, full)
    rng = np.random.default_rng(1)
    pattern = dense != 0.0
    a = dense + pattern * rng.uniform(0.0, 0.5, dense.shape)  # not symmetric
    b = rng.standard_normal(m.nv)
    x = b.copy()
    solve_tree(a.copy(), x, imp[22])
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-10, atol=1e-12)


def test_implicit_step_hands_its_acceleration_to_mujoco_and_tends_to_explicit(amputee):
    """MuJoCo's mj_step2 with the scheme's qfrc_applied gives the solved acceleration (1e-9);
    as dt → 0 that acceleration is the explicit scheme's (relative 1e-6), at 1 ms it differs
    (the implicit terms act)."""
    m, d, arrays, root, _ = _state(amputee)
    forces(mujoco_views(d), arrays, root, 1e-9)
    mujoco.mj_step2(m, d)
    explicit = d.qacc.copy()
    for dt, close in ((1e-9, True), (1e-3, False)):
        m, d, arrays, root, imp = _state(amputee, dt=dt)
        implicit_forces(mujoco_views(d), arrays, imp, root, dt)
        assert np.abs(d.xfrc_applied).max() == 0.0
        solved = imp[12].copy()
        mujoco.mj_step2(m, d)
        np.testing.assert_allclose(d.qacc, solved, atol=1e-9 * np.abs(solved).max())
        scale = np.abs(explicit).max()
        assert (np.abs(solved - explicit).max() < 1e-6 * scale) == close


def test_hip_capsule_torque_and_its_stiffness_in_the_implicit_terms():
    """The human body's hip capsule, τ = 3.91·exp(−0.075·H) N·m (H in degrees): the implicit
    scheme linearises it with its stiffness −dτ/dq = 0.075·(180/π)·τ (the torque itself at
    the step's start is the explicit kernel's, tested against the collocation twin; the
    recorded one is the step's effective torque)."""
    human = build_runner("able", body="human")
    m, d, arrays, root, imp = _state(human)
    implicit_forces(mujoco_views(d), arrays, imp, root, 1e-3)
    lkd = imp[17]
    for side in ("l", "r"):
        j = human.dof(f"hip_flexion_{side}")
        tau = 3.91 * math.exp(-0.075 * math.degrees(d.qpos[j]))
        assert lkd[j, 0] == pytest.approx(0.075 * 180.0 / math.pi * tau, rel=1e-12)


@pytest.mark.parametrize("integrator", ["implicit", "newmark"])
def test_compiled_loop_equals_python_loop(amputee, integrator):
    """The compiled loop's own update (mj_step1/mj_step2 replaced by the stages the scheme
    needs, on the site-free model with bladelab placing the sites) gives the trajectory of the
    Python loop, which calls mj_step1 (and, for the Euler scheme, mj_step2) on the model with
    sites."""
    u = np.full(len(amputee.muscle_names), 0.2)
    kw = {"duration": 0.5, "dt": 1e-3, "integrator": integrator, "record_every": 1}
    a = simulate_runner(amputee, excitations=u, **kw)
    b = simulate_runner(amputee, controller=lambda t, s: u, **kw)
    np.testing.assert_allclose(a.qpos, b.qpos, atol=1e-12)
    np.testing.assert_allclose(a.contacts, b.contacts, atol=1e-8)
    np.testing.assert_allclose(a.muscles, b.muscles, rtol=1e-8, atol=1e-8)


def test_site_kinematics_matches_mujoco(amputee):
    """Sites placed by bladelab on the site-free model = MuJoCo's sites (1e-14 m)."""
    from bladelab.runner.implicit_setup import site_views

    m, d, _, _, _ = _state(amputee)
    dyn = amputee.mj_dynamics_model
    assert dyn.nsite == 0 and dyn.nbody == m.nbody and dyn.nv == m.nv
    dd = mujoco.MjData(dyn)
    dd.qpos[:] = d.qpos
    mujoco.mj_forward(dyn, dd)
    imp = implicit_arrays(amputee, dyn, dd, "implicit", own_sites=True)
    views = site_views(dd, imp)
    np.testing.assert_allclose(views[2], d.site_xpos, atol=1e-14)
    for s in imp[29]:
        np.testing.assert_allclose(views[3][s], d.site_xmat[s], atol=1e-14)


@pytest.mark.parametrize("integrator", ["implicit", "newmark"])
def test_drop_test_at_1ms(amputee, integrator):
    """Joints held by MuJoCo springs (taken implicitly too), 5 cm drop, 1 ms step: the
    static GRF equals body weight within 0.1 % (measured −0.002 % and −0.008 %)."""
    res = simulate_runner(amputee, duration=1.5, hold_pose=True, drop_height=0.05, record_every=5,
                          dt=1e-3, integrator=integrator)
    fz = res.contacts[res.time > 1.3, :, 1].sum(axis=1).mean()
    assert fz == pytest.approx(amputee.body_weight, rel=1e-3)


@pytest.mark.parametrize(
    "kind,u", [("amputee", 0.05), ("amputee", 0.4), ("able", 0.2), ("able-toes", 0.2)]
)
def test_power_balance_at_1ms(kind, u):
    """The runner tests' power-balance case (2 s, constant excitations, ground contact) at a
    1 ms step: RMS residual ≤ 0.5 % of peak kinetic power (measured 0.31–0.38 %; the explicit
    scheme at 0.25 ms: 0.08–0.12 %, at 1 ms: up to 1.5 %), and the external work equals the
    kinetic-energy change within 5 % of its range."""
    runner = build_runner("able", body="toes") if kind == "able-toes" else build_runner(kind)
    res = simulate_runner(runner, duration=2.0, excitations=u, record_every=1,
                          fall_height=-math.inf, dt=1e-3, integrator="implicit")
    assert res.duration == pytest.approx(2.0)
    assert (res.contacts[:, :, 1].sum(axis=1) > 0).mean() > 0.5
    assert power_balance_residual_pct(res) <= 0.5
    from bladelab.runner.analyses import forward_pass

    pb = power_balance(res)
    ek = forward_pass(res)["ek"]
    work = np.trapezoid(pb.external, pb.time)
    assert work == pytest.approx(ek[-1] - ek[0], abs=0.05 * np.ptp(ek))


def test_agreement_with_the_quarter_millisecond_step(amputee):
    """2 s, excitations 0.4 (the model sinks onto its feet and blade): against a 0.05 ms
    explicit reference, the 1 ms implicit trajectory's largest joint-angle error in the first
    0.5 s is at most 6× the 0.25 ms explicit one's (measured 4.0×: the scheme is first order,
    like the explicit one) and below 7.5° (measured 6.0°); over the 2 s the pelvis stays within
    7 cm of the reference (measured 5.2 cm; 0.25 ms: 0.9 cm)."""
    kw = {"duration": 2.0, "excitations": 0.4, "fall_height": -math.inf}
    ref = simulate_runner(amputee, dt=5e-5, record_every=40, **kw)
    old = simulate_runner(amputee, dt=2.5e-4, record_every=8, **kw)
    new = simulate_runner(amputee, dt=1e-3, record_every=2, integrator="implicit", **kw)
    early = ref.time <= 0.5

    def angle_error(res):
        return np.degrees(np.abs(res.qpos[early, 2:] - ref.qpos[early, 2:])).max()

    assert angle_error(new) < 6.0 * angle_error(old)
    assert angle_error(new) < 7.5
    assert np.abs(new.qpos[:, :2] - ref.qpos[:, :2]).max() < 0.07


def test_running_loads_at_1ms():
    """The shipped amputee reflex solution (optimised at 0.25 ms), first 0.8 s at a 1 ms step:
    the explicit scheme rings (second differences of the vertical contact forces of 10 kN, 31 %
    power-balance residual); the implicit one does not (measured 285 N, 1.4 %; 0.25 ms explicit:
    172 N, 0.5 %)."""
    from bladelab.predict.reflex.controller import read_parameters
    from bladelab.predict.reflex.objective import simulate_controlled
    from bladelab.predict.reflex.optimize import runner_and_layout, stored_settings
    from bladelab.runner.params import REFLEX_STARTS_DIR

    path = REFLEX_STARTS_DIR / "amputee-Cat6-3.5.json"
    data = json.loads(path.read_text())
    runner, layout = runner_and_layout(data["model"], data["blade"])
    x = read_parameters(path, layout)
    base = stored_settings(data, speed=3.5, duration=0.8, nominal=True)
    out = {}
    for integrator in ("explicit", "implicit"):
        settings = dataclasses.replace(base, dt=1e-3, integrator=integrator)
        ev, res = simulate_controlled(runner, x, layout=layout, settings=settings, record_every=1)
        ringing = np.abs(np.diff(res.contacts[:, :, 1], 2, axis=0)).max()
        out[integrator] = (ev.fell, ringing, power_balance_residual_pct(res))
    assert out["explicit"][1] > 5000.0 and out["explicit"][2] > 10.0
    assert not out["implicit"][0]
    assert out["implicit"][1] < 1000.0 and out["implicit"][2] < 3.0


def _shipped_amputee_run(dt, integrator, duration=0.8):
    """The shipped amputee reflex solution's first ``duration`` [s], sampled every step."""
    from bladelab.predict.reflex.controller import read_parameters
    from bladelab.predict.reflex.objective import simulate_controlled
    from bladelab.predict.reflex.optimize import runner_and_layout, stored_settings
    from bladelab.runner.params import REFLEX_STARTS_DIR

    path = REFLEX_STARTS_DIR / "amputee-Cat6-3.5.json"
    data = json.loads(path.read_text())
    runner, layout = runner_and_layout(data["model"], data["blade"])
    base = stored_settings(data, speed=3.5, duration=duration, nominal=True)
    settings = dataclasses.replace(base, dt=dt, integrator=integrator)
    return simulate_controlled(runner, read_parameters(path, layout), layout=layout,
                               settings=settings, record_every=1)


def test_newmark_under_running_loads():
    """The shipped amputee solution's first 0.8 s (running loads, reflexes acting): Newmark's
    power-balance residual at 1 ms is at most 0.5 % and below the 0.25 ms explicit step's
    (measured 0.22 % and 0.39 %; the first-order scheme at 1 ms: 1.32 %), and halving the step
    at least halves it again (measured 0.11 %)."""
    out = {}
    for dt, integrator in ((1e-3, "newmark"), (5e-4, "newmark"), (2.5e-4, "explicit")):
        ev, res = _shipped_amputee_run(dt, integrator)
        assert not ev.fell
        out[dt] = power_balance_residual_pct(res)
    assert out[1e-3] <= 0.5
    assert out[1e-3] < out[2.5e-4]
    assert out[5e-4] < 0.6 * out[1e-3]


def test_newmark_accuracy_against_a_fine_step(amputee):
    """The sinking test (excitations 0.4) against Newmark at 0.0625 ms, first 1 s: at 1 ms the
    largest joint-angle error is below a fifth of the 0.25 ms explicit step's (measured 0.32°
    against 1.84°) and the pelvis stays as close (0.21 cm against 0.22 cm); halving the step
    cuts the angle error by at least 2× (measured 2.4×: the rule is second order, the
    ligaments' damping switch and the contacts' stick–slip switch are not smooth)."""
    kw = {"duration": 1.0, "excitations": 0.4, "fall_height": -math.inf}
    ref = simulate_runner(amputee, dt=6.25e-5, record_every=32, integrator="newmark", **kw)

    def errors(dt, integrator):
        res = simulate_runner(amputee, dt=dt, record_every=round(2e-3 / dt),
                              integrator=integrator, **kw)
        return (np.degrees(np.abs(res.qpos[:, 2:] - ref.qpos[:, 2:])).max(),
                np.abs(res.qpos[:, :2] - ref.qpos[:, :2]).max())

    angle_1, pelvis_1 = errors(1e-3, "newmark")
    angle_half, _ = errors(5e-4, "newmark")
    angle_old, pelvis_old = errors(2.5e-4, "explicit")
    assert angle_1 < 0.2 * angle_old
    assert pelvis_1 < 1.5 * pelvis_old
    assert angle_half < 0.5 * angle_1


@pytest.mark.parametrize("kind,u", [("amputee", 0.05), ("amputee", 0.4), ("able", 0.2)])
def test_newmark_power_balance_at_1ms(kind, u):
    """Constant excitations, 2 s with ground contact: Newmark at 1 ms keeps the power balance
    within 0.1 % (measured 0.02–0.05 %; the first-order scheme 0.31–0.35 %)."""
    res = simulate_runner(build_runner(kind), duration=2.0, excitations=u, record_every=1,
                          fall_height=-math.inf, dt=1e-3, integrator="newmark")
    assert power_balance_residual_pct(res) <= 0.1


def test_newmark_power_balance_converges_on_the_human_body():
    """The human body (toe hinge, hip capsule's exponential moment in the linearised terms)
    collapsing under constant excitations 0.2 for 2 s: the power balance within 0.15 % at 1 ms
    (measured 0.11 %) and halved or better at 0.5 ms (measured 0.054 %): the residual is the
    scheme's step-size error, not a missing term."""
    runner = build_runner("able", body="human")
    residual = [power_balance_residual_pct(simulate_runner(
        runner, duration=2.0, excitations=0.2, record_every=1, fall_height=-math.inf, dt=dt,
        integrator="newmark")) for dt in (1e-3, 5e-4)]
    assert residual[0] <= 0.15
    assert residual[1] <= 0.5 * residual[0]


def test_newmark_starts_exactly_and_records_synchronous_velocities(amputee):
    """The first Newmark sample is the initial state itself (the first step takes its exact
    acceleration, no correction), and the recorded velocity is the position's derivative:
    central differences of the positions within 3 % of the velocity scale (measured 2.0 %, at
    the touch-downs; 0.5 ms: 0.5 %), against 8.5 % for the first-order scheme, whose recorded
    velocity is the one that led to the position."""
    u = np.full(len(amputee.muscle_names), 0.2)
    kw = {"duration": 0.5, "dt": 1e-3, "integrator": "newmark", "record_every": 1}
    a = simulate_runner(amputee, excitations=u, **kw)
    q0, v0 = initial_qpos(amputee, "stand")
    np.testing.assert_allclose(a.qpos[0], q0, atol=1e-12)
    np.testing.assert_allclose(a.qvel[0], v0, atol=1e-12)
    central = (a.qpos[2:] - a.qpos[:-2]) / 2e-3
    scale = np.abs(a.qvel).max()
    assert np.abs(central - a.qvel[1:-1]).max() < 0.03 * scale
    e = simulate_runner(amputee, excitations=u, **{**kw, "integrator": "implicit"})
    lag = np.abs((e.qpos[2:] - e.qpos[:-2]) / 2e-3 - e.qvel[1:-1]).max()
    assert lag > 2 * np.abs(central - a.qvel[1:-1]).max()


def test_unknown_integrator(amputee):
    from bladelab.errors import BladelabError

    with pytest.raises(BladelabError, match="integrator"):
        simulate_runner(amputee, duration=0.01, integrator="rk4")
