"""Ground contact and passive joint torques as smooth CasADi (SX) expressions.

Same geometry and parameters as the forward kernel (:func:`bladelab.runner.kernel.forces`),
read from ``RunnerModel.contact_params`` and ``RunnerModel.joint_params``:

- **Contact point**: the lowest point of the sphere (or of the ellipse with semi-axes a_x, a_z
  in the site's x–z plane), depth ``δ = h − z_site``; its velocity is that of the body's
  material point there.
- **Hunt–Crossley** (law 0): forward ``k·δⁿ·max(1 + 1.5·c·δ̇, 0)`` for δ > 0; here
  ``k·δ_sⁿ·x_s`` with ``δ_s = smooth_max0(δ, ε_d)`` and ``x_s = smooth_max0(1 + 1.5·c·δ̇, ε_x)``.
- **Spring–damper** (law 1, multi-link blade soles): forward ``smoothstep(δ/w)·max(kδ + cδ̇, 0)``;
  here ``smoothstep(δ/w)·smooth_max0(k·δ + c·δ̇, ε_F)``, the same C¹ cubic onset (over ε'
  where the forward onset is sharp, w = 0).
- **Friction**: forward an elastic–plastic bristle with a state, ``−μ·Fn`` while sliding;
  here ``−μ·Fn·tanh(v_x/v_t)`` (no state). The two agree while sliding; while the forward
  bristle sticks, its force is any value within ±μ·Fn that the anchor's state gives.
- **Ligaments**: forward ``−max(K·(q − hi) + D·q̇, 0)`` above the upper limit and
  ``max(K·(lo − q) − D·q̇, 0)`` below the lower one; here the excursion is a softplus, the
  damping is gated by its derivative (a sigmoid) and the outer max is :func:`smooth_max0`.
- **Socket and blade joints**: ``−(K·q + K2·q·|q|) − D·q̇`` with ``|q| ≈ √(q² + ε²)``.
- **Capsule** (e.g. the hip's, within the range): ``A·exp(B·q)``, smooth as it is.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from bladelab.predict.collocation.multibody import Frame, point_force, point_velocity, rotate
from bladelab.predict.collocation.planar import PlanarTree
from bladelab.predict.collocation.smooth import Smoothing, sigmoid, smooth_max0, softplus
from bladelab.runner.layout import (
    CP_AZ,
    CP_C,
    CP_DAMP,
    CP_EXP,
    CP_K,
    CP_LAW,
    CP_MU,
    CP_RADIUS,
    CP_SITE,
    CP_WIDTH,
    JP_D,
    JP_EA,
    JP_EB,
    JP_HI,
    JP_K,
    JP_LO,
    JP_SD,
    JP_SDX,
    JP_SK,
    JP_SK2,
    LAW_HUNT_CROSSLEY,
)


def contact_point(tree: PlanarTree, frames: list[Frame], row: np.ndarray):
    """Lowest point (x, z) [m] of one contact's sphere or ellipse, its depth [m] (positive when
    penetrating) and its body."""
    site = int(row[CP_SITE])
    body = int(tree.site_body[site])
    x, z, th = frames[body]
    sx, sz = rotate(th, *tree.site_pos[site])
    sx, sz = x + sx, z + sz
    phi = th + float(tree.site_pitch[site])
    exx, exz = ca.cos(phi), -ca.sin(phi)  # site x axis in the lab
    ezx, ezz = ca.sin(phi), ca.cos(phi)  # site z axis
    ax, az = float(row[CP_RADIUS]), float(row[CP_AZ])
    h = ca.sqrt((ax * exz) ** 2 + (az * ezz) ** 2)
    px = sx - (ax * ax * exz * exx + az * az * ezz * ezx) / h
    return ca.vertcat(px, sz - h), h - sz, body


def normal_force(depth, depth_rate, row: np.ndarray, smoothing: Smoothing):
    """Smooth normal force [N] of one contact row at penetration ``depth`` [m] and its rate
    ``depth_rate`` [m/s] (positive while penetrating further)."""
    k, c = float(row[CP_K]), float(row[CP_C])
    if int(row[CP_LAW]) == LAW_HUNT_CROSSLEY:
        d = smooth_max0(depth, smoothing.contact_depth_m)
        x = smooth_max0(1.0 + 1.5 * c * depth_rate, smoothing.contact_damping)
        return k * d ** float(row[CP_EXP]) * x
    # the forward law's own cubic onset smoothstep(δ/w), C¹ and 0 for δ ≤ 0, so that the two
    # agree from first touch (a tanh gate, used until 2026-11-26, gave 40-60 % of the forward
    # force at a touching-down sole's first node: dynamics residuals of 19-48 %); a sharp
    # forward onset (w = 0) gets the cubic over ε'
    width = float(row[CP_WIDTH]) if row[CP_WIDTH] > 0 else smoothing.spring_damper_depth_m
    x = depth / width
    gate = ca.if_else(x <= 0.0, 0.0, ca.if_else(x >= 1.0, 1.0, x * x * (3.0 - 2.0 * x)))
    force = k * depth + float(row[CP_DAMP]) * depth_rate
    return gate * smooth_max0(force, smoothing.contact_force_n)


def contact_kinematics(tree: PlanarTree, frames: list[Frame], q: ca.SX, qd: ca.SX,
                       contact_params: np.ndarray):
    """Per contact row: (lowest point (x, z) [m], depth [m] (positive when penetrating), body,
    velocity (x, z) [m/s] of the body's material point there)."""
    for row in contact_params:
        p, depth, body = contact_point(tree, frames, row)
        yield p, depth, body, point_velocity(frames, q, qd, body, p)


def contact_forces(
    tree: PlanarTree,
    frames: list[Frame],
    q: ca.SX,
    qd: ca.SX,
    contact_params: np.ndarray,
    smoothing: Smoothing,
) -> tuple[ca.SX, ca.SX, ca.SX]:
    """Ground forces of every contact.

    Returns
    -------
    forces
        (n_contacts, 2): friction Fx and normal Fz [N] on the body.
    points
        (n_contacts, 2): lab (x, z) of the contact points [m].
    generalised
        (nv,) generalised force of all contacts [N or N·m].
    """
    forces, points = [], []
    gen = ca.SX.zeros(tree.nv)
    for row, (p, depth, body, v) in zip(
            contact_params, contact_kinematics(tree, frames, q, qd, contact_params), strict=True):
        fn = normal_force(depth, -v[1], row, smoothing)
        ft = -float(row[CP_MU]) * fn * ca.tanh(v[0] / smoothing.friction_velocity_mps)
        f = ca.vertcat(ft, fn)
        gen += point_force(frames, q, body, p, f)
        forces.append(f.T)
        points.append(p.T)
    return ca.vertcat(*forces), ca.vertcat(*points), gen


def passive_torques(q: ca.SX, qd: ca.SX, joint_params: np.ndarray, smoothing: Smoothing,
                    *, limits_only: bool = False) -> ca.SX:
    """Smooth ligament, socket (blade-joint) and capsule torques (nv,) [N·m] at (q [rad],
    qd [rad/s]); ``limits_only``: the ligaments' and the capsule's alone (the joints' limits),
    without the joint springs and dampers."""
    eps_t = smoothing.ligament_torque_nm
    eps_s = smoothing.socket_angle_rad
    out = []
    for j, row in enumerate(joint_params):
        tau = 0.0
        k, d = float(row[JP_K]), float(row[JP_D])
        w = smoothing.ligament_width(k)
        if k != 0.0 or d != 0.0:
            if math.isfinite(row[JP_HI]):
                e = q[j] - float(row[JP_HI])
                tau -= smooth_max0(k * softplus(e, w) + d * qd[j] * sigmoid(e, w), eps_t)
            if math.isfinite(row[JP_LO]):
                e = float(row[JP_LO]) - q[j]
                tau += smooth_max0(k * softplus(e, w) - d * qd[j] * sigmoid(e, w), eps_t)
        if not limits_only and (row[JP_SK] != 0.0 or row[JP_SD] != 0.0 or row[JP_SDX] != 0.0):
            absq = ca.sqrt(q[j] * q[j] + eps_s * eps_s)
            tau -= float(row[JP_SK]) * q[j] + float(row[JP_SK2]) * q[j] * absq
            d_neg, d_pos = float(row[JP_SD]), float(row[JP_SDX])
            if d_neg == d_pos:
                tau -= d_neg * qd[j]
            else:  # a hydraulic knee: one damping flexing, another extending
                gate = sigmoid(qd[j], smoothing.damping_switch_rad_s)
                tau -= (d_neg + (d_pos - d_neg) * gate) * qd[j]
        if row[JP_EA] != 0.0:  # the capsule's passive moment within the range (smooth as is)
            tau += float(row[JP_EA]) * ca.exp(float(row[JP_EB]) * q[j])
        out.append(tau)
    return ca.vertcat(*out)
