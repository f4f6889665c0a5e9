"""The trapezoidal stride NLP on a toy model whose optimum is known."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from bladelab.errors import SpecError
from bladelab.predict.collocation import ipopt_options
from bladelab.predict.collocation.alternating_steps import alternation_rows, step_phase
from bladelab.predict.collocation.transcription import StrideNLP
from toy_stride import G, K, M, bouncing_guess, toy_dynamics


def test_the_toy_settles_on_its_spring_at_the_prescribed_speed():
    nlp = StrideNLP(toy_dynamics(), n=40, speed=2.0, compiled=False)
    sol = nlp.solve(nlp.initial_vector(bouncing_guess(40, 2.0)), hessian="exact", tol=1e-6)
    assert sol.success, sol.status
    assert sol.speed == pytest.approx(2.0, rel=1e-8)
    assert sol.max_violation < 1e-6
    # the muscle stays at its minimum (resting or bouncing on the spring cost the same); the
    # motion conserves mechanical energy (gravity, the spring, the muscle's constant 500·a N)
    assert sol.activation.max() < 0.02
    z, zd, f = sol.q[:, 1], sol.qd[:, 1], 500 * sol.tendon_force[:, 0]
    pen = np.maximum(-z, 0.0)
    energy_mech = 0.5 * M * zd**2 + M * G * z + 0.5 * K * pen**2 - f * z
    assert np.ptp(energy_mech) < 0.02 * M * G * 0.05  # < 2 % of a 5 cm drop's energy
    # the objective is the cost of transport: ∫100·a² dt / (m·v·T)
    energy, distance = nlp.energy_and_distance(sol)
    assert distance == pytest.approx(2.0 * sol.period)
    assert sol.objective_terms["metabolic"] == pytest.approx(energy / (M * distance))
    # trapezoidal defects hold: q̇ integrates to q
    dq = np.diff(sol.q, axis=0)
    h = sol.period / 40
    np.testing.assert_allclose(dq, h / 2 * (sol.qd[1:] + sol.qd[:-1]), atol=1e-7)


def test_bad_settings_are_refused():
    with pytest.raises(SpecError, match="mesh intervals"):
        StrideNLP(toy_dynamics(), n=2)
    with pytest.raises(SpecError, match="speed"):
        StrideNLP(toy_dynamics(), speed=-1.0)


def test_an_objective_of_one_term_unpacks():
    """Effort alone (metabolic weight 0): the solution still names its one term."""
    from bladelab.predict.collocation.stride_problem import StrideWeights

    nlp = StrideNLP(toy_dynamics(), n=10, speed=2.0, weights=StrideWeights(metabolic=0.0), compiled=False)
    sol = nlp.solve(nlp.initial_vector(bouncing_guess(10, 2.0)), hessian="exact", max_iter=5)
    assert list(sol.objective_terms) == ["effort"]
    assert sol.objective == pytest.approx(sol.objective_terms["effort"])


def test_squared_muscle_metabolic_rates_term_is_its_stated_integral():
    """PredSim's term (StrideWeights.metabolic_squared): Σ_m (Ė_m / M)², integrated with the
    trapezoidal rule over the stride, over the distance, / 10; and the muscles' rates add up
    to the whole-body rate less the basal rate."""
    from bladelab.predict.collocation import build_collocation_model
    from bladelab.predict.collocation.dynamics import stride_dynamics
    from bladelab.predict.collocation.guess import template_guess
    from bladelab.predict.collocation.stride_problem import (
        METABOLIC_SQUARED_SCALE,
        StrideWeights,
    )
    from bladelab.runner import build_runner
    from bladelab.runner.metabolics import BASAL_RATE_W_PER_KG

    runner = build_runner("able")
    dyn = stride_dynamics(build_collocation_model(runner))
    n, speed = 8, 3.5
    nlp = StrideNLP(dyn, n=n, speed=speed, weights=StrideWeights(metabolic_squared=2.0))
    lbx, ubx, lbg, ubg = nlp.bounds()
    sol = nlp.unpack(nlp.initial_vector(template_guess(runner, speed=speed, n=n)), {}, 0.0, 0.0,
                     lbg, ubg, np.zeros(lbg.size))
    per_node = np.zeros(n + 1)
    for k in range(n + 1):
        args = (sol.q[k], sol.qd[k], sol.activation[k], sol.tendon_force[k],
                sol.tendon_force_rate[k], sol.excitation[k])
        rates = np.array(dyn.muscle_metabolic_rates(*args)).ravel()
        assert rates.sum() + BASAL_RATE_W_PER_KG * dyn.mass == pytest.approx(
            float(dyn.metabolic_rate(*args)), rel=1e-12)
        per_node[k] = np.sum((rates / dyn.mass) ** 2)
    h = sol.period / n
    expected = 2.0 * np.sum((per_node[:-1] + per_node[1:]) / 2 * h) / (
        speed * sol.period) / METABOLIC_SQUARED_SCALE
    assert sol.objective_terms["metabolic_squared"] == pytest.approx(expected, rel=1e-9)
    assert expected > 0.0


def test_force_rate_term_is_its_stated_integral():
    """StrideWeights.force_rate: Σ_m (dF̃_m/dt)² / n_m / 100, integrated with the trapezoidal
    rule over the stride, over the stride time; computed here from the unpacked controls."""
    from bladelab.predict.collocation import build_collocation_model
    from bladelab.predict.collocation.dynamics import stride_dynamics
    from bladelab.predict.collocation.guess import template_guess
    from bladelab.predict.collocation.stride_problem import StrideWeights
    from bladelab.runner import build_runner

    runner = build_runner("able")
    dyn = stride_dynamics(build_collocation_model(runner))
    n, speed = 8, 3.5
    nlp = StrideNLP(dyn, n=n, speed=speed, weights=StrideWeights(force_rate=3.0))
    lbx, ubx, lbg, ubg = nlp.bounds()
    x0 = nlp.initial_vector(template_guess(runner, speed=speed, n=n))
    rng = np.random.default_rng(7)  # some force rates: the template's are zero
    nX = nlp.nx * (n + 1)
    x0[nX:nX + nlp.nu * (n + 1)] += rng.normal(0.0, 0.5, nlp.nu * (n + 1))
    sol = nlp.unpack(x0, {}, 0.0, 0.0, lbg, ubg, np.zeros(lbg.size))
    per_node = np.sum(sol.tendon_force_rate**2, axis=1) / dyn.nm / 100.0
    h = sol.period / n
    expected = 3.0 * np.sum((per_node[:-1] + per_node[1:]) / 2 * h) / sol.period
    assert expected > 0.0
    assert sol.objective_terms["force_rate"] == pytest.approx(expected, rel=1e-9)


def test_passive_term_counts_the_body_s_joint_limits_alone():
    """StrideWeights.passive: Σ_j τ_j² / n_j / 100 over the body's own joints' limit torques
    (ligaments, hip capsule), integrated with the trapezoidal rule over the stride time; the
    joint springs (the lumbar's, the toes') and a prosthesis's joints are not counted."""
    from bladelab.predict.collocation import build_collocation_model
    from bladelab.predict.collocation.dynamics import body_joints, stride_dynamics
    from bladelab.predict.collocation.guess import template_guess
    from bladelab.predict.collocation.stride_problem import PASSIVE_TORQUE_SCALE, StrideWeights
    from bladelab.runner import build_runner
    from bladelab.runner.layout import JP_EA, JP_EB
    from bladelab.runner.params import default_runner_params

    runner = build_runner(default_runner_params("able", body="human"))
    cm = build_collocation_model(runner)
    dyn = stride_dynamics(cm)
    joints = body_joints(runner)
    assert "mtp_angle_l" in joints and "lumbar_extension" in joints
    n, speed = 8, 3.5
    nlp = StrideNLP(dyn, n=n, speed=speed, weights=StrideWeights(passive=2.0))
    lbx, ubx, lbg, ubg = nlp.bounds()
    sol = nlp.unpack(nlp.initial_vector(template_guess(runner, speed=speed, n=n)), {}, 0.0, 0.0,
                     lbg, ubg, np.zeros(lbg.size))
    tau = np.array([np.asarray(dyn.passive_joint_torques(sol.q[k], sol.qd[k])).ravel()
                    for k in range(n + 1)])
    per_node = np.sum(tau**2, axis=1) / len(joints) / PASSIVE_TORQUE_SCALE
    h = sol.period / n
    expected = 2.0 * np.sum((per_node[:-1] + per_node[1:]) / 2 * h) / sol.period
    assert expected > 0.0
    assert sol.objective_terms["passive"] == pytest.approx(expected, rel=1e-9)
    # within the hip's range the torque is the capsule's closed form a·exp(b·q)
    hip = runner.dof("hip_flexion_l")
    row = runner.joint_params[hip]
    capsule = row[JP_EA] * np.exp(row[JP_EB] * sol.q[:, hip])
    np.testing.assert_allclose(tau[:, joints.index("hip_flexion_l")], capsule, rtol=1e-6)
    # the lumbar's spring bends the trunk back, but is not a limit: not counted
    q = sol.q[0].copy()
    q[runner.dof("lumbar_extension")] += 0.05
    lumbar = runner.dof("lumbar_extension")
    assert abs(float(np.asarray(cm.passive(q, sol.qd[0])).ravel()[lumbar])) > 10.0
    assert abs(np.asarray(dyn.passive_joint_torques(q, sol.qd[0])).ravel()[
        joints.index("lumbar_extension")]) < 1.0
    # a knee hyperextended past its ligament is
    q[runner.dof("knee_angle_l")] = 0.2
    assert abs(np.asarray(dyn.passive_joint_torques(q, sol.qd[0])).ravel()[
        joints.index("knee_angle_l")]) > 10.0
    # a prosthesis's joints are devices
    tf = build_runner(default_runner_params("transfemoral", body="human"))
    assert "knee_angle_r" in tf.dof_names and "knee_angle_r" not in body_joints(tf)
    tt = build_runner(default_runner_params("amputee", body="human", blade="Cat6"))
    assert "ankle_angle_r" not in body_joints(tt) and "knee_angle_r" in body_joints(tt)


