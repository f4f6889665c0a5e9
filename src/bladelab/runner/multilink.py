"""Wear a multi-link blade (:class:`bladelab.blade.BladeModel`) on an amputee runner.

This links the characterise and predict workflows: a blade whose compliant joints carry
identified K* and D* (``BladeModel.with_joint_parameters``) replaces seed 001's massless contact
sphere. Placement (our choice, see docs/runner-model.md): the blade's clamp frame (x forward,
z up along the pylon) is aligned with the socket frame, its origin 3 cm behind the socket axis
and at the height that puts the lowest sole point of the undeformed blade 3 cm below the intact
foot (straight legs), like the sphere model. Runs of rigidly joined segments become one MuJoCo
body each (composite mass, COM and sagittal inertia); every compliant joint is a hinge about +y
(the blade module's sign) with ``τ = −(K·q + K2·q·|q|) − D·q̇``. The socket body keeps Table
2.1's prosthesis mass minus the blade's mass. The soles are ellipse contacts with the blade's
own contact law (smooth spring–damper or Hunt–Crossley) and friction cap ``friction_kinetic``.

The blade's contact stiffness (about 1e6 N/m on links of a few hundred grams) needs a time step
of about 1e-4 s; the sphere model runs at 2.5e-4 s.
"""

from __future__ import annotations

import mujoco

from bladelab.blade.model import BladeModel
from bladelab.errors import ModelError
from bladelab.runner.layout import LAW_HUNT_CROSSLEY, LAW_SPRING_DAMPER
from bladelab.sim.mujoco_blade import BladeNames, add_blade_bodies, lowest_sole_z

CLAMP_OFFSET_X_M = -0.03
# MuJoCo names of the blade's links, hinges (index in ``blade.joints``) and sole sites; no tip.
BLADE_NAMES = BladeNames(body="blade_link{index}", joint="blade_joint{index}",
                         sole="blade_sole{index}", tip=None)


def add_multilink_blade(bodies, joint_child, params, s, mr, axis, blade, bottom, *,
                        parent: str = "tibia_res_r", pos=(0.0, 0.0, 0.0),
                        joint: str = "socket_angle_r", com_z: float = 0.05) -> None:
    """Add the prosthesis body on a hinge ``joint`` of ``parent`` at ``pos`` (parent frame
    [m]) and the blade's links under it (MjSpec): the socket under the residual tibia (the
    transtibial runner), or the knee unit and pylon under the residual femur (the
    transfemoral runner). The body keeps the prosthesis mass minus the blade's, its COM
    ``com_z`` [m, reference athlete] above the hinge (negative: below); the blade's lowest
    sole point lies ``bottom`` [m] below the hinge."""
    if not blade.soles or not blade.joints:
        raise ModelError(
            "the blade needs at least one sole and one compliant joint", where="blade_model"
        )
    seg = params.segments["prosthesis_r"]
    socket_mass = seg.mass_kg * mr - blade.mass
    if socket_mass <= 0:
        raise ModelError(
            f"blade mass {blade.mass:.2f} kg exceeds the prosthesis mass {seg.mass_kg * mr:.2f} kg",
            where="blade_model",
            hint="the Table 2.1 prosthesis mass includes socket and blade",
        )
    body = bodies[parent].add_body(name="prosthesis_r", pos=list(pos))
    body.add_joint(name=joint, type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
    ixx, iyy, izz = seg.inertia_kg_m2
    f = socket_mass / seg.mass_kg * s * s
    body.explicitinertial = True
    body.mass = socket_mass
    body.ipos = [0.0, 0.0, com_z * s]
    body.inertia = [max(ixx * f, izz * f - iyy * f + 1e-6), izz * f, iyy * f]
    bodies["prosthesis_r"] = body
    joint_child["prosthesis_r"] = (0.0, 0.0, 0.0)
    clamp = (CLAMP_OFFSET_X_M, -bottom - lowest_sole_z(blade))
    add_blade_bodies(body, blade, origin=clamp, merge_rigid_links=True, names=BLADE_NAMES)


def multilink_contact_rows(model: mujoco.MjModel, blade: BladeModel) -> list[tuple]:
    """Contact parameter rows (``RunnerModel.contact_params`` layout) of the blade's soles."""
    c = blade.contact
    law = LAW_HUNT_CROSSLEY if c.law == "hunt_crossley" else LAW_SPRING_DAMPER
    rows = []
    for k, sole in enumerate(blade.soles):
        site = model.site(f"blade_sole{k}").id
        rows.append(
            (
                site,
                model.site_bodyid[site],
                sole.semi_axis_x,
                c.stiffness,
                c.dissipation,
                c.friction_kinetic,
                1,
                1,
                sole.semi_axis_z,
                law,
                c.exponent,
                c.damping,
                c.transition_width,
            )
        )
    return rows
