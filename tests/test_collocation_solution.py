"""The collocation solution: settings, file, summary, trajectory, dynamic consistency, the
two-stage solve's failure path and determinism, and the report."""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import replace

import numpy as np
import pytest

from bladelab.errors import DataError, InputFileError, SpecError
from bladelab.predict.collocation.consistency import (
    dynamics_residual,
    dynamics_residual_pct,
    forward_generalised_forces,
    inverse_dynamics,
)
from bladelab.predict.collocation.continuation import max_speed_settings
from bladelab.predict.collocation.guess import measured_trial_guess, template_guess
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.ipopt_options import PREDICTIVE_LBFGS_OPTIONS
from bladelab.predict.collocation.running_bands import reference_band
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solution import (
    BEST_ITERATE_KIND,
    CONTACT_THRESHOLD_N,
    SOLUTION_KIND,
    CollocationSolution,
)
from bladelab.predict.collocation.solve import SolveProgress, predict_stride
from bladelab.predict.collocation.stride_problem import StrideWeights
from bladelab.runner.params import RUNNER_DATA_DIR
from collocation_fake import SPEED, fake_solution

N = 12


@pytest.fixture(scope="module")
def able():
    return fake_solution("able", N)


# ---------------------------------------------------------------- settings


def test_settings_round_trip_and_refuse_bad_values():
    s = CollocationSettings(mesh_intervals=30, speed_m_per_s=4.0, max_iter=200)
    assert CollocationSettings.from_dict(json.loads(json.dumps(s.to_dict()))) == s
    assert s.weights == StrideWeights(metabolic=1.0, activation=1.0, acceleration=0.1)
    fastest = CollocationSettings(speed_m_per_s=None)
    assert fastest.max_speed and fastest.weights.metabolic == 0.0 and fastest.weights.speed == 1
    assert CollocationSettings.from_dict(fastest.to_dict()) == fastest
    straight = CollocationSettings(knee_flexion_max_loaded_deg=5)
    assert straight.knee_flexion_max_loaded_deg == 5.0 and not straight.same_problem(
        CollocationSettings())
    assert CollocationSettings.from_dict(straight.to_dict()) == straight
    socket = CollocationSettings(prosthetic_load_max_bw=3)
    assert socket.prosthetic_load_max_bw == 3.0 and not socket.same_problem(
        CollocationSettings())
    assert CollocationSettings.from_dict(json.loads(json.dumps(socket.to_dict()))) == socket
    assert CollocationSettings().imposed_stride_time is None
    assert CollocationSettings(stride_time_range_s=(0.7, 0.7)).imposed_stride_time == "0.7 s"
    assert CollocationSettings(stride_time_range_s=(0.64, 0.78)).imposed_stride_time == (
        "0.64–0.78 s")
    people = CollocationSettings(speed_m_per_s=9.0, stride_time_people=True)
    assert people.period_bounds_s == pytest.approx((0.40, 0.55))  # the band at 9 m/s
    assert not people.same_problem(CollocationSettings(speed_m_per_s=9.0))
    assert not max_speed_settings(people).stride_time_people
    for bad, where in (({"mesh_intervals": 3}, "mesh_intervals"),
                       ({"speed_m_per_s": -1.0}, "speed_m_per_s"),
                       ({"hessian": "bfgs"}, "hessian"), ({"tol": 0.0}, "tol"),
                       ({"max_iter": 0}, "max_iter"), ({"tracking_weight": math.nan},
                                                       "tracking_weight"),
                       ({"warm_start_mu": 0.0}, "warm_start_mu"),
                       ({"knee_moment_min_nm": 5.0}, "knee_moment_min_nm"),
                       ({"knee_flexion_max_loaded_deg": -1.0}, "knee_flexion_max_loaded_deg"),
                       ({"knee_flexion_max_loaded_deg": True}, "knee_flexion_max_loaded_deg"),
                       ({"prosthetic_load_max_bw": 0.0}, "prosthetic_load_max_bw"),
                       ({"prosthetic_load_max_bw": math.inf}, "prosthetic_load_max_bw"),
                       ({"stride_time_people": 1}, "stride_time_people"),
                       ({"stride_time_people": True, "stride_time_range_s": (0.6, 0.7)},
                        "stride_time_people")):
        with pytest.raises(SpecError) as err:
            CollocationSettings(**bad)
        assert err.value.where == where
    upright = CollocationSettings(pelvis_tilt_range_deg=[-16, -2])
    assert upright.pelvis_tilt_range_deg == (-16.0, -2.0)
    assert not upright.same_problem(CollocationSettings())
    assert CollocationSettings.from_dict(json.loads(json.dumps(upright.to_dict()))) == upright
    for bad in ((-2, -16), (-70, 0), (-16,), "ab", (-16, math.inf), (True, 2)):
        with pytest.raises(SpecError) as err:
            CollocationSettings(pelvis_tilt_range_deg=bad)
        assert err.value.where == "pelvis_tilt_range_deg"
    cadence = CollocationSettings(stride_time_range_s=[0.64, 0.78])
    assert cadence.stride_time_range_s == (0.64, 0.78) == cadence.period_bounds_s
    assert not cadence.same_problem(CollocationSettings())
    assert CollocationSettings.from_dict(json.loads(json.dumps(cadence.to_dict()))) == cadence
    assert CollocationSettings(stride_time_range_s=(0.7, 0.7)).period_bounds_s == (0.7, 0.7)
    for bad in ((0.78, 0.64), (0.3, 0.7), (0.6, 1.5), (0.7,), "ab", (0.6, math.nan),
                (True, 0.7)):
        with pytest.raises(SpecError) as err:
            CollocationSettings(stride_time_range_s=bad)
        assert err.value.where == "stride_time_range_s"
    stepping = CollocationSettings(step_phase_tolerance=0.1)
    assert not stepping.same_problem(CollocationSettings())
    assert CollocationSettings.from_dict(json.loads(json.dumps(stepping.to_dict()))) == stepping
    for bad in (0, 0.5, -0.1, math.nan, True, "0.1"):
        with pytest.raises(SpecError) as err:
            CollocationSettings(step_phase_tolerance=bad)
        assert err.value.where == "step_phase_tolerance"
    with pytest.raises(SpecError, match="unknown setting"):
        CollocationSettings.from_dict({"mesh": 50})
    with pytest.raises(SpecError, match="unknown objective weight"):
        CollocationSettings.from_dict({"weights": {"metabolism": 1.0}})