def test_one_built_solver_serves_every_speed():
    """The speed is a parameter: an NLP built at 2 m/s and solved at 2.5 m/s gives the same
    solution as one built at 2.5 m/s, and its solver is built only once."""
    n = 16
    shared = StrideNLP(toy_dynamics(), n=n, speed=2.0, compiled=False)
    first = shared.solve(shared.initial_vector(bouncing_guess(n, 2.0)), hessian="exact",
                         tol=1e-8)
    again = shared.solve(shared.initial_vector(bouncing_guess(n, 2.5)), hessian="exact",
                         tol=1e-8, speed=2.5)
    fresh = StrideNLP(toy_dynamics(), n=n, speed=2.5, compiled=False)
    alone = fresh.solve(fresh.initial_vector(bouncing_guess(n, 2.5)), hessian="exact",
                        tol=1e-8)
    assert first.success and again.success and alone.success
    assert first.timings["build_s"] > 10 * again.timings["build_s"]  # reused, not rebuilt
    for sol in (first, again):  # the wall time split: build, our functions, IPOPT's own
        t = sol.timings
        assert t["functions_s"] == pytest.approx(sum(v for k, v in t.items()
                                                     if k.startswith("nlp_")))
        assert t["build_s"] + t["functions_s"] + t["ipopt_own_s"] == pytest.approx(sol.wall_s)
        assert t["ipopt_own_s"] > 0.0 and t["peak_memory_MB"] > 50.0
    assert again.speed == pytest.approx(2.5, rel=1e-8)
    assert again.objective == pytest.approx(alone.objective, rel=1e-9)
    assert again.objective_terms["metabolic"] == pytest.approx(
        alone.objective_terms["metabolic"], rel=1e-9)
    np.testing.assert_allclose(again.q, alone.q, atol=1e-9)


