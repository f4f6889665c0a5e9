"""A toy stride model whose optimum is known: a mass on a smooth ground spring, for tests of
the stride NLP (:mod:`bladelab.predict.collocation.transcription`) and of constraints added
to it."""

from __future__ import annotations

import casadi as ca
import numpy as np

from bladelab.predict.collocation.stride_guess import StrideGuess
from bladelab.predict.collocation.stride_problem import StrideDynamics

M, G, K = 80.0, 9.81, 2.0e4  # kg, m/s², N/m


def toy_dynamics() -> StrideDynamics:
    """A mass on a smooth ground spring, carried forward at constant speed, with one 'muscle'
    (force 500·F̃ₜ [N] upward, rigid: F̃ₜ = a) that costs 100·a² [W]."""
    q, qd, qdd = (ca.SX.sym(n, 3) for n in ("q", "qd", "qdd"))
    a, f, df, e = (ca.SX.sym(n, 1) for n in ("a", "f", "df", "e"))
    grf = K * 0.5 * (-q[1] + ca.sqrt(q[1] ** 2 + 1e-8))
    r_mb = ca.vertcat(M * qdd[0], M * qdd[1] + M * G - grf - 500 * f, qdd[2])
    return StrideDynamics(
        dof_names=("pelvis_tx", "pelvis_tz", "pelvis_tilt"), muscle_names=("push",), mass=M,
        gravity=G,
        residuals=ca.Function("r", [q, qd, qdd, a, f, df], [r_mb, f - a]),
        activation_rate=ca.Function("ad", [e, a], [(e - a) * 50]),
        metabolic_rate=ca.Function("met", [q, qd, a, f, df, e], [100 * a[0] ** 2]),
        q_bounds=np.array([[-1, 1], [-0.5, 0.5], [-1, 1]]),
        qd_bounds=np.array([[-10.0, 10.0]] * 3), residual_scale=np.full(3, M * G))


def bouncing_guess(n: int, speed: float) -> StrideGuess:
    """A 0.6 s stride bouncing 5 cm on the spring at ``speed`` [m/s], on ``n`` intervals."""
    t = np.linspace(0, 0.6, n + 1)
    w = 2 * np.pi / 0.6
    q = np.stack([speed * t, 0.05 * np.sin(w * t), 0 * t], 1)
    qd = np.stack([speed + 0 * t, 0.05 * w * np.cos(w * t), 0 * t], 1)
    return StrideGuess("toy", 0.6, q, qd)