def test_a_reference_term_is_part_of_the_problem_by_its_file_name():
    kept = CollocationSettings(reference="/a/centre.json", reference_weight=10,
                               reference_dofs=["hip_flexion_l"])
    assert CollocationSettings.from_dict(json.loads(json.dumps(kept.to_dict()))) == kept
    moved = CollocationSettings(reference="elsewhere/centre.json", reference_weight=10.0,
                                reference_dofs=("hip_flexion_l",))
    assert kept.same_problem(moved)  # a study cloned into another folder
    for other in (CollocationSettings(), CollocationSettings(
            reference="/a/other.json", reference_weight=10, reference_dofs=["hip_flexion_l"]),
                  CollocationSettings(reference="/a/centre.json", reference_weight=30,
                                      reference_dofs=["hip_flexion_l"]),
                  CollocationSettings(reference="/a/centre.json", reference_weight=10)):
        assert not kept.same_problem(other)
    # a reference without weight is no term at all
    assert CollocationSettings(reference="/a/centre.json").same_problem(CollocationSettings())
    for bad, where in (({"reference_weight": -1.0, "reference": "r.json"}, "reference_weight"),
                       ({"reference_weight": 1.0}, "reference"),
                       ({"reference_weight": 1.0, "reference": "r.json",
                         "reference_dofs": "hip_flexion_l"}, "reference_dofs")):
        with pytest.raises(SpecError) as err:
            CollocationSettings(**bad)
        assert err.value.where == where


# ---------------------------------------------------------------- file


def test_file_round_trip_is_exact(able, tmp_path):
    _, _, sol = able
    path = sol.write(tmp_path / "solution.json")
    data = json.loads(path.read_text())
    assert data["kind"] == SOLUTION_KIND and data["model"] == {"model": "able", "blade": None}
    assert data["max_violation"] is None  # NaN is written as null (strict JSON)
    back = CollocationSolution.read(path)
    for attr in ("time", "q", "qd", "qdd", "activation", "tendon_force", "excitation",
                 "tendon_force_rate"):
        np.testing.assert_array_equal(getattr(back.nlp, attr), getattr(sol.nlp, attr))
    np.testing.assert_array_equal(back.contact_forces, sol.contact_forces)
    assert back.settings == sol.settings and back.model_spec == sol.model_spec
    assert back.nlp.worst_constraints == sol.nlp.worst_constraints
    assert back.summary() == sol.summary() and back.converged
    assert math.isnan(back.nlp.max_violation)
    assert [p.name for p in tmp_path.iterdir()] == ["solution.json"]


def test_the_reference_phase_round_trips_into_the_next_start(able, tmp_path):
    """A stride solved against people's angles keeps the phase it was solved with: in its
    file, and in the guess a next solve starts from (and every resampling of it)."""
    _, _, sol = able
    assert sol.reference_phase is None and sol.to_guess().reference_phase is None
    back = CollocationSolution.read(replace(sol, reference_phase=0.0325).write(
        tmp_path / "solution.json"))
    assert back.reference_phase == 0.0325
    assert back.to_guess().resample(8).with_speed(4.0).reference_phase == 0.0325


def test_a_maximum_speed_s_floor_round_trips_and_says_whether_the_speed_is_on_it(able,
                                                                                tmp_path):
    from bladelab.predict.collocation.continuation_records import speed_floor_columns

    _, _, sol = able
    assert sol.speed_floor_mps is None
    assert speed_floor_columns(sol) == {"speed_floor_mps": "", "on_speed_floor": False}
    v = sol.mean_speed_mps
    back = CollocationSolution.read(replace(sol, speed_floor_mps=v - 5e-4).write(
        tmp_path / "solution.json"))
    assert back.speed_floor_mps == v - 5e-4
    assert speed_floor_columns(back) == {"speed_floor_mps": v - 5e-4, "on_speed_floor": True}
    below = replace(back, speed_floor_mps=v - 0.05)
    assert speed_floor_columns(below)["on_speed_floor"] is False


def test_a_non_converged_solve_is_a_best_iterate(able, tmp_path):
    _, _, sol = able
    bad = replace(sol, nlp=replace(sol.nlp, success=False, status="Maximum_Iterations_Exceeded"))
    assert not bad.converged and bad.kind == BEST_ITERATE_KIND
    back = CollocationSolution.read(bad.write(tmp_path / "best_iterate.json"))
    assert not back.converged and back.summary()["converged"] is False
    # a file claiming to be a solution must have converged
    data = json.loads((tmp_path / "best_iterate.json").read_text())
    data["kind"] = SOLUTION_KIND
    (tmp_path / "liar.json").write_text(json.dumps(data))
    with pytest.raises(DataError, match="did not converge"):
        CollocationSolution.read(tmp_path / "liar.json")


def test_multipliers_round_trip_and_bad_ones_are_named(able, tmp_path):
    _, _, sol = able
    assert sol.nlp.multipliers is None
    assert CollocationSolution.read(sol.write(tmp_path / "none.json")).nlp.multipliers is None
    rng = np.random.default_rng(7)
    lam = (rng.normal(size=40), rng.normal(size=30))
    with_lam = replace(sol, nlp=replace(sol.nlp, multipliers=lam))
    back = CollocationSolution.read(with_lam.write(tmp_path / "solution.json"))
    for a, b in zip(back.nlp.multipliers, lam, strict=True):
        np.testing.assert_array_equal(a, b)
    guess = back.to_guess()
    assert guess.multipliers is not None
    np.testing.assert_array_equal(guess.qdd, sol.nlp.qdd)  # the solution's own controls
    np.testing.assert_array_equal(guess.excitation, sol.nlp.excitation)
    good = with_lam.to_dict()
    for i, (value, where) in enumerate([
            ({"bounds": [1.0]}, "multipliers.constraints"),
            ({"bounds": [[1.0]], "constraints": [1.0]}, "multipliers.bounds"),
            ([1.0, 2.0], "multipliers")]):
        path = tmp_path / f"bad{i}.json"
        path.write_text(json.dumps({**good, "multipliers": value}))
        with pytest.raises(DataError) as err:
            CollocationSolution.read(path)
        assert err.value.where == where and err.value.file == str(path), err.value


def test_read_errors_name_the_file_and_the_field(able, tmp_path):
    _, _, sol = able
    good = sol.to_dict()
    cases = [
        ({k: v for k, v in good.items() if k != "q"}, "q", "missing field"),
        ({**good, "q": good["q"][:-1]}, "q", "shape"),
        ({**good, "period_s": "long"}, "period_s", "number"),
        ({**good, "kind": "design-study"}, "kind", "not a collocation solution"),
        ({**good, "model": {"model": "robot"}}, "model", "unknown model"),
        ({**good, "settings": {**good["settings"], "mesh_intervals": 2}}, "mesh_intervals",
         "mesh intervals"),
        ({**good, "activation": [[None] * len(r) for r in good["activation"]]}, "activation",
         "non-finite"),
    ]
    for i, (data, field, text) in enumerate(cases):
        path = tmp_path / f"bad{i}.json"
        path.write_text(json.dumps(data))
        with pytest.raises(DataError) as err:
            CollocationSolution.read(path)
        assert err.value.where == field and err.value.file == str(path), (field, err.value)
        assert text in str(err.value)
    (tmp_path / "broken.json").write_text('{"kind": ')
    with pytest.raises(InputFileError, match="not valid JSON"):
        CollocationSolution.read(tmp_path / "broken.json")


