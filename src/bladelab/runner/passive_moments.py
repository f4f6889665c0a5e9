"""Passive joint moments of the runner's muscles, and people's (Riener & Edrich 1999).

The passive moment of a pose: every leg muscle at zero activation in static equilibrium
(:func:`~bladelab.runner.muscle.equilibrium_fiber_length`, its tendon force) times its moment
arm, the MTU length's derivative by the coordinate (MuJoCo's spatial tendons of
``RunnerModel.mj_analysis_model``), plus the joint's capsule moment where the parameter set
has one (``RunnerParams.capsule_moments``). Joint ligaments are left out: they act only beyond
the joint limits.

Riener & Edrich (1999) fitted the passive moments of all structures measured on people, with
angles in degrees (knee flexion K, hip flexion H, ankle dorsiflexion A); Miller et al. (2012)
used them in their sprinting model. They are the reference the human body's passive fibre
curve is calibrated to (docs/runner-model.md, "The human body").
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from bladelab.runner.geometry import LEG_MUSCLES
from bladelab.runner.layout import JP_EA, JP_EB
from bladelab.runner.muscle import (
    MP_ACTIVE,
    equilibrium_fiber_lengths,
    tendon_force_of_state,
)

__all__ = ["equilibrium_tendon_force", "leg_muscle_forces", "muscle_lengths_and_arms",
           "passive_flexion_moment", "riener_edrich_hip_moment", "riener_edrich_knee_moment"]

#: Step [rad] of the central difference of the MTU lengths.
_STEP_RAD = 1e-6


def riener_edrich_knee_moment(knee_deg: float, hip_deg: float, ankle_deg: float = 0.0) -> float:
    """People's passive knee flexion moment [N·m] at knee flexion, hip flexion and ankle
    dorsiflexion [deg]: ``exp(1.800 + 0.0460A − 0.0352K + 0.0217H) − exp(−3.971 + 0.0004A +
    0.0495K − 0.0128H) − 4.820 + exp(2.220 − 1.50K)``."""
    k, h, a = knee_deg, hip_deg, ankle_deg
    return (math.exp(1.800 + 0.0460 * a - 0.0352 * k + 0.0217 * h)
            - math.exp(-3.971 + 0.0004 * a + 0.0495 * k - 0.0128 * h)
            - 4.820 + math.exp(2.220 - 1.50 * k))


def riener_edrich_hip_moment(knee_deg: float, hip_deg: float) -> float:
    """People's passive hip flexion moment [N·m] at knee and hip flexion [deg]:
    ``exp(1.4655 − 0.0034K − 0.0750H) − exp(1.3403 − 0.0226K + 0.0305H) + 8.072``."""
    k, h = knee_deg, hip_deg
    return (math.exp(1.4655 - 0.0034 * k - 0.0750 * h)
            - math.exp(1.3403 - 0.0226 * k + 0.0305 * h) + 8.072)


def muscle_lengths_and_arms(runner, dof: str, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every muscle's MTU length [m] at the pose ``q`` (MuJoCo coordinates) and its derivative
    by the coordinate ``dof`` [m/rad or m/m] (MuJoCo's spatial tendons of
    ``RunnerModel.mj_analysis_model``, a central difference), in ``runner.muscle_names``
    order."""
    model = runner.mj_analysis_model
    data = mujoco.MjData(model)
    j = runner.dof(dof)

    def lengths(qpos: np.ndarray) -> np.ndarray:
        data.qpos[:] = qpos
        mujoco.mj_forward(model, data)
        return data.ten_length.copy()

    qp, qm = q.copy(), q.copy()
    qp[j] += _STEP_RAD
    qm[j] -= _STEP_RAD
    return lengths(q), (lengths(qp) - lengths(qm)) / (2.0 * _STEP_RAD)


def equilibrium_tendon_force(muscle_params: np.ndarray, mtu_length: float,
                             activation: float) -> float:
    """Tendon force [N] of one muscle (its ``muscle_params`` row) at an MTU length [m] and
    activation [-], the fibre in static equilibrium with its compliant tendon."""
    fibre = equilibrium_fiber_lengths(muscle_params[None, :], [mtu_length], activation)[0]
    return tendon_force_of_state(mtu_length, fibre, *muscle_params[:MP_ACTIVE])


def leg_muscle_forces(runner, dof: str, q: np.ndarray, *, activation: float,
                      side: str = "l") -> dict[str, float]:
    """Each leg muscle of ``side``'s generalised force on the coordinate ``dof`` [N·m or N] at
    the pose ``q`` (MuJoCo coordinates) and ``activation`` [-], in static equilibrium (module
    docstring), by muscle type (``vasti``, ...)."""
    length, d_length = muscle_lengths_and_arms(runner, dof, q)
    out = {}
    for m in LEG_MUSCLES:
        if f"{m}_{side}" not in runner.muscle_names:
            continue
        i = runner.muscle_names.index(f"{m}_{side}")
        out[m] = -equilibrium_tendon_force(runner.muscle_params[i], length[i],
                                           activation) * d_length[i]
    return out


def passive_flexion_moment(runner, joint: str, *, knee_deg: float, hip_deg: float,
                           side: str = "l") -> float:
    """The passive flexion moment [N·m] of the muscles and the capsule about ``joint``
    (``"knee"`` or ``"hip"``) of the leg ``side`` at knee and hip flexion [deg], the other
    coordinates of the standing pose (module docstring)."""
    if joint not in ("knee", "hip"):
        raise ValueError(f"joint must be 'knee' or 'hip', got {joint!r}")
    knee, hip = f"knee_angle_{side}", f"hip_flexion_{side}"
    dof, sign = (knee, 1.0) if joint == "knee" else (hip, -1.0)  # knee_angle = −flexion
    q = runner.stand_qpos.copy()
    q[runner.dof(knee)], q[runner.dof(hip)] = -math.radians(knee_deg), math.radians(hip_deg)
    forces = leg_muscle_forces(runner, dof, q, activation=0.0, side=side)
    row = runner.joint_params[runner.dof(dof)]
    capsule = row[JP_EA] * math.exp(row[JP_EB] * q[runner.dof(dof)])  # along the coordinate
    return -sign * (sum(forces.values()) + capsule)
