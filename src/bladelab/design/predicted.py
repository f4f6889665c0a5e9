"""Seed 002's responses from a predicted stride: a collocation solution of an
amputee runner (the transfemoral one, whose knee can buckle) read as seed 002 reads its
inverse-dynamics runs.

:func:`stride_responses` takes a converged :class:`~bladelab.predict.collocation.solution.
CollocationSolution` of the periodic stride and returns (name, unit):

==================================  =========  ==============================================
``delta_vx_m_per_s``                m/s        Δv_x = I_x/m over the prosthetic stance
``avg_vx_m_per_s``                  m/s        the stride's mean speed (prescribed or found)
``impulse_x_Ns``                    N·s        ∫F_x dt of the prosthetic leg over its stance
``impulse_z_Ns``                    N·s        ∫F_z dt over that stance (gross)
``impulse_z_net_Ns``                N·s        ∫(F_z − m·g) dt
``evaluation_E_m``                  m          bouncing-ball parameter I_x·I_z,net/(m²·g)
``knee_moment_min_Nm``              N·m        minimum extension moment of the prosthetic
                                               leg's GRF about the knee axis over the loaded
                                               stance's mesh intervals (their means)
``swing_clearance_m``               m          lowest point of the prosthesis's contacts over
                                               the middle half of its swing
``contact_time_prosthetic_s``       s          the stance's duration
``cost_of_transport_J_per_kg_m``    J/(kg·m)   the solution's metabolic cost of transport
``stride_objective``                -          the optimum's value: the stride's objective
                                               (energy, effort, accelerations and people's
                                               angles, weighted; the settings' terms)
``socket_force_max_N``              N          largest force the residual limb carries into
                                               the prosthesis at its socket hinge
``socket_moment_max_Nm``            N·m        largest moment about that hinge
``blade_moment_max_Nm``             N·m        largest moment about any of the blade's
                                               joints (its bending load); NaN for a blade
                                               without joints (a category's contact sphere)
==================================  =========  ==============================================

The stride objective is the value the solver minimised, and so, of a design's local optima, the
response that the start moves least; every other response is a feature of the optimal stride
(its argmin), which near-equal optima can share out differently: two strides of one blade 0.1 %
apart in objective can differ by 1.5 % in cost of transport (docs/design.md, "What the start
decides").

The loads are those the model transmits, over the whole stride, each a largest magnitude over
the mesh intervals' means (node values ring, as for the knee moment below). The socket hinge is
the joint of the prosthesis's root body (``prosthesis_r``): the transtibial runner's socket
(``socket_angle_r``, a torsional spring on the residual tibia), the transfemoral runner's
prosthetic knee (its socket is rigid on the residual thigh, so the knee axis is where the
prosthesis's load enters it). A hinge carries only its own torque about its axis, so the moments
are the hinges' passive torques (springs, dampers, stops); the force is the momentum balance of
everything below the hinge, Σm·(a − g) minus the ground force on it, with the subtree's centre
of mass acceleration from the stride's own accelerations (exact for this planar tree, no finite
differences in time).

The stance is the longest loaded stretch (vertical force above 20 N, the analyses' threshold)
of the prosthetic leg's periodic force, the node values interpolated linearly on a grid 20
times finer (the solution's own contact times use the same rule on a grid 50 times finer:
they agree within two steps of this grid, tested); integrals are trapezoidal on that grid.
The contacts' lowest points, for the swing clearance, are the collocation model's.
The knee moment is summed per node over the prosthetic contacts (r × F about MuJoCo's knee
axis) and its minimum taken over the mesh intervals' means (the mean of each interval's two
nodes, as the collocation constraint ``CollocationSettings.knee_moment_min_nm`` sees it) of
the loaded intervals (mean vertical force above 5 % of its peak, seed 002's knee-buckling
check, :func:`~bladelab.design.constraints.knee_buckling`). Node values alternate: a sliding
blade sole rings by ±1 mm from node to node (the trapezoidal rule's period-2 mode), its
friction saturating at ±μ·F_n, and the moment swings by ±20–60 N·m about a mean that the
momentum balance, which integrates interval means, sees (measured on the design's centre
stride, 2026-11-26); until then the minimum over the nodes, interpolated, was reported and
was that ringing's trough. Until 2026-11-26 a centre of pressure was interpolated instead,
which was 0 (the lab origin) at the unloaded node before touch-down and gave spurious minima
of −150 to −300 N·m in the interval of touch-down.
"""