def test_an_interrupted_write_leaves_no_file(able, tmp_path, monkeypatch):
    _, _, sol = able

    def interrupted(obj, fh, **kwargs):
        fh.write('{"kind": "collocation-solution", ')
        raise KeyboardInterrupt

    monkeypatch.setattr("bladelab._io.json.dump", interrupted)
    with pytest.raises(KeyboardInterrupt):
        sol.write(tmp_path / "solution.json")
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------- summary and trajectory


def test_summary_has_the_issue_keys_per_model(able):
    runner, _, sol = able
    s = sol.summary()
    legs = ("left", "right")
    assert list(s) == [
        "converged", "status", "mean_speed_mps", "stride_time_s",
        "cost_of_transport_J_per_kg_m", "contact_time_s",
        *(f"contact_time_{leg}_s" for leg in legs),
        *(f"peak_vertical_grf_{leg}_bw" for leg in legs),
        "flight_fraction", "step_phase", "dynamics_residual_pct", "iterations", "wall_s",
        "warnings"]
    json.dumps(s, allow_nan=False)
    assert s["converged"] is True and s["mean_speed_mps"] == pytest.approx(SPEED)
    assert s["stride_time_s"] == pytest.approx(sol.nlp.period)
    assert s["iterations"] == 7 + 3 and s["wall_s"] == pytest.approx(1.5 + 0.5)
    assert s["contact_time_s"] == pytest.approx((s["contact_time_left_s"]
                                                 + s["contact_time_right_s"]) / 2)
    # the sunk template: each foot loaded for part of the stride, the legs half a period apart
    assert 0.05 < s["contact_time_left_s"] < sol.nlp.period
    assert s["contact_time_left_s"] == pytest.approx(s["contact_time_right_s"], rel=0.05)
    assert s["peak_vertical_grf_left_bw"] > 0.2 and 0.0 <= s["flight_fraction"] < 1.0
    assert s["step_phase"] == pytest.approx(0.5, abs=0.05)
    assert s["cost_of_transport_J_per_kg_m"] > 0 and math.isfinite(s["dynamics_residual_pct"])
    fz = sol.leg_vertical_force()
    assert s["peak_vertical_grf_left_bw"] == pytest.approx(fz[:, 0].max() / runner.body_weight)


def test_a_hop_and_a_stride_on_its_bound_are_named_in_the_warnings(able):
    _, _, sol = able
    assert sol.gait_warnings() == [] and sol.summary()["warnings"] == ""
    forces = sol.contact_forces.copy()
    forces[:, sol.contact_legs == 1, :] = 0.0  # the right leg never lands
    hop = dataclasses.replace(sol, contact_forces=forces,
                              nlp=dataclasses.replace(sol.nlp, period=0.4))
    warnings = hop.gait_warnings()
    assert any("right leg never touches" in w for w in warnings)
    assert any("bound (0.4 s)" in w for w in warnings)
    assert "right leg never touches" in hop.summary()["warnings"]
    # the right foot only brushing the ground (0.03 body weights, above the contact threshold)
    brush = sol.contact_forces.copy()
    right = sol.contact_legs == 1
    brush[:, right, :] *= 0.03 * sol.body_weight_N / sol.leg_vertical_force()[:, 1].max()
    brushed = dataclasses.replace(sol, contact_forces=brush)
    assert brushed.leg_vertical_force()[:, 1].max() > CONTACT_THRESHOLD_N
    assert brushed.gait_warnings() == [
        "the right leg never carries the body: its peak vertical force is 0.03 body weights "
        "(below 1: a one-legged hop, the other foot only brushing the ground)"]
    # a swinging left foot that strikes the ground mid-swing: a second loaded stretch
    strike = sol.contact_forces.copy()
    left = sol.leg_vertical_force()[:, 0]
    swing = int(np.argmin(left))  # a node of the left swing
    assert left[swing] < CONTACT_THRESHOLD_N
    strike[swing, np.flatnonzero(sol.contact_legs == 0)[0], 1] = 5 * CONTACT_THRESHOLD_N
    struck = dataclasses.replace(sol, contact_forces=strike).gait_warnings()
    assert struck == ["the left leg touches the ground 2 times per stride (a swinging foot "
                      "strikes the ground, or the stance bounces)"]
    # a landing spike of 9 body weights on the right leg
    spike = sol.contact_forces.copy()
    right = np.flatnonzero(sol.contact_legs == 1)[0]
    k = int(np.argmax(sol.leg_vertical_force()[:, 1]))
    spike[k, right, 1] += 9.0 * sol.body_weight_N
    assert dataclasses.replace(sol, contact_forces=spike).gait_warnings() == [
        "the right leg's peak vertical force is "
        f"{(sol.leg_vertical_force()[k, 1] / sol.body_weight_N + 9.0):.1f} body weights "
        "(above 8: an impact no runner survives)"]
    # a stride the forward model does not reproduce (a residual of 9 % of the peak force)
    inconsistent = dataclasses.replace(sol, residual={**sol.residual,
                                                      "dynamics_residual_pct": 9.0})
    assert inconsistent.gait_warnings() == [
        "the dynamics residual against the forward model is 9.0 % (above 5 %: the smoothed "
        "model's gait only)"]
    assert dataclasses.replace(sol, residual={**sol.residual, "dynamics_residual_pct": 4.9}
                               ).gait_warnings() == []


def test_amputee_summary_names_intact_and_prosthetic_legs():
    _, _, sol = fake_solution("amputee", 8)
    s = sol.summary()
    assert sol.model_spec == {"model": "amputee", "blade": "Cat6"}
    for key in ("contact_time_intact_s", "contact_time_prosthetic_s",
                "peak_vertical_grf_intact_bw", "peak_vertical_grf_prosthetic_bw"):
        assert key in s
    assert not any("left" in k or "right" in k for k in s)


