"""Planar multibody kinematics and inverse dynamics as CasADi (SX) expressions.

Built from a :class:`~bladelab.predict.collocation.planar.PlanarTree` (read from the forward
model's ``MjModel``): body frames follow MuJoCo's own composition (parent frame, body offset and
rotation, then each joint in order: a slide moves the frame along its axis, a hinge turns it
about its anchor), so positions equal MuJoCo's ``xpos``/``site_xpos`` to round-off.

Inverse dynamics by d'Alembert's principle (virtual work): with ``r_b(q)`` the centre of mass
and ``θ_b(q)`` the pitch of body b,

    τ = Σ_b J_b(q)ᵀ·m_b·(r̈_b − g) + (∂θ_b/∂q)ᵀ·I_b·θ̈_b + armature·q̈ + damping·q̇ + k·(q − q_ref),

where ``r̈_b = J_b·q̈ + J̇_b·q̇`` comes from CasADi's exact directional derivatives. In planar
motion the gyroscopic term ω×Iω has no component about y, so this is M(q)·q̈ + C(q, q̇) + G(q)
exactly; it equals MuJoCo's ``mj_inverse`` (``qfrc_inverse``, which adds armature and subtracts
the passive damping and spring forces) for a model without constraints.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from bladelab.predict.collocation.planar import HINGE, PlanarTree

Frame = tuple[object, object, object]  # (x [m], z [m], θ [rad]) as SX or float


def rotate(theta, x, z) -> tuple[object, object]:
    """Lab (x, z) of a body-frame vector (x, z) in a frame pitched by ``theta`` about +y."""
    c, s = ca.cos(theta), ca.sin(theta)
    return c * x + s * z, -s * x + c * z


def body_frames(tree: PlanarTree, q: ca.SX) -> list[Frame]:
    """Origin (x, z) [m] and pitch θ [rad] of every body frame (body 0, the world, is zero).

    Parameters
    ----------
    tree
        The planar model.
    q
        Generalised coordinates (nv,) [m or rad].
    """
    frames: list[Frame] = [(0.0, 0.0, 0.0)]
    for b in range(1, tree.nbody):
        px, pz, pth = frames[int(tree.parent[b])]
        dx, dz = rotate(pth, *tree.pos[b])
        x, z, th = px + dx, pz + dz, pth + float(tree.pitch[b])
        for j in tree.joints[b]:
            dq = q[j.dof] - j.qpos0
            if j.kind == HINGE:
                ax, az = rotate(th, *j.anchor)
                th = th + j.axis[0] * dq
                rx, rz = rotate(th, *j.anchor)
                x, z = x + ax - rx, z + az - rz
            else:
                ux, uz = rotate(th, *j.axis)
                x, z = x + ux * dq, z + uz * dq
        frames.append((x, z, th))
    return frames


def point_position(frames: list[Frame], body: int, local) -> ca.SX:
    """Lab (x, z) [m] of the point with body-frame coordinates ``local`` (x, z) [m]."""
    x, z, th = frames[body]
    dx, dz = rotate(th, local[0], local[1])
    return ca.vertcat(x + dx, z + dz)


def point_velocity(frames: list[Frame], q: ca.SX, qd: ca.SX, body: int, point) -> ca.SX:
    """Lab velocity (x, z) [m/s] of the material point of ``body`` at lab point ``point``."""
    x, z, th = frames[body]
    vo = ca.jtimes(ca.vertcat(x, z), q, qd)
    w = ca.jtimes(ca.SX(th), q, qd)
    return vo + w * ca.vertcat(point[1] - z, -(point[0] - x))


def point_force(frames: list[Frame], q: ca.SX, body: int, point, force) -> ca.SX:
    """Generalised force (nv,) [N or N·m] of a force ``force`` (x, z) [N] acting on ``body``
    at lab point ``point`` (x, z) [m]: ``J_pᵀ·f`` with J_p the Jacobian of the material point
    there (the point is not differentiated: a contact point that slides over the body gets the
    same generalised force as MuJoCo's ``mj_applyFT``)."""
    x, z, th = frames[body]
    moment = (point[1] - z) * force[0] - (point[0] - x) * force[1]
    return ca.jtimes(ca.vertcat(x, z), q, force, True) + ca.jtimes(ca.SX(th), q, moment, True)


def inverse_dynamics(tree: PlanarTree, q: ca.SX, qd: ca.SX, qdd: ca.SX) -> ca.SX:
    """Generalised forces τ (nv,) [N or N·m] that produce accelerations ``qdd`` at (q, qd).

    Parameters
    ----------
    tree
        The planar model.
    q, qd, qdd
        Coordinates [m, rad], velocities [m/s, rad/s], accelerations [m/s², rad/s²] (nv,).
    """
    frames = body_frames(tree, q)
    g = ca.DM(tree.gravity)
    tau = ca.SX.zeros(tree.nv)
    for b in range(1, tree.nbody):
        m, inertia = float(tree.mass[b]), float(tree.inertia[b])
        th = ca.SX(frames[b][2])
        if m > 0.0:
            r = point_position(frames, b, tree.com[b])
            v = ca.jtimes(r, q, qd)
            a = ca.jtimes(v, q, qd) + ca.jtimes(r, q, qdd)
            tau += ca.jtimes(r, q, m * (a - g), True)
        if inertia > 0.0:
            tau += ca.jtimes(th, q, inertia * ca.jtimes(th, q, qdd), True)
    arm, damp, stiff = (ca.DM(np.asarray(v)) for v in (tree.armature, tree.damping, tree.stiffness))
    return tau + arm * qdd + damp * qd + stiff * (q - ca.DM(tree.springref))