def test_progress_is_reported_every_iteration_of_each_solve():
    nlp = StrideNLP(toy_dynamics(), n=10, speed=2.0, compiled=False)
    for speed in (2.0, 2.2):
        seen: list[tuple[int, float, float]] = []
        sol = nlp.solve(nlp.initial_vector(bouncing_guess(10, speed)), hessian="exact",
                        speed=speed, progress=lambda it, f, v, seen=seen: seen.append((it, f, v)))
        assert [s[0] for s in seen] == list(range(sol.iterations + 1))
        assert seen[-1][1] == pytest.approx(sol.objective, rel=1e-9)
    assert len(nlp._solvers) == 1


def test_backward_euler_rows_for_stiff_coordinates():
    """``StrideDynamics.backward_euler_dofs``: those coordinates' q defects are
    ``q_{k+1} − q_k − h·q̇_{k+1}`` (a start built by backward differences meets them exactly),
    the others stay trapezoidal."""
    import dataclasses

    n, period = 20, 0.6
    h = period / n
    g = bouncing_guess(n, 2.0)
    z = g.q[:, 1]
    zd = np.empty_like(z)
    zd[1:] = np.diff(z) / h  # backward differences
    zd[0] = zd[-1]
    g = dataclasses.replace(g, qd=np.column_stack([g.qd[:, 0], zd, g.qd[:, 2]]))

    def z_defects(dyn):
        nlp = StrideNLP(dyn, n=n, speed=2.0)
        f = ca.Function("g", [nlp.nlp["x"], nlp.nlp["p"]], [nlp.nlp["g"]])
        values = np.asarray(f(nlp.initial_vector(g), 2.0)).ravel()
        rows = [i for i, name in enumerate(nlp._g_names) if name.startswith("defect q ")]
        return {name: values[i] for i, name in ((i, nlp._g_names[i]) for i in rows)}

    be = z_defects(dataclasses.replace(toy_dynamics(), backward_euler_dofs=("pelvis_tz",)))
    trap = z_defects(toy_dynamics())
    be_z = np.array([v for k, v in be.items() if "pelvis_tz" in k])
    trap_z = np.array([v for k, v in trap.items() if "pelvis_tz" in k])
    assert np.abs(be_z).max() < 1e-9  # met exactly by the backward differences
    assert np.abs(trap_z).max() > 1e-3  # which the trapezoidal rule does not accept
    x_rows = [k for k in be if "pelvis_tx" in k]
    np.testing.assert_allclose([be[k] for k in x_rows], [trap[k] for k in x_rows], atol=1e-12)


