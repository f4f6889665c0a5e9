"""The same model on both sides: the CasADi collocation model equals the forward model
(MuJoCo + bladelab's numba kernels) at random states, exactly or within the stated bounds of
its smooth approximations (bladelab.predict.collocation.bounds, docs/collocation.md)."""

from __future__ import annotations

import math

import casadi as ca
import mujoco
import numpy as np
import pytest

from bladelab.blade import load_blade
from bladelab.contact import hunt_crossley_force, smooth_spring_damper_force
from bladelab.predict.collocation import Smoothing, build_collocation_model
from bladelab.predict.collocation.bounds import (
    damping_switch_bound,
    hunt_crossley_bound,
    ligament_bound,
    sliding_friction_bound,
    socket_bound,
    spring_damper_bound,
)
from bladelab.runner.kernel import forces, mujoco_views, path_kinematics
from bladelab.runner.layout import (
    CP_BLADE,
    CP_BODY,
    CP_C,
    CP_DAMP,
    CP_EXP,
    CP_K,
    CP_LAW,
    CP_MU,
    CP_WIDTH,
    JP_D,
    JP_HI,
    JP_K,
    JP_LO,
    JP_SD,
    JP_SDX,
    JP_SK,
    JP_SK2,
)
from bladelab.runner.model import build_runner, contact_heights
from bladelab.runner.muscle import (
    FIBER_DAMPING,
    MP_TSTRAIN,
    MP_VMAX,
    TENDON_REF_STRAIN,
    equilibrium_fiber_length,
    force_length,
    force_velocity,
    muscle_step,
    passive_force,
    tendon_force,
    tendon_force_of_state,
)
from bladelab.runner.params import ArchSpring, default_runner_params
from bladelab.runner.scaling import athlete_params

N_STATES = 20
KINDS = ("able", "amputee-Cat6", "able-toes", "transfemoral", "able-human", "amputee-human",
         "transfemoral-human", "amputee-human-short", "able-human-long-thighs",
         "able-human-arch")
# the toe body's Achilles tendons are twice as compliant; the human body's tendons differ per
# muscle and its strengths come from a table
# and a human body with faster fibres: every muscle's v_max 15 l_opt/s, not 10
MUSCLE_KINDS = ("able", "able-toes", "able-human", "able-human-vmax15", "able-human-arch")
SM = Smoothing()


@pytest.fixture(scope="module")
def models():
    """The forward runners and their collocation models, built once."""
    out = {}
    for kind in KINDS + ("able-human-vmax15",):
        runner = {"able": lambda: build_runner("able"),
                  "able-human-vmax15": lambda: build_runner(default_runner_params(
                      "able", body="human").model_copy(
                          update={"max_shortening_velocity_lopt_per_s": 15.0})),
                  "able-toes": lambda: build_runner("able", body="toes"),
                  "amputee-Cat6": lambda: build_runner("amputee", blade="Cat6"),
                  "transfemoral": lambda: build_runner("transfemoral"),
                  "able-human": lambda: build_runner("able", body="human"),
                  # a foot with an arch: a midtarsal hinge with its spring and damper
                  "able-human-arch": lambda: build_runner(default_runner_params(
                      "able", body="human").model_copy(update={"arch": ArchSpring()})),
                  "amputee-human": lambda: build_runner("amputee", body="human"),
                  # an athlete's own thighs and shanks: segments and muscles rescaled
                  "able-human-long-thighs": lambda: build_runner(athlete_params(
                      default_runner_params("able", body="human"), thigh_length_m=0.46,
                      shank_length_m=0.42)),
                  # a short residual limb: 12 cm of tibia (28 %), a longer prosthesis
                  "amputee-human-short": lambda: build_runner(athlete_params(
                      default_runner_params("amputee", body="human"),
                      residual_limb_length_m=0.12)),
                  # the residual limb with a myodesis: hip-only hamstrings and rectus femoris
                  "transfemoral-human": lambda: build_runner("transfemoral", body="human"),
                  }[kind]()
        out[kind] = (runner, build_collocation_model(runner))
    return out


def _states(runner, seed: int):
    """20 random poses, velocities and accelerations around the standing pose."""
    rng = np.random.default_rng(seed)
    nv = runner.mj_model.nv
    for _ in range(N_STATES):
        q = runner.stand_qpos + rng.normal(0.0, 0.4, nv)
        yield q, rng.normal(0.0, 2.0, nv), rng.normal(0.0, 20.0, nv)


def _np(x) -> np.ndarray:
    return np.array(x, dtype=np.float64)


# ---------------------------------------------------------------- (a) multibody dynamics


@pytest.mark.parametrize("kind", KINDS)
def test_inverse_dynamics_equals_mj_inverse(models, kind):
    runner, cm = models[kind]
    m = runner.mj_model
    assert not (m.dof_armature.any() or m.dof_damping.any() or m.dof_frictionloss.any())
    assert cm.tree.gravity[1] == pytest.approx(-runner.gravity)
    d = mujoco.MjData(m)
    worst = 0.0
    for q, qd, qdd in _states(runner, 1):
        d.qpos[:], d.qvel[:], d.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(m, d)
        tau = _np(cm.inverse_dynamics(q, qd, qdd)).ravel()
        worst = max(worst, np.abs(tau - d.qfrc_inverse).max() / np.abs(d.qfrc_inverse).max())
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        np.testing.assert_allclose(_np(cm.mass_matrix(q)), full, rtol=0, atol=1e-9)
    assert worst < 1e-6, worst


