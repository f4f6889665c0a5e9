"""Numeric description of a planar runner, read from its MuJoCo model (no CasADi here).

The collocation model is derived from the very ``MjModel`` that the forward simulation runs, so
that one definition feeds both sides: body tree, body positions and orientations, joint types,
axes, anchors and reference positions, masses, centres of mass, sagittal inertias, armature,
damping and springs, sites (muscle path points, contact spheres) and gravity.

The model must be planar in the lab's x–z plane: every body, site and inertial frame turned
about y only, hinges about ±y, slides in the x–z plane, one dof per joint (no free or ball
joints) and no friction loss (a constraint, not a force law). :func:`planar_tree` checks this
and raises :class:`bladelab.errors.ModelError` otherwise.

Pitch angles ``θ`` [rad] are rotations about the lab's +y axis: a body-frame vector (x, z)
has lab components ``(cos θ·x + sin θ·z, −sin θ·x + cos θ·z)``. A hinge about local
``(0, s, 0)`` (s = ±1) turns its body by ``s·(q − q0)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from bladelab.errors import ModelError

HINGE, SLIDE = 0, 1
_TOL = 1e-9


@dataclass(frozen=True)
class PlanarJoint:
    """One single-dof joint: type, its index in qpos/qvel, local axis and anchor, reference.

    ``axis`` is (x, z) of a slide's direction in its body frame [-], or (s, 0) for a hinge
    about ±y (s = ±1); ``anchor`` the hinge point (x, z) in the body frame [m]; ``qpos0`` the
    coordinate at which the body sits at its reference pose [m or rad].
    """

    kind: int
    dof: int
    axis: tuple[float, float]
    anchor: tuple[float, float]
    qpos0: float


@dataclass(frozen=True)
class PlanarTree:
    """The planar multibody description of a MuJoCo model (SI units, body 0 = world).

    Attributes
    ----------
    parent
        Parent body of each body (parents come first; ``parent[0] = 0``).
    pos
        Body frame origin in its parent's frame, (x, z) [m].
    pitch
        Fixed rotation of each body frame relative to its parent [rad].
    joints
        The joints of each body, in MuJoCo's order (applied one after the other).
    mass, com, inertia
        Mass [kg], centre of mass (x, z) in the body frame [m], inertia about y [kg·m²].
    armature, damping, stiffness, springref
        Per dof [kg·m² or kg, N·m·s/rad or N·s/m, N·m/rad or N/m, rad or m].
    site_body, site_pos, site_y, site_pitch
        Site body, (x, z) in the body frame [m], lateral lab offset [m] and pitch [rad].
    gravity
        (x, z) of the gravitational acceleration [m/s²] (``mj_model.opt.gravity``).
    """

    parent: np.ndarray
    pos: np.ndarray
    pitch: np.ndarray
    joints: tuple[tuple[PlanarJoint, ...], ...]
    mass: np.ndarray
    com: np.ndarray
    inertia: np.ndarray
    armature: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    springref: np.ndarray
    site_body: np.ndarray
    site_pos: np.ndarray
    site_y: np.ndarray
    site_pitch: np.ndarray
    gravity: np.ndarray

    @property
    def nbody(self) -> int:
        return int(self.parent.shape[0])

    @property
    def nv(self) -> int:
        return int(self.armature.shape[0])


def _pitch_of_quat(quat: np.ndarray, where: str) -> float:
    """Angle [rad] of a unit quaternion (w, x, y, z) that turns about y only."""
    w, x, yq, z = (float(v) for v in quat)
    if abs(x) > _TOL or abs(z) > _TOL:
        raise ModelError(
            f"{where} is rotated out of the x–z plane (quaternion {tuple(quat)})",
            where=where,
            hint="the collocation model is planar: rotate bodies and sites about y only",
        )
    return 2.0 * math.atan2(yq, w)


def _inertia_about_y(inertia: np.ndarray, iquat: np.ndarray) -> float:
    """Moment of inertia about the body's y axis [kg·m²] of principal inertias in a frame
    rotated by ``iquat`` (only this component acts in planar motion)."""
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, np.asarray(iquat, dtype=np.float64))
    row_y = r.reshape(3, 3)[1]
    return float(np.sum(row_y * row_y * inertia))


def planar_tree(model: mujoco.MjModel) -> PlanarTree:
    """Read the planar multibody description of ``model`` (see the module docstring).

    Raises
    ------
    ModelError
        If the model is not planar in x–z, has a joint with more than one dof, a friction
        loss, or a gravity component along y.
    """
    nb = model.nbody
    joints: list[tuple[PlanarJoint, ...]] = [()]
    pitch = np.zeros(nb)
    for b in range(1, nb):
        name = f"body {model.body(b).name!r}"
        pitch[b] = _pitch_of_quat(model.body_quat[b], name)
        row = []
        for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
            jname = f"joint {model.joint(j).name!r}"
            ax = model.jnt_axis[j]
            dof = int(model.jnt_dofadr[j])
            if model.jnt_qposadr[j] != dof:
                raise ModelError(f"{jname}: qpos and qvel layouts differ", where=jname)
            q0 = float(model.qpos0[model.jnt_qposadr[j]])
            anchor = (float(model.jnt_pos[j, 0]), float(model.jnt_pos[j, 2]))
            if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
                if abs(ax[0]) > _TOL or abs(ax[2]) > _TOL:
                    raise ModelError(f"{jname} does not turn about y", where=jname,
                                     hint="planar models need hinges about ±y")
                row.append(PlanarJoint(HINGE, dof, (math.copysign(1.0, ax[1]), 0.0), anchor, q0))
            elif model.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE:
                if abs(ax[1]) > _TOL:
                    raise ModelError(f"{jname} slides out of the x–z plane", where=jname)
                row.append(PlanarJoint(SLIDE, dof, (float(ax[0]), float(ax[2])), anchor, q0))
            else:
                raise ModelError(f"{jname} has more than one dof", where=jname,
                                 hint="use slide and hinge joints only")
        joints.append(tuple(row))
    if np.any(model.dof_frictionloss != 0.0):
        raise ModelError("a dof has friction loss", where="dof_frictionloss",
                         hint="friction loss is a constraint; model it as a force instead")
    if abs(model.opt.gravity[1]) > _TOL:
        raise ModelError("gravity has a lateral (y) component", where="opt.gravity")
    site_pitch = np.array(
        [_pitch_of_quat(model.site_quat[s], f"site {model.site(s).name!r}")
         for s in range(model.nsite)]
    )
    for b in range(1, nb):
        _pitch_of_quat(model.body_iquat[b], f"inertial frame of body {model.body(b).name!r}")
    # MuJoCo keeps the stiffness per joint and the reference in qpos_spring
    stiffness = np.zeros(model.nv)
    springref = np.zeros(model.nv)
    for j in range(model.njnt):
        stiffness[model.jnt_dofadr[j]] = model.jnt_stiffness[j]
        springref[model.jnt_dofadr[j]] = model.qpos_spring[model.jnt_qposadr[j]]
    return PlanarTree(
        parent=np.asarray(model.body_parentid, dtype=np.int64).copy(),
        pos=model.body_pos[:, [0, 2]].copy(),
        pitch=pitch,
        joints=tuple(joints),
        mass=model.body_mass.copy(),
        com=model.body_ipos[:, [0, 2]].copy(),
        inertia=np.array(
            [_inertia_about_y(model.body_inertia[b], model.body_iquat[b]) for b in range(nb)]
        ),
        armature=model.dof_armature.copy(),
        damping=model.dof_damping.copy(),
        stiffness=stiffness,
        springref=springref,
        site_body=np.asarray(model.site_bodyid, dtype=np.int64).copy(),
        site_pos=model.site_pos[:, [0, 2]].copy(),
        site_y=_site_lab_y(model),
        site_pitch=site_pitch,
        gravity=np.array([model.opt.gravity[0], model.opt.gravity[2]], dtype=np.float64),
    )


def _site_lab_y(model: mujoco.MjModel) -> np.ndarray:
    """Lab y [m] of every site: constant in a planar model (rotations about y keep y)."""
    body_y = np.zeros(model.nbody)
    for b in range(1, model.nbody):
        body_y[b] = body_y[model.body_parentid[b]] + model.body_pos[b, 1]
    return body_y[model.site_bodyid] + model.site_pos[:, 1]