from __future__ import annotations

import mujoco
import numpy as np

from bladelab.design.performance import bouncing_ball
from bladelab.errors import SpecError
from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.nodes import evaluate_nodes, on_fine_grid, periodic_runs
from bladelab.runner.layout import CP_LEG

__all__ = ["prosthesis_loads", "stride_responses"]

_FINE = 20  # interpolation points per mesh interval
_LOADED_N = 20.0  # N
_KNEE_LOADED = 0.05  # of the peak vertical force


def _kinematics(runner, q: np.ndarray, qd: np.ndarray) -> dict[str, np.ndarray]:
    """Per node: the centre of mass and its velocity (x, z) and the prosthetic knee axis (x, z)
    [m, m/s]; and which contacts are the prosthesis's."""
    m = runner.mj_model
    d = mujoco.MjData(m)
    knee = m.joint("knee_angle_r").id if "knee_angle_r" in runner.dof_names else None
    out = {k: [] for k in ("com", "com_velocity", "knee")}
    for qk, vk in zip(q, qd, strict=True):
        d.qpos[:], d.qvel[:] = qk, vk
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        out["com"].append(d.subtree_com[0, [0, 2]].copy())
        out["com_velocity"].append(d.subtree_linvel[0, [0, 2]].copy())
        out["knee"].append(d.xanchor[knee, [0, 2]].copy() if knee is not None else (np.nan,) * 2)
    res = {k: np.asarray(v) for k, v in out.items()}
    res["prosthetic"] = runner.contact_params[:, CP_LEG] == 1
    return res


def _subtree_com_acceleration(runner, body: int, q, qd, qdd, eps: float = 1e-6) -> np.ndarray:
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
    root = m.body("prosthesis_r").id
    hinge = m.joint(int(m.body_jntadr[root])).name
    names = list(runner.dof_names)
    blade = [i for i, n in enumerate(names) if n.startswith("blade_joint")]
    acc = _subtree_com_acceleration(runner, root, nlp.q, nlp.qd, nlp.qdd)
    weight = np.array([0.0, -runner.gravity])
    ground = forces[:, prosthetic, :].sum(axis=1)
    return {"socket_force": m.body_subtreemass[root] * (acc - weight) - ground,
            "socket_moment": passive[:, names.index(hinge)],
            "blade_moment": passive[:, blade]}


def _interval_means(values: np.ndarray) -> np.ndarray:
    """The mesh intervals' means of node values (n + 1, ...) -> (n, ...)."""
    return 0.5 * (values[:-1] + values[1:])


def _fine(values: np.ndarray) -> np.ndarray:
    """Node values (n + 1, ...) of the periodic stride on the fine grid (n·_FINE, ...)."""
    return on_fine_grid(values, _FINE)


def _stance(loaded: np.ndarray) -> np.ndarray:
    """Indices, in order, of the longest True stretch of a periodic mask (may wrap)."""
    if loaded.all() or not loaded.any():
        raise SpecError("the prosthetic leg is loaded throughout or never: no stance to read",
                        where="solution")
    start, length = max(periodic_runs(loaded), key=lambda run: run[1])  # the first longest
    return (start + np.arange(length)) % loaded.size


