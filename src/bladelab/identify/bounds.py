"""Search bounds for K and D (seed 000 §2.3).

K's bounds come from the instantaneous torsional stiffness of the measured stance,

    K(t) = M_y(t) / Δθ(t) = b(t)·GRF(t) / (θ(t) − θ(t0)),

computed here for a blade with one hinge (a compliant joint at ``hinge``, clamp frame) whose
distal part carries the tip marker (``tip``, clamp frame, undeformed posture):

1. The deflection q(t) of the hinge [rad] is solved from the measured characteristic distance:
   d(q) = |h + R(q)·(tip − h)| (R: rotation about +y), on the branch through q = 0.
   Δθ(t) = q(t) − q(t0), t0 = the first contact sample.
2. The GRF is applied at the deflected contact point (default: the tip marker; any point of the
   distal part may be given), located in the lab with the measured clamp pose, and its moment
   about the hinge M_y = r_z·F_x − r_x·F_z is taken (r: hinge → contact point, lab frame).
3. K(t) = M_y / Δθ on the loaded samples (vertical GRF ≥ ``load_fraction`` × peak, default 0.3,
   and |Δθ| ≥ ``min_deflection_deg``, default 2°); the bounds are
   [``lower_factor`` × P10, ``upper_factor`` × P50] of those K(t) (defaults 0.5 and 2). The quasi-
   static estimate ignores damping, inertia, friction and the moving centre of pressure: on six
   MuJoCo-simulated sprint stances (K 14–21 N·m/deg, both built-in blades) P10 was 0.67–0.83 K and
   the median 1.24–1.43 K, so the default box spans about 0.35 K to 2.5–2.9 K.

D's bounds are [0.01, 1] N·m·s/deg (seed 000: under-damped composite). Internally all bounds are
SI (N·m/rad, N·m·s/rad).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from bladelab.errors import DataError, OptimizationError
from bladelab.parameters import JOINT_PARAMETERS

DAMPING_BOUNDS_NMS_PER_DEG: tuple[float, float] = (0.01, 1.0)
"""Seed 000's damping search range [N·m·s/deg]."""

FALLBACK_STIFFNESS_BOUNDS_NM_PER_DEG: tuple[float, float] = (3.0, 60.0)
"""Used only when the stance has no distance channel to estimate K(t) from [N·m/deg]
(seed 000 found 13–22 N·m/deg)."""



@dataclasses.dataclass(frozen=True)
class ParameterBounds:
    """Box bounds of the identified parameters, SI units.

    Attributes
    ----------
    names
        Parameter names, e.g. ``("K", "D")`` or ``("K", "D", "K2")``.
    lower, upper
        Bounds in SI (K [N·m/rad], D [N·m·s/rad], K2 [N·m/rad²]).
    source
        How K's bounds were obtained (``"instantaneous stiffness"``, ``"fallback"``, ``"user"``).
    """

    names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    source: str = "user"

    def __post_init__(self) -> None:
        if not (len(self.names) == len(self.lower) == len(self.upper)) or not self.names:
            raise OptimizationError("names, lower and upper must have the same non-zero length",
                                    where="bounds")
        for name, lo, hi in zip(self.names, self.lower, self.upper, strict=True):
            if not (np.isfinite(lo) and np.isfinite(hi)):
                raise OptimizationError(f"bounds of {name} must be finite", where=f"bounds.{name}")
            if lo >= hi:
                p = JOINT_PARAMETERS.get(name)
                lo_e, hi_e = (p.to_edge(lo), p.to_edge(hi)) if p else (lo, hi)
                raise OptimizationError(
                    f"min {lo_e:.6g} is not below max {hi_e:.6g} ({p.edge_key if p else name})",
                    where=f"bounds.{name}", hint="give the bounds as (min, max) with min < max",
                )

    def as_array(self) -> np.ndarray:
        """(d, 2) array of (lower, upper) in SI."""
        return np.column_stack([self.lower, self.upper]).astype(float)

    def to_dict(self) -> dict:
        """Edge units: ``{"K_Nm_per_deg": [min, max], "D_Nms_per_deg": [min, max], ...}``."""
        out: dict = {}
        for name, lo, hi in zip(self.names, self.lower, self.upper, strict=True):
            p = JOINT_PARAMETERS.get(name)
            out[p.edge_key if p else name] = [p.to_edge(lo), p.to_edge(hi)] if p else [lo, hi]
        out["source"] = self.source
        return out