def test_interval_mean_inequalities_are_imposed_on_each_intervals_mean():
    """``StrideDynamics.interval_mean_inequalities``: those rows of the path inequalities are
    imposed on (g_k + g_{k+1})/2 per interval, the others at the nodes; a value alternating in
    sign from node to node (the trapezoidal rule's period-2 mode) has interval means near 0."""
    import dataclasses

    n = 20
    q, qd = ca.SX.sym("q", 3), ca.SX.sym("qd", 3)
    a, f, df = (ca.SX.sym(s, 1) for s in ("a", "f", "df"))
    ineq = ca.Function("ineq", [q, qd, a, f, df], [ca.vertcat(qd[1], q[1])])
    toy = dataclasses.replace(toy_dynamics(), inequalities=ineq,
                              inequality_bounds=np.array([[-1.0, 1.0], [-1.0, 1.0]]))
    g = bouncing_guess(n, 2.0)
    ringing = dataclasses.replace(g, qd=g.qd.copy())
    ringing.qd[:, 1] = 0.3 * (-1.0) ** np.arange(n + 1)  # ±0.3 m/s from node to node

    def rows(dyn):
        nlp = StrideNLP(dyn, n=n, speed=2.0)
        fn = ca.Function("g", [nlp.nlp["x"], nlp.nlp["p"]], [nlp.nlp["g"]])
        values = np.asarray(fn(nlp.initial_vector(ringing), 2.0)).ravel()
        return np.array([values[i] for i, name in enumerate(nlp._g_names)
                         if name.startswith("inequality ")]).reshape(n, 2)

    at_nodes = rows(toy)
    means = rows(dataclasses.replace(toy, interval_mean_inequalities=(0,)))
    np.testing.assert_allclose(np.abs(at_nodes[:, 0]), 0.3, rtol=1e-9)  # ringing at nodes
    np.testing.assert_allclose(means[:, 0], 0.0, atol=1e-9)  # its interval means vanish
    np.testing.assert_allclose(means[:, 1], at_nodes[:, 1], atol=1e-12)  # row 1 untouched


