"""The prosthesis of the amputee runners in MjSpec, with seed 001's blade contact sphere.

One rigid body below a hinge: the socket, pylon and blade of the transtibial runner (on the
residual tibia, hinge ``socket_angle_r``) or the knee unit, pylon and blade of the transfemoral
runner (on the residual femur, hinge ``knee_angle_r``), with seed 001 Table 2.1's prosthesis mass
and inertia and the blade as a Hertz sphere whose bottom makes the straight prosthetic leg 3 cm
(unless the parameter set says otherwise) longer, knee to ground, than the intact one (seed 001
§2.1; Fig. 2.3 for the transtibial COM),
its modulus E [N/m²] the blade category's stiffness at the athlete's body weight
(:func:`blade_contact_modulus`; :mod:`bladelab.runner.blade_categories`). A multi-link blade
replaces the sphere in :mod:`bladelab.runner.multilink`. Lengths [m] at the reference athlete
(1.80 m), scaled with the height.
"""

from __future__ import annotations

import math

import mujoco

from bladelab.runner import geometry as geo
from bladelab.runner.blade_categories import (
    BLADE_ALIGNMENT_DEG,
    BLADE_EXTRA_LENGTH_M,
    BLADE_OFFSET_A_M,
    BLADE_OFFSET_B_M,
    BLADE_RADIUS_M,
    blade_category,
    blade_modulus,
)
from bladelab.runner.frames import lab_inertia
from bladelab.runner.params import RunnerParams

# The transfemoral prosthesis's COM below the knee axis, as a fraction of the knee-to-ground
# depth: a 1.2 kg knee unit at the top and about as much pylon and blade below (our estimate).
PROSTHETIC_SHANK_COM = 0.4
# With a multi-link blade, the knee unit and pylon (the prosthesis mass minus the blade's) have
# their COM this far below the knee axis [m, reference athlete]: mostly the knee unit.
PROSTHETIC_PYLON_COM_M = 0.08


def prosthetic_bottom(s: float, k_shank: float, res_len: float,
                      extra: float = BLADE_EXTRA_LENGTH_M) -> float:
    """Depth [m] below the socket of the prosthetic leg's lowest point, for a socket
    ``res_len`` [m at 1.80 m, before ``k_shank``] below the knee: the straight prosthetic leg
    is ``extra`` [m at 1.80 m] longer (knee to ground) than the intact one, whose shank is
    ``k_shank`` times the model's; ``s``: the height's scale."""
    intact = geo.TIBIA_LENGTH_M * k_shank + geo.ANKLE_TO_SOLE_M
    return (intact + extra) * s - res_len * k_shank * s


def add_prosthesis(bodies, joint_child, params, s, mr, axis, *, parent: str, pos,
                   joint: str, depth: float, com_fraction: float | None = None) -> None:
    """The prosthesis below a hinge ``joint`` on ``parent`` at ``pos`` (parent frame [m]), with
    the blade contact sphere: the socket, pylon and blade of the transtibial runner (on the
    residual tibia, hinge ``socket_angle_r``) or the knee unit, pylon and blade of the
    transfemoral runner (on the residual femur, hinge ``knee_angle_r``).

    The sphere's bottom lies ``depth`` [m] below the hinge (the straight prosthetic leg
    :attr:`~bladelab.runner.params.RunnerParams.prosthesis_extra_length_m` longer than the
    intact one, knee to ground). The transtibial prosthesis's COM lies
    a = 0.069 m behind and b = 0.0693 m above the sphere centre, that offset turned by the 9°
    alignment (seed 001 Fig. 2.3, our reading); with ``com_fraction`` the COM lies that
    fraction of ``depth`` straight below the hinge instead.
    """
    centre = (0.0, -(depth - BLADE_RADIUS_M))  # (x, z) in the hinge frame
    if com_fraction is None:
        ox, oz = geo.rotate_pitch(
            BLADE_OFFSET_A_M * s, -BLADE_OFFSET_B_M * s, math.radians(BLADE_ALIGNMENT_DEG)
        )
        com = [centre[0] - ox, 0.0, centre[1] - oz]
    else:
        com = [0.0, 0.0, -com_fraction * depth]
    body = bodies[parent].add_body(name="prosthesis_r", pos=list(pos))
    body.add_joint(name=joint, type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
    seg = params.segments["prosthesis_r"]
    ixx, iyy, izz = seg.inertia_kg_m2
    body.explicitinertial = True
    body.mass = seg.mass_kg * mr
    body.ipos = com
    body.inertia = lab_inertia(ixx, iyy, izz, mr * s * s)
    body.add_site(name="blade_r", pos=[centre[0], 0.0, centre[1]], size=[BLADE_RADIUS_M, 0, 0])
    bodies["prosthesis_r"] = body
    joint_child["prosthesis_r"] = (0.0, 0.0, 0.0)


def blade_contact_modulus(params: RunnerParams) -> float:
    """E [N/m²] of the blade sphere for this athlete: the category's stiffness at body weight."""
    cat = blade_category(params.blade)
    return blade_modulus(cat.stiffness_n_per_m, params.athlete.body_mass_kg * params.gravity_m_per_s2)


__all__ = [
    "PROSTHETIC_PYLON_COM_M",
    "PROSTHETIC_SHANK_COM",
    "add_prosthesis",
    "blade_contact_modulus",
    "prosthetic_bottom",
]
