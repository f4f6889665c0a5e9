"""Seed 002's responses, and the prosthesis's loads, from predicted amputee strides.

The fixture ``tests/data/transfemoral-4mps.json`` is a converged collocation stride of the
transfemoral runner at 4 m/s (mesh 50, from the template guess; dynamics residual
1.4 %). Its intact foot strikes the ground during the prosthetic stance, so the test of the
impulses adds the intact leg's over the same window."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np
import pytest

from bladelab.design import predicted
from bladelab.design.collocation_evaluator import DEFAULT_STARTS
from bladelab.design.predicted import stride_responses
from bladelab.design.responses import PREDICTED_RESPONSE_UNITS
from bladelab.errors import SpecError
from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.nodes import evaluate_nodes
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.runner.layout import CP_LEG

FIXTURE = Path(__file__).parent / "data" / "transfemoral-4mps.json"


@pytest.fixture(scope="module")
def stride():
    sol = CollocationSolution.read(FIXTURE)
    runner = runner_from_spec(sol.model_spec)
    return sol, runner, stride_responses(sol, runner)


def test_every_response_has_its_unit(stride):
    _, _, res = stride
    assert set(res) == set(PREDICTED_RESPONSE_UNITS)
    # this runner's prosthesis is a rigid contact sphere: no blade joint to carry a moment
    assert np.isnan(res.pop("blade_moment_max_Nm"))
    assert all(np.isfinite(v) for v in res.values())


@pytest.fixture(scope="module")
def blade_stride():
    """The transtibial runner on the human body wearing the design box's centre blade (six
    links): the collocation evaluator's built-in start."""
    sol = CollocationSolution.read(DEFAULT_STARTS[("transtibial", "human")])
    runner = runner_from_spec(sol.model_spec)
    cm = build_collocation_model(runner)
    nodes = evaluate_nodes(cm, sol.nlp.q, sol.nlp.qd, sol.nlp.tendon_force,
                           sol.nlp.tendon_force_rate)
    return sol, runner, nodes, stride_responses(sol, runner, cm=cm)


def test_the_centre_of_mass_acceleration_balances_the_ground_forces(blade_stride):
    """Newton for the whole body at every node: M·(a − g) from the stride's accelerations
    (the loads' method, applied to the root's subtree) equals the ground forces' sum."""
    sol, runner, nodes, _ = blade_stride
    acc = predicted._subtree_com_acceleration(runner, 0, sol.nlp.q, sol.nlp.qd, sol.nlp.qdd)
    newton = runner.total_mass * (acc - np.array([0.0, -runner.gravity]))
    weight = runner.total_mass * runner.gravity
    assert np.abs(newton - nodes["forces"].sum(axis=1)).max() < 1e-3 * weight


def test_the_socket_carries_the_blades_ground_force_and_its_moment(blade_stride):
    """At the prosthesis's peak load the light prosthesis (0.79 kg and the blade's links)
    passes the ground force and its moment about the socket axis (MuJoCo's anchor) on to the
    residual limb within a few per cent; the blade's joints carry moments of that order."""
    sol, runner, nodes, res = blade_stride
    pros = runner.contact_params[:, CP_LEG] == 1
    loads = predicted.prosthesis_loads(runner, sol.nlp, nodes["forces"], nodes["passive"], pros)
    ground = nodes["forces"][:, pros, :].sum(axis=1)
    k = int(np.argmax(ground[:, 1]))
    assert loads["socket_force"][k] == pytest.approx(-ground[k], rel=0.05, abs=0.02 * ground[k, 1])
    m = runner.mj_model
    d = mujoco.MjData(m)
    d.qpos[:] = sol.nlp.q[k]
    mujoco.mj_forward(m, d)
    arm = nodes["points"][k, pros] - d.xanchor[m.joint("socket_angle_r").id, [0, 2]]
    force = nodes["forces"][k, pros]
    about_socket = float((arm[:, 0] * force[:, 1] - arm[:, 1] * force[:, 0]).sum())
    assert abs(loads["socket_moment"][k]) == pytest.approx(abs(about_socket), rel=0.05)
    assert loads["blade_moment"].shape == (sol.nlp.q.shape[0], 5)
    assert res["socket_force_max_N"] >= 0.95 * ground[k, 1]
    assert res["socket_moment_max_Nm"] >= 0.95 * abs(about_socket)
    assert 0.1 * res["socket_moment_max_Nm"] < res["blade_moment_max_Nm"] < 1e4


def test_the_stride_objective_is_the_solved_value_and_holds_its_energy_term(stride):
    """The objective is the solution's own; with the metabolic weight 1 and every other term
    a non-negative mean (effort, squared accelerations), it is at least the cost of transport."""
    sol, _, res = stride
    assert res["stride_objective"] == sol.nlp.objective
    assert sol.settings.weights.metabolic == 1.0
    assert res["stride_objective"] >= res["cost_of_transport_J_per_kg_m"]


