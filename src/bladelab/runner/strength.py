"""Maximal isometric joint moments of the runner's leg muscles against the joint angle, and
people's (Anderson, Madigan & Nussbaum 2007).

An exertion (hip, knee or ankle; extension or flexion) is tested as on a dynamometer: the left
leg at a fixed posture, one joint moved through its range. The model's **active** moment at an
angle is, over the muscles that act in the exertion's direction (the antagonists are taken as
silent), the tendon force at full activation minus the same at zero activation, each muscle in
static equilibrium with its compliant tendon, times its moment arm (the MTU length's
derivative by the coordinate: :func:`~bladelab.runner.passive_moments.muscle_lengths_and_arms`).

People's maximal voluntary active moment (Anderson et al. 2007, J Biomech 40:3105, Table 3,
men aged 18–25) is ``c1·m·g·h·cos(c2·(θ − c3))``, θ in radians with hip and knee flexion and
ankle dorsiflexion positive, m·g·h the body weight times the height. Test postures are not in
the paper's table; the ones here are the common dynamometer set-ups: knee exertions seated (hip
flexed 80°), ankle exertions with the knee extended, hip exertions supine with the knee flexed
90°. The hip's curves depend on that choice through the biarticular muscles: with the knee
extended the hamstrings dominate hip extension and the human body's curve peaks at 30–35°
instead of people's 53° (benchmarks/human_body/README.md).

The comparison is one of shape (:func:`shape_difference`): both curves divided by their own
largest value over the range, so that it says where a muscle group is strong, not how strong
(the body's active strength is a separate choice, docs/runner-model.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bladelab.runner.geometry import LEG_MUSCLES
from bladelab.runner.passive_moments import equilibrium_tendon_force, muscle_lengths_and_arms

__all__ = ["ANDERSON_2007", "EXERTIONS", "Exertion", "active_moments", "exertion_geometry",
           "peak_ratio", "people_moments", "shape_difference"]

#: Anderson et al. (2007) Table 3, men 18–25: exertion -> (c1 [-], c2 [-], c3 [rad]).
ANDERSON_2007 = {
    "hip extension": (0.161, 0.958, 0.932),
    "hip flexion": (0.113, 0.738, -0.214),
    "knee extension": (0.163, 1.258, 1.133),
    "knee flexion": (0.087, 0.869, 0.522),
    "plantarflexion": (0.095, 1.391, 0.408),
    "dorsiflexion": (0.033, 1.510, -0.187),
}

@dataclass(frozen=True)
class Exertion:
    """One dynamometer test of the left leg.

    Attributes
    ----------
    joint
        The moved coordinate without its side (``hip_flexion``, ``knee_angle``,
        ``ankle_angle``).
    coordinate_per_angle
        The model coordinate per unit of people's angle (the knee's coordinate is minus its
        flexion).
    moment_sign
        Sign of the coordinate's generalised force that acts in the exertion's direction.
    posture_deg
        The other coordinates that are set [deg, model convention], by name without side.
    angles_deg
        The tested range of people's angle [deg].
    """

    joint: str
    coordinate_per_angle: float
    moment_sign: float
    posture_deg: dict = field(default_factory=dict)
    angles_deg: tuple[float, ...] = ()


_HIP = tuple(float(a) for a in range(-20, 91, 5))
_KNEE = tuple(float(a) for a in range(0, 101, 5))
_ANKLE = tuple(float(a) for a in range(-30, 31, 5))
#: The six exertions of :data:`ANDERSON_2007` (module docstring: the postures).
EXERTIONS = {
    "hip extension": Exertion("hip_flexion", 1.0, -1.0, {"knee_angle": -90.0}, _HIP),
    "hip flexion": Exertion("hip_flexion", 1.0, 1.0, {"knee_angle": -90.0}, _HIP),
    "knee extension": Exertion("knee_angle", -1.0, 1.0, {"hip_flexion": 80.0}, _KNEE),
    "knee flexion": Exertion("knee_angle", -1.0, -1.0, {"hip_flexion": 80.0}, _KNEE),
    "plantarflexion": Exertion("ankle_angle", 1.0, -1.0, {"knee_angle": 0.0}, _ANKLE),
    "dorsiflexion": Exertion("ankle_angle", 1.0, 1.0, {"knee_angle": 0.0}, _ANKLE),
}


def exertion_geometry(runner, exertion: Exertion, *, side: str = "l"):
    """(rows, MTU lengths [m], d length / d coordinate [m/rad]) of ``side``'s leg muscles at
    the exertion's angles: ``rows`` their indices in ``runner.muscle_names``, the arrays
    (n_angles, n_muscles)."""
    rows = [runner.muscle_names.index(f"{m}_{side}") for m in LEG_MUSCLES
            if f"{m}_{side}" in runner.muscle_names]
    dof = f"{exertion.joint}_{side}"
    length, arm = [], []
    for angle in exertion.angles_deg:
        q = runner.stand_qpos.copy()
        for name, value in exertion.posture_deg.items():
            q[runner.dof(f"{name}_{side}")] = math.radians(value)
        q[runner.dof(dof)] = math.radians(exertion.coordinate_per_angle * angle)
        lengths, arms = muscle_lengths_and_arms(runner, dof, q)
        length.append(lengths[rows])
        arm.append(arms[rows])
    return rows, np.array(length), np.array(arm)


def active_moments(muscle_params: np.ndarray, length: np.ndarray, arm: np.ndarray,
                   moment_sign: float) -> np.ndarray:
    """The active moment [N·m] at each row of ``length``/``arm`` (:func:`exertion_geometry`)
    of the muscles ``muscle_params`` (their rows, in the same order): agonists only (module
    docstring)."""
    out = np.zeros(length.shape[0])
    for k in range(length.shape[0]):
        for i, mp in enumerate(muscle_params):
            active = (equilibrium_tendon_force(mp, length[k, i], 1.0)
                      - equilibrium_tendon_force(mp, length[k, i], 0.0))
            out[k] += max(0.0, -moment_sign * active * arm[k, i])
    return out


def people_moments(name: str, angles_deg, *, body_mass_kg: float, height_m: float,
                   gravity: float = 9.81) -> np.ndarray:
    """People's maximal voluntary active moment [N·m] of the exertion ``name`` at
    ``angles_deg`` (:data:`ANDERSON_2007`; negative values of the cosine clipped to 0)."""
    c1, c2, c3 = ANDERSON_2007[name]
    cos = np.cos(c2 * (np.radians(np.asarray(angles_deg, float)) - c3))
    return c1 * body_mass_kg * gravity * height_m * np.clip(cos, 0.0, None)


def shape_difference(runner, name: str, *, side: str = "l") -> dict:
    """The model's active moment–angle curve of the exertion ``name`` against people's:
    ``angles_deg``, ``model_Nm``, ``people_Nm`` (for the runner's mass and height), the
    angles of their peaks [deg] and ``rms`` [-], the root mean square of the difference of
    the two curves each divided by its own peak."""
    ex = EXERTIONS[name]
    rows, length, arm = exertion_geometry(runner, ex, side=side)
    model = active_moments(np.asarray(runner.muscle_params)[rows], length, arm, ex.moment_sign)
    athlete = runner.params.athlete
    people = people_moments(name, ex.angles_deg, body_mass_kg=athlete.body_mass_kg,
                            height_m=athlete.height_m)
    angles = np.asarray(ex.angles_deg)
    rms = float(np.sqrt(np.mean((model / model.max() - people / people.max()) ** 2)))
    return {"angles_deg": angles, "model_Nm": model, "people_Nm": people,
            "model_peak_deg": float(angles[np.argmax(model)]),
            "people_peak_deg": float(math.degrees(ANDERSON_2007[name][2])), "rms": rms}


def peak_ratio(runner, name: str, *, side: str = "l") -> float:
    """The model's largest active moment of the exertion ``name`` over people's largest
    voluntary one [-] (:func:`shape_difference`'s curves): how strong, where the shape says
    where. People's voluntary activation is about 90 % of their muscles' capacity, so a ratio
    of about 1.1 is people's maximal strength."""
    d = shape_difference(runner, name, side=side)
    return float(d["model_Nm"].max() / d["people_Nm"].max())
