"""Muscle–tendon paths as CasADi (SX) expressions: lengths, lengthening velocities, moment arms.

The same straight-line via-point paths as the forward model
(:func:`bladelab.runner.kernel.path_kinematics` and MuJoCo's spatial tendons of
``RunnerModel.mj_analysis_model``): muscle i runs through the sites of
``RunnerModel.path_points[path_start[i]:path_start[i+1]]``; its length is the sum of the
3-D distances between consecutive points (the lateral offsets of the sites are constant in the
planar model but count), its lengthening velocity ``∂l/∂q·q̇`` and its moment arms
``r = −∂l/∂q`` (positive when the muscle force accelerates the coordinate positively), so that
the generalised force of tendon forces F is ``rᵀ·F`` — exactly what the forward model applies as
point-force pairs along the path.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from bladelab.predict.collocation.multibody import Frame, point_position
from bladelab.predict.collocation.planar import PlanarTree


def mtu_lengths(
    tree: PlanarTree, frames: list[Frame], path_points: np.ndarray, path_start: np.ndarray
) -> ca.SX:
    """Muscle–tendon lengths (n_muscles,) [m] at the pose of ``frames``.

    Parameters
    ----------
    tree
        The planar model (site positions).
    frames
        Body frames at the pose (:func:`~bladelab.predict.collocation.multibody.body_frames`).
    path_points, path_start
        ``RunnerModel.path_points`` (site id, body id rows) and ``RunnerModel.path_start``.
    """
    sites = {int(s) for s in path_points[:, 0]}
    pos = {s: point_position(frames, int(tree.site_body[s]), tree.site_pos[s]) for s in sites}
    lengths = []
    for i in range(len(path_start) - 1):
        total = 0.0
        for k in range(int(path_start[i]), int(path_start[i + 1]) - 1):
            a, b = int(path_points[k, 0]), int(path_points[k + 1, 0])
            d = pos[b] - pos[a]
            dy = float(tree.site_y[b] - tree.site_y[a])
            total = total + ca.sqrt(ca.sumsqr(d) + dy * dy)
        lengths.append(total)
    return ca.vertcat(*lengths)


def mtu_velocities(lengths: ca.SX, q: ca.SX, qd: ca.SX) -> ca.SX:
    """Lengthening velocities (n_muscles,) [m/s]: ``∂l/∂q·q̇``."""
    return ca.jtimes(lengths, q, qd)


def moment_arms(lengths: ca.SX, q: ca.SX) -> ca.SX:
    """Moment arms (n_muscles, nv) [m or m/rad]: ``−∂l/∂q``."""
    return -ca.jacobian(lengths, q)