def test_impulses_change_the_momentum_of_the_centre_of_mass(stride):
    """Newton over the prosthetic stance: m·Δv of the centre of mass (MuJoCo's, from the
    nodes' states) equals the prosthetic impulses plus the intact leg's over the same window,
    minus gravity's (within the trapezoid's error on this mesh)."""
    sol, runner, res = stride
    kin = predicted._kinematics(runner, sol.nlp.q, sol.nlp.qd)
    fz = sol.leg_vertical_force()
    idx = predicted._stance(predicted._fine(fz[:, 1]) > 20.0)
    n = sol.nlp.q.shape[0] - 1
    dt = sol.period_s / (n * predicted._FINE)
    intact = sol.contact_forces[:, sol.contact_legs == 0, :].sum(axis=1)
    fine = predicted._fine(intact)[idx]
    intact_imp = dt * (fine.sum(axis=0) - 0.5 * (fine[0] + fine[-1]))
    v = predicted._fine(kin["com_velocity"])
    m = runner.total_mass
    dv = v[idx[-1]] - v[idx[0]]
    assert res["impulse_x_Ns"] + intact_imp[0] == pytest.approx(m * dv[0], abs=0.03 * m)
    assert res["impulse_z_net_Ns"] + intact_imp[1] == pytest.approx(m * dv[1], rel=0.03)
    assert res["impulse_z_Ns"] - res["impulse_z_net_Ns"] == pytest.approx(
        m * runner.gravity * (idx.size - 1) * dt, rel=1e-9)
    assert res["delta_vx_m_per_s"] == pytest.approx(res["impulse_x_Ns"] / m, rel=1e-12)
    assert res["evaluation_E_m"] == pytest.approx(
        res["impulse_x_Ns"] * res["impulse_z_net_Ns"] / (m * m * runner.gravity), rel=1e-12)
    # the stance agrees with the solution's own contact time
    legs = sol.contact_phases()["legs"]
    assert res["contact_time_prosthetic_s"] == pytest.approx(
        legs["prosthetic"]["contact_time_s"], abs=2 * dt)


def test_the_knee_moment_is_the_grf_moment_about_the_knee(stride):
    """The extension moment is r × F about the knee axis (sign: the GRF in front of the knee,
    pointing up, extends it), and the minimum is over the loaded stance's interval means."""
    from bladelab.predict.collocation import build_collocation_model

    sol, runner, res = stride
    cm = build_collocation_model(runner)
    kin = predicted._kinematics(runner, sol.nlp.q, sol.nlp.qd)
    pros = kin["prosthetic"]
    moments, loads = [], []
    for k in range(sol.nlp.q.shape[0]):
        f, p, _ = (np.asarray(x) for x in cm.contacts(sol.nlp.q[k], sol.nlp.qd[k]))
        r = p[pros] - kin["knee"][k]
        moments.append(float(np.sum(r[:, 0] * f[pros, 1] - r[:, 1] * f[pros, 0])))
        loads.append(float(f[pros, 1].sum()))
    moments, loads = np.array(moments), np.array(loads)
    # the minimum over the loaded intervals' means (the interval's two nodes averaged)
    means, mean_loads = 0.5 * (moments[:-1] + moments[1:]), 0.5 * (loads[:-1] + loads[1:])
    peak = predicted._fine(loads)[predicted._stance(predicted._fine(loads) > 20.0)].max()
    want = means[mean_loads > 0.05 * peak].min()
    assert res["knee_moment_min_Nm"] == pytest.approx(want, rel=1e-9)
    assert res["knee_moment_min_Nm"] >= moments[loads > 0.05 * loads.max()].min()
    # moving the whole stride 1 m forward changes nothing (moments are relative)
    q = sol.nlp.q.copy()
    q[:, runner.dof("pelvis_tx")] += 1.0
    moved = dataclasses.replace(sol, nlp=dataclasses.replace(sol.nlp, q=q))
    again = stride_responses(moved, runner)
    assert again["knee_moment_min_Nm"] == pytest.approx(res["knee_moment_min_Nm"], abs=1e-6)
    assert again["swing_clearance_m"] == pytest.approx(res["swing_clearance_m"], abs=1e-9)


def test_only_a_converged_amputee_stride_is_read(stride):
    sol, runner, _ = stride
    failed = dataclasses.replace(sol, nlp=dataclasses.replace(sol.nlp, success=False))
    with pytest.raises(SpecError, match="did not converge"):
        stride_responses(failed, runner)
    able = dataclasses.replace(sol, leg_names=("left", "right"))
    with pytest.raises(SpecError, match="no prosthesis"):
        stride_responses(able, runner)


def test_the_report_names_the_transfemoral_runner(stride):
    from bladelab.report.collocation import _label

    sol, _, _ = stride
    assert _label(sol) == "transfemoral amputee Cat4 4 m/s (collocation)"
