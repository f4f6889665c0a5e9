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

The loads are :func:`~bladelab.predict.collocation.loads.peak_loads`' (that module: where
they are taken and how).

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
from bladelab.predict.collocation.loads import peak_loads
from bladelab.predict.collocation.nodes import evaluate_nodes, on_fine_grid, periodic_runs
from bladelab.runner.layout import CP_LEG

__all__ = ["stride_responses"]

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
    loads = peak_loads(runner, nlp, ev["forces"], ev["passive"], pros)
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
        **loads,
    }
