"""The one MuJoCo builder of a :class:`~bladelab.blade.model.BladeModel`: its bodies, compliant
hinges and sole/tip sites, added under a parent body of an ``MjSpec``.

Used by the blade engine's reference model (:func:`bladelab.sim.mujoco_engine.build_spec`), the
transfemoral runner (:mod:`bladelab.design.transfemoral`) and the amputee runner wearing a blade
(:mod:`bladelab.runner.multilink`); each builds its own root down to the parent body.

Frames: the blade's clamp frame (x forward, z up along the pylon, pitch about +y) maps to the
parent's x–z plane, its origin at ``origin`` in the parent's frame. Each body's frame sits at the
start point of its first segment, with the same orientation as the clamp frame (undeformed).
Every compliant joint is a hinge about +y (the blade module's sign of q). The sole ellipses are
ellipsoid sites (semi-axes a along the site's x, c along its z, 2 cm thick along y), the tip
marker a point site.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from bladelab.blade.model import BladeModel

__all__ = ["BladeBodies", "BladeNames", "add_blade_bodies", "lowest_sole_z", "quat_y",
           "rigid_links"]

SOLE_SITE_THICKNESS_M = 0.02  # y extent of the sole ellipsoid sites (display only)


@dataclasses.dataclass(frozen=True)
class BladeNames:
    """Name templates of the elements :func:`add_blade_bodies` creates (``str.format`` fields).

    Attributes
    ----------
    body
        Body name; ``{index}`` is the segment (per-segment bodies) or link index (merged links).
    joint
        Hinge name; ``{index}`` is the joint's index in ``blade.joints``, ``{number}`` = index + 1.
    sole
        Sole ellipse site name; ``{index}`` is the sole's index in ``blade.soles``.
    tip
        Tip marker site name; ``None``: no tip site.
    """

    body: str = "seg{index}"
    joint: str = "joint{number}"
    sole: str = "sole{index}"
    tip: str | None = "tip"


@dataclasses.dataclass(frozen=True)
class BladeBodies:
    """Handles (``MjsBody``/``MjsJoint``/``MjsSite``) of the elements :func:`add_blade_bodies`
    added, for looking them up in the compiled model by name.

    Attributes
    ----------
    bodies
        One body per segment or per rigid link, proximal to distal.
    segments
        The segment indices of each body.
    joints
        The hinge of each compliant joint, in ``blade.joints`` order.
    soles
        The site of each sole ellipse, in ``blade.soles`` order.
    tip
        The tip marker site, or ``None``.
    """

    bodies: tuple[Any, ...]
    segments: tuple[tuple[int, ...], ...]
    joints: tuple[Any, ...]
    soles: tuple[Any, ...]
    tip: Any | None


def quat_y(angle: float) -> list[float]:
    """Unit quaternion (w, x, y, z) of a rotation by ``angle`` [rad] about +y."""
    return [math.cos(angle / 2), 0.0, math.sin(angle / 2), 0.0]


def lowest_sole_z(blade: BladeModel) -> float:
    """Lowest point z [m] of the blade's sole ellipses in the clamp frame, undeformed
    (``inf`` without soles)."""
    low = math.inf
    for sole in blade.soles:
        # ellipse x axis at angle a about +y: ex = (cos a, −sin a) in (x, z); ez = (sin a, cos a)
        half = math.hypot(sole.semi_axis_x * math.sin(sole.angle),
                          sole.semi_axis_z * math.cos(sole.angle))
        low = min(low, sole.center[1] - half)
    return low


def rigid_links(blade: BladeModel) -> list[list[int]]:
    """Segments of each rigid link: the blade split at its compliant joints' points, proximal
    to distal (empty runs dropped)."""
    cuts = sorted(j.point for j in blade.joints)
    links, start = [], 0
    for c in cuts + [blade.n_segments]:
        if c > start:
            links.append(list(range(start, c)))
        start = c
    return links


def _inertial(blade: BladeModel, segs: list[int], merged: bool) -> tuple[float, np.ndarray, float]:
    """Mass [kg], centre of mass (x, z) [m] in the clamp frame and inertia about it and +y
    [kg·m²] of a body: the segment's own (``merged`` False, one segment) or the composite of
    ``segs`` (parallel-axis theorem)."""
    if not merged:
        s = segs[0]
        return (float(blade.segment_mass[s]), np.asarray(blade.segment_com[s], float),
                float(blade.segment_inertia[s]))
    m = float(np.sum(blade.segment_mass[segs]))
    com = np.sum(blade.segment_com[segs] * blade.segment_mass[segs, None], axis=0) / m
    iy = float(np.sum(blade.segment_inertia[segs]
                      + blade.segment_mass[segs] * np.sum((blade.segment_com[segs] - com) ** 2,
                                                          axis=1)))
    return m, com, iy


def add_blade_bodies(
    parent,
    blade: BladeModel,
    *,
    origin: Sequence[float] | None = None,
    merge_rigid_links: bool = False,
    stiffness: Sequence[float] | np.ndarray | None = None,
    damping: Sequence[float] | np.ndarray | None = None,
    min_inertia: float = 1e-12,
    capsule_radius: float | None = None,
    names: BladeNames | None = None,
) -> BladeBodies:
    """Add the blade's bodies, compliant hinges and sole/tip sites under ``parent``.

    Bodies are added proximal to distal as a chain (each the child of the previous one); per
    body, in this order: the hinge (if a compliant joint sits at its first point), the explicit
    inertial (mass, COM, the sagittal inertia on all three axes), the segment capsules, the sole
    sites (``blade.soles`` order), the tip site.

    Parameters
    ----------
    parent
        ``MjsBody`` (e.g. a clamp or socket body, or ``spec.worldbody``).
    blade
        The blade (clamp frame, undeformed posture, SI units).
    origin
        (x, z) [m] of the blade's clamp-frame origin in ``parent``'s frame; ``None``: at
        ``parent``'s origin.
    merge_rigid_links
        ``False``: one body per segment, rigid neighbours welded (MuJoCo composes the inertia).
        ``True``: one body per rigid link (:func:`rigid_links`), with the composite mass, COM and
        inertia.
    stiffness, damping
        Per compliant joint (``blade.joints`` order), K [N·m/rad] and D [N·m·s/rad] as MuJoCo's
        joint ``stiffness`` and ``damping``; ``None``: no MuJoCo spring/damper (the caller
        applies the joint torque itself).
    min_inertia
        Lower bound [kg·m²] of each body's inertia.
    capsule_radius
        Radius [m] of a massless, non-colliding capsule drawn along every segment; ``None``: no
        geoms.
    names
        Name templates; ``None``: :class:`BladeNames` ``()`` (``seg{index}``, ``joint{number}``,
        ``sole{index}``, ``tip``).

    Returns
    -------
    BladeBodies
        Handles of the added elements.
    """
    names = BladeNames() if names is None else names
    points = np.asarray(blade.points, float)
    joint_at = {j.point: i for i, j in enumerate(blade.joints)}
    groups = rigid_links(blade) if merge_rigid_links else [[s] for s in range(blade.n_segments)]
    bodies, joints, soles = [], [None] * len(blade.joints), [None] * len(blade.soles)
    tip = None
    prev = np.zeros(2)
    for n, segs in enumerate(groups):
        p = points[segs[0]]
        rel = p - prev  # in the parent's frame
        if n == 0 and origin is not None:
            rel = np.asarray(origin, float) + rel
        body = parent.add_body(name=names.body.format(index=n), pos=[rel[0], 0.0, rel[1]])
        if segs[0] in joint_at:
            i = joint_at[segs[0]]
            spring = {}
            if stiffness is not None:
                spring["stiffness"] = [float(stiffness[i]), 0, 0]
            if damping is not None:
                spring["damping"] = [float(damping[i]), 0, 0]
            joints[i] = body.add_joint(name=names.joint.format(index=i, number=i + 1),
                                       type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0], **spring)
        mass, com, inertia = _inertial(blade, segs, merge_rigid_links)
        body.explicitinertial = True
        body.mass = mass
        c = com - p
        body.ipos = [c[0], 0.0, c[1]]
        inertia = max(inertia, min_inertia)
        body.inertia = [inertia, inertia, inertia]
        if capsule_radius is not None:
            for s in segs:
                a, b = points[s] - p, points[s + 1] - p
                body.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                              fromto=[a[0], 0, a[1], b[0], 0, b[1]], size=[capsule_radius, 0, 0],
                              contype=0, conaffinity=0, mass=0)
        for e, sole in enumerate(blade.soles):
            if sole.segment in segs:
                soles[e] = body.add_site(
                    name=names.sole.format(index=e), type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
                    pos=[sole.center[0] - p[0], 0.0, sole.center[1] - p[1]],
                    quat=quat_y(sole.angle),
                    size=[sole.semi_axis_x, SOLE_SITE_THICKNESS_M, sole.semi_axis_z])
        if names.tip is not None and blade.tip_segment in segs:
            tip = body.add_site(name=names.tip,
                                pos=[blade.tip[0] - p[0], 0.0, blade.tip[1] - p[1]])
        bodies.append(body)
        parent = body
        prev = p
    return BladeBodies(bodies=tuple(bodies), segments=tuple(tuple(g) for g in groups),
                       joints=tuple(joints), soles=tuple(soles), tip=tip)
