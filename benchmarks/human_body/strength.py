"""Maximal isometric joint moments of the human body against the angle (a measuring probe).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/strength.py [ACTIVE_SPECIFIC_TENSION_N_PER_CM2]

Every leg muscle of the left leg at full activation in static equilibrium (compliant tendon)
at a pose of the standing runner with one joint moved, its tendon force times its moment arm
(:func:`bladelab.runner.passive_moments.leg_muscle_forces`). Printed per angle:
the knee extension moment (hip 0°), the plantarflexion moment (knee 0°) and the hip extension
moment (knee 0°) [N·m], and each muscle's share. The argument replaces the body's active
specific tension (default: the body's own, 60 N/cm²).
"""

from __future__ import annotations

import json
import math
import sys

from bladelab.runner import build_runner
from bladelab.runner.params import default_runner_params, runner_params_from_dict
from bladelab.runner.passive_moments import leg_muscle_forces


def joint_moments(runner, dof: str, pose_deg: dict[str, float]) -> dict[str, float]:
    """Each left-leg muscle's generalised force on ``dof`` [N·m] at full activation."""
    q = runner.stand_qpos.copy()
    for name, value in pose_deg.items():
        q[runner.dof(name)] = math.radians(value)
    return leg_muscle_forces(runner, dof, q, activation=1.0)


def main() -> None:
    data = json.loads(default_runner_params("able", body="human").model_dump_json())
    if len(sys.argv) > 1:
        data["active_specific_tension_N_per_cm2"] = float(sys.argv[1])
    runner = build_runner(runner_params_from_dict(data))
    print(f"active specific tension {data['active_specific_tension_N_per_cm2']} N/cm²")
    rows = (("knee extension moment [N·m], hip 0°, by knee flexion [deg]", "knee_angle_l",
             lambda a: {"knee_angle_l": -a}, (0, 15, 30, 45, 60, 75, 90), 1.0),
            ("plantarflexion moment [N·m], knee 0°, by ankle dorsiflexion [deg]",
             "ankle_angle_l", lambda a: {"ankle_angle_l": a}, (-30, -20, -10, 0, 10, 20, 30),
             -1.0),
            ("hip extension moment [N·m], knee 0°, by hip flexion [deg]", "hip_flexion_l",
             lambda a: {"hip_flexion_l": a}, (-20, -10, 0, 20, 45, 70, 90), -1.0))
    for title, dof, pose, angles, sign in rows:
        print(title)
        for angle in angles:
            parts = {k: sign * v for k, v in joint_moments(runner, dof, pose(angle)).items()
                     if sign * v > 1e-3}  # the muscles that do not cross the joint: ~0
            print(f"  {angle:4d}: {sum(parts.values()):6.0f}   "
                  + ", ".join(f"{k} {v:.0f}" for k, v in parts.items()))


if __name__ == "__main__":
    main()