def test_tracking_term_follows_only_the_named_coordinates():
    """tracking=(q_ref, w, dofs): w × the time-averaged mean squared deviation of the named
    coordinates only; the default follows pelvis tilt and every joint; an unknown name is
    refused with the model's coordinates in the hint."""
    n, speed = 20, 2.0
    guess = bouncing_guess(n, speed)
    q_ref = guess.q.copy()
    q_ref[:, 2] = 0.3  # the tilt's reference is 0.3 rad off the guess's 0
    q_ref[:, 1] += 1.0  # a translation: not followed by default
    ref = {}
    for key, dofs in (("default", ()), ("tz", (["pelvis_tz"],))):
        nlp = StrideNLP(toy_dynamics(), n=n, speed=speed, tracking=(q_ref, 2.0, *dofs))
        lbx, ubx, lbg, ubg = nlp.bounds()
        x0 = nlp.initial_vector(guess)
        ref[key] = nlp.unpack(x0, {}, 0.0, 0.0, lbg, ubg, np.zeros(lbg.size))
    assert ref["default"].objective_terms["tracking"] == pytest.approx(2.0 * 0.3**2, rel=1e-9)
    assert ref["tz"].objective_terms["tracking"] == pytest.approx(2.0, rel=1e-9)
    with pytest.raises(SpecError, match="hip_flexion_l") as err:
        StrideNLP(toy_dynamics(), n=n, speed=speed, tracking=(q_ref, 2.0, ["hip_flexion_l"]))
    assert "pelvis_tilt" in err.value.hint


def test_period_tracking_term_is_the_squared_log_ratio_of_the_stride_times():
    n, speed = 20, 2.0
    guess = bouncing_guess(n, speed)  # a 0.6 s stride
    nlp = StrideNLP(toy_dynamics(), n=n, speed=speed, period_tracking=(0.5, 3.0))
    lbx, ubx, lbg, ubg = nlp.bounds()
    sol = nlp.unpack(nlp.initial_vector(guess), {}, 0.0, 0.0, lbg, ubg, np.zeros(lbg.size))
    assert sol.period == pytest.approx(0.6)
    assert sol.objective_terms["period_tracking"] == pytest.approx(3.0 * np.log(1.2) ** 2,
                                                                   rel=1e-9)
    with pytest.raises(SpecError, match="reference stride time"):
        StrideNLP(toy_dynamics(), n=n, speed=speed, period_tracking=(0.0, 3.0))