def test_runner_result_repeats_the_stride_for_the_analyses(able):
    from bladelab.runner.analyses import gait_events, spatiotemporal

    runner, cm, sol = able
    res = sol.to_runner_result(3, refine=2, runner=runner, cm=cm)
    n, nv, nm, nc = N, len(runner.dof_names), len(runner.muscle_names), len(
        runner.contact_names)
    rows = 3 * n * 2 + 1
    assert res.qpos.shape == (rows, nv) and res.muscles.shape == (rows, nm, 4)
    assert res.mtu.shape == (rows, nm, 2) and res.contacts.shape == (rows, nc, 7)
    assert res.ligament.shape == (rows, nv) and res.excitation.shape == (rows, nm)
    assert res.dt == pytest.approx(sol.nlp.period / n / 2) and not res.fell
    np.testing.assert_allclose(res.time[-1], 3 * sol.nlp.period)
    # every other sample is a node; the 2nd stride is the 1st, pelvis_tx advanced
    itx = runner.dof("pelvis_tx")
    second = sol.nlp.q.copy()
    second[:, itx] += sol.stride_length_m
    np.testing.assert_allclose(res.qpos[2 * n:4 * n + 1:2], second, atol=1e-12)
    np.testing.assert_allclose(res.contacts[:2 * n + 1:2, :, :2], sol.contact_forces, atol=1e-9)
    fmax = runner.muscle_params[:, 0]
    np.testing.assert_allclose(res.muscles[::2, :, 3][:n + 1], sol.nlp.tendon_force * fmax)
    assert np.all(res.contacts[:, :, 6] >= 0)
    ev = gait_events(res)
    assert set(ev.leg) == {"left", "right"}
    st = spatiotemporal(res)
    stride = st[(st.leg == "right") & (st.variable == "stride_time")].value.iloc[0]
    assert stride == pytest.approx(sol.nlp.period, abs=2 * res.dt)
    with pytest.raises(SpecError, match="stride"):
        sol.to_runner_result(0, runner=runner, cm=cm)


def test_runner_result_contact_velocities_are_those_of_the_material_points(able):
    """As the forward kernel records them: the velocity of the body's material point at the
    contact point, so that Σ f·v (the analyses' contact power) is the power of the contacts'
    generalised force, τ_c·q̇ (a rolling sphere's lowest point moves otherwise)."""
    runner, cm, sol = able
    res = sol.to_runner_result(1, refine=3, runner=runner, cm=cm)
    f, v = res.contacts[:, :, :2], res.contacts[:, :, 4:6]
    power = (f * v).sum(axis=(1, 2))
    gen = np.array([np.asarray(cm.contacts(q, qd)[2]).ravel() @ qd
                    for q, qd in zip(res.qpos, res.qvel, strict=True)])
    scale = np.abs(f).sum(axis=(1, 2)) * np.abs(res.qvel).max() + 1.0  # [W]
    assert np.max(np.abs(power - gen) / scale) < 1e-9


# ---------------------------------------------------------------- dynamic consistency


def test_dynamics_residual_is_small_for_consistent_states_and_large_when_perturbed(able):
    """Accelerations that balance the forward model's forces (M·q̈ = applied − bias) give a
    round-off residual; 100 rad/s² more at one knee gives a large one."""
    runner, cm, sol = able
    s = sol.nlp
    # a sticking contact carries the collocation model's friction (within ±μ·Fn)
    held = np.stack([np.asarray(cm.contacts(s.q[k], s.qd[k])[0])[:, 0]
                     for k in range(s.q.shape[0])])
    bias = inverse_dynamics(runner, s.q, s.qd, np.zeros_like(s.q))
    for friction in ("coulomb", "bristle"):
        fwd = forward_generalised_forces(runner, s.q, s.qd, s.tendon_force, s.period,
                                         friction=friction, stick_friction=held)
        assert fwd.tendon_force_mismatch < 1e-9
        qdd = np.stack([np.linalg.solve(np.asarray(cm.mass_matrix(s.q[k])),
                                        fwd.total[k] - bias[k]) for k in range(s.q.shape[0])])
        r = dynamics_residual(replace(s, qdd=qdd), runner, cm=cm, friction=friction)
        assert r.pct < 1e-6 and r.friction == friction, r
        # the collocation model's smooth forces differ from the forward ones; not the muscles
        assert r.collocation_pct > r.pct
        assert set(r.component_pct) == {"muscle", "passive", "contact"}
        assert r.component_pct["muscle"] < 1e-6 and r.contact_force_diff_N["normal"] > 0
    fwd = forward_generalised_forces(runner, s.q, s.qd, s.tendon_force, s.period,
                                     stick_friction=held)
    qdd = np.stack([np.linalg.solve(np.asarray(cm.mass_matrix(s.q[k])), fwd.total[k] - bias[k])
                    for k in range(s.q.shape[0])])
    bumped = qdd.copy()
    bumped[:, runner.dof("knee_angle_l")] += 100.0
    r2 = dynamics_residual(replace(s, qdd=bumped), runner, cm=cm)
    assert r2.pct > 5.0 and r2.per_dof["knee_angle_l"] > 1.0  # N·m
    assert dynamics_residual_pct(replace(s, qdd=bumped), runner, cm=cm) == pytest.approx(r2.pct)


# ---------------------------------------------------------------- the solve


