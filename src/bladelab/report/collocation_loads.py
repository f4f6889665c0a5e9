"""The "Prosthesis loads" section of a collocation stride's report (amputee runners): the force
and moment the residual limb passes into the prosthesis at its socket hinge, and the moments
about the blade's joints, over the stride (:mod:`bladelab.predict.collocation.loads`)."""

from __future__ import annotations

import mujoco
import numpy as np
import pandas as pd

from bladelab.predict.collocation.human_running import stride_from_left_touchdown
from bladelab.predict.collocation.loads import PROSTHESIS_BODY, peaks_of, prosthesis_loads
from bladelab.predict.collocation.nodes import evaluate_nodes
from bladelab.runner.layout import CP_LEG

__all__ = ["add_loads_section"]


def _figure(sol, loads: dict, ground_bw: np.ndarray, weight_n: float):
    """Socket force and the blade's ground force [BW]; socket and blade-joint moments [N·m],
    over % of the stride from the intact touch-down."""
    import matplotlib.pyplot as plt

    def rolled(values):  # node values (n + 1,) or (n + 1, k), from the intact touch-down
        values = np.asarray(values)
        out = stride_from_left_touchdown(sol, values=values.reshape(values.shape[0], -1))
        return out[:, 0] if values.ndim == 1 else out

    force = rolled(np.linalg.norm(loads["socket_force"], axis=1) / weight_n)
    pct = np.linspace(0.0, 100.0, force.shape[0])
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 3.2))
    left.plot(pct, force, "o-", ms=3, label="socket force (magnitude)")
    left.plot(pct, rolled(ground_bw), "--", color="0.5", label="ground force on the prosthesis")
    left.set_xlabel("stride (% of the gait cycle, from the intact touch-down)")
    left.set_ylabel("force (body weights)")
    left.legend(fontsize=7)
    right.plot(pct, rolled(loads["socket_moment"]), "o-", ms=3, color="k", label="socket")
    blade = rolled(loads["blade_moment"])
    for j in range(blade.shape[1]):
        right.plot(pct, blade[:, j], lw=1, label=f"blade joint {j}")
    right.set_xlabel("stride (% of the gait cycle, from the intact touch-down)")
    right.set_ylabel("moment about the hinge (N·m)")
    right.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


def add_loads_section(report, sol, runner, cm) -> None:
    """Add the section for an amputee stride ``sol`` (its ``runner`` and collocation model
    ``cm``); nothing for a runner without a prosthesis."""
    if mujoco.mj_name2id(runner.mj_model, mujoco.mjtObj.mjOBJ_BODY, PROSTHESIS_BODY) < 0:
        return
    import matplotlib.pyplot as plt

    nlp = sol.nlp
    nodes = evaluate_nodes(cm, nlp.q, nlp.qd, nlp.tendon_force, nlp.tendon_force_rate)
    pros = runner.contact_params[:, CP_LEG] == 1
    loads = prosthesis_loads(runner, nlp, nodes["forces"], nodes["passive"], pros)
    peaks = peaks_of(loads)
    weight = runner.total_mass * runner.gravity
    table = pd.DataFrame([
        {"load": "socket force, peak", "value": peaks["socket_force_max_N"], "unit": "N",
         "in body weights": peaks["socket_force_max_N"] / weight},
        {"load": "socket moment, peak", "value": peaks["socket_moment_max_Nm"], "unit": "N·m",
         "in body weights": None},
        {"load": "blade joint moment, peak", "value": peaks["blade_moment_max_Nm"],
         "unit": "N·m", "in body weights": None}])
    fig = _figure(sol, loads, nodes["forces"][:, pros, 1].sum(axis=1) / weight, weight)
    report.add_section(
        "Prosthesis loads",
        text=("What the residual limb carries: the force and moment it passes into the "
              "prosthesis at the socket hinge (the transfemoral runner's: its prosthetic knee), "
              "and the moments about the blade's joints. A hinge carries only its own torque "
              "about its axis, so the moments are the hinges' springs and dampers; the force "
              "is the momentum balance of everything below the socket. Peaks over the mesh "
              "intervals' means (node values of a sliding sole ring from node to node). The "
              "model's socket is a torsional spring with no tolerance of its own: whether a "
              "residual limb bears these loads is the prosthetist's question."
              + ("" if loads["blade_moment"].size else " This blade is a rigid contact "
                 "sphere: it has no joints, and no bending moment is modelled.")),
        figures=[("The socket's force against the blade's ground force, and the moments about "
                  "the socket and the blade's joints, over the stride", fig)],
        tables=[("Peak loads", table)])
    plt.close(fig)