def test_a_solution_restarted_from_its_multipliers_ends_at_once():
    """A solution solved again from its primal and dual values (IPOPT's warm start, at the
    library's tolerance) ends in at most two iterations at the same point; from its primal
    values alone IPOPT's barrier starts again and takes longer. Multipliers that do not fit
    the NLP are not used."""
    n = 16
    nlp = StrideNLP(toy_dynamics(), n=n, speed=2.0, compiled=False)
    cold = nlp.solve(nlp.initial_vector(bouncing_guess(n, 2.0)), hessian="exact")
    assert cold.success and cold.multipliers is not None
    lam_x, lam_g = cold.multipliers
    assert lam_x.shape == (nlp.n_vars,) and lam_g.shape == (nlp.n_cons,)
    guess = cold.to_guess()
    lam = nlp.initial_multipliers(guess)
    assert lam is not None
    warm = nlp.solve(nlp.initial_vector(guess), hessian="exact", multipliers=lam)
    primal = nlp.solve(nlp.initial_vector(guess), hessian="exact")
    assert warm.success and warm.iterations <= 2 < primal.iterations
    assert warm.objective == pytest.approx(cold.objective, rel=1e-6)
    np.testing.assert_allclose(warm.q, cold.q, atol=1e-5)
    # kept by a change of speed, dropped by another mesh; the wrong size or a NaN is refused
    assert nlp.initial_multipliers(guess.with_speed(2.2)) is not None
    assert guess.resample(8).multipliers is None
    assert nlp.initial_multipliers(bouncing_guess(n, 2.0)) is None
    short = dataclasses.replace(guess, multipliers=(lam_x[:-1], lam_g))
    assert nlp.initial_multipliers(short) is None
    bad = dataclasses.replace(guess, multipliers=(lam_x, np.full_like(lam_g, np.nan)))
    assert nlp.initial_multipliers(bad) is None


def test_the_maximum_speed_problem_keeps_at_least_the_speed_it_is_given():
    """The maximum-speed NLP has one inequality the prescribed-speed NLP lacks: the stride's
    mean speed at least the solve's ``speed`` parameter (distance − P·T ≥ 0); a 2 m/s stride
    meets a 1.5 m/s floor and violates a 2.5 m/s one."""
    from bladelab.predict.collocation.stride_problem import StrideWeights

    fastest = StrideNLP(toy_dynamics(), n=10, speed=None,
                        weights=StrideWeights(metabolic=0.0, speed=1.0))
    prescribed = StrideNLP(toy_dynamics(), n=10, speed=2.0)
    assert fastest.n_cons == prescribed.n_cons  # the speed row, an inequality now
    _, _, lbg, ubg = fastest.bounds()
    rows = np.flatnonzero(np.isinf(ubg))
    assert rows.size == 1 and lbg[rows[0]] == 0.0
    assert not np.isinf(prescribed.bounds()[3]).any()
    g = ca.Function("g", [fastest.nlp["x"], fastest.nlp["p"]], [fastest.nlp["g"]])
    x0 = fastest.initial_vector(bouncing_guess(10, 2.0))
    assert float(g(x0, 1.5)[rows[0]]) == pytest.approx(0.5 * 0.6, rel=1e-9)
    assert float(g(x0, 2.5)[rows[0]]) < 0.0



@pytest.mark.parametrize("band, low, high", [
    ((1.0, 0.5, 0.7, 3.0, 0.3, 0.4), 0.6 - 0.4, 0.6 - 0.55),  # 2 m/s: halfway between anchors
    ((3.0, 0.5, 0.7, 4.0, 0.3, 0.4), 0.6 - 0.5, 0.6 - 0.7),  # below v0: the band at v0
    ((0.5, 0.9, 1.1, 1.0, 0.5, 0.8), 0.6 - 0.5, 0.6 - 0.8)])  # above v1: the band at v1
def test_a_stride_time_band_that_moves_with_the_speed(band, low, high):
    """The maximum-speed NLP with a period band: rows T − lo(v) >= 0 and T − hi(v) <= 0 at the
    stride's own speed v = d/T (linear between the anchors, constant outside); refused with a
    prescribed speed or a malformed band."""
    from bladelab.predict.collocation.stride_problem import StrideWeights

    nlp = StrideNLP(toy_dynamics(), n=10, speed=None, period_band=band,
                    weights=StrideWeights(metabolic=0.0, speed=1.0))
    plain = StrideNLP(toy_dynamics(), n=10, speed=None,
                      weights=StrideWeights(metabolic=0.0, speed=1.0))
    assert nlp.n_cons == plain.n_cons + 2
    _, _, lbg, ubg = nlp.bounds()
    lo_row, hi_row = (nlp._g_names.index(f"stride time band ({k})") for k in ("low", "high"))
    assert (lbg[lo_row], ubg[lo_row], lbg[hi_row], ubg[hi_row]) == (0.0, np.inf, -np.inf, 0.0)
    g = ca.Function("g", [nlp.nlp["x"], nlp.nlp["p"]], [nlp.nlp["g"]])
    x0 = nlp.initial_vector(bouncing_guess(10, 2.0))  # 2 m/s, 0.6 s
    values = np.asarray(g(x0, 0.0)).ravel()
    assert values[lo_row] == pytest.approx(low, abs=1e-9)
    assert values[hi_row] == pytest.approx(high, abs=1e-9)
    with pytest.raises(SpecError, match="maximum-speed problem"):
        StrideNLP(toy_dynamics(), n=10, speed=2.0, period_band=band)
    with pytest.raises(SpecError, match="v0 < v1"):
        StrideNLP(toy_dynamics(), n=10, speed=None, period_band=(3.0, 0.5, 0.7, 1.0, 0.3, 0.4))

