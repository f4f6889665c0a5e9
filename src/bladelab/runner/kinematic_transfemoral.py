"""The kinematics-driven planar transfemoral runner of seed 002, built in MuJoCo (``MjSpec``).

The model of :func:`bladelab.design.transfemoral.simulate_transfemoral` (x forward, z up, pitch
about +y), in SI units:

- root: slide x, slide z and the trunk pitch hinge ``trunk`` at the hips; the pelvis carries the
  head-arms-trunk mass (``torso`` + ``pelvis`` of the runner parameters); the biological segment
  masses are scaled so that the whole model (with socket, knee and blade) weighs
  ``body_mass_kg``;
- sound leg: thigh, shank, foot (segment masses of :mod:`bladelab.runner.params`) on the hinges
  ``hip_s``, ``knee_s``, ``ankle_s``; two contact circles (heel, toe, radius
  :data:`FOOT_RADIUS_M`) under the foot, sites ``foot0``, ``foot1``;
- prosthetic leg: residual thigh + socket (60 % of the thigh mass, + :data:`SOCKET_MASS_KG`) on
  ``hip_p``; the passive knee unit ``knee_p`` (:class:`~bladelab.runner.prosthetic_knee.
  ProstheticKnee`'s mass) at the sound knee's height; below it a massless adapter to the blade
  clamp, sized so that the standing prosthetic leg (knee to the ground, blade undeformed) is
  ``extra_leg_length_m`` longer than the sound one; the multi-link blade under the clamp
  (:func:`bladelab.sim.mujoco_blade.add_blade_bodies`: bodies ``seg{k}``, hinges
  ``joint{i}`` with K and D, sole sites ``sole{e}``, ``tip``).

MuJoCo's own contact is off; the servos, the knee law, K2 and the contact forces are applied by
the simulation. The musculoskeletal transfemoral runner of predict is
:func:`bladelab.runner.model.build_runner` (``"transfemoral"``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from bladelab.blade.model import BladeModel
from bladelab.constants import STANDARD_GRAVITY
from bladelab.errors import ModelError
from bladelab.runner import geometry as geo
from bladelab.runner.params import default_runner_params
from bladelab.runner.prosthetic_knee import ProstheticKnee
from bladelab.sim.mujoco_blade import add_blade_bodies, lowest_sole_z

__all__ = ["FOOT_CIRCLES", "FOOT_RADIUS_M", "SERVO_JOINTS", "SOCKET_MASS_KG",
           "KinematicTransfemoral", "build_kinematic_transfemoral", "standing_depth"]

#: Radius of the sound foot's contact circles [m].
FOOT_RADIUS_M = 0.03
#: Mass of the socket [kg], added to the residual thigh.
SOCKET_MASS_KG = 1.0
#: Heel and toe circle centres (x, z) below the ankle [m].
FOOT_CIRCLES = ((-0.05, -0.06), (0.15, -0.06))
#: The servo-driven hinges, in the order of the servo arrays.
SERVO_JOINTS = ("trunk", "hip_s", "knee_s", "ankle_s", "hip_p")


def _body(parent, name, pos, mass, com, inertia):
    b = parent.add_body(name=name, pos=list(pos))
    b.explicitinertial = True
    b.mass = float(mass)
    b.ipos = list(com)
    b.inertia = [max(float(inertia), 1e-8)] * 3
    return b


def _hinge(body, name):
    body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])


def standing_depth(blade: BladeModel) -> float:
    """Depth [m] of the lowest undeformed sole point below the clamp at pitch 0."""
    low = min(0.0, lowest_sole_z(blade))
    return -min(low, float(np.min(np.asarray(blade.points)[:, 1])))


@dataclass(frozen=True)
class KinematicTransfemoral:
    """A built kinematics-driven transfemoral runner: the MuJoCo model and its addresses.

    Attributes
    ----------
    model
        The compiled ``mujoco.MjModel``.
    sites, axes, site_body
        Contact sites (the blade's soles, then ``foot0``, ``foot1``), their (x, z) semi-axes [m]
        and their bodies.
    n_soles
        Number of blade soles (the first ``n_soles`` sites).
    blade_q, blade_d
        qpos and dof addresses of the blade's hinges.
    servo_q, servo_d
        qpos and dof addresses of :data:`SERVO_JOINTS`.
    knee_q, knee_d, knee_body
        qpos and dof address of the prosthetic knee, and its body.
    seg_bodies, tip_site
        The blade's segment bodies and its tip site.
    adapter
        Length of the adapter between knee axis and blade clamp [m].
    """

    model: Any
    sites: np.ndarray
    axes: np.ndarray
    site_body: np.ndarray
    n_soles: int
    blade_q: np.ndarray
    blade_d: np.ndarray
    servo_q: np.ndarray
    servo_d: np.ndarray
    knee_q: int
    knee_d: int
    knee_body: int
    seg_bodies: np.ndarray
    tip_site: int
    adapter: float


def build_kinematic_transfemoral(blade: BladeModel, body_mass: float, height: float,
                                 knee: ProstheticKnee, extra_leg: float, dt: float,
                                 knee_offset: float = 0.0) -> KinematicTransfemoral:
    """Build the runner (module docstring) wearing ``blade``: body mass ``body_mass`` [kg]
    (prosthesis included), height ``height`` [m] (segment lengths scaled from the reference
    athlete), prosthetic ``knee``, standing prosthetic leg ``extra_leg`` [m] longer than the
    sound one, MuJoCo step ``dt`` [s], blade clamp ``knee_offset`` [m] forward of the knee
    axis."""
    params = default_runner_params("able")
    s = height / params.athlete.height_m
    seg = params.segments
    bio = (seg["torso"].mass_kg + seg["pelvis"].mass_kg + seg["femur_l"].mass_kg
           + seg["tibia_l"].mass_kg + seg["calcn_l"].mass_kg + 0.6 * seg["femur_r"].mass_kg)
    prosthesis = SOCKET_MASS_KG + knee.mass + blade.mass
    if body_mass <= prosthesis + 10.0:
        raise ModelError(f"body mass {body_mass} kg is too small for the prosthesis "
                         f"({prosthesis:.1f} kg)", where="body_mass_kg")
    mr = (body_mass - prosthesis) / bio  # the model's total mass equals body_mass
    thigh = (0.226 + 0.17) * s
    shank = geo.TIBIA_LENGTH_M * s
    ankle_h = 0.06 + FOOT_RADIUS_M
    spec = mujoco.MjSpec()
    spec.modelname = "bladelab_transfemoral"
    spec.option.timestep = dt
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.gravity = [0.0, 0.0, -STANDARD_GRAVITY]
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    bx = _body(spec.worldbody, "root_x", (0, 0, 0), 1e-6, (0, 0, 0), 1e-9)
    bx.add_joint(name="root_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    bz = _body(bx, "root_z", (0, 0, 0), 1e-6, (0, 0, 0), 1e-9)
    bz.add_joint(name="root_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    hat_m = (seg["torso"].mass_kg + seg["pelvis"].mass_kg) * mr
    pelvis = _body(bz, "pelvis", (0, 0, 0), hat_m, (0, 0, 0.30 * s), hat_m * (0.3 * s) ** 2 / 3)
    _hinge(pelvis, "trunk")
    # sound leg
    th_s = _body(pelvis, "thigh_s", (0, 0, 0), seg["femur_l"].mass_kg * mr, (0, 0, -0.17 * s),
                 seg["femur_l"].inertia_kg_m2[2] * mr * s * s)
    _hinge(th_s, "hip_s")
    sh_s = _body(th_s, "shank_s", (0, 0, -thigh), seg["tibia_l"].mass_kg * mr,
                 (0, 0, -0.1867 * s), seg["tibia_l"].inertia_kg_m2[2] * mr * s * s)
    _hinge(sh_s, "knee_s")
    ft = _body(sh_s, "foot_s", (0, 0, -shank), seg["calcn_l"].mass_kg * mr, (0.05, 0, -0.04),
               seg["calcn_l"].inertia_kg_m2[2] * mr * s * s)
    _hinge(ft, "ankle_s")
    for i, (x, z) in enumerate(FOOT_CIRCLES):
        ft.add_site(name=f"foot{i}", type=mujoco.mjtGeom.mjGEOM_ELLIPSOID, pos=[x, 0, z],
                    size=[FOOT_RADIUS_M, 0.02, FOOT_RADIUS_M])
    # prosthetic leg
    m_th = 0.6 * seg["femur_r"].mass_kg * mr + SOCKET_MASS_KG
    th_p = _body(pelvis, "thigh_p", (0, 0, 0), m_th, (0, 0, -0.15 * s),
                 0.6 * seg["femur_r"].inertia_kg_m2[2] * mr * s * s)
    _hinge(th_p, "hip_p")
    depth = standing_depth(blade)
    adapter = shank + ankle_h + extra_leg - depth
    if adapter < 0.01:
        raise ModelError(f"the blade is too tall for this leg ({depth * 1e3:.0f} mm below the "
                         "clamp)", where=f"{blade.name}: transfemoral runner",
                         hint="lower extra_leg_length_m or use a shorter blade")
    kb = _body(th_p, "knee_p", (0, 0, -thigh), knee.mass, (0, 0, -0.03),
               knee.mass * 0.05**2)
    _hinge(kb, "knee_p")
    parent = _body(kb, "clamp", (knee_offset, 0, -adapter), 1e-6, (0, 0, 0), 1e-9)
    parent.add_site(name="clamp", pos=[0, 0, 0])
    add_blade_bodies(parent, blade, stiffness=[j.stiffness for j in blade.joints],
                     damping=[j.damping for j in blade.joints], min_inertia=1e-8)
    m = spec.compile()
    ne = len(blade.soles)
    names = [f"sole{e}" for e in range(ne)] + ["foot0", "foot1"]
    sites = np.array([m.site(n).id for n in names])
    axes = np.array([[e.semi_axis_x, e.semi_axis_z] for e in blade.soles]
                    + [[FOOT_RADIUS_M, FOOT_RADIUS_M]] * 2, float)
    jn = [f"joint{i + 1}" for i in range(len(blade.joints))]
    return KinematicTransfemoral(
        model=m, sites=sites, axes=axes, site_body=np.ascontiguousarray(m.site_bodyid[sites]),
        n_soles=ne,
        blade_q=np.array([m.jnt_qposadr[m.joint(n).id] for n in jn], np.int64),
        blade_d=np.array([m.jnt_dofadr[m.joint(n).id] for n in jn], np.int64),
        servo_q=np.array([m.jnt_qposadr[m.joint(n).id] for n in SERVO_JOINTS], np.int64),
        servo_d=np.array([m.jnt_dofadr[m.joint(n).id] for n in SERVO_JOINTS], np.int64),
        knee_q=int(m.jnt_qposadr[m.joint("knee_p").id]),
        knee_d=int(m.jnt_dofadr[m.joint("knee_p").id]),
        knee_body=int(m.body("knee_p").id),
        seg_bodies=np.array([m.body(f"seg{k}").id for k in range(blade.n_segments)]),
        tip_site=int(m.site("tip").id), adapter=float(adapter),
    )