def make_bounds(
    *,
    k_nm_per_deg: tuple[float, float],
    d_nms_per_deg: tuple[float, float] = DAMPING_BOUNDS_NMS_PER_DEG,
    k2_nm_per_deg2: tuple[float, float] | None = None,
    source: str = "user",
) -> ParameterBounds:
    """Bounds from edge units (N·m/deg, N·m·s/deg, N·m/deg²), validated, stored in SI.

    Raises
    ------
    OptimizationError
        A minimum is not below its maximum, or a bound is not finite.
    """
    edge = {"K": k_nm_per_deg, "D": d_nms_per_deg}
    if k2_nm_per_deg2 is not None:
        edge["K2"] = k2_nm_per_deg2
    names = list(edge)
    lo = [JOINT_PARAMETERS[n].from_edge(v[0]) for n, v in edge.items()]
    hi = [JOINT_PARAMETERS[n].from_edge(v[1]) for n, v in edge.items()]
    return ParameterBounds(tuple(names), tuple(lo), tuple(hi), source=source)


def _rotate(q, vx, vz):
    """Rotate (vx, vz) by q [rad] about +y (positive turns +z toward +x)."""
    c, s = np.cos(q), np.sin(q)
    return vx * c + vz * s, -vx * s + vz * c


def hinge_deflection(distance, *, hinge: Sequence[float], tip: Sequence[float]) -> np.ndarray:
    """Hinge rotation q [rad] that gives the measured clamp–tip distance [m] (q = 0 undeformed).

    Distances outside the reachable range are clipped to it; NaN stays NaN.
    """
    h = np.asarray(hinge, dtype=float)
    a = np.asarray(tip, dtype=float) - h
    c0 = float(h @ h + a @ a)
    dot = float(h @ a)
    cross = float(h[0] * a[1] - h[1] * a[0])
    rho = float(np.hypot(dot, cross))
    if rho < 1e-12:
        raise DataError("the hinge coincides with the clamp origin or the tip", where="hinge",
                        hint="place the compliant joint between clamp and tip")
    phi = float(np.arctan2(cross, dot))
    d = np.asarray(distance, dtype=float)
    arg = np.clip((d**2 - c0) / (2.0 * rho), -1.0, 1.0)
    return phi - np.sign(phi) * np.arccos(arg) if phi != 0 else -np.arccos(arg)