def _two_stances(n: int, right_after: float, duty: float = 0.25) -> np.ndarray:
    """Half-sine vertical forces [N] of two legs on n nodes: the left stance from 0, the right
    one ``right_after`` of the stride later."""
    t = np.arange(n) / n
    out = np.zeros((n, 2))
    for j, start in enumerate((0.0, right_after)):
        s = (t - start) % 1.0
        out[:, j] = np.where(s < duty, 1500.0 * np.sin(np.pi * s / duty), 0.0)
    return out


@pytest.mark.parametrize("right_after", [0.5, 0.15, 0.62, 0.9])
def test_step_phase_is_the_delay_between_the_legs_stance_centres(right_after):
    assert step_phase(_two_stances(200, right_after)) == pytest.approx(right_after, abs=1e-9)


def test_alternation_constraint_admits_alternating_steps_and_rules_out_a_gallop():
    """The constraint (≤ 0 to hold) is negative inside 0.5 ± tolerance, zero on its edges and
    positive outside, whichever leg leads."""
    n, bw, tol = 200, 700.0, 0.1

    def g(right_after: float, right_share: float = 1.0) -> np.ndarray:
        forces = _two_stances(n, right_after) * [1.0, right_share]
        return np.asarray(alternation_rows(ca.DM(forces.T), bw, tol)).ravel()

    assert g(0.5)[0] < 0 and g(0.45)[0] < 0 and g(0.58)[0] < 0
    assert g(0.4)[0] == pytest.approx(0.0, abs=1e-6)
    assert g(0.6)[0] == pytest.approx(0.0, abs=1e-6)
    assert g(0.15)[0] > 0 and g(0.85)[0] > 0 and g(0.3)[0] > 0
    # each leg must carry a stance: a one-legged hop meets the phase only up to ε
    assert (g(0.5)[1:] < 0).all()
    hop = g(0.5, right_share=0.0)
    assert hop[0] == pytest.approx(0.0, abs=1e-4) and hop[2] > 0 and hop[1] < 0