def test_a_stage_that_does_not_converge_ends_the_solve_deterministically(able):
    runner, _, _ = able
    settings = CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED, max_iter=4)
    events: list[SolveProgress] = []
    runs = [predict_stride(runner, settings, template_guess(runner, speed=SPEED, n=6),
                           model_spec={"model": "able"}, progress=events.append)
            for _ in range(2)]
    a, b = runs
    assert not a.converged and a.stage == "tracking" and a.kind == BEST_ITERATE_KIND
    assert a.nlp.status == "Maximum_Iterations_Exceeded" and a.nlp.iterations == 4
    assert a.nlp.worst_constraints and all(" " in name for name, _ in a.nlp.worst_constraints)
    for attr in ("q", "qd", "qdd", "activation", "tendon_force", "excitation"):
        np.testing.assert_array_equal(getattr(a.nlp, attr), getattr(b.nlp, attr))
    assert a.nlp.period == b.nlp.period and a.summary()["converged"] is False
    kinds = [(e.stage, e.event) for e in events[:len(events) // 2]]
    assert kinds[0] == ("tracking", "start") and kinds[-1] == ("tracking", "end")
    assert [e.iteration for e in events if e.event == "iteration"][:5] == [0, 1, 2, 3, 4]
    # a collocation solution as the guess goes straight to the predictive stage
    warm = predict_stride(runner, settings, a.to_guess(), model_spec={"model": "able"})
    assert warm.stage == "predictive" and warm.tracking is None


def test_a_speed_floor_belongs_to_the_maximum_speed_problem(able):
    """A floor [m/s] with a prescribed speed, or a negative or infinite one, is refused before
    anything is built, naming the argument."""
    runner, _, _ = able
    guess = template_guess(runner, speed=SPEED, n=6)
    for settings, floor in ((CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED), 3.0),
                            (CollocationSettings(mesh_intervals=6, speed_m_per_s=None), -1.0),
                            (CollocationSettings(mesh_intervals=6, speed_m_per_s=None),
                             math.inf)):
        with pytest.raises(SpecError, match="speed floor") as err:
            predict_stride(runner, settings, guess, model_spec={"model": "able"},
                           speed_floor=floor)
        assert err.value.where == "speed_floor"


def test_a_pelvis_tilt_range_bounds_every_node(able):
    # IPOPT's iterates stay inside the bounds: after a few iterations the tilt of every node
    # lies in the range, where the same solve without it leaves the range
    runner, _, _ = able
    guess = template_guess(runner, speed=SPEED, n=6)
    tilt = runner.dof("pelvis_tilt")
    free = predict_stride(runner, CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED,
                                                      max_iter=3), guess,
                          model_spec={"model": "able"})
    seen = np.degrees(free.nlp.q[:, tilt])
    lo, hi = float(seen.min()) + 0.25 * np.ptp(seen), float(seen.max()) - 0.25 * np.ptp(seen)
    assert hi > lo + 0.1
    bounded = predict_stride(
        runner, CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED, max_iter=3,
                                    pelvis_tilt_range_deg=(lo, hi)),
        guess, model_spec={"model": "able"})
    got = np.degrees(bounded.nlp.q[:, tilt])
    assert got.min() >= lo - 1e-6 and got.max() <= hi + 1e-6
    assert bounded.settings.pelvis_tilt_range_deg == (lo, hi)


def test_a_stride_time_range_bounds_the_period_of_every_stage(able):
    # the same few iterations with and without a range that excludes the free solve's
    # stride time: IPOPT's iterates stay inside the bounds, in the tracking stage too
    runner, _, _ = able
    guess = template_guess(runner, speed=SPEED, n=6)
    free = predict_stride(runner, CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED,
                                                      max_iter=3), guess,
                          model_spec={"model": "able"})
    lo, hi = free.period_s + 0.05, free.period_s + 0.08
    for track in (True, False):
        bounded = predict_stride(
            runner, CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED, max_iter=3,
                                        stride_time_range_s=(lo, hi)),
            guess, model_spec={"model": "able"}, track=track)
        assert lo - 1e-9 <= bounded.period_s <= hi + 1e-9
    stride = [c for c in human_running_criteria(bounded) if c.name == "stride time"]
    assert f"imposed: {lo:g}–{hi:g} s" in stride[0].note


def test_people_stride_time_bounds_the_period_by_their_band_at_the_speed(able):
    # the same few iterations free and with people's band: the free solve's stride time lies
    # outside the band, the bounded one inside it; the criterion says it was imposed
    runner, _, _ = able
    guess = template_guess(runner, speed=SPEED, n=6)
    lo, hi, _ = reference_band("stride time", SPEED)
    free = predict_stride(runner, CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED,
                                                      max_iter=3), guess,
                          model_spec={"model": "able"})
    assert not lo <= free.period_s <= hi
    people = CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED, max_iter=3,
                                 stride_time_people=True)
    bounded = predict_stride(runner, people, guess, model_spec={"model": "able"})
    assert lo - 1e-6 <= bounded.period_s <= hi + 1e-6
    stride = [c for c in human_running_criteria(bounded) if c.name == "stride time"]
    assert f"imposed: people's band at {SPEED:g} m/s" in stride[0].note
    assert CollocationSettings.from_dict(json.loads(json.dumps(people.to_dict()))) == people



def test_people_stride_time_in_the_maximum_speed_problem_moves_with_the_speed():
    """Without a prescribed speed people's band is no pair of period bounds but a band at the
    anchor speeds, which the NLP applies at the stride's own speed; a different problem from
    the free one, and said so."""
    import dataclasses

    from bladelab.predict.collocation.running_bands import ANCHOR_SPEEDS_MPS
    from bladelab.predict.collocation.transcription import PERIOD_BOUNDS_S

    fastest = CollocationSettings(mesh_intervals=6, speed_m_per_s=None, stride_time_people=True)
    assert fastest.period_bounds_s == PERIOD_BOUNDS_S
    v0, lo0, hi0, v1, lo1, hi1 = fastest.period_band
    assert (v0, v1) == ANCHOR_SPEEDS_MPS
    assert (lo0, hi0) == reference_band("stride time", v0)[:2]
    assert (lo1, hi1) == reference_band("stride time", v1)[:2]
    assert fastest.imposed_stride_time == "people's band at the stride's speed"
    assert not fastest.same_problem(dataclasses.replace(fastest, stride_time_people=False))
    assert CollocationSettings(speed_m_per_s=SPEED, stride_time_people=True).period_band is None
    assert CollocationSettings(speed_m_per_s=None).period_band is None

def _relabelled_solves(monkeypatch):
    """Spy on every IPOPT solve of ``StrideNLP``: returns (calls, labels); each call appends
    (nlp, x0, keywords, solution), and ``labels[i]`` (if given: ``(status, max_violation)``,
    violation None to keep it) relabels the i-th call's solution, so a test can drive
    predict_stride's control flow through any status."""
    from bladelab.predict.collocation.transcription import StrideNLP

    calls, labels = [], []
    solve = StrideNLP.solve

    def fake(self, x0, **kw):
        sol = solve(self, x0, **kw)
        if len(calls) < len(labels):
            status, violation = labels[len(calls)]
            sol = dataclasses.replace(
                sol, success=status == "Solve_Succeeded", status=status,
                max_violation=sol.max_violation if violation is None else violation)
        calls.append((self, np.asarray(x0).copy(), kw, sol))
        return sol

    monkeypatch.setattr(StrideNLP, "solve", fake)
    return calls, labels


