"""The built blade: the planar multibody description that simulation engines consume.

A :class:`BladeModel` is what a blade spec (YAML, ``docs/blade-spec.md``) becomes after
segmentation and mass distribution. Everything is in SI units and in the **clamp frame** at the
undeformed posture: origin at the clamp origin, z along the pylon axis (up when the clamp pitch is
zero), x forward. Segment 0 is welded to the clamp; consecutive segments are joined rigidly except
at the compliant joints, so an engine may merge every run of rigidly joined segments into one body.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np


@dataclasses.dataclass(frozen=True)
class CompliantJoint:
    """A revolute spring-damper between segment ``point - 1`` and segment ``point``.

    The spring law is ``τ = −(K·q + K2·q·|q|) − D·q̇`` with q [rad] the rotation of the distal
    segment relative to the proximal one about +y, measured from the undeformed posture.

    Attributes
    ----------
    point
        Index into :attr:`BladeModel.points` of the hinge (1 ≤ point ≤ N−1).
    stiffness
        K [N·m/rad] (nominal; identification overrides it).
    damping
        D [N·m·s/rad].
    stiffness_quadratic
        K2 [N·m/rad²]; 0 for the linear spring of seed 000.
    """

    point: int
    stiffness: float
    damping: float
    stiffness_quadratic: float = 0.0


@dataclasses.dataclass(frozen=True)
class SoleEllipse:
    """A contact ellipse welded to a segment (seed 000: three, under segments 14–16).

    Attributes
    ----------
    segment
        Index of the segment it is welded to.
    center
        Centre (x, z) [m] in the clamp frame, undeformed posture.
    semi_axis_x, semi_axis_z
        Semi-axes [m] along the ellipse's own x and z axes.
    angle
        Orientation [rad] of the ellipse's x axis about +y relative to the clamp frame.
    """

    segment: int
    center: tuple[float, float]
    semi_axis_x: float
    semi_axis_z: float
    angle: float = 0.0


@dataclasses.dataclass(frozen=True)
class ContactModel:
    """Sole–ground contact: normal law, friction and ground compliance (SI units).

    ``law = "spring_damper"`` uses ``stiffness`` [N/m], ``damping`` [N·s/m] and
    ``transition_width`` [m] (seed 000's Simscape smooth spring-damper);
    ``law = "hunt_crossley"`` uses ``stiffness`` [N/mⁿ], ``exponent`` n and ``dissipation`` [s/m].
    Friction is the smooth stick-slip law (``friction_static``, ``friction_kinetic`` [-],
    ``critical_velocity`` [m/s]); ``friction_static = 0`` switches friction off.
    ``track_stiffness`` [N/m] and ``track_damping`` [N·s/m] describe a compliant track layer in
    series with the contact; ``track_stiffness = None`` is rigid ground.
    """

    law: Literal["spring_damper", "hunt_crossley"] = "spring_damper"
    stiffness: float = 1.0e6
    damping: float = 1.0e3
    transition_width: float = 1.0e-4
    exponent: float = 1.5
    dissipation: float = 0.0
    friction_static: float = 0.9
    friction_kinetic: float = 0.7
    critical_velocity: float = 0.05
    track_stiffness: float | None = None
    track_damping: float = 0.0


@dataclasses.dataclass(frozen=True, eq=False)
class BladeModel:
    """A segmented blade ready for simulation (clamp frame, undeformed posture, SI units).

    Attributes
    ----------
    name
        Human-readable name.
    points
        (N+1, 2) segment end points (x, z) [m]; segment i runs from points[i] to points[i+1].
    segment_mass
        (N,) masses [kg].
    segment_com
        (N, 2) centres of mass (x, z) [m].
    segment_inertia
        (N,) moments of inertia about the centre of mass and the y axis [kg·m²].
    joints
        Compliant joints (at least one); all other inter-segment joints are rigid.
    soles
        Contact ellipses.
    tip
        (x, z) [m] of the tip marker, welded to segment ``tip_segment``; the characteristic
        distance d(t) is |tip − clamp origin|.
    tip_segment
        Index of the segment carrying the tip marker (normally the last one).
    contact
        Contact law parameters.
    """

    name: str
    points: np.ndarray
    segment_mass: np.ndarray
    segment_com: np.ndarray
    segment_inertia: np.ndarray
    joints: tuple[CompliantJoint, ...]
    soles: tuple[SoleEllipse, ...]
    tip: tuple[float, float]
    tip_segment: int
    contact: ContactModel = dataclasses.field(default_factory=ContactModel)

    @property
    def n_segments(self) -> int:
        """Number of rigid segments N."""
        return len(self.segment_mass)

    @property
    def mass(self) -> float:
        """Total blade mass [kg]."""
        return float(np.sum(self.segment_mass))

    @property
    def rest_distance(self) -> float:
        """Characteristic distance d0 [m] at the undeformed posture."""
        return float(np.hypot(*self.tip))

    def with_joint_parameters(
        self, stiffness: np.ndarray, damping: np.ndarray, stiffness_quadratic: np.ndarray | None = None
    ) -> BladeModel:
        """A copy with new K [N·m/rad], D [N·m·s/rad] (and K2 [N·m/rad²]) per compliant joint."""
        k2 = np.zeros(len(self.joints)) if stiffness_quadratic is None else stiffness_quadratic
        joints = tuple(
            dataclasses.replace(j, stiffness=float(k), damping=float(d), stiffness_quadratic=float(q))
            for j, k, d, q in zip(self.joints, np.atleast_1d(stiffness), np.atleast_1d(damping),
                                  np.atleast_1d(k2), strict=True)
        )
        return dataclasses.replace(self, joints=joints)

    def with_contact(self, **changes) -> BladeModel:
        """A copy with contact parameters changed (keyword names of :class:`ContactModel`)."""
        return dataclasses.replace(self, contact=dataclasses.replace(self.contact, **changes))
