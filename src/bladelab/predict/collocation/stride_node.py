"""One mesh node of the stride NLP: its variables' scales and bounds, its SX function and the
names of its rows.

At a node the NLP holds the states x = (q, q̇, a, F̃ₜ) — coordinates [m, rad], speeds, muscle
activations [-], tendon forces normalised by F_max [-] — and the controls u = (q̈, e, dF̃ₜ/dt),
each divided by its scale (:func:`node_scales`) so that IPOPT sees numbers of order one, and
bounded (:func:`node_bounds`; the NLP frees pelvis_tx).
:func:`node_function` is what every node evaluates (mapped over the mesh by
:class:`~bladelab.predict.collocation.transcription.StrideNLP`, or compiled to C by
:mod:`~bladelab.predict.collocation.compiled`): the scaled state derivative, the path
residuals and the integrands of the objective's terms.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from bladelab.errors import SpecError
from bladelab.predict.collocation.stride_problem import (
    FORCE_RATE_SCALE,
    METABOLIC_SQUARED_SCALE,
    PASSIVE_TORQUE_SCALE,
    StrideDynamics,
    StrideWeights,
    VariableScales,
)

__all__ = ["control_names", "leg_forces_function", "node_bounds", "node_function",
           "node_scales", "path_names", "state_names"]


def node_scales(dynamics: StrideDynamics,
                scales: VariableScales) -> tuple[np.ndarray, np.ndarray]:
    """The scales (sx, su) of a node's states and controls: a scaled variable is the variable
    divided by its scale (activations, excitations and normalised tendon forces 1)."""
    nq, nm = dynamics.nq, dynamics.nm
    sx = np.concatenate([np.full(nq, scales.q), np.full(nq, scales.qd), np.ones(nm),
                         np.ones(nm)])
    su = np.concatenate([np.full(nq, scales.qdd), np.ones(nm),
                         np.full(nm, scales.tendon_force_rate)])
    return sx, su


def node_bounds(dynamics: StrideDynamics, min_activation: float, min_tendon_force: float,
                max_tendon_force: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The bounds (lx, ux, lu, uu) of a node's states and controls, unscaled: the model's
    coordinate and speed bounds, activations and excitations within [``min_activation``, 1],
    normalised tendon forces within [``min_tendon_force``, ``max_tendon_force`` × the muscle's
    active strength], accelerations within ±1e4 [m/s², rad/s²] and tendon-force rates within
    ±1e3 [1/s]."""
    d = dynamics
    nq, nm = d.nq, d.nm
    lx = np.concatenate([d.q_bounds[:, 0], d.qd_bounds[:, 0], np.full(nm, min_activation),
                         np.full(nm, min_tendon_force)])
    strength = np.ones(nm) if d.active_strength is None else d.active_strength
    ux = np.concatenate([d.q_bounds[:, 1], d.qd_bounds[:, 1], np.ones(nm),
                         max_tendon_force * strength])
    qdd_max = 1e4
    lu = np.concatenate([np.full(nq, -qdd_max), np.full(nm, min_activation), np.full(nm, -1e3)])
    uu = np.concatenate([np.full(nq, qdd_max), np.ones(nm), np.full(nm, 1e3)])
    return lx, ux, lu, uu


