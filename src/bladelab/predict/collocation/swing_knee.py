"""People's swing knee as a constraint of the predictive stage (``swing_knee_min_deg``).

A predicted stride of the human body swings its leg with a shallower knee than people: the
able runner at 3.5 m/s folds its knees to 91–94° where the measured runners fold theirs to
108–109°, and pays for the shallow swing with a quicker stride (0.62 s against people's
0.64–0.78 s). People's angles in the objective (:mod:`~bladelab.predict.collocation.people`)
do not close the gap at any weight tried (10, 20, 40: knees 92–95°), because a mean squared
deviation over the whole stride hardly sees one peak. Holding each biological knee's peak
flexion at people's value does: at 3.5 m/s every human-running criterion is met and the
metabolic cost rises by about 2 % (benchmarks/human_body/swing-knee/README.md).

The constraint, per knee, is a smooth maximum of its flexion over the stride's nodes (the
log-sum-exp with sharpness :data:`SHARPNESS`) at or above the minimum. The log-sum-exp is at
least the largest node's flexion and at most ln(n)/sharpness above it (1.1° at 50 nodes,
usually less: neighbouring nodes near the peak share it), so the stride's peak reaches the
minimum to within that. Running knees flex most in swing (stance: 40–50°), so the peak over
the stride is the swing's peak. It is a prescription from measured running, reported as such
with every answer (docs/collocation.md).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from bladelab.predict.collocation.people import PROSTHETIC_JOINTS, subject_joint_angles

__all__ = ["KNEES", "SHARPNESS", "biological_knees", "peak_flexion_rows",
           "people_swing_knee_deg"]

#: The runners' knee coordinates (flexion negative).
KNEES = ("knee_angle_l", "knee_angle_r")
#: Sharpness of the smooth maximum [1/rad]: the log-sum-exp over n nodes exceeds the largest
#: node's value by at most ln(n)/SHARPNESS (0.020 rad, 1.1°, at 50 nodes).
SHARPNESS = 200.0


def people_swing_knee_deg() -> float:
    """People's peak knee flexion in swing [deg]: the mean of the two reference runners'
    peaks (:func:`~bladelab.predict.collocation.people.subject_joint_angles`, 3.5 m/s)."""
    return float(np.degrees(-subject_joint_angles()["knee_angle"].min(axis=0)).mean())


def biological_knees(dof_names, kind: str) -> tuple[str, ...]:
    """The knee coordinates of a runner of ``kind`` that are a person's (the transfemoral
    runner's prosthetic knee left out)."""
    excluded = PROSTHETIC_JOINTS.get(kind, ())
    return tuple(k for k in KNEES if k in dof_names and k not in excluded)


def peak_flexion_rows(X, sx: np.ndarray, dof_names, minimum_rad: dict[str, float]):
    """Constraint rows (one per knee of ``minimum_rad``) that are >= 0 when the knee's smooth
    peak flexion over the nodes reaches its minimum [rad].

    ``X``: the scaled states on the nodes 0..n-1 (columns; node n repeats node 0), ``sx``
    their scales, ``dof_names`` the coordinates (the first rows of ``X``)."""
    rows = []
    for knee, minimum in minimum_rad.items():
        if not (math.isfinite(minimum) and minimum > 0):
            raise ValueError(f"minimum flexion of {knee} must be > 0 rad, got {minimum}")
        j = list(dof_names).index(knee)
        excess = -X[j, :] * sx[j] - minimum  # flexion above the minimum [rad] per node
        rows.append(ca.log(ca.sum2(ca.exp(SHARPNESS * excess))) / SHARPNESS)
    return ca.vertcat(*rows)