def test_a_locally_infeasible_tracking_stage_is_solved_again_from_its_iterate(able, monkeypatch):
    # the control flow of predict_stride (a local infeasibility was seen on one host for the
    # able template at 4 m/s)
    runner, _, _ = able
    calls, labels = _relabelled_solves(monkeypatch)
    settings = CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED, max_iter=5)
    guess = template_guess(runner, speed=SPEED, n=6)
    labels[:] = [("Infeasible_Problem_Detected", None), ("Solve_Succeeded", None)]
    out = predict_stride(runner, settings, guess, model_spec={"model": "able"})
    assert len(calls) == 3 and out.stage == "predictive"  # tracking, its restart, predictive
    (nlp, _, _, first), (_, x_restart, _, restart), _ = calls
    # from the iterate, not the guess
    np.testing.assert_array_equal(x_restart, nlp.initial_vector(first.to_guess("x")))
    assert out.tracking["restarted_after"] == "Infeasible_Problem_Detected"
    assert out.tracking["iterations"] == first.iterations + restart.iterations == 10
    # IPOPT's own time of both tracking solves, as the iterations
    assert out.tracking["ipopt_own_s"] == pytest.approx(
        first.timings["ipopt_own_s"] + restart.timings["ipopt_own_s"])
    assert first.timings["ipopt_own_s"] > 0
    # a second local infeasibility ends the solve: one restart, no loop
    calls.clear()
    labels[:] = [("Restoration_Failed", None), ("Infeasible_Problem_Detected", None)]
    out = predict_stride(runner, settings, guess, model_spec={"model": "able"})
    assert len(calls) == 2 and out.stage == "tracking" and not out.converged
    assert out.nlp.status == "Infeasible_Problem_Detected"
    # a tracking stage that runs out of iterations is not restarted
    calls.clear()
    labels[:] = [("Maximum_Iterations_Exceeded", None)]
    out = predict_stride(runner, settings, guess, model_spec={"model": "able"})
    assert len(calls) == 1 and "restarted_after" not in out.tracking


def test_the_tracking_stage_alone_keeps_a_swinging_foot_clear_of_the_ground(able, monkeypatch):
    """A cold start's tracking stage holds every swinging contact TRACKING_SWING_CLEARANCE_M
    above the ground (one path inequality per contact more than the predictive stage's);
    settings with a larger clearance of their own keep theirs in both stages."""
    from bladelab.predict.collocation.solve import TRACKING_SWING_CLEARANCE_M

    runner, _, _ = able
    calls, labels = _relabelled_solves(monkeypatch)
    guess = template_guess(runner, speed=SPEED, n=6)
    rows = {}
    for clearance in (0.0, 0.05):
        calls.clear()
        labels[:] = [("Solve_Succeeded", None)]  # the tracking stage goes on to the next
        settings = CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED, max_iter=3,
                                       swing_clearance_m=clearance)
        predict_stride(runner, settings, guess, model_spec={"model": "able"})
        assert len(calls) == 2  # tracking, then predictive
        rows[clearance] = [c[0].dyn.inequalities.size1_out(0) for c in calls]
    n_contacts = runner.contact_params.shape[0]
    (tracking, predictive), (tracking_own, predictive_own) = rows[0.0], rows[0.05]
    assert tracking == predictive + n_contacts
    assert tracking_own == predictive_own == tracking
    assert 0.0 < TRACKING_SWING_CLEARANCE_M < 0.05


def test_a_predictive_stage_stalled_near_a_feasible_point_is_polished(able, monkeypatch):
    runner, _, sol = able
    calls, labels = _relabelled_solves(monkeypatch)
    settings = CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED, max_iter=3,
                                   polish_iter=4)
    stalled = ("Maximum_Iterations_Exceeded", 1e-9)
    labels[:] = [stalled, ("Solve_Succeeded", 1e-9)]
    out = predict_stride(runner, settings, sol.to_guess(), model_spec={"model": "able"})
    assert len(calls) == 2  # the predictive stage, then the polish
    (_, _, _, first), (_, _, kw, polished) = calls
    assert kw["hessian"] == "exact" and kw["max_iter"] == 4
    assert kw["multipliers"] is first.multipliers  # from the stalled iterate's duals
    assert out.converged and out.nlp.status == "Solve_Succeeded"
    assert out.nlp.iterations == first.iterations + polished.iterations
    assert out.nlp.timings["polished"] == 1.0
    assert out.nlp.timings["polish_iterations"] == polished.iterations
    # a polish that does not converge returns the stalled iterate, the polish counted
    calls.clear()
    labels[:] = [stalled, ("Maximum_Iterations_Exceeded", 1e-9)]
    out = predict_stride(runner, settings, sol.to_guess(), model_spec={"model": "able"})
    assert len(calls) == 2 and not out.converged
    assert out.nlp.objective == calls[0][3].objective and out.nlp.timings["polished"] == 0.0
    # no polish: an infeasible stall, polish_iter 0, or a stage already on the exact Hessian
    for label, changed in ((("Maximum_Iterations_Exceeded", 1e-3), {}),
                           (stalled, {"polish_iter": 0}), (stalled, {"hessian": "exact"})):
        calls.clear()
        labels[:] = [label]
        out = predict_stride(runner, dataclasses.replace(settings, **changed), sol.to_guess(),
                             model_spec={"model": "able"})
        assert len(calls) == 1 and "polished" not in out.nlp.timings, (label, changed)
    with pytest.raises(SpecError, match="iterations"):
        CollocationSettings(polish_iter=-1)


def test_warm_start_mu_sets_the_barrier_of_a_warm_start_only_and_the_lbfgs_update_the_stage(
        able, monkeypatch):
    from bladelab.predict.collocation.transcription import StrideNLP

    runner, _, sol = able
    seen = []
    solve = StrideNLP.solve

    def spy(self, x0, **kw):
        seen.append(dict(kw.get("options") or {}))
        return solve(self, x0, **kw)

    monkeypatch.setattr(StrideNLP, "solve", spy)
    settings = CollocationSettings(mesh_intervals=6, speed_m_per_s=SPEED, max_iter=2,
                                   warm_start_mu=1e-4)
    predict_stride(runner, settings, sol.to_guess(), model_spec={"model": "able"})
    assert seen[-1]["ipopt.mu_init"] == 1e-4 and seen[-1]["ipopt.bound_push"] == 1e-8
    # the predictive stage's L-BFGS update inside the augmented system
    assert seen[-1]["ipopt.limited_memory_aug_solver"] == "extended"
    # tracking, then the predictive stage: IPOPT's defaults in both
    seen.clear()
    predict_stride(runner, dataclasses.replace(settings, max_iter=200),
                   template_guess(runner, speed=SPEED, n=6), model_spec={"model": "able"})
    assert seen and all("ipopt.mu_init" not in o for o in seen)
    # the tracking stage keeps IPOPT's default L-BFGS update
    assert "ipopt.limited_memory_aug_solver" not in seen[0]
    seen.clear()
    predict_stride(runner, dataclasses.replace(settings, warm_start_mu=None), sol.to_guess(),
                   model_spec={"model": "able"})
    assert "ipopt.mu_init" not in seen[-1]


