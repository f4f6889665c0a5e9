"""The runner's passive joint moments: ``RunnerModel.joint_params``, one row per coordinate.

Ligaments are joint-limit springs–dampers beyond a range (H0918 and seed 001 §2.1); the socket of
the transtibial runner, the toe hinge, the arch, a multi-link blade's joints and (smooth, on
request) the lumbar joint are springs–dampers ``τ = −(K·q + K2·q·|q|) − D·q̇``; a capsule moment
``A·exp(B·q)`` acts within the range (``RunnerParams.capsule_moments``); the transfemoral runner's
knee is its prosthetic knee's (:mod:`bladelab.runner.prosthetic_knee`). Columns:
:mod:`bladelab.runner.layout`'s ``JP_*``; angles in rad, moments in N·m.
"""

from __future__ import annotations

import math

import numpy as np

from bladelab.blade.model import BladeModel
from bladelab.runner.layout import JP_COLUMNS, JP_EA, JP_EB, JP_HI, JP_LO, JP_SK
from bladelab.runner.params import RunnerParams

# Ligaments (joint-limit springs–dampers): (lower, upper) [deg], stiffness [N·m/rad],
# damping [N·m·s/rad]. Hip and ankle ranges and the knee's stiffness/damping from H0918; the knee
# range (−90°, 0°) and the soft lumbar limit at 0° from seed 001 §2.1 (the knee's flexion limit
# is the parameter set's ``knee_flexion_limit_deg``).
LIGAMENTS: dict[str, tuple[float, float, float, float]] = {
    "hip_flexion": (-40.0, 120.0, 500.0, 5.0),
    "knee_angle": (-90.0, 0.0, 114.592, 2.86479),
    "ankle_angle": (-60.0, 60.0, 500.0, 5.0),
    "lumbar_extension": (0.0, 0.0, 500.0, 5.0),
    "mtp_angle": (-30.0, 60.0, 100.0, 1.0),
    "midtarsal_angle": (-15.0, 30.0, 500.0, 5.0),
}
# Socket: stiff nonlinear torsional spring τ = −(K·q + K2·q·|q|) − D·q̇ (seed 001 §2.1).
SOCKET_STIFFNESS = 1000.0  # N·m/rad
SOCKET_STIFFNESS_QUADRATIC = 2.0e4  # N·m/rad²
SOCKET_DAMPING = 10.0  # N·m·s/rad


def joint_params(params: RunnerParams, dof_names: tuple[str, ...],
                 blade_model: BladeModel | None = None) -> np.ndarray:
    """(n_dof, ``JP_COLUMNS``) joint parameters of a runner with the coordinates ``dof_names``
    (its MuJoCo joints in order), wearing ``blade_model`` if given."""
    transfemoral = params.kind == "transfemoral"
    jp = np.zeros((len(dof_names), JP_COLUMNS))
    jp[:, JP_LO], jp[:, JP_HI] = -np.inf, np.inf
    for i, dn in enumerate(dof_names):
        base = dn[:-2] if dn.endswith(("_l", "_r")) else dn
        if base in LIGAMENTS:
            lo, hi, k, d = LIGAMENTS[base]
            if base == "knee_angle":
                lo = -params.knee_flexion_limit_deg
            if base == "lumbar_extension" and params.lumbar_passive == "spring":
                jp[i, JP_SK:JP_EA] = (k, 0.0, d, d)  # the limit's K and D about 0°, no limit
            else:
                jp[i, :4] = (math.radians(lo), math.radians(hi), k, d)
        capsule = params.capsule_moments.get(base)
        if capsule is not None:
            jp[i, JP_EA] = capsule.moment_at_zero_Nm
            jp[i, JP_EB] = math.degrees(capsule.rate_per_deg)  # 1/deg → 1/rad
        if base == "mtp_angle":
            toe = params.toe_hinge
            jp[i, JP_SK:JP_EA] = (toe.stiffness_Nm_per_rad, 0.0, toe.damping_Nms_per_rad,
                                  toe.damping_Nms_per_rad)
        if base == "midtarsal_angle":
            arch = params.arch
            jp[i, JP_SK:JP_EA] = (arch.stiffness_Nm_per_rad, 0.0, arch.damping_Nms_per_rad,
                                  arch.damping_Nms_per_rad)
        if dn == "socket_angle_r":
            jp[i, JP_SK:JP_EA] = (SOCKET_STIFFNESS, SOCKET_STIFFNESS_QUADRATIC,
                                  SOCKET_DAMPING, SOCKET_DAMPING)
        if dn == "knee_angle_r" and transfemoral:
            jp[i] = params.prosthetic_knee.joint_row()
        if dn.startswith("blade_joint") and blade_model is not None:
            j = blade_model.joints[int(dn.removeprefix("blade_joint"))]
            jp[i, JP_SK:JP_EA] = (j.stiffness, j.stiffness_quadratic, j.damping, j.damping)
    return jp


__all__ = [
    "LIGAMENTS",
    "SOCKET_DAMPING",
    "SOCKET_STIFFNESS",
    "SOCKET_STIFFNESS_QUADRATIC",
    "joint_params",
]
