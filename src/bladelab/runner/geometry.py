"""Segment geometry and muscle paths of the planar runner, ported from SCONE's H0918 model.

Source: ``H0918.hfd`` of SCONE (scone-core, Copyright Thomas Geijtenbeek, Apache License 2.0;
a copy with its licence in the project's ``tests/data/scone-h0918/``). Its numbers were typed
into the tables below; no SCONE code is used or run. Hyfydy gives every position relative to the
centre of mass (COM) of its body in OpenSim axes (x forward, y up, z right); :func:`to_lab`
converts to bladelab's lab frame (x forward, y left, z up). All lengths are for the reference
athlete (1.80 m) and are scaled with the athlete's height.

Additions that H0918 does not have (seed 001 §2.1 has them; values are ours, see
docs/runner-model.md): the lumbar joint is free (H0918 locks it), six torso muscles (rectus
abdominis, internal oblique, erector spinae, left and right), the residual tibia (60 % of the
tibia length) and the prosthesis with its contact sphere.
"""

from __future__ import annotations

import math

REFERENCE_HEIGHT_M = 1.80

# Joint positions: (parent body, position in parent [COM-relative], position in child).
JOINTS: dict[str, tuple[str, tuple[float, float, float], tuple[float, float, float]]] = {
    "hip_r": ("pelvis", (0.0, -0.0661, 0.0835), (0.0, 0.17, 0.0)),
    "knee_r": ("femur_r", (0.0, -0.226, 0.0), (0.0, 0.1867, 0.0)),
    "ankle_r": ("tibia_r", (0.0, -0.2433, 0.0), (-0.05123, 0.01195, -0.00792)),
    "hip_l": ("pelvis", (0.0, -0.0661, -0.0835), (0.0, 0.17, 0.0)),
    "knee_l": ("femur_l", (0.0, -0.226, 0.0), (0.0, 0.1867, 0.0)),
    "ankle_l": ("tibia_l", (0.0, -0.2433, 0.0), (-0.05123, 0.01195, 0.00792)),
    "lumbar": ("pelvis", (-0.03, 0.0815, 0.0), (0.03, -0.32, 0.0)),
}

TIBIA_LENGTH_M = 0.1867 + 0.2433  # knee to ankle
THIGH_LENGTH_M = JOINTS["hip_l"][2][1] - JOINTS["knee_l"][1][1]  # hip to knee
RESIDUAL_TIBIA_FRACTION = 0.6

# Foot contact spheres on the calcaneus (COM-relative), radius 0.03 m.
FOOT_SPHERES: dict[str, tuple[float, float, float]] = {
    "heel": (-0.085, -0.015, 0.0),
    "toe": (0.085, -0.015, 0.0),
}
FOOT_SPHERE_RADIUS_M = 0.03
# ankle joint to the sole of the foot standing flat (the spheres' lowest points)
ANKLE_TO_SOLE_M = JOINTS["ankle_l"][2][1] - FOOT_SPHERES["heel"][1] + FOOT_SPHERE_RADIUS_M

# Muscle paths: list of (body, point) for the right side; the left side mirrors z.
# Leg muscles from H0918; torso muscles are ours (H0918 has none).
_LEG_PATHS: dict[str, list[tuple[str, tuple[float, float, float]]]] = {
    "hamstrings": [
        ("pelvis", (-0.05526, -0.10257, 0.06944)),
        ("tibia", (-0.028, 0.1667, 0.02943)),
        ("tibia", (-0.021, 0.1467, 0.0343)),
    ],
    "bifemsh": [
        ("femur", (0.005, -0.0411, 0.0234)),
        ("tibia", (-0.028, 0.1667, 0.02943)),
        ("tibia", (-0.021, 0.1467, 0.0343)),
    ],
    "glut_max": [
        ("pelvis", (-0.0642, 0.0176, 0.0563)),
        ("pelvis", (-0.0669, -0.052, 0.0914)),
        ("femur", (-0.0426, 0.117, 0.0293)),
        ("femur", (-0.0156, 0.0684, 0.0419)),
    ],
    "iliopsoas": [
        ("pelvis", (0.006, 0.0887, 0.0289)),
        ("pelvis", (0.0407, -0.01, 0.076)),
        ("femur", (0.033, 0.135, 0.0038)),
        ("femur", (-0.0188, 0.1103, 0.0104)),
    ],
    "rect_fem": [
        ("pelvis", (0.0412, -0.0311, 0.0968)),
        ("tibia", (0.04, 0.2117, 0.0018)),
    ],
    "vasti": [
        ("femur", (0.029, -0.0224, 0.031)),
        ("femur", (0.0335, -0.0384, 0.0285)),
        ("tibia", (0.04, 0.2117, 0.0018)),
    ],
    "gastroc": [
        ("femur", (-0.02, -0.216, -0.024)),
        ("calcn", (-0.1, 0.001, -0.0053)),
    ],
    "soleus": [
        ("tibia", (-0.0024, 0.0334, 0.0071)),
        ("calcn", (-0.1, 0.001, -0.0053)),
    ],
    "tib_ant": [
        ("tibia", (0.0179, 0.0243, 0.0115)),
        ("tibia", (0.0329, -0.2084, -0.0177)),
        ("calcn", (0.0166, -0.0122, -0.0305)),
    ],
}

# Torso muscles (ours): origin on the pelvis, insertion on the torso (COM-relative).
_TORSO_PATHS: dict[str, list[tuple[str, tuple[float, float, float]]]] = {
    "rect_abd": [("pelvis", (0.045, -0.075, 0.03)), ("torso", (0.10, -0.06, 0.03))],
    "int_obl": [("pelvis", (0.0, 0.06, 0.12)), ("torso", (0.09, -0.15, 0.10))],
    "erect_sp": [("pelvis", (-0.09, 0.0, 0.03)), ("torso", (-0.03, -0.06, 0.03))],
}

LEG_MUSCLES: tuple[str, ...] = tuple(_LEG_PATHS)
SHANK_MUSCLES: tuple[str, ...] = ("gastroc", "soleus", "tib_ant")
TORSO_MUSCLES: tuple[str, ...] = tuple(_TORSO_PATHS)


def muscle_path(muscle_type: str, side: str) -> list[tuple[str, tuple[float, float, float]]]:
    """Path points ``(body, COM-relative point in OpenSim axes)`` of one muscle on one side.

    ``side`` is ``"r"`` or ``"l"``; body names come back with the side suffix (``femur_r``),
    the pelvis and torso without.
    """
    table = _LEG_PATHS if muscle_type in _LEG_PATHS else _TORSO_PATHS
    sign = 1.0 if side == "r" else -1.0
    out = []
    for body, (x, y, z) in table[muscle_type]:
        name = body if body in ("pelvis", "torso") else f"{body}_{side}"
        out.append((name, (x, y, sign * z)))
    return out


def to_lab(point: tuple[float, float, float], scale: float = 1.0) -> tuple[float, float, float]:
    """OpenSim axes (x forward, y up, z right) -> lab axes (x forward, y left, z up), scaled."""
    x, y, z = point
    return (scale * x, -scale * z, scale * y)


def rotate_pitch(x: float, z: float, angle: float) -> tuple[float, float]:
    """Rotate an x–z vector by ``angle`` [rad] in the OpenSim flexion sense (+z toward −x)."""
    c, s = math.cos(angle), math.sin(angle)
    return (c * x - s * z, s * x + c * z)