def nlp_x_index(n_vars: int, sol, node: int) -> int:
    """Index of pelvis_tx (row 0, scale 1) at ``node`` in the scaled NLP vector (states
    column-major first)."""
    n1 = sol.nlp.q.shape[0]
    nx = 2 * len(sol.dof_names) + 2 * len(sol.muscle_names)
    return nx * (node % n1)


def test_a_guess_with_fitting_multipliers_starts_from_its_duals(able, monkeypatch):
    from bladelab.predict.collocation.transcription import StrideNLP

    runner, _, sol = able
    seen = []
    solve = StrideNLP.solve

    def spy(self, x0, **kw):
        seen.append((self.n_vars, self.n_cons, kw.get("multipliers"),
                     dict(kw.get("options") or {}), np.array(x0)))
        return solve(self, x0, **kw)

    monkeypatch.setattr(StrideNLP, "solve", spy)
    # on the solution's own mesh (another mesh drops the multipliers)
    settings = CollocationSettings(mesh_intervals=sol.nlp.q.shape[0] - 1, speed_m_per_s=SPEED,
                                   max_iter=2)
    nlp = predict_stride(runner, settings, sol.to_guess(), model_spec={"model": "able"}).nlp
    n_vars, n_cons, lam, _, _ = seen[-1]
    assert lam is None  # the fake solution has none
    fitting = (np.zeros(n_vars), np.zeros(n_cons))
    guess = replace(sol.to_guess(), multipliers=fitting)
    predict_stride(runner, dataclasses.replace(settings, warm_start_mu=1e-5), guess,
                   model_spec={"model": "able"})
    _, _, lam, options, _ = seen[-1]
    assert lam is not None and options == {**PREDICTIVE_LBFGS_OPTIONS, "ipopt.mu_init": 1e-5}
    assert nlp.multipliers is not None and nlp.multipliers[0].shape == (n_vars,)
    wrong = replace(sol.to_guess(), multipliers=(np.zeros(n_vars + 1), np.zeros(n_cons)))
    predict_stride(runner, settings, wrong, model_spec={"model": "able"})
    assert seen[-1][2] is None
    # at another speed the primal-dual start keeps the solution's own point (the speed the
    # one violated constraint); a primal start is scaled to the speed
    faster = dataclasses.replace(settings, speed_m_per_s=1.1 * SPEED)
    for start, scaled in ((guess, False), (sol.to_guess(), True)):
        predict_stride(runner, faster, start, model_spec={"model": "able"})
        x0 = seen[-1][4]
        distance = (x0[nlp_x_index(n_vars, sol, -1)] - x0[nlp_x_index(n_vars, sol, 0)])
        expected = sol.stride_length_m * (1.1 if scaled else 1.0)
        assert distance == pytest.approx(expected, rel=1e-9), scaled


# ---------------------------------------------------------------- report


def test_the_force_figure_starts_at_the_left_touch_down_beside_the_measured_force(able):
    """The report's force figure: each leg's vertical force rolled to start at the left leg's
    touch-down (loaded at the first node, unloaded just before), and with a measured stride
    its total beside the measured total, point for point."""
    import matplotlib.pyplot as plt

    from bladelab.predict.collocation.human_running import stride_from_left_touchdown
    from bladelab.report.collocation import _grf_figure

    runner, _, sol = able
    force = sol.leg_vertical_force()
    rolled = stride_from_left_touchdown(sol, values=force)
    assert rolled[0, 0] > 20.0 and rolled[-2, 0] <= 20.0
    np.testing.assert_array_equal(rolled[-1], rolled[0])
    np.testing.assert_allclose(np.sort(rolled[:-1].ravel()), np.sort(force[:-1].ravel()))
    trial = measured_trial_guess(runner, n=100)
    fig = _grf_figure(sol, trial)
    try:
        assert len(fig.axes) == 4  # vertical and horizontal; each leg, total against measured
        model, measured = fig.axes[1].get_lines()
        np.testing.assert_allclose(model.get_ydata(), rolled.sum(axis=1) / sol.body_weight_N)
        np.testing.assert_array_equal(measured.get_ydata(), trial.vertical_grf_bw)
        assert 2.0 < measured.get_ydata().max() < 3.2  # people's peak at 3.5 m/s
        model, measured = (line for line in fig.axes[3].get_lines() if len(line.get_ydata()) > 2)
        fx = sol.contact_forces[:, :, 0].sum(axis=1, keepdims=True)
        np.testing.assert_allclose(
            model.get_ydata(), stride_from_left_touchdown(sol, values=fx)[:, 0] / sol.body_weight_N)
        np.testing.assert_array_equal(measured.get_ydata(), trial.horizontal_grf_bw)
    finally:
        plt.close(fig)
    fig = _grf_figure(sol)
    assert len(fig.axes) == 2
    plt.close(fig)


def test_the_predictive_report_renders_a_collocation_solution(able, tmp_path):
    from bladelab.report import Report
    from bladelab.report.collocation import collocation_sections
    from bladelab.report.predictive import build_predictive_report, predictive_kind

    _, _, sol = able
    path = sol.write(tmp_path / "run" / "solution.json")
    assert predictive_kind(path) == "collocation" and predictive_kind(path.parent) == "collocation"
    # the 'bladelab predict --method collocation' folder itself, as the CLI's help offers (the
    # file itself is reported below)
    rep = build_predictive_report(path.parent, tmp_path / "report", progress=False,
                                  animate=False)
    assert rep.kind == "collocation" and rep.solutions == ("able-bodied 3.5 m/s (collocation)",)
    html = (tmp_path / "report" / "index.html").read_text()
    assert "Collocation solution" in html and "Joint angles per leg" in html
    # at the measured trial's speed its joint angles are drawn beside the solution's
    assert "Joint angles against the measured trial" in html
    # the report opens with the stride against people, criterion by criterion
    assert html.index("Against measured human running") < html.index("Collocation solution")
    assert "contact time, left leg" in html and "knee flexion RMSE against the measured" in html
    assert "the totals against the measured 3.5 m/s stride" in html  # the force's shape too
    assert "At touch-down the left leg" in html and "How a foot lands" in html
    assert "vertical force peaks at" in html and "% of its nodes here, the measured" in html
    assert "The stance knee lands at" in html and "is most flexed at" in html
    # and the first section puts that shape beside the criteria, in words and in a table
    first = html[html.rindex("Against measured human running"):html.rindex("Collocation solution")]
    assert "Beside the criteria, the shape of a stance" in first
    assert "The shape of each stance beside the measured runner" in first
    assert "knee flexion at touch-down, left leg" in first
    assert "Not a free prediction" not in html  # the fake solve held no reference term
    assert "Prosthesis loads" not in html  # an able runner carries none
    # a stride solved with people's angles in its objective says so in its first lines
    people = replace(sol, settings=CollocationSettings(**people_term(10.0)),
                     nlp=replace(sol.nlp, objective_terms={**sol.nlp.objective_terms,
                                                           "tracking": 0.25}))
    # (the collocation solution's own sections suffice here: the gait figures are not drawn)
    report = Report("people")
    collocation_sections(report, people.write(tmp_path / "people.json"))
    html = report.write(tmp_path / "report3").read_text()
    first = html[html.index("This stride is"):html.index("The stride against people")]
    assert "Not a free prediction" in first and "weight 10 1/rad²" in first
    assert "RBDS002" in first and "0.25 of the objective" in first
    assert "Symmetric by constraint" not in first and "Stride time imposed" not in first
    report = Report("symmetric")
    collocation_sections(report, replace(sol, settings=CollocationSettings(
        symmetric=True, stride_time_range_s=(0.7, 0.7))).write(tmp_path / "symmetric.json"))
    html = report.write(tmp_path / "report4").read_text()
    first = html[:html.index("The stride against people")]
    assert "Symmetric by constraint" in first and "Stride time imposed at 0.7 s" in first
    bad = replace(sol, nlp=replace(sol.nlp, success=False)).write(tmp_path / "best.json")
    with pytest.raises(InputFileError, match="did not converge"):
        predictive_kind(bad)