def instantaneous_stiffness(
    *,
    clamp_x,
    clamp_z,
    clamp_pitch,
    grf_x,
    grf_z,
    distance,
    hinge: Sequence[float],
    tip: Sequence[float],
    contact_point: Sequence[float] | None = None,
    contact_threshold: float = 20.0,
    reference: str = "touchdown",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Instantaneous torsional stiffness K(t) = M_y(t)/Δθ(t) of a one-hinge blade (SI).

    Parameters
    ----------
    clamp_x, clamp_z, clamp_pitch
        Measured clamp pose [m, m, rad], shape (n,).
    grf_x, grf_z
        Measured ground reaction force [N].
    distance
        Measured characteristic distance clamp–tip [m].
    hinge, tip
        Hinge and tip marker (x, z) [m], clamp frame, undeformed posture.
    contact_point
        Point of the distal part where the GRF acts (clamp frame, undeformed); default the tip.
    contact_threshold
        Vertical GRF [N] that marks contact; t0 is the first sample above it.
    reference
        ``"touchdown"`` (seed 000: Δθ = θ(t) − θ(t0)) or ``"rest"`` (Δθ = q(t), the deflection
        from the blade's undeformed geometry; exact when the distance agrees with the model).

    Returns
    -------
    stiffness, moment, deflection
        K(t) [N·m/rad] (NaN where Δθ = 0), M_y(t) [N·m] about the hinge, Δθ(t) [rad].
    """
    grf_z = np.asarray(grf_z, dtype=float)
    in_contact = np.flatnonzero(grf_z > contact_threshold)
    if in_contact.size == 0:
        raise DataError("the stance has no contact", where="grf_z column")
    if reference not in ("touchdown", "rest"):
        raise OptimizationError(f"unknown reference {reference!r}", where="reference",
                                hint="use 'touchdown' or 'rest'")
    q = hinge_deflection(distance, hinge=hinge, tip=tip)
    dtheta = q - q[in_contact[0]] if reference == "touchdown" else q
    h = np.asarray(hinge, dtype=float)
    p = np.asarray(tip if contact_point is None else contact_point, dtype=float)
    # contact point in the clamp frame after the hinge rotates by q, then in the lab frame
    px, pz = _rotate(q, p[0] - h[0], p[1] - h[1])  # hinge -> contact point, clamp frame
    rx, rz = _rotate(np.asarray(clamp_pitch, float), px, pz)  # clamp frame -> lab: R(pitch)
    moment = rz * np.asarray(grf_x, float) - rx * grf_z
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(dtheta != 0, moment / dtheta, np.nan)
    return k, moment, dtheta


def stiffness_bounds(
    stance,
    *,
    hinge: Sequence[float],
    tip: Sequence[float],
    contact_point: Sequence[float] | None = None,
    load_fraction: float = 0.3,
    min_deflection_deg: float = 2.0,
    lower_factor: float = 0.5,
    upper_factor: float = 2.0,
    percentiles: tuple[float, float] = (10.0, 50.0),
    contact_threshold: float = 20.0,
    reference: str = "touchdown",
) -> tuple[float, float]:
    """K bounds [N·m/rad] from a stance's instantaneous stiffness (see the module docstring).

    Raises
    ------
    DataError
        No contact, no distance channel, or fewer than 3 loaded, deflected samples with K(t) > 0.
    """
    dist = np.asarray(stance.distance, dtype=float)
    if not np.any(np.isfinite(dist)):
        raise DataError("no distance values: K(t) needs the clamp–tip distance",
                        where="distance column", hint="give explicit K bounds")
    k, _, dtheta = instantaneous_stiffness(
        clamp_x=stance.clamp_x, clamp_z=stance.clamp_z, clamp_pitch=stance.clamp_pitch,
        grf_x=stance.grf_x, grf_z=stance.grf_z, distance=dist, hinge=hinge, tip=tip,
        contact_point=contact_point, contact_threshold=contact_threshold, reference=reference,
    )
    grf = np.asarray(stance.grf_z, dtype=float)
    ok = (grf >= load_fraction * np.max(grf)) & (np.abs(dtheta) >= np.deg2rad(min_deflection_deg))
    ok &= np.isfinite(k) & (k > 0)
    if ok.sum() < 3:
        raise DataError(
            f"only {int(ok.sum())} loaded samples with a deflection ≥ {min_deflection_deg}° "
            "give a positive K(t)",
            where="distance column",
            hint="check the hinge/tip geometry and the distance channel, or give explicit K bounds",
        )
    p_lo, p_hi = np.percentile(k[ok], list(percentiles))
    return float(lower_factor * p_lo), float(upper_factor * p_hi)


def parameter_bounds(
    stance,
    *,
    hinge: Sequence[float],
    tip: Sequence[float],
    contact_point: Sequence[float] | None = None,
    damping_nms_per_deg: tuple[float, float] = DAMPING_BOUNDS_NMS_PER_DEG,
    nonlinear: bool = False,
    **stiffness_options,
) -> ParameterBounds:
    """K and D bounds for a stance (K from K(t), D from seed 000), SI.

    Without a distance channel K falls back to :data:`FALLBACK_STIFFNESS_BOUNDS_NM_PER_DEG`
    (``source="fallback"``). With ``nonlinear`` a third parameter K2 [N·m/rad²] is bounded by
    ±K_max/0.5 rad (the quadratic term may change the stiffness by up to ±K_max at 0.5 rad ≈ 29°).
    """
    try:
        k_lo, k_hi = stiffness_bounds(stance, hinge=hinge, tip=tip, contact_point=contact_point,
                                      **stiffness_options)
        source = "instantaneous stiffness"
    except DataError as err:
        if "no distance values" not in err.message:
            raise
        k_lo, k_hi = (JOINT_PARAMETERS["K"].from_edge(v) for v in FALLBACK_STIFFNESS_BOUNDS_NM_PER_DEG)
        source = "fallback"
    names = ["K", "D"]
    lo = [k_lo, JOINT_PARAMETERS["D"].from_edge(damping_nms_per_deg[0])]
    hi = [k_hi, JOINT_PARAMETERS["D"].from_edge(damping_nms_per_deg[1])]
    if nonlinear:
        names.append("K2")
        lo.append(-k_hi / 0.5)
        hi.append(k_hi / 0.5)
    return ParameterBounds(tuple(names), tuple(lo), tuple(hi), source=source)
