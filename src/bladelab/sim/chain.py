"""A :class:`~bladelab.blade.model.BladeModel` reduced to the arrays the planar kernel needs.

Segments between compliant joints are merged into rigid bodies (mass, centre of mass and
inertia about it by the parallel-axis theorem). Body 0 is welded to the clamp; body ``b`` (b ≥ 1)
turns about hinge ``b − 1`` relative to body ``b − 1``. All coordinates are in the clamp frame at
the undeformed posture [m].
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bladelab.blade.model import BladeModel
from bladelab.errors import ModelError

# Contact-law codes shared by the kernel and the MuJoCo reference.
LAW_SPRING_DAMPER = 0
LAW_HUNT_CROSSLEY = 1


@dataclasses.dataclass(frozen=True, eq=False)
class Chain:
    """Planar chain of rigid bodies (SI units, clamp frame, undeformed posture).

    Attributes
    ----------
    body_mass
        (nb,) [kg].
    body_com
        (nb, 2) centre of mass (x, z) [m].
    body_inertia
        (nb,) inertia about the centre of mass and +y [kg·m²].
    hinge
        (nj, 2) hinge points (x, z) [m]; hinge j joins body j and body j + 1.
    sole_body
        (ne,) body index carrying each sole ellipse.
    sole_geom
        (ne, 5) centre x, centre z [m], semi-axis x, semi-axis z [m], angle [rad].
    tip_body, tip
        Body carrying the tip marker and its position (x, z) [m].
    contact
        (11,) law code, k, c, transition width, exponent, dissipation, μ_s, μ_k, v_c,
        track stiffness k_t [N/m] (0 = rigid ground), track damping c_t [N·s/m].
    stiffness, damping, stiffness_quadratic
        (nj,) the blade's own K [N·m/rad], D [N·m·s/rad], K2 [N·m/rad²].
    """

    body_mass: np.ndarray
    body_com: np.ndarray
    body_inertia: np.ndarray
    hinge: np.ndarray
    sole_body: np.ndarray
    sole_geom: np.ndarray
    tip_body: int
    tip: np.ndarray
    contact: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    stiffness_quadratic: np.ndarray

    @property
    def n_joints(self) -> int:
        """Number of compliant joints (degrees of freedom of the prescribed-clamp chain)."""
        return len(self.hinge)

    @property
    def n_soles(self) -> int:
        """Number of sole ellipses."""
        return len(self.sole_body)


def segment_body_index(blade: BladeModel) -> np.ndarray:
    """Body index of every segment: the number of compliant joints at or before it."""
    points = sorted(j.point for j in blade.joints)
    seg = np.arange(blade.n_segments)
    return np.searchsorted(np.asarray(points), seg, side="right").astype(np.int64)


def build_chain(blade: BladeModel) -> Chain:
    """Merge the blade's segments into the bodies of the planar chain.

    Raises
    ------
    ModelError
        No compliant joint, a joint outside 1..N−1, two joints at one point, no sole ellipse,
        or a body without mass.
    """
    n_seg = blade.n_segments
    if not blade.joints:
        raise ModelError("the blade has no compliant joint", where=f"blade {blade.name!r}",
                         hint="add at least one joint to the blade spec")
    pts = [j.point for j in blade.joints]
    if sorted(pts) != pts or len(set(pts)) != len(pts):
        raise ModelError(f"compliant joints must be at distinct, increasing points, got {pts}",
                         where=f"blade {blade.name!r}")
    if pts[0] < 1 or pts[-1] > n_seg - 1:
        raise ModelError(f"joint points must lie in 1..{n_seg - 1}, got {pts}",
                         where=f"blade {blade.name!r}")
    if not blade.soles:
        raise ModelError("the blade has no sole ellipse", where=f"blade {blade.name!r}")
    body_of = segment_body_index(blade)
    nb = len(pts) + 1
    mass = np.zeros(nb)
    com = np.zeros((nb, 2))
    inertia = np.zeros(nb)
    seg_m = np.asarray(blade.segment_mass, float)
    seg_c = np.asarray(blade.segment_com, float)
    seg_i = np.asarray(blade.segment_inertia, float)
    for b in range(nb):
        sel = body_of == b
        m = seg_m[sel].sum()
        if not m > 0:
            raise ModelError(f"body {b} (segments {np.flatnonzero(sel).tolist()}) has no mass",
                             where=f"blade {blade.name!r}")
        c = (seg_m[sel, None] * seg_c[sel]).sum(axis=0) / m
        d2 = ((seg_c[sel] - c) ** 2).sum(axis=1)
        mass[b], com[b] = m, c
        inertia[b] = float((seg_i[sel] + seg_m[sel] * d2).sum())
    hinge = np.asarray([blade.points[p] for p in pts], float).reshape(-1, 2)
    sole_body = np.asarray([body_of[s.segment] for s in blade.soles], np.int64)
    sole_geom = np.asarray(
        [[s.center[0], s.center[1], s.semi_axis_x, s.semi_axis_z, s.angle] for s in blade.soles],
        float,
    )
    c = blade.contact
    law = {"spring_damper": LAW_SPRING_DAMPER, "hunt_crossley": LAW_HUNT_CROSSLEY}.get(c.law)
    if law is None:
        raise ModelError(f"unknown contact law {c.law!r}", where="contact.law",
                         hint="use 'spring_damper' or 'hunt_crossley'")
    if c.track_stiffness is not None and not (c.track_stiffness > 0
                                              and np.isfinite(c.track_stiffness)):
        raise ModelError(f"track stiffness must be > 0 [N/m], got {c.track_stiffness}",
                         where="contact.track_stiffness",
                         hint="leave it empty for rigid ground")
    if not (c.track_damping >= 0 and np.isfinite(c.track_damping)):
        raise ModelError(f"track damping must be >= 0 [N·s/m], got {c.track_damping}",
                         where="contact.track_damping")
    track_k = 0.0 if c.track_stiffness is None else float(c.track_stiffness)
    contact = np.array([
        law, c.stiffness, c.damping, c.transition_width, c.exponent, c.dissipation,
        c.friction_static, c.friction_kinetic, c.critical_velocity, track_k,
        c.track_damping if track_k > 0 else 0.0,
    ], float)
    if c.friction_static > 0 and not c.critical_velocity > 0:
        raise ModelError("critical_velocity must be > 0 when friction is on",
                         where="contact.critical_velocity")
    return Chain(
        body_mass=mass, body_com=com, body_inertia=inertia, hinge=hinge,
        sole_body=sole_body, sole_geom=sole_geom,
        tip_body=int(body_of[blade.tip_segment]), tip=np.asarray(blade.tip, float),
        contact=contact,
        stiffness=np.array([j.stiffness for j in blade.joints], float),
        damping=np.array([j.damping for j in blade.joints], float),
        stiffness_quadratic=np.array([j.stiffness_quadratic for j in blade.joints], float),
    )