def node_function(dynamics: StrideDynamics, weights: StrideWeights, sx: np.ndarray,
                  su: np.ndarray) -> ca.Function:
    """The SX function of one mesh node, ``(x, u) -> (ẋ scaled, path residuals, effort,
    metabolic rate [W], inequalities, vertical force [N], squared metabolic rate, force rate,
    passive torque)`` of the scaled states and controls (scales ``sx``, ``su``); the last three
    are 0 unless ``weights`` asks for their terms."""
    d = dynamics
    nq, nm = d.nq, d.nm
    xs = ca.SX.sym("x", 2 * nq + 2 * nm)
    us = ca.SX.sym("u", nq + 2 * nm)
    x, u = xs * sx, us * su
    q, qd = x[:nq], x[nq:2 * nq]
    a, fnt = x[2 * nq:2 * nq + nm], x[2 * nq + nm:]
    qdd, e, dfnt = u[:nq], u[nq:nq + nm], u[nq + nm:]
    r_mb, r_hill = d.residuals(q, qd, qdd, a, fnt, dfnt)
    adot = d.activation_rate(e, a)
    xdot_scaled = ca.vertcat(qd, qdd, adot, dfnt) / sx
    path = ca.vertcat(r_mb / d.residual_scale, r_hill)
    w = weights
    pelvis_scale = np.array([10.0 if n_ in ("pelvis_tx", "pelvis_tz") else 100.0
                             for n_ in d.dof_names[:3]])
    effort = (w.activation * ca.sum1(a**3) / max(nm, 1)
              + w.acceleration * ca.sumsqr(qdd[3:]) / max(nq - 3, 1) / 1e4
              + w.pelvis_acceleration * ca.sumsqr(qdd[:3] / pelvis_scale) / 3)
    met = d.metabolic_rate(q, qd, a, fnt, dfnt, e)
    ineq = (d.inequalities(q, qd, a, fnt, dfnt) if d.inequalities is not None
            else ca.SX.zeros(0, 1))
    fz = d.vertical_grf(q, qd) if d.vertical_grf is not None else ca.SX(0.0)
    if w.metabolic_squared:
        if d.muscle_metabolic_rates is None:
            raise SpecError("metabolic_squared needs the muscles' metabolic rates",
                            where="weights", hint="build the dynamics with stride_dynamics")
        per_kg = d.muscle_metabolic_rates(q, qd, a, fnt, dfnt, e) / d.mass
        met_sq = ca.sumsqr(per_kg) / METABOLIC_SQUARED_SCALE
    else:
        met_sq = ca.SX(0.0)
    frate = ca.sumsqr(dfnt) / max(nm, 1) / FORCE_RATE_SCALE
    if w.passive:
        if d.passive_joint_torques is None:
            raise SpecError("the passive-torque term needs the joints' passive torques",
                            where="weights", hint="build the dynamics with stride_dynamics")
        tau_p = d.passive_joint_torques(q, qd)
        passive = ca.sumsqr(tau_p) / max(int(tau_p.numel()), 1) / PASSIVE_TORQUE_SCALE
    else:
        passive = ca.SX(0.0)
    return ca.Function("node", [xs, us],
                       [xdot_scaled, path, effort, met, ineq, fz, met_sq, frate, passive])


def leg_forces_function(dynamics: StrideDynamics, sx: np.ndarray) -> ca.Function:
    """``x -> the vertical ground force of each leg (2,) [N]`` of a node's scaled states
    (scales ``sx``; ``StrideDynamics.leg_vertical_grf``)."""
    nq = dynamics.nq
    xs = ca.SX.sym("x", sx.size)
    x = xs * sx
    q, qd = x[:nq], x[nq:2 * nq]
    return ca.Function("legs", [xs], [dynamics.leg_vertical_grf(q, qd)])


def state_names(dynamics: StrideDynamics) -> list[str]:
    """Names of a node's states, in order (``q <dof>``, ``qd <dof>``, ``a <muscle>``,
    ``Ft <muscle>``)."""
    d = dynamics
    return ([f"q {n}" for n in d.dof_names] + [f"qd {n}" for n in d.dof_names]
            + [f"a {n}" for n in d.muscle_names] + [f"Ft {n}" for n in d.muscle_names])


def control_names(dynamics: StrideDynamics) -> list[str]:
    """Names of a node's controls, in order (``qdd <dof>``, ``e <muscle>``,
    ``dFt <muscle>``)."""
    d = dynamics
    return ([f"qdd {n}" for n in d.dof_names] + [f"e {n}" for n in d.muscle_names]
            + [f"dFt {n}" for n in d.muscle_names])


def path_names(dynamics: StrideDynamics) -> list[str]:
    """Names of a node's path residuals, in order (``dynamics <dof>``, ``hill <muscle>``)."""
    d = dynamics
    return [f"dynamics {n}" for n in d.dof_names] + [f"hill {n}" for n in d.muscle_names]
