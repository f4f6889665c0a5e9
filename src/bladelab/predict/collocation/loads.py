"""The loads a prosthesis carries over a solved stride: the force and moment the residual limb
passes into it at its socket hinge, and the moments about the blade's joints.

The socket hinge is the joint of the prosthesis's root body (:data:`PROSTHESIS_BODY`): the
transtibial runner's socket (``socket_angle_r``, a torsional spring on the residual tibia), the
transfemoral runner's prosthetic knee (its socket is rigid on the residual thigh, so the knee
axis is where the prosthesis's load enters it). A hinge carries only its own torque about its
axis, so the moments are the hinges' passive torques (springs, dampers, stops); the force is the
momentum balance of everything below the hinge, Σm·(a − g) minus the ground force on it, with the
subtree's centre-of-mass acceleration from the stride's own accelerations (J·q̈ + J̇·q̇; exact for
this planar tree up to a central difference along q̇, no differences in time).

:func:`prosthesis_loads` gives them per node; :func:`peak_loads` the largest magnitudes over the
stride, each over the mesh intervals' means (node values of a sliding sole ring from node to
node; the momentum balance that the solve enforces sees interval means):

==========================  =====  ===========================================================
``socket_force_max_N``      N      largest force of the residual limb on the prosthesis
``socket_moment_max_Nm``    N·m    largest moment about the socket hinge
``blade_moment_max_Nm``     N·m    largest moment about any blade joint (its bending load);
                                   NaN for a blade without joints (a category's contact sphere)
==========================  =====  ===========================================================
"""

from __future__ import annotations

import mujoco
import numpy as np

__all__ = ["PEAK_LOAD_UNITS", "PROSTHESIS_BODY", "peak_loads", "peaks_of", "prosthesis_loads",
           "subtree_com_acceleration"]

#: The root body of every runner's prosthesis (socket, pylon and blade below it).
PROSTHESIS_BODY = "prosthesis_r"

#: The keys of :func:`peak_loads` and their units.
PEAK_LOAD_UNITS = {"socket_force_max_N": "N", "socket_moment_max_Nm": "N·m",
                   "blade_moment_max_Nm": "N·m"}


def subtree_com_acceleration(runner, body: int, q, qd, qdd, eps: float = 1e-6) -> np.ndarray:
    """Per node, the (x, z) acceleration [m/s²] of the centre of mass of ``body``'s subtree:
    J(q)·q̈ + J̇(q)·q̇, the second term as a central difference of J(q)·q̇ along q̇ (every
    joint of the planar runner is a hinge or a slide, so q ± ε·q̇ is a position)."""
    m = runner.mj_model
    d = mujoco.MjData(m)

    def com_velocity(qk, vk) -> np.ndarray:
        d.qpos[:], d.qvel[:] = qk, vk
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        return d.subtree_linvel[body, [0, 2]].copy()

    return np.array([com_velocity(qk, ak) + (com_velocity(qk + eps * vk, vk)
                                             - com_velocity(qk - eps * vk, vk)) / (2 * eps)
                     for qk, vk, ak in zip(q, qd, qdd, strict=True)])


def prosthesis_loads(runner, nlp, forces: np.ndarray, passive: np.ndarray,
                     prosthetic: np.ndarray) -> dict[str, np.ndarray]:
    """Per node, the loads the prosthesis carries (module docstring): ``socket_force`` (x, z)
    on the prosthesis from the residual limb [N], ``socket_moment`` about its root hinge and
    ``blade_moment`` (n + 1, n_blade_joints) about each blade joint [N·m].

    ``forces`` (n + 1, n_contacts, 2) are the ground forces on the body, ``passive``
    (n + 1, n_dof) the passive joint torques (:func:`~bladelab.predict.collocation.nodes.
    evaluate_nodes`), ``prosthetic`` the mask of the prosthesis's contacts."""
    m = runner.mj_model
    root = m.body(PROSTHESIS_BODY).id
    hinge = m.joint(int(m.body_jntadr[root])).name
    names = list(runner.dof_names)
    blade = [i for i, n in enumerate(names) if n.startswith("blade_joint")]
    acc = subtree_com_acceleration(runner, root, nlp.q, nlp.qd, nlp.qdd)
    weight = np.array([0.0, -runner.gravity])
    ground = forces[:, prosthetic, :].sum(axis=1)
    return {"socket_force": m.body_subtreemass[root] * (acc - weight) - ground,
            "socket_moment": passive[:, names.index(hinge)],
            "blade_moment": passive[:, blade]}


def _interval_means(values: np.ndarray) -> np.ndarray:
    """The mesh intervals' means of node values (n + 1, ...) -> (n, ...)."""
    return 0.5 * (values[:-1] + values[1:])


def peaks_of(loads: dict[str, np.ndarray]) -> dict[str, float]:
    """The largest loads over the stride (module docstring; units in :data:`PEAK_LOAD_UNITS`)
    of :func:`prosthesis_loads`' per-node loads."""
    blade = np.abs(_interval_means(loads["blade_moment"]))
    return {
        "socket_force_max_N": float(
            np.linalg.norm(_interval_means(loads["socket_force"]), axis=1).max()),
        "socket_moment_max_Nm": float(np.abs(_interval_means(loads["socket_moment"])).max()),
        "blade_moment_max_Nm": float(blade.max()) if blade.size else float("nan"),
    }


def peak_loads(runner, nlp, forces: np.ndarray, passive: np.ndarray,
               prosthetic: np.ndarray) -> dict[str, float]:
    """:func:`peaks_of` the :func:`prosthesis_loads` of these arguments."""
    return peaks_of(prosthesis_loads(runner, nlp, forces, passive, prosthetic))
