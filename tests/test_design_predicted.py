"""Seed 002's responses from a predicted transfemoral stride.

The fixture ``tests/data/transfemoral-4mps.json`` is a converged collocation stride of the
transfemoral runner at 4 m/s (mesh 50, from the template guess; dynamics residual
1.4 %). Its intact foot strikes the ground during the prosthetic stance, so the test of the
impulses adds the intact leg's over the same window."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from bladelab.design import predicted
from bladelab.design.predicted import stride_responses
from bladelab.design.responses import PREDICTED_RESPONSE_UNITS
from bladelab.errors import SpecError
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec

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