def test_model_spec_names_the_body_only_when_it_is_not_seed_001s():
    """Files written before the bodies existed (no "body") and "seed001" mean the same model;
    the toe body is part of the problem's identity and of its label."""
    from bladelab.errors import SpecError
    from bladelab.predict.collocation.stored import check_model_spec, model_label

    old = check_model_spec({"model": "able", "blade": None})
    assert old == check_model_spec({"model": "able", "body": "seed001"}) == {
        "model": "able", "blade": None}
    toes = check_model_spec({"model": "amputee", "blade": "Cat6", "body": "toes"})
    assert toes != check_model_spec({"model": "amputee", "blade": "Cat6"})
    assert model_label(toes) == "amputee Cat6 (toes body)"
    human = check_model_spec({"model": "able", "body": "human"})
    assert human == {"model": "able", "blade": None, "body": "human"}
    assert model_label(human) == "able (human body)"
    with pytest.raises(SpecError, match="unknown body"):
        check_model_spec({"model": "able", "body": "robot"})


def test_two_model_specs_are_the_same_runner_to_round_off_not_beyond():
    """A stored blade's numbers an ulp off a regenerated one's are the same runner; a change
    of 1e-6 relative, another key or another string is not."""
    from bladelab.predict.collocation.stored import same_model_spec

    spec = {"model": "amputee", "blade": "b", "blade_spec": {"joints": [
        {"K_Nm_per_deg": 6.063704033452058, "D_Nms_per_deg": 0.1179053562060122}]}}
    joint = spec["blade_spec"]["joints"][0]
    ulp = {**spec, "blade_spec": {"joints": [
        {**joint, "K_Nm_per_deg": np.nextafter(joint["K_Nm_per_deg"], 0.0)}]}}
    assert ulp != spec and same_model_spec(ulp, spec)
    moved = {**spec, "blade_spec": {"joints": [
        {**joint, "K_Nm_per_deg": joint["K_Nm_per_deg"] * (1 + 1e-6)}]}}
    assert not same_model_spec(moved, spec)
    assert not same_model_spec({**spec, "blade": "c"}, spec)
    assert not same_model_spec({**spec, "body": "human"}, spec)
    assert not same_model_spec({**spec, "blade_spec": {"joints": []}}, spec)


def test_model_spec_carries_the_athlete_into_the_runner_the_label_and_the_file(able, tmp_path):
    """An athlete other than the parameter set's is part of the problem: checked field by
    field, named in the label, the runner built to it, and kept by the solution file."""
    from bladelab.predict.collocation.stored import check_model_spec, model_label, runner_from_spec

    plain = {"model": "amputee", "blade": "Cat6", "body": "human"}
    spec = check_model_spec({**plain, "athlete": {"body_mass_kg": 68, "height_m": 1.75,
                                                  "muscle_strength": None}})
    assert spec["athlete"] == {"body_mass_kg": 68.0, "height_m": 1.75}
    assert spec != check_model_spec(plain) == check_model_spec({**plain, "athlete": {}})
    assert model_label(spec) == "amputee Cat6 (human body; 68 kg, 1.75 m)"
    from bladelab.predict.collocation.stored import athlete_label
    assert athlete_label({**plain, "athlete": {"muscle_strength": 1.5}}) == (
        "muscle strength ×1.5")
    fast = check_model_spec({**plain, "athlete": {"max_shortening_velocity": 15}})
    assert athlete_label(fast) == "fibres' maximum velocity 15 l_opt/s"
    assert set(runner_from_spec(fast).muscle_params[:, 7]) == {15.0}
    assert athlete_label(plain) == ""
    assert runner_from_spec(spec).total_mass == pytest.approx(68.0, rel=1e-12)
    for bad, where in (({"body_mass_kg": -70}, "athlete.body_mass_kg"),
                       ({"muscle_strength": float("nan")}, "athlete.muscle_strength"),
                       ({"height_m": True}, "athlete.height_m"),
                       ({"weight": 70}, "athlete"), (70, "athlete")):
        with pytest.raises(SpecError) as err:
            check_model_spec({**plain, "athlete": bad})
        assert err.value.where == where
    _, _, sol = able
    strong = check_model_spec({"model": "able", "athlete": {"muscle_strength": 1.5}})
    path = replace(sol, model_spec=strong).write(tmp_path / "solution.json")
    assert CollocationSolution.read(path).model_spec == strong


def test_a_force_that_zigzags_from_node_to_node_is_named_in_the_warnings():
    """The shipped able stride's stance is resolved by its mesh (no warning); the same stride
    with its left leg's vertical force alternating ±0.4 BW from node to node is flagged, on
    that leg only."""
    sol = CollocationSolution.read(RUNNER_DATA_DIR / "collocation" / "able-3.5-human.json")
    assert sol.gait_warnings() == []
    forces = sol.contact_forces.copy()
    left = np.flatnonzero(sol.contact_legs == 0)
    fz = sol.leg_vertical_force()[:, 0] / sol.body_weight_N
    sign = (-1.0) ** np.arange(fz.size)
    forces[:, left[0], 1] += np.where(fz > 0.5, 0.4 * sol.body_weight_N * sign, 0.0)
    warnings = dataclasses.replace(sol, contact_forces=forces).gait_warnings()
    assert len(warnings) == 1 and warnings[0].startswith(
        "the left leg's vertical force zigzags from node to node")
