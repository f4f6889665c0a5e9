"""The loads a prosthesis carries over a solved stride (``collocation.loads``), on the
transtibial runner of the human body wearing the design box's centre blade (six links): Newton
for the whole body at every node, and the socket passing on the blade's ground force and its
moment about the socket axis (MuJoCo's anchor) at the peak load."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from bladelab.design.collocation_evaluator import DEFAULT_STARTS
from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.loads import (
    PEAK_LOAD_UNITS,
    peak_loads,
    prosthesis_loads,
    subtree_com_acceleration,
)
from bladelab.predict.collocation.nodes import evaluate_nodes
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.runner.layout import CP_LEG


@pytest.fixture(scope="module")
def blade_stride():
    """The transtibial runner on the human body wearing the design box's centre blade (six
    links): the collocation evaluator's built-in start."""
    sol = CollocationSolution.read(DEFAULT_STARTS[("transtibial", "human")])
    runner = runner_from_spec(sol.model_spec)
    cm = build_collocation_model(runner)
    nodes = evaluate_nodes(cm, sol.nlp.q, sol.nlp.qd, sol.nlp.tendon_force,
                           sol.nlp.tendon_force_rate)
    peaks = peak_loads(runner, sol.nlp, nodes["forces"], nodes["passive"],
                       runner.contact_params[:, CP_LEG] == 1)
    return sol, runner, nodes, peaks


def test_the_centre_of_mass_acceleration_balances_the_ground_forces(blade_stride):
    """Newton for the whole body at every node: M·(a − g) from the stride's accelerations
    (the loads' method, applied to the root's subtree) equals the ground forces' sum."""
    sol, runner, nodes, _ = blade_stride
    acc = subtree_com_acceleration(runner, 0, sol.nlp.q, sol.nlp.qd, sol.nlp.qdd)
    newton = runner.total_mass * (acc - np.array([0.0, -runner.gravity]))
    weight = runner.total_mass * runner.gravity
    assert np.abs(newton - nodes["forces"].sum(axis=1)).max() < 1e-3 * weight


def test_the_socket_carries_the_blades_ground_force_and_its_moment(blade_stride):
    """At the prosthesis's peak load the light prosthesis (0.79 kg and the blade's links)
    passes the ground force on to the residual limb within a few per cent; around it (its five
    most loaded nodes) the ground force's moment about the socket axis (MuJoCo's anchor)
    within 15 % of the stride's largest socket moment (the rest is the prosthesis's own
    inertia, which changes sign from node to node: 5–12 N·m); the blade's joints carry moments
    of that order."""
    sol, runner, nodes, res = blade_stride
    pros = runner.contact_params[:, CP_LEG] == 1
    loads = prosthesis_loads(runner, sol.nlp, nodes["forces"], nodes["passive"], pros)
    ground = nodes["forces"][:, pros, :].sum(axis=1)
    peak = int(np.argmax(ground[:, 1]))
    assert loads["socket_force"][peak] == pytest.approx(-ground[peak], rel=0.05,
                                                        abs=0.02 * ground[peak, 1])
    m = runner.mj_model
    d = mujoco.MjData(m)
    about_socket = {}
    for k in np.argsort(-ground[:, 1])[:5]:
        d.qpos[:] = sol.nlp.q[k]
        mujoco.mj_forward(m, d)
        arm = nodes["points"][k, pros] - d.xanchor[m.joint("socket_angle_r").id, [0, 2]]
        force = nodes["forces"][k, pros]
        about_socket[k] = float((arm[:, 0] * force[:, 1] - arm[:, 1] * force[:, 0]).sum())
        assert abs(abs(loads["socket_moment"][k]) - abs(about_socket[k])) \
            <= 0.15 * res["socket_moment_max_Nm"]
    assert loads["blade_moment"].shape == (sol.nlp.q.shape[0], 5)
    assert res["socket_force_max_N"] >= 0.95 * ground[peak, 1]
    assert res["socket_moment_max_Nm"] >= 0.95 * max(abs(v) for v in about_socket.values())
    assert 0.1 * res["socket_moment_max_Nm"] < res["blade_moment_max_Nm"] < 1e4
    assert res.keys() == PEAK_LOAD_UNITS.keys()


def test_the_stride_report_shows_the_loads_it_computes(blade_stride, tmp_path):
    """An amputee stride's report has a "Prosthesis loads" section whose peaks are
    :func:`peak_loads`' own, in N, BW and N·m, with its figure."""
    from bladelab.report import Report
    from bladelab.report.collocation_loads import add_loads_section

    sol, runner, _, peaks = blade_stride
    report = Report("loads")
    add_loads_section(report, sol, runner, build_collocation_model(runner))
    (section,) = report.sections
    assert section.title == "Prosthesis loads" and len(section.figures) == 1
    table = section.tables[0].frame.set_index("load")
    assert table.loc["socket force, peak", "value"] == pytest.approx(peaks["socket_force_max_N"])
    assert table.loc["socket force, peak", "in body weights"] == pytest.approx(
        peaks["socket_force_max_N"] / (runner.total_mass * runner.gravity))
    assert table.loc["socket moment, peak", "unit"] == "N·m"
    assert table.loc["blade joint moment, peak", "value"] == pytest.approx(
        peaks["blade_moment_max_Nm"])