def stride_responses(solution, runner, *, cm=None) -> dict[str, float]:
    """Seed 002's responses of a predicted stride (module docstring; values in
    :data:`~bladelab.design.responses.PREDICTED_RESPONSE_UNITS`).

    Parameters
    ----------
    solution
        A converged :class:`~bladelab.predict.collocation.solution.CollocationSolution` of an
        amputee runner.
    runner
        Its runner (:func:`~bladelab.predict.collocation.stored.runner_from_spec`).
    cm
        Its collocation model (built if not given): the contact points.

    Raises
    ------
    SpecError
        The solution did not converge, is of the able model, or has no prosthetic stance.
    """
    if not solution.converged:
        raise SpecError("the solve did not converge: its last iterate is not a stride",
                        where="solution", hint="solve again (--resume) or from another guess")
    if solution.leg_names[1] != "prosthetic":
        raise SpecError(f"a {solution.kind} model has no prosthesis", where="solution",
                        hint="responses are for an amputee runner")
    nlp = solution.nlp
    cm = cm or build_collocation_model(runner)
    kin = _kinematics(runner, nlp.q, nlp.qd)
    ev = evaluate_nodes(cm, nlp.q, nlp.qd, nlp.tendon_force, nlp.tendon_force_rate)
    pros = kin["prosthetic"]
    f = ev["forces"][:, pros, :]  # (n + 1, k, 2): Fx, Fz on the body
    fx, fz = f[:, :, 0].sum(axis=1), f[:, :, 1].sum(axis=1)
    # per node, Σ r × F about the knee axis over the prosthetic contacts (0 in swing), then
    # interpolated: interpolating a centre of pressure instead would put it at the lab origin
    # where the stance begins (no force, no centre of pressure) and invent flexing moments
    arm = ev["points"][:, pros, :] - kin["knee"][:, None, :]
    knee_moment = (arm[:, :, 0] * f[:, :, 1] - arm[:, :, 1] * f[:, :, 0]).sum(axis=1)
    n = nlp.q.shape[0] - 1
    dt = solution.period_s / (n * _FINE)
    fx_f, fz_f = _fine(fx), _fine(fz)
    idx = _stance(fz_f > _LOADED_N)
    mass, g = runner.total_mass, runner.gravity

    def integral(y: np.ndarray) -> float:  # over the stance, trapezoidal, one grid step apart
        v = y[idx]
        return float(dt * (v.sum() - 0.5 * (v[0] + v[-1])))

    i_x, i_z = integral(fx_f), integral(fz_f)
    i_z_net = integral(fz_f - mass * g)
    _, dvx, e = bouncing_ball(i_x, i_z_net, mass, g=g)
    mean_moment = 0.5 * (knee_moment[:-1] + knee_moment[1:])  # per mesh interval
    mean_fz = 0.5 * (fz[:-1] + fz[1:])
    loaded = mean_fz > _KNEE_LOADED * fz_f[idx].max()
    # swing: from the stance's end round to its start; its middle half
    n_fine = fz_f.size
    swing = (idx[-1] + 1 + np.arange(n_fine - idx.size)) % n_fine
    mid = swing[len(swing) // 4: len(swing) - len(swing) // 4]
    heights = _fine(ev["points"][:, pros, 1]).min(axis=1)  # the contacts' lowest points
    loads = prosthesis_loads(runner, nlp, ev["forces"], ev["passive"], pros)
    return {
        "delta_vx_m_per_s": dvx,
        "avg_vx_m_per_s": solution.mean_speed_mps,
        "impulse_x_Ns": i_x,
        "impulse_z_Ns": i_z,
        "impulse_z_net_Ns": i_z_net,
        "evaluation_E_m": e,
        "knee_moment_min_Nm": float(mean_moment[loaded].min()),
        "swing_clearance_m": float(heights[mid].min()),
        "contact_time_prosthetic_s": float(idx.size * dt),
        "cost_of_transport_J_per_kg_m": solution.cost_of_transport_J_per_kg_m,
        "stride_objective": float(nlp.objective),
        "socket_force_max_N": float(
            np.linalg.norm(_interval_means(loads["socket_force"]), axis=1).max()),
        "socket_moment_max_Nm": float(np.abs(_interval_means(loads["socket_moment"])).max()),
        "blade_moment_max_Nm": (float(np.abs(_interval_means(loads["blade_moment"])).max())
                                if loads["blade_moment"].size else float("nan")),
    }