def test_the_nlp_holds_the_alternation_constraint_only_when_asked():
    """``step_phase_tolerance`` adds three inequalities on the node forces 0..n−1 (the phase
    and a stance per leg), bounded above by 0; without it there are none; a tolerance outside (0, 0.5) or dynamics without the
    legs' forces are refused."""
    toy = toy_dynamics()
    q, qd = ca.SX.sym("q", 3), ca.SX.sym("qd", 3)
    spring = [K * 0.5 * (-z + ca.sqrt(z**2 + 1e-8)) for z in (q[1], q[2])]  # tilt as a 2nd leg
    legs = dataclasses.replace(toy, leg_vertical_grf=ca.Function("legs", [q, qd],
                                                                 [ca.vertcat(*spring)]))
    n = 40
    free = StrideNLP(legs, n=n, speed=2.0)
    steps = StrideNLP(legs, n=n, speed=2.0, step_phase_tolerance=0.1)
    assert "alternating steps" not in free._g_names
    assert steps.n_cons == free.n_cons + 3
    i = steps._g_names.index("alternating steps")
    _, _, lbg, ubg = steps.bounds()
    assert (lbg[i:i + 3] == -np.inf).all() and (ubg[i:i + 3] == 0.0).all()
    g = ca.Function("g", [steps.nlp["x"], steps.nlp["p"]], [steps.nlp["g"]])
    for lag in (0.5, 0.2):  # the 'right leg' sinks `lag` of the stride after the left
        guess = bouncing_guess(n, 2.0)
        t = np.arange(n + 1) / n
        guess.q[:, 2] = 0.05 * np.sin(2 * np.pi * (t - lag))
        guess.q[:, 1] = 0.05 * np.sin(2 * np.pi * t)
        x = steps.initial_vector(guess)
        forces = np.stack([np.asarray(legs.leg_vertical_grf(qk, qk * 0)).ravel()
                           for qk in guess.q[:n]])
        expected = np.asarray(alternation_rows(ca.DM(forces.T), M * G, 0.1)).ravel()
        np.testing.assert_allclose(np.asarray(g(x, 2.0)[i:i + 3]).ravel(), expected, rtol=1e-9)
        assert (expected[0] < 0) == (lag == 0.5)
    with pytest.raises(SpecError, match="step phase"):
        StrideNLP(legs, n=n, speed=2.0, step_phase_tolerance=0.5)
    with pytest.raises(SpecError, match="vertical ground force"):
        StrideNLP(toy, n=n, speed=2.0, step_phase_tolerance=0.1)


def test_an_lbfgs_solve_stops_where_its_objective_stalls_near_the_full_solution():
    """The acceptable-level stop (``STALL_STOP_OPTIONS``) reaches IPOPT on every L-BFGS solve,
    cold or warm, and not on the exact Hessian's; a warm start with it ends feasible, at the
    speed, within 0.1 % of the objective that IPOPT's full convergence reaches from the same
    primal and dual values. (The toy converges within a few iterations, before the stop can
    act; what it saves on strides is measured in benchmarks/collocation_speed/README.md.)"""
    n = 16
    nlp = StrideNLP(toy_dynamics(), n=n, speed=2.0, compiled=False)
    cold = nlp.solve(nlp.initial_vector(bouncing_guess(n, 2.0)))
    assert cold.success, cold.status
    guess = cold.to_guess()
    lam = nlp.initial_multipliers(guess)
    stopped = nlp.solve(nlp.initial_vector(guess), speed=2.2, multipliers=lam)
    keys = [dict(key) for key in nlp._solvers]
    assert len(keys) == 2 and all("ipopt.acceptable_iter" in k for k in keys)
    saved = dict(ipopt_options.STALL_STOP_OPTIONS)
    ipopt_options.STALL_STOP_OPTIONS.clear()
    try:
        full = nlp.solve(nlp.initial_vector(guess), speed=2.2, multipliers=lam)
    finally:
        ipopt_options.STALL_STOP_OPTIONS.update(saved)
    assert stopped.success and full.success, (stopped.status, full.status)
    assert stopped.speed == pytest.approx(2.2, rel=1e-6)
    assert stopped.max_violation < 1e-4
    assert stopped.iterations <= full.iterations
    assert stopped.objective == pytest.approx(full.objective, rel=1e-3)
    # the predictive stages' L-BFGS update inside the augmented system: the same optimum
    extended = nlp.solve(nlp.initial_vector(guess), speed=2.2, multipliers=lam,
                         options=ipopt_options.PREDICTIVE_LBFGS_OPTIONS)
    assert extended.success and extended.max_violation < 1e-4
    assert extended.objective == pytest.approx(full.objective, rel=1e-3)
    exact = nlp.solve(nlp.initial_vector(guess), speed=2.2, multipliers=lam, hessian="exact")
    assert exact.success
    exact_keys = [dict(key) for key in nlp._solvers
                  if dict(key)["ipopt.hessian_approximation"] == repr("exact")]
    assert exact_keys and not any("ipopt.acceptable_iter" in k for k in exact_keys)