# ---------------------------------------------------------------- (b) muscle paths


@pytest.mark.parametrize("kind", KINDS)
def test_mtu_lengths_velocities_moment_arms(models, kind):
    runner, cm = models[kind]
    m, ma = runner.mj_model, runner.mj_analysis_model
    assert np.all(ma.actuator_gear[:, 0] == 1.0)
    d, da = mujoco.MjData(m), mujoco.MjData(ma)
    nm = len(runner.muscle_names)
    mtu = np.zeros((nm, 2))
    seg_u = np.zeros((runner.path_points.shape[0], 3))
    for q, qd, _ in _states(runner, 2):
        for data, model in ((d, m), (da, ma)):
            data.qpos[:], data.qvel[:] = q, qd
            mujoco.mj_forward(model, data)
        path_kinematics(d.site_xpos, d.cvel, d.subtree_com[1].copy(), runner.path_points,
                        runner.path_start, mtu, seg_u)
        length, vel = (_np(x).ravel() for x in cm.mtu(q, qd))
        arms = _np(cm.moment_arms(q))
        np.testing.assert_allclose(length, mtu[:, 0], rtol=1e-6)
        np.testing.assert_allclose(length, da.ten_length, rtol=1e-6)
        scale = np.abs(mtu[:, 1]).max()
        np.testing.assert_allclose(vel, mtu[:, 1], rtol=0, atol=1e-6 * scale)
        np.testing.assert_allclose(vel, da.ten_velocity, rtol=0, atol=1e-6 * scale)
        jac = np.zeros((ma.nu, ma.nv))
        mujoco.mju_sparse2dense(jac, da.actuator_moment, da.moment_rownnz, da.moment_rowadr,
                                da.moment_colind)
        np.testing.assert_allclose(arms, -jac, rtol=0, atol=1e-6 * np.abs(jac).max())


# ---------------------------------------------------------------- (c) contact and passive


def _penetrating_states(runner, seed: int):
    """Random poses lowered so that the lowest contact is 3–40 mm deep, random velocities."""
    rng = np.random.default_rng(seed)
    iz = runner.dof("pelvis_tz")
    for q, qd, _ in _states(runner, seed):
        qd = 0.5 * qd
        q[iz] -= contact_heights(runner, q).min() + rng.uniform(0.003, 0.04)
        yield q, qd


def _forward_forces(runner, d):
    """One call of the forward kernel: contact rows (ft, fn, px, pz, vx, vz, depth) with the
    friction bristle in its sliding state, and the ligament + socket torques."""
    mp, cp = runner.muscle_params, runner.contact_params
    nm, nc = mp.shape[0], cp.shape[0]
    ms = np.zeros((nm, 4))
    ms[:, 0], ms[:, 1] = 0.01, mp[:, 1]
    crec, lig = np.zeros((nc, 7)), np.zeros(runner.mj_model.nv)
    cstate = np.zeros((nc, 1))
    arrays = (mp, ms, np.zeros((nm, 2)), np.zeros((runner.path_points.shape[0], 3)),
              np.zeros(nm), runner.path_points, runner.path_start, cp, cstate,
              runner.joint_params, crec, lig)
    root = d.subtree_com[1].copy()
    forces(mujoco_views(d), arrays, root, 2.5e-4)
    cstate[:, 0] = np.sign(crec[:, 4])  # anchor 1 m behind: the bristle slides
    forces(mujoco_views(d), arrays, root, 2.5e-4)
    return crec.copy(), lig.copy()


@pytest.mark.parametrize("kind", KINDS)
def test_contact_forces_match_forward_hunt_crossley(models, kind):
    runner, cm = models[kind]
    m = runner.mj_model
    d = mujoco.MjData(m)
    n_in_contact = 0
    for q, qd in _penetrating_states(runner, 3):
        d.qpos[:], d.qvel[:] = q, qd
        mujoco.mj_forward(m, d)
        crec, _ = _forward_forces(runner, d)
        f, p, tau = (_np(x) for x in cm.contacts(q, qd))
        np.testing.assert_allclose(p, crec[:, 2:4], rtol=0, atol=1e-12)
        qfrc = np.zeros(m.nv)
        for c, row in enumerate(runner.contact_params):
            depth, vx, vz = crec[c, 6], crec[c, 4], crec[c, 5]
            k, n, diss, mu = row[CP_K], row[CP_EXP], row[CP_C], row[CP_MU]
            fn = hunt_crossley_force(depth, -vz, k, n, diss)
            assert crec[c, 1] == pytest.approx(fn, rel=1e-12, abs=1e-12)
            bound_n = hunt_crossley_bound(depth, -vz, k, n, diss, SM)
            assert abs(f[c, 1] - fn) <= bound_n + 1e-9, (c, f[c, 1], fn, bound_n)
            if abs(vx) >= 0.1:  # the forward bristle slides: −μ·Fn·sign(v)
                assert crec[c, 0] == pytest.approx(-mu * fn * np.sign(vx), rel=1e-12, abs=1e-12)
                bound_t = mu * bound_n + sliding_friction_bound(vx, f[c, 1], mu, SM)
                assert abs(f[c, 0] - crec[c, 0]) <= bound_t + 1e-9
            assert abs(f[c, 0]) <= mu * f[c, 1] + 1e-12
            n_in_contact += depth > 0.003
            mujoco.mj_applyFT(m, d, np.array([f[c, 0], 0.0, f[c, 1]]), np.zeros(3),
                              np.array([p[c, 0], 0.0, p[c, 1]]), int(row[CP_BODY]), qfrc)
        np.testing.assert_allclose(tau.ravel(), qfrc, rtol=0, atol=1e-9 * np.abs(qfrc).max())
    assert n_in_contact >= N_STATES


@pytest.mark.parametrize("kind", ["amputee-human", "transfemoral-human"])
def test_each_legs_vertical_force_sums_that_legs_contacts(models, kind):
    """``StrideDynamics.leg_vertical_grf``: the contacts' vertical forces of the intact leg,
    then of the prosthetic leg (``CP_LEG``), which add up to ``vertical_grf``."""
    from bladelab.predict.collocation.dynamics import stride_dynamics
    from bladelab.runner.layout import CP_LEG

    runner, cm = models[kind]
    dyn = stride_dynamics(cm)
    legs = runner.contact_params[:, CP_LEG]
    for q, qd in _penetrating_states(runner, 4):
        fz = _np(cm.contacts(q, qd)[0])[:, 1]
        per_leg = _np(dyn.leg_vertical_grf(q, qd)).ravel()
        np.testing.assert_allclose(per_leg, [fz[legs == 0].sum(), fz[legs == 1].sum()],
                                   rtol=1e-12, atol=1e-9)
        assert per_leg.sum() == pytest.approx(float(dyn.vertical_grf(q, qd)), rel=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_ligament_and_socket_torques_match_forward(models, kind):
    runner, cm = models[kind]
    m = runner.mj_model
    d = mujoco.MjData(m)
    jp = runner.joint_params
    checked = 0
    for q, qd, _ in _states(runner, 4):
        d.qpos[:], d.qvel[:] = q, qd
        mujoco.mj_forward(m, d)
        _, lig = _forward_forces(runner, d)
        tau = _np(cm.passive(q, qd)).ravel()
        for j, row in enumerate(jp):
            spring = row[JP_SK] != 0.0 or row[JP_SK2] != 0.0  # socket, toe hinge
            if not spring and row[JP_K] == 0.0:
                assert tau[j] == 0.0 and lig[j] == 0.0
                continue
            bound = socket_bound(row[JP_SK2], SM) if spring else 0.0
            bound += damping_switch_bound(row[JP_SD], row[JP_SDX], SM)  # a hydraulic knee
            if row[JP_K] != 0.0:  # a ligament (the toe hinge has both)
                margin = min(abs(q[j] - row[JP_LO]), abs(q[j] - row[JP_HI]))
                if margin < 0.1:
                    continue
                bound += ligament_bound(margin, qd[j], row[JP_K], row[JP_D], SM)
            assert abs(tau[j] - lig[j]) <= bound + 1e-9, (j, tau[j], lig[j])
            checked += 1
    assert checked >= 3 * N_STATES


@pytest.mark.parametrize("kind", ["able-human", "amputee-human"])
def test_hip_capsule_moment_is_riener_and_edrichs_extension_term(models, kind):
    """Within the hip's range (no ligament), both twins' passive hip torque is the capsule's
    3.91·exp(−0.075·H) N·m (H in degrees, flexing), the parameter file's numbers; the
    knee and ankle carry none."""
    runner, cm = models[kind]
    m = runner.mj_model
    d = mujoco.MjData(m)
    for hip_deg in (-25.0, -10.0, 0.0, 30.0):
        q = runner.stand_qpos.copy()
        for side in ("l", "r"):
            q[runner.dof(f"hip_flexion_{side}")] = math.radians(hip_deg)
        d.qpos[:], d.qvel[:] = q, 0.0
        mujoco.mj_forward(m, d)
        _, lig = _forward_forces(runner, d)
        tau = _np(cm.passive(q, np.zeros(m.nv))).ravel()
        expected = 3.91 * math.exp(-0.075 * hip_deg)
        for side in ("l", "r"):
            j = runner.dof(f"hip_flexion_{side}")
            assert lig[j] == pytest.approx(expected, rel=1e-12)
            assert tau[j] == pytest.approx(expected, rel=1e-12)
        assert lig[runner.dof("knee_angle_l")] == 0.0 == lig[runner.dof("ankle_angle_l")]


@pytest.mark.parametrize("kind", ["able-human", "amputee-human", "transfemoral-human"])
def test_human_lumbar_spring_is_the_same_law_in_both_twins_across_zero(models, kind):
    """The human body's lumbar joint is a linear spring–damper about 0° (500 N·m/rad,
    5 N·m·s/rad): both twins give −500·q − 5·q̇ to round-off, also where the trunk crosses 0°
    with speed, where seed 001's two-sided ligament's damping jumps."""
    runner, cm = models[kind]
    m = runner.mj_model
    d = mujoco.MjData(m)
    j = runner.dof("lumbar_extension")
    for q_deg, qd in ((0.0, 2.0), (0.05, -1.5), (-0.05, 1.5), (-10.0, 0.3), (8.0, -0.7)):
        q, v = runner.stand_qpos.copy(), np.zeros(m.nv)
        q[j], v[j] = math.radians(q_deg), qd
        d.qpos[:], d.qvel[:] = q, v
        mujoco.mj_forward(m, d)
        _, lig = _forward_forces(runner, d)
        tau = _np(cm.passive(q, v)).ravel()
        expected = -500.0 * q[j] - 5.0 * qd
        assert lig[j] == pytest.approx(expected, rel=1e-12, abs=1e-12)
        assert tau[j] == pytest.approx(expected, rel=1e-12, abs=1e-12)


def test_seed001_lumbar_ligament_pushes_only_beyond_zero(models):
    """Seed 001's body keeps its lumbar ligament at 0° both ways: moving out of 0° its
    damping acts at once (−5·q̇ just beyond the limit), moving back in it never pulls."""
    runner, _ = models["able"]
    m = runner.mj_model
    d = mujoco.MjData(m)
    j = runner.dof("lumbar_extension")
    for q_rad, qd, expected in ((1e-6, 2.0, -500.0 * 1e-6 - 10.0), (1e-6, -2.0, 0.0),
                                (-1e-6, -2.0, 500.0 * 1e-6 + 10.0)):
        q, v = runner.stand_qpos.copy(), np.zeros(m.nv)
        q[j], v[j] = q_rad, qd
        d.qpos[:], d.qvel[:] = q, v
        mujoco.mj_forward(m, d)
        _, lig = _forward_forces(runner, d)
        assert lig[j] == pytest.approx(expected, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("kind", ["amputee", "transfemoral"])
def test_multilink_blade_model_matches_forward(kind):
    """An amputee wearing a multi-link blade (extra hinge about +y, ellipse soles turned in
    their bodies, spring–damper law): inverse dynamics, contact geometry, sole normal forces
    (within the stated bound) and the blade joint's spring."""
    runner = build_runner(kind, blade_model=load_blade("xtreme-cat5").build())
    cm = build_collocation_model(runner)
    m = runner.mj_model
    d = mujoco.MjData(m)
    for q, qd, qdd in _states(runner, 8):
        d.qpos[:], d.qvel[:], d.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(m, d)
        tau = _np(cm.inverse_dynamics(q, qd, qdd)).ravel()
        assert np.abs(tau - d.qfrc_inverse).max() < 1e-6 * np.abs(d.qfrc_inverse).max()
    rng = np.random.default_rng(9)
    iz, blade = runner.dof("pelvis_tz"), runner.contact_params[:, CP_BLADE] == 1
    jb = runner.dof("blade_joint0")
    checked = 0
    for q, qd, _ in _states(runner, 9):
        qd = 0.5 * qd
        # from first touch (inside the soles' 0.1-mm onset) to 4 mm deep
        q[iz] -= contact_heights(runner, q)[blade].min() + rng.uniform(0.00002, 0.004)
        d.qpos[:], d.qvel[:] = q, qd
        mujoco.mj_forward(m, d)
        crec, lig = _forward_forces(runner, d)
        f, p, _ = (_np(x) for x in cm.contacts(q, qd))
        np.testing.assert_allclose(p, crec[:, 2:4], rtol=0, atol=1e-12)
        for c, row in enumerate(runner.contact_params):
            depth, rate = crec[c, 6], -crec[c, 5]
            if row[CP_LAW] != 1 or depth <= 0.0:
                continue
            fn = smooth_spring_damper_force(depth, rate, row[CP_K], row[CP_DAMP], row[CP_WIDTH])
            assert crec[c, 1] == pytest.approx(fn, rel=1e-12)
            bound = spring_damper_bound(depth, rate, row[CP_K], row[CP_DAMP], row[CP_WIDTH], SM)
            assert abs(f[c, 1] - fn) <= bound + 1e-9
            checked += 1
        tau = _np(cm.passive(q, qd)).ravel()
        assert abs(tau[jb] - lig[jb]) <= socket_bound(runner.joint_params[jb, JP_SK2], SM) + 1e-9
    assert checked >= N_STATES


# ---------------------------------------------------------------- (d) muscles

# Stated fit errors of the smooth curves at the default Smoothing (docs/collocation.md).
FV_ERROR = 1.0e-3  # force–velocity, on −1 ≤ ṽ ≤ 1
FP_ERROR = 3.0e-4  # passive force, absolute [-]
FT_ERROR = 6.0e-4  # tendon force, absolute [-]
ADOT_ERROR = 0.14  # activation rate [1/s]: 75/s · w/e
EQ_ERROR = (1.0e-3, FP_ERROR)  # equilibrium tendon force: relative, absolute [-]


def _curve(f):
    x = ca.SX.sym("x")
    fun = ca.Function("curve", [x], [f(x)])
    return lambda v: _np(fun(v)).ravel()


def test_muscle_curves_match_forward_hill():
    from bladelab.predict.collocation import muscles as dg

    v = np.linspace(-1.0, 1.0, 4001)
    fv = _curve(lambda x: dg.force_velocity(x, SM))(v)
    assert np.abs(fv - [force_velocity(x) for x in v]).max() <= FV_ERROR
    ln = np.linspace(0.2, 2.0, 4001)
    fl = _curve(dg.force_length)(ln)
    np.testing.assert_allclose(fl, [force_length(x) for x in ln], rtol=1e-12, atol=1e-15)
    fp = _curve(lambda x: dg.passive_force(x, SM))(ln)
    assert np.abs(fp - [passive_force(x) for x in ln]).max() <= FP_ERROR
    eps = np.linspace(-0.05, 0.12, 4001)
    ft = _curve(lambda x: dg.tendon_force_curve(x, SM))(eps)
    assert np.abs(ft - [tendon_force(x) for x in eps]).max() <= FT_ERROR
    # a more compliant tendon (8 % at Fmax): the same softplus width is a smaller share of it
    ft8 = _curve(lambda x: dg.tendon_force_curve(x, SM, 0.08))(eps)
    assert np.abs(ft8 - [tendon_force(x, 0.08) for x in eps]).max() <= FT_ERROR / 4
    assert tendon_force(0.08, 0.08) == pytest.approx(1.0) and tendon_force(0.04) == 1.0
    # the inverse tendon curve is the inverse
    f = np.linspace(0.01, 2.0, 200)
    for ref in (TENDON_REF_STRAIN, 0.08):
        back = _curve(lambda x, r=ref: dg.tendon_force_curve(dg.tendon_strain(x, SM, r), SM, r))(f)
        np.testing.assert_allclose(back, f, rtol=1e-10)


def test_activation_rate_matches_forward(models):
    runner, cm = models["able"]
    rng = np.random.default_rng(5)
    mp = runner.muscle_params
    nm, dt = mp.shape[0], 1e-6
    for _ in range(N_STATES):
        a = rng.uniform(0.02, 0.98, nm)
        u = rng.uniform(0.0, 1.0, nm)
        ms = np.zeros((nm, 4))
        ms[:, 0], ms[:, 1] = a, mp[:, 1]
        muscle_step(mp, ms, np.full(nm, 0.5), u, dt)
        forward = (ms[:, 0] - a) / dt
        smooth = _np(cm.activation_rate(u, a)).ravel()
        np.testing.assert_allclose(smooth, forward, rtol=0, atol=ADOT_ERROR + 1e-6)


def _fibre_force(a, ln, vn, cos_a, strength=1.0, e0=0.6):
    """The forward model's normalised fibre force along the tendon (``strength``: the
    muscle's active strength, ``e0`` its passive strain at Fmax)."""
    return (strength * a * force_length(ln) * force_velocity(vn) + passive_force(ln, e0)
            + FIBER_DAMPING * vn) * cos_a


@pytest.mark.parametrize("kind", MUSCLE_KINDS)
def test_static_equilibrium_tendon_force_matches_forward(models, kind):
    """Isometric equilibrium (ṽ = 0) at random activations and fibre lengths: the forward
    model's equilibrium fibre length and tendon force against the De Groote residual's root."""
    runner, cm = models[kind]
    mp = runner.muscle_params
    nm = mp.shape[0]
    rng = np.random.default_rng(6)
    ft, p = ca.SX.sym("ft", nm), ca.SX.sym("p", 2 * nm)
    res = cm.muscle_residual(p[:nm], ft, 0.0, p[nm:], 0.0)
    solve = ca.rootfinder("eq", "newton", ca.Function("g", [ft, p], [res]),
                          {"abstol": 1e-13, "max_iter": 50})
    worst = 0.0
    for _ in range(N_STATES):
        a, ln = rng.uniform(0.1, 1.0, nm), rng.uniform(0.6, 1.5, nm)
        l_mt = np.zeros(nm)
        for i, (_, l_opt, l_ts, penn, eref, _, _, _) in enumerate(mp):
            cos_a = np.sqrt(1.0 - (np.sin(penn) / ln[i]) ** 2)
            f = _fibre_force(a[i], ln[i], 0.0, cos_a, mp[i, 5], mp[i, 6])
            l_mt[i] = ln[i] * l_opt * cos_a + l_ts * (1.0 + eref * np.sqrt(f))
        forward = np.array([
            tendon_force_of_state(l_mt[i], equilibrium_fiber_length(l_mt[i], a[i], *mp[i, 1:7]),
                                  *mp[i, :5]) / mp[i, 0] for i in range(nm)])
        dg = _np(solve(forward, np.concatenate([a, l_mt]))).ravel()
        assert np.abs(_np(cm.muscle_residual(a, dg, 0.0, l_mt, 0.0))).max() < 1e-10
        excess = np.abs(dg - forward) - (EQ_ERROR[0] * forward + EQ_ERROR[1])
        worst = max(worst, excess.max())
    assert worst <= 0.0, worst


@pytest.mark.parametrize("kind", MUSCLE_KINDS)
def test_fibre_state_and_residual_match_forward_in_motion(models, kind):
    """At forward states with fibre and MTU velocities, the De Groote fibre length and velocity
    (from F̃_T and dF̃_T/dt) equal the forward fibre's, and the equilibrium residual is within
    the force–velocity fit error."""
    runner, cm = models[kind]
    mp = runner.muscle_params
    nm = mp.shape[0]
    rng = np.random.default_rng(7)
    for _ in range(N_STATES):
        a, ln = rng.uniform(0.1, 1.0, nm), rng.uniform(0.6, 1.4, nm)
        vn = rng.uniform(-0.9, 0.9, nm)
        v_mt = rng.uniform(-0.5, 0.5, nm)
        l_ce, v_ce, l_mt, ft, dft, cos_a = (np.zeros(nm) for _ in range(6))
        for i, (fmax, l_opt, l_ts, penn, eref, _, _, _) in enumerate(mp):
            cos_a[i] = np.sqrt(1.0 - (np.sin(penn) / ln[i]) ** 2)
            f = max(_fibre_force(a[i], ln[i], vn[i], cos_a[i], mp[i, 5], mp[i, 6]), 0.05)
            l_ce[i], v_ce[i] = ln[i] * l_opt, vn[i] * mp[i, MP_VMAX] * l_opt
            l_mt[i] = l_ce[i] * cos_a[i] + l_ts * (1.0 + eref * np.sqrt(f))
            ft[i] = tendon_force_of_state(l_mt[i], l_ce[i], *mp[i, :5]) / fmax
            h = 1e-6
            hi = tendon_force_of_state(l_mt[i] + h * v_mt[i], l_ce[i] + h * v_ce[i], *mp[i, :5])
            lo = tendon_force_of_state(l_mt[i] - h * v_mt[i], l_ce[i] - h * v_ce[i], *mp[i, :5])
            dft[i] = (hi - lo) / (2 * h * fmax)
        l_m, v_m, cos_m = (_np(x).ravel() for x in cm.fiber(l_mt, v_mt, ft, dft))
        np.testing.assert_allclose(l_m, l_ce, rtol=1e-5)
        np.testing.assert_allclose(cos_m, cos_a, rtol=1e-5)
        # the tendon curve's softplus changes the tendon compliance by e^{−s/w}/(1 − e^{−s/w})
        v_t = v_mt - v_ce / cos_a
        r = np.exp(-mp[:, MP_TSTRAIN] * np.sqrt(ft) / SM.tendon_strain)
        # plus 5e-8 m/s: the central difference of dF̃_T/dt above (h = 1e-6) carries round-off
        # of about that size into the fibre velocity of the stiffest tendons
        np.testing.assert_array_less(np.abs(v_m - v_ce), 1.01 * r / (1 - r) * np.abs(v_t) + 5e-8)
        # residual of the forward state: forward fibre force minus F̃_T, up to the fits
        forward = np.array([_fibre_force(a[i], ln[i], vn[i], cos_a[i], mp[i, 5], mp[i, 6])
                            for i in range(nm)])
        expected = forward - ft
        res = _np(cm.muscle_residual(a, ft, dft, l_mt, v_mt)).ravel()
        # the fit error of the active force; the passive one scales with 1/e0²
        bound = mp[:, 5] * a * FV_ERROR + FP_ERROR * (0.6 / mp[:, 6]) ** 2 + 1e-4
        assert np.all(np.abs(res - expected) <= bound), np.abs(res - expected).max()


@pytest.mark.parametrize("metabolic_model", ["uchida2016", "uchida2016-vmax15", "bhargava2004"])
def test_smooth_metabolic_rate_matches_forward(models, metabolic_model):
    """The collocation model's whole-body metabolic rate equals the forward model's
    (bladelab.runner.metabolics) at the same fibre states, within the smooth switches' widths:
    ≤ 0.5 % per state at random activations, excitations, fibre lengths and velocities — including
    stretched, weakly active muscles whose total rate the forward model floors at 0. Both
    metabolic models (Bhargava's on the human body, whose active strength enters its heat);
    Uchida's shortening heat also with faster fibres (v_max 15 l_opt/s)."""
    from bladelab.predict.collocation.dynamics import MAX_FIBER_ALONG, MIN_FIBER_ALONG
    from bladelab.predict.collocation.metabolics import metabolic_rate
    from bladelab.runner.metabolics import metabolic_params, total_metabolic_rate

    if metabolic_model == "uchida2016":
        runner, cm = models["able"]
    elif metabolic_model == "uchida2016-vmax15":
        runner = build_runner(default_runner_params("able").model_copy(
            update={"max_shortening_velocity_lopt_per_s": 15.0}))
        cm = build_collocation_model(runner)
    else:
        runner = build_runner(default_runner_params("able", body="human").model_copy(
            update={"metabolic_model": metabolic_model}))
        cm = build_collocation_model(runner)
    mp = runner.muscle_params
    nm = mp.shape[0]
    syms = [ca.SX.sym(n, nm) for n in ("u", "a", "ft", "dft", "lmt", "vmt")]
    f_met = ca.Function("met", syms, [metabolic_rate(runner, *syms[:4], syms[4], syms[5],
                                                     cm.smoothing)])
    mb = metabolic_params(runner)
    body_mass = float(np.sum(runner.mj_model.body_mass))
    rng = np.random.default_rng(11)
    floored, worst, states = 0, 0.0, 0
    while states < N_STATES:
        a = rng.uniform(0.01, 1.0, nm)
        u = np.clip(a + rng.normal(0.0, 0.3, nm), 0.01, 1.0)
        ft = rng.uniform(0.02, 1.2, nm)
        dft = rng.normal(0.0, 5.0, nm)
        l_mt = np.array([p[1] + p[2] * 1.03 for p in mp]) * rng.uniform(0.9, 1.1, nm)
        v_mt = rng.uniform(-0.5, 0.5, nm)
        l_m, v_m, cos_a = (_np(x).ravel() for x in cm.fiber(l_mt, v_mt, ft, dft))
        along = l_m * cos_a / mp[:, 1]
        if np.any(along < MIN_FIBER_ALONG) or np.any(along > MAX_FIBER_ALONG):
            continue  # a state the NLP's path bounds exclude (fibres nearly folded)
        states += 1
        ms = np.stack([a, l_m, v_m, ft * mp[:, 0]], axis=1)
        forward = total_metabolic_rate(u, ms, mp, mb, body_mass)
        smooth = float(f_met(u, a, ft, dft, l_mt, v_mt))
        worst = max(worst, abs(smooth - forward) / forward)
        per_muscle_work = -(ft * mp[:, 0]) * v_m / mb[:, 0]
        floored += int(np.sum(per_muscle_work < -200.0))
    assert worst <= 0.005, worst  # measured 5e-4
    assert floored > 0  # the states reach the floor at 0 (absorbed work not refunded)


def test_swing_clearance_binds_only_a_contact_moving_forward(models):
    """The swing-clearance inequality (the toe clearance as a constraint): a stance
    contact (at rest while the pelvis moves on) is free even when it penetrates; a contact
    moving forward faster than the pelvis must be ``h`` above the ground (its value is its
    height minus h)."""
    from bladelab.predict.collocation.dynamics import SWING_ALLOWANCE_M, swing_clearance

    runner, cm = models["transfemoral"]
    q_s, qd_s = ca.SX.sym("q", cm.nv), ca.SX.sym("qd", cm.nv)
    fn = ca.Function("clearance", [q_s, qd_s], [swing_clearance(cm, q_s, qd_s, 0.02)])
    ix, iz, tilt = (runner.dof(n) for n in ("pelvis_tx", "pelvis_tz", "pelvis_tilt"))
    q = runner.stand_qpos.copy()
    q[iz] -= 0.01  # every contact 1 cm deep, as in a stance
    stance = np.zeros(cm.nv)
    stance[ix] = 4.0  # the body runs on; the contacts' points move forward at 4 m/s too
    stance[tilt] = 0.0
    heights = contact_heights(runner, q)
    assert np.all(heights < -0.005)
    # with the pelvis: each contact moves at the pelvis's speed, not faster: not swinging
    values = np.asarray(fn(q, stance)).ravel()
    assert np.all(values > heights + 0.95 * SWING_ALLOWANCE_M) and np.all(values > 0)
    assert np.all(values <= heights + SWING_ALLOWANCE_M)
    # a whole-body pitch at 6 rad/s about the pelvis: the contacts below it swing
    # forward several m/s faster than the pelvis, and must clear the ground by 2 cm
    q[iz] += 0.06
    swing = stance.copy()
    swing[tilt] = 6.0  # backward tilt: the top goes back, the feet forward
    heights = contact_heights(runner, q)
    values = np.asarray(fn(q, swing)).ravel()
    np.testing.assert_allclose(values, heights - 0.02, atol=1e-6)


def test_knee_moment_is_the_prosthetic_grf_moment_about_the_knee_axis(models):
    """Seed 002's knee-buckling moment as the collocation constraint sees it, against MuJoCo's
    knee axis and the contact forces by hand; 0 with the prosthesis in the air."""
    from bladelab.errors import SpecError
    from bladelab.predict.collocation.dynamics import knee_extension_moment
    from bladelab.runner.layout import CP_LEG

    runner, cm = models["transfemoral"]
    q_s, qd_s = ca.SX.sym("q", cm.nv), ca.SX.sym("qd", cm.nv)
    fn = ca.Function("knee", [q_s, qd_s], [knee_extension_moment(cm, q_s, qd_s)])
    m, d = runner.mj_model, mujoco.MjData(runner.mj_model)
    rng = np.random.default_rng(21)
    pros = runner.contact_params[:, CP_LEG] == 1
    for _ in range(5):
        q = runner.stand_qpos.copy()
        q[runner.dof("pelvis_tz")] -= rng.uniform(0.005, 0.03)
        q[runner.dof("pelvis_tilt")] += rng.uniform(-0.05, 0.05)
        qd = rng.normal(0.0, 0.5, cm.nv)
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        kx, _, kz = d.xanchor[m.joint("knee_angle_r").id]
        forces, points, _ = (np.asarray(x) for x in cm.contacts(q, qd))
        want = np.sum((points[pros, 0] - kx) * forces[pros, 1]
                      - (points[pros, 1] - kz) * forces[pros, 0])
        assert forces[pros, 1].sum() > 50.0  # loaded
        assert float(fn(q, qd)) == pytest.approx(want, rel=1e-9, abs=1e-9)
    q[runner.dof("pelvis_tz")] += 0.3  # in the air
    assert abs(float(fn(q, qd))) < 1e-6
    with pytest.raises(SpecError, match="no prosthetic knee"):
        knee_extension_moment(models["amputee-Cat6"][1], q_s, qd_s)


def _assert_last_path_inequality(cm, q, qd, want: float, **setting) -> None:
    """The stride dynamics built with one path-constraint ``setting`` end their path
    inequalities with it (``want`` at the state q, qd), one row, bounded below by 0."""
    from bladelab.predict.collocation.dynamics import stride_dynamics

    dyn = stride_dynamics(cm, **setting)
    nm = cm.n_muscles
    a = ft = dft = np.full(nm, 0.1)
    path = np.asarray(dyn.inequalities(q, qd, a, ft, dft)).ravel()
    assert path.size == 2 * nm + 1 and path[-1] == pytest.approx(want, rel=1e-12)
    np.testing.assert_array_equal(dyn.inequality_bounds[-1], [0.0, np.inf])


def test_loaded_knee_flexion_limit_is_weighted_by_the_prosthetic_load(models):
    """The straight-stance path function: (F_z / m·g)·(q_knee + limit), F_z the prosthetic
    contacts' vertical force by hand; its sign says whether the loaded knee flexes past the
    limit, and it is 0 with the prosthesis in the air whatever the knee does."""
    from bladelab.errors import SpecError
    from bladelab.predict.collocation.dynamics import knee_straight_while_loaded
    from bladelab.runner.layout import CP_LEG

    runner, cm = models["transfemoral"]
    q_s, qd_s = ca.SX.sym("q", cm.nv), ca.SX.sym("qd", cm.nv)
    limit = np.radians(5.0)
    fn = ca.Function("knee", [q_s, qd_s], [knee_straight_while_loaded(cm, q_s, qd_s, limit)])
    pros = runner.contact_params[:, CP_LEG] == 1
    weight = runner.total_mass * runner.gravity
    knee = runner.dof("knee_angle_r")
    q = runner.stand_qpos.copy()
    q[runner.dof("pelvis_tz")] -= 0.01
    qd = np.zeros(cm.nv)
    for angle, sign in ((0.0, 1), (-np.radians(3.0), 1), (-np.radians(8.0), -1)):
        q[knee] = angle
        f_z = np.asarray(cm.contacts(q, qd)[0])[pros, 1].sum()
        assert f_z > 50.0  # loaded
        value = float(fn(q, qd))
        assert value == pytest.approx(f_z / weight * (angle + limit), rel=1e-9)
        assert np.sign(value) == sign
    _assert_last_path_inequality(cm, q, qd, float(fn(q, qd)), knee_flexion_max_loaded_deg=5.0)
    q[runner.dof("pelvis_tz")] += 0.3  # in the air: free, even flexed 60°
    q[knee] = -np.radians(60.0)
    assert abs(float(fn(q, qd))) < 1e-6
    with pytest.raises(SpecError, match="no prosthetic knee"):
        knee_straight_while_loaded(models["amputee-Cat6"][1], q_s, qd_s, limit)


@pytest.mark.parametrize("kind", ["transfemoral", "amputee-Cat6"])
def test_prosthetic_load_limit_is_the_prosthetic_legs_vertical_force(models, kind):
    """The socket-load path function: limit − F_z/(m·g), F_z summed by hand over the
    prosthetic (right) leg's contacts only; the intact foot's load does not enter, and the
    NLP's last path inequality is it, bounded below by 0."""
    from bladelab.errors import SpecError
    from bladelab.predict.collocation.dynamics import prosthetic_load_margin
    from bladelab.runner.layout import CP_LEG

    runner, cm = models[kind]
    q_s, qd_s = ca.SX.sym("q", cm.nv), ca.SX.sym("qd", cm.nv)
    fn = ca.Function("load", [q_s, qd_s], [prosthetic_load_margin(cm, q_s, qd_s, 0.5)])
    legs = runner.contact_params[:, CP_LEG]
    weight = runner.total_mass * runner.gravity
    q = runner.stand_qpos.copy()
    qd = np.zeros(cm.nv)
    for sink in (0.01, 0.03):
        q[runner.dof("pelvis_tz")] = runner.stand_qpos[runner.dof("pelvis_tz")] - sink
        forces = np.asarray(cm.contacts(q, qd)[0])
        assert forces[legs == 1, 1].sum() > 0.05 * weight < forces[legs == 0, 1].sum()
        want = 0.5 - forces[legs == 1, 1].sum() / weight
        assert float(fn(q, qd)) == pytest.approx(want, rel=1e-9)
    assert float(fn(q, qd)) < 0  # sunk 3 cm: the prosthetic leg carries more than 0.5 BW
    q[runner.dof("pelvis_tz")] += 0.3  # in the air: the whole limit is left
    assert float(fn(q, qd)) == pytest.approx(0.5, abs=1e-6)
    _assert_last_path_inequality(cm, q, qd, float(fn(q, qd)), prosthetic_load_max_bw=0.5)
    with pytest.raises(SpecError, match="no prosthetic leg"):
        prosthetic_load_margin(models["able"][1], q_s, qd_s, 0.5)
