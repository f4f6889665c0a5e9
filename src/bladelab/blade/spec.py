"""Blade spec: the YAML description of a blade, validated by pydantic (``docs/blade-spec.md``).

A :class:`BladeSpec` holds the profile (parametric elements, a CSV polyline or inline points),
the segmentation threshold, mass and thickness, compliant joints, sole ellipses, the contact
law and the stiffness categories. :meth:`BladeSpec.build` turns it into the
:class:`~bladelab.blade.model.BladeModel` that simulation engines consume. Units are in every
key name; K and D are in the literature's N·m/deg and N·m·s/deg and converted to SI on build.
Segment numbers in the spec are **1-based** (as in seed 000: "joint between segments 7 and 8");
the built model uses 0-based indices.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import pydantic
import yaml
from pydantic import BaseModel, ConfigDict, Field

from bladelab import units
from bladelab._io import read_yaml
from bladelab.blade.model import BladeModel, CompliantJoint, ContactModel, SoleEllipse
from bladelab.blade.profile import (
    Profile,
    ProfileElement,
    profile_from_elements,
    read_profile_csv,
)
from bladelab.blade.segmentation import Segmentation, segment_profile
from bladelab.errors import BladelabError, ModelError, SpecError
from bladelab.parameters import JOINT_PARAMETERS

__all__ = [
    "BladeSpec",
    "ContactSpec",
    "JointSpec",
    "ProfileSpec",
    "SegmentationSpec",
    "SoleSpec",
    "read_blade_spec",
    "segment_mass_properties",
    "spec_from_dict",
]

PositiveFloat = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]
NonNegativeFloat = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]
FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]

# A sole ellipse's lowest point must lie in the lowest part of the blade: within this fraction
# of the build height above the profile's lowest point.
_SOLE_LOW_FRACTION = 0.25
# ... and its centre within (largest semi-axis + this) [m] of the segment it is welded to.
_SOLE_ATTACH_MARGIN = 0.01


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ElementSpec(_Strict):
    """A straight line (``turn_deg`` 0) or circular arc of the parametric profile."""

    length_mm: PositiveFloat
    turn_deg: FiniteFloat = 0.0


class ProfileSpec(_Strict):
    """The profile: exactly one of ``elements``, ``csv`` or ``points_mm``."""

    start_heading_deg: FiniteFloat = -90.0
    elements: list[ElementSpec] | None = None
    csv: str | None = None
    points_mm: list[tuple[FiniteFloat, FiniteFloat]] | None = None

    @pydantic.model_validator(mode="after")
    def _one_source(self) -> ProfileSpec:
        given = [k for k in ("elements", "csv", "points_mm") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'elements', 'csv' or 'points_mm' "
                             f"(got {given or 'none'})")
        if self.elements is not None and len(self.elements) == 0:
            raise ValueError("'elements' is empty")
        if self.points_mm is not None and len(self.points_mm) < 2:
            raise ValueError(f"a profile needs at least two points, got {len(self.points_mm)}")
        return self


class SegmentationSpec(_Strict):
    """How to cut the profile: automatic N from a threshold, or a fixed N."""

    max_error_mm2_per_mm: PositiveFloat = 1.0
    n_segments: Annotated[int, Field(ge=1, le=200)] | None = None


class JointSpec(_Strict):
    """A compliant joint between two consecutive segments (1-based numbers)."""

    between_segments: tuple[Annotated[int, Field(ge=1)], Annotated[int, Field(ge=1)]]
    K_Nm_per_deg: PositiveFloat
    D_Nms_per_deg: NonNegativeFloat = 0.0
    K2_Nm_per_deg2: NonNegativeFloat = 0.0

    @pydantic.field_validator("between_segments")
    @classmethod
    def _consecutive(cls, v: tuple[int, int]) -> tuple[int, int]:
        if v[1] != v[0] + 1:
            raise ValueError(f"segments must be consecutive, like [7, 8]; got {list(v)}")
        return v


class SoleSpec(_Strict):
    """A sole ellipse welded under a segment (1-based number)."""

    segment: Annotated[int, Field(ge=1)]
    semi_axes_mm: tuple[PositiveFloat, PositiveFloat]
    position: Annotated[float, Field(ge=0.0, le=1.0)] = 0.5
    offset_mm: FiniteFloat = 0.0
    angle_deg: FiniteFloat = 0.0


class TrackSpec(_Strict):
    """A compliant track layer in series with the contact."""

    stiffness_N_per_m: PositiveFloat
    damping_Ns_per_m: NonNegativeFloat = 0.0


class ContactSpec(_Strict):
    """Sole–ground contact (fields of :class:`~bladelab.blade.model.ContactModel`, SI units)."""

    law: Literal["spring_damper", "hunt_crossley"] = "spring_damper"
    stiffness_N_per_m: PositiveFloat | None = None
    stiffness_N_per_m_pow_n: PositiveFloat | None = None
    damping_Ns_per_m: NonNegativeFloat = 1.0e3
    transition_width_m: PositiveFloat = 1.0e-4
    exponent: Annotated[float, Field(ge=1.0, le=3.0)] = 1.5
    dissipation_s_per_m: NonNegativeFloat = 0.0
    friction_static: NonNegativeFloat = 0.9
    friction_kinetic: NonNegativeFloat = 0.7
    critical_velocity_m_per_s: PositiveFloat = 0.05
    track: TrackSpec | None = None

    @pydantic.model_validator(mode="after")
    def _stiffness_for_law(self) -> ContactSpec:
        if self.law == "spring_damper" and self.stiffness_N_per_m_pow_n is not None:
            raise ValueError("'stiffness_N_per_m_pow_n' is for law 'hunt_crossley'; "
                             "use 'stiffness_N_per_m' with 'spring_damper'")
        if self.law == "hunt_crossley" and self.stiffness_N_per_m is not None:
            raise ValueError("law 'hunt_crossley' takes 'stiffness_N_per_m_pow_n' [N/m^n], "
                             "not 'stiffness_N_per_m'")
        if self.friction_kinetic > self.friction_static > 0.0:
            raise ValueError("friction_kinetic must not exceed friction_static")
        return self

    def to_model(self) -> ContactModel:
        """The SI :class:`ContactModel`."""
        if self.law == "spring_damper":
            k = 1.0e6 if self.stiffness_N_per_m is None else self.stiffness_N_per_m
        else:
            k = 1.0e8 if self.stiffness_N_per_m_pow_n is None else self.stiffness_N_per_m_pow_n
        return ContactModel(
            law=self.law,
            stiffness=float(k),
            damping=float(self.damping_Ns_per_m),
            transition_width=float(self.transition_width_m),
            exponent=float(self.exponent),
            dissipation=float(self.dissipation_s_per_m),
            friction_static=float(self.friction_static),
            friction_kinetic=float(self.friction_kinetic),
            critical_velocity=float(self.critical_velocity_m_per_s),
            track_stiffness=None if self.track is None else float(self.track.stiffness_N_per_m),
            track_damping=0.0 if self.track is None else float(self.track.damping_Ns_per_m),
        )


class CategorySpec(_Strict):
    """A stiffness category: nominal K per joint (one value for all joints, or one per joint)."""

    K_Nm_per_deg: PositiveFloat | list[PositiveFloat]


class BladeSpec(_Strict):
    """A blade spec (YAML). See ``docs/blade-spec.md`` for every field."""

    name: Annotated[str, Field(min_length=1)]
    description: str = ""
    sources: list[str] = Field(default_factory=list)
    profile: ProfileSpec
    segmentation: SegmentationSpec = Field(default_factory=SegmentationSpec)
    mass_kg: PositiveFloat
    thickness_mm: list[tuple[Annotated[float, Field(ge=0.0, le=1.0)], PositiveFloat]] | None = None
    joints: Annotated[list[JointSpec], Field(min_length=1)]
    soles: Annotated[list[SoleSpec], Field(min_length=1)]
    contact: ContactSpec = Field(default_factory=ContactSpec)
    categories: dict[str, CategorySpec] = Field(default_factory=dict)
    category: str | None = None

    @pydantic.model_validator(mode="after")
    def _check(self) -> BladeSpec:
        if self.category is not None and self.category not in self.categories:
            raise ValueError(f"category {self.category!r} is not among categories "
                             f"{sorted(self.categories)}")
        points = [j.between_segments[0] for j in self.joints]
        if len(set(points)) != len(points):
            raise ValueError("two joints between the same pair of segments")
        for name, cat in self.categories.items():
            if isinstance(cat.K_Nm_per_deg, list) and len(cat.K_Nm_per_deg) != len(self.joints):
                raise ValueError(f"category {name!r}: {len(cat.K_Nm_per_deg)} K values for "
                                 f"{len(self.joints)} joints")
        if self.thickness_mm is not None:
            s = [p[0] for p in self.thickness_mm]
            if len(s) < 1 or any(b <= a for a, b in zip(s[:-1], s[1:], strict=False)):
                raise ValueError("thickness_mm: arc-length fractions must increase strictly")
        return self

    # ------------------------------------------------------------------ building
    @property
    def model_name(self) -> str:
        """Name of the built model: ``name-category`` when a category is selected."""
        return self.name if self.category is None else f"{self.name}-{self.category}"

    def with_category(self, category: str) -> BladeSpec:
        """A copy with another stiffness category selected; the joints' K [N·m/deg] become the
        category's, so that the copy's YAML (:meth:`to_yaml`) reads back without a conflict."""
        if category not in self.categories:
            raise SpecError(f"unknown category {category!r}", where=f"{self.name}: category",
                            hint=f"choose one of {sorted(self.categories)}")
        ks = self._category_stiffness(category)
        joints = [j.model_copy(update={"K_Nm_per_deg": k}) for j, k in zip(self.joints, ks,
                                                                            strict=True)]
        return self.model_copy(update={"category": category, "joints": joints})

    def _category_stiffness(self, category: str) -> list[float]:
        """K [N·m/deg] per joint of ``category``."""
        cat = self.categories[category].K_Nm_per_deg
        return [float(k) for k in cat] if isinstance(cat, list) else [float(cat)] * len(self.joints)

    def check_category(self, *, file: str | Path | None = None) -> None:
        """Refuse a joint K that differs from the selected category's K (both given, one would
        silently win). Raises :class:`SpecError` naming the joint, both values and the category."""
        if self.category is None:
            return
        for i, (j, k) in enumerate(zip(self.joints, self._category_stiffness(self.category),
                                       strict=True)):
            if not math.isclose(j.K_Nm_per_deg, k, rel_tol=1e-9):
                raise SpecError(
                    f"joint K = {j.K_Nm_per_deg:g} N·m/deg conflicts with category "
                    f"{self.category!r}, whose K = {k:g} N·m/deg",
                    file=file, where=f"joints.{i}.K_Nm_per_deg",
                    hint=f"to use K = {j.K_Nm_per_deg:g}, delete the line 'category: "
                         f"{self.category}'; to use the category, set K_Nm_per_deg: {k:g}",
                )

    def joint_stiffness_Nm_per_deg(self) -> list[float]:
        """Nominal K [N·m/deg] per joint, after applying the selected category."""
        if self.category is not None:
            return self._category_stiffness(self.category)
        return [float(j.K_Nm_per_deg) for j in self.joints]

    def profile_geometry(self) -> Profile:
        """The profile polyline (clamp frame, m)."""
        p = self.profile
        try:
            if p.elements is not None:
                els = [ProfileElement(e.length_mm * 1e-3, units.deg2rad(e.turn_deg))
                       for e in p.elements]
                return profile_from_elements(els, start_heading=units.deg2rad(p.start_heading_deg),
                                             name=self.name)
            if p.csv is not None:
                return read_profile_csv(p.csv)
            return Profile(np.asarray(p.points_mm, dtype=float) * 1e-3, name=self.name)
        except ModelError as err:
            raise SpecError(err.message, where=f"{self.name}: profile", hint=err.hint) from None

    def segmentation_result(self, profile: Profile | None = None) -> Segmentation:
        """Segment the profile as the spec says (raises :class:`SpecError` on failure)."""
        prof = self.profile_geometry() if profile is None else profile
        try:
            return segment_profile(prof, max_error_mm2_per_mm=self.segmentation.max_error_mm2_per_mm,
                                   n_segments=self.segmentation.n_segments)
        except ModelError as err:
            raise SpecError(err.message, where=f"{self.name}: segmentation", hint=err.hint) from None

    def build(self) -> BladeModel:
        """Build the :class:`BladeModel` (SI units, clamp frame, 0-based indices).

        Raises
        ------
        SpecError
            Bad profile, self-intersecting segmentation, a joint or sole on a segment that does
            not exist, or a sole ellipse that is not under the blade.
        """
        prof = self.profile_geometry()
        seg = self.segmentation_result(prof)
        n = seg.n
        mass, com, inertia = segment_mass_properties(prof, seg, self.mass_kg,
                                                     thickness=self._thickness_table())
        ks = self.joint_stiffness_Nm_per_deg()
        joints = []
        for i, (j, k) in enumerate(zip(self.joints, ks, strict=True)):
            a = j.between_segments[0]
            if a + 1 > n:
                raise SpecError(f"segments {list(j.between_segments)} do not exist: the blade has "
                                f"{n} segments", where=f"{self.name}: joints[{i}].between_segments",
                                hint="segment numbers are 1-based; check segmentation.n_segments")
            joints.append(CompliantJoint(
                point=a,
                stiffness=JOINT_PARAMETERS["K"].from_edge(k),
                damping=JOINT_PARAMETERS["D"].from_edge(j.D_Nms_per_deg),
                stiffness_quadratic=JOINT_PARAMETERS["K2"].from_edge(j.K2_Nm_per_deg2),
            ))
        joints.sort(key=lambda jt: jt.point)
        soles = tuple(self._sole(i, s, seg, prof) for i, s in enumerate(self.soles))
        tip = seg.points[-1]
        return BladeModel(
            name=self.model_name,
            points=seg.points.copy(),
            segment_mass=mass,
            segment_com=com,
            segment_inertia=inertia,
            joints=tuple(joints),
            soles=soles,
            tip=(float(tip[0]), float(tip[1])),
            tip_segment=n - 1,
            contact=self.contact.to_model(),
        )

    def _thickness_table(self) -> np.ndarray | None:
        if self.thickness_mm is None:
            return None
        return np.asarray(self.thickness_mm, dtype=float)

    def _sole(self, i: int, s: SoleSpec, seg: Segmentation, prof: Profile) -> SoleEllipse:
        where = f"{self.name}: soles[{i}]"
        if s.segment > seg.n:
            raise SpecError(f"segment {s.segment} does not exist: the blade has {seg.n} segments",
                            where=where + ".segment", hint="segment numbers are 1-based")
        a, b = seg.points[s.segment - 1], seg.points[s.segment]
        chord = b - a
        u = chord / float(np.hypot(*chord))
        normal = np.array([u[1], -u[0]])  # right of the direction clamp -> toe: under the sole
        centre = a + s.position * chord + s.offset_mm * 1e-3 * normal
        # Ellipse x axis along the chord, turned by angle_deg; angle about +y turns +x to -z.
        angle = math.atan2(-u[1], u[0]) + units.deg2rad(s.angle_deg)
        ell = SoleEllipse(segment=s.segment - 1, center=(float(centre[0]), float(centre[1])),
                          semi_axis_x=s.semi_axes_mm[0] * 1e-3, semi_axis_z=s.semi_axes_mm[1] * 1e-3,
                          angle=float(angle))
        low = _ellipse_lowest_z(ell)
        z_min = float(np.min(prof.points[:, 1]))
        height = prof.height
        if low >= 0.0 or low > z_min + _SOLE_LOW_FRACTION * height:
            raise SpecError(
                f"the ellipse is not under the blade: its lowest point is at z = {low * 1e3:.0f} mm, "
                f"the profile's lowest point at {z_min * 1e3:.0f} mm (allowed: within "
                f"{_SOLE_LOW_FRACTION * height * 1e3:.0f} mm above it)", where=where,
                hint="attach sole ellipses to the distal segments that touch the ground")
        dist = _point_segment_distance(centre, a, b)
        if dist > max(s.semi_axes_mm) * 1e-3 + _SOLE_ATTACH_MARGIN:
            raise SpecError(f"the ellipse centre is {dist * 1e3:.0f} mm from segment {s.segment}",
                            where=where + ".offset_mm",
                            hint="a sole ellipse must touch the segment it is welded to")
        return ell

    # ------------------------------------------------------------------ output
    def to_yaml(self) -> str:
        """The spec as YAML text (round-trips through :func:`read_blade_spec`)."""
        data = self.model_dump(mode="json", exclude_none=True)
        return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)

    def summary(self) -> dict[str, Any]:
        """Key numbers of the built blade (units in the key names)."""
        prof = self.profile_geometry()
        seg = self.segmentation_result(prof)
        model = self.build()
        return {
            "name": model.name,
            "description": self.description,
            "category": self.category,
            "mass_kg": model.mass,
            "profile_length_m": prof.length,
            "height_m": prof.height,
            "toe_length_m": prof.toe_length,
            "n_segments": seg.n,
            "segmentation_error_mm2_per_mm": seg.error,
            "segmentation_threshold_mm2_per_mm": seg.threshold,
            "rest_distance_m": model.rest_distance,
            "joints": [
                {"between_segments": [j.point, j.point + 1],
                 **{JOINT_PARAMETERS[n].edge_key: JOINT_PARAMETERS[n].to_edge(v) for n, v in (
                     ("K", j.stiffness), ("D", j.damping), ("K2", j.stiffness_quadratic))}}
                for j in model.joints],
            "soles": [{"segment": s.segment + 1, "center_x_m": s.center[0],
                       "center_z_m": s.center[1], "semi_axis_x_m": s.semi_axis_x,
                       "semi_axis_z_m": s.semi_axis_z, "angle_deg": float(units.rad2deg(s.angle))}
                      for s in model.soles],
            "contact_law": model.contact.law,
            "categories": {k: v.K_Nm_per_deg for k, v in self.categories.items()},
        }


def segment_mass_properties(
    profile: Profile,
    segmentation: Segmentation,
    mass_kg: float,
    *,
    thickness: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, centre of mass and inertia of each segment from the blade mass and its profile.

    The blade is a thin curved bar along the profile. Its linear density is uniform, or
    proportional to the thickness (``thickness``: rows of arc-length fraction [0–1] and thickness,
    linearly interpolated, constant beyond the ends) when given; the total is ``mass_kg``. Each
    segment gets the mass of its piece of the profile, with centre of mass and moment of inertia
    (about the centre of mass and the y axis) integrated along the curved piece; with a thickness
    table [mm], each piece also adds its cross-section term dm·t²/12 (the laminate's thickness
    lies in the x–z plane).

    Returns
    -------
    mass : (N,) [kg]
    com : (N, 2) [m] (x, z), clamp frame
    inertia : (N,) [kg·m²]
    """
    dense = profile.densified()
    # Split the dense polyline exactly at the segment breaks, so no piece straddles two segments.
    s = np.union1d(dense.arc_length, segmentation.breaks)
    s = s[np.concatenate([[True], np.diff(s) > 1e-12])]
    pts = profile.at(s)
    length = float(s[-1])
    mid_s = 0.5 * (s[:-1] + s[1:])
    mid = 0.5 * (pts[:-1] + pts[1:])
    ds = np.hypot(*np.diff(pts, axis=0).T)
    if thickness is None:
        lam = np.ones_like(ds)
    else:
        lam = np.interp(mid_s / length, thickness[:, 0], thickness[:, 1])
    dm = lam * ds
    dm *= mass_kg / dm.sum()
    which = np.clip(np.searchsorted(segmentation.breaks, mid_s, side="right") - 1,
                    0, segmentation.n - 1)
    n = segmentation.n
    mass = np.bincount(which, weights=dm, minlength=n)
    com = np.stack([np.bincount(which, weights=dm * mid[:, k], minlength=n) for k in (0, 1)],
                   axis=1) / mass[:, None]
    r2 = np.sum((mid - com[which]) ** 2, axis=1) + ds**2 / 12.0
    if thickness is not None:
        # The laminate's thickness lies in the x-z plane, across the profile: + t²/12 per piece.
        r2 = r2 + (lam * 1e-3) ** 2 / 12.0
    inertia = np.bincount(which, weights=dm * r2, minlength=n)
    return mass, com, inertia


def _ellipse_lowest_z(e: SoleEllipse) -> float:
    a = e.angle
    return float(e.center[1] - math.hypot(e.semi_axis_x * math.sin(a), e.semi_axis_z * math.cos(a)))


def _point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    t = float(np.clip((p - a) @ ab / (ab @ ab), 0.0, 1.0))
    return float(np.hypot(*(p - (a + t * ab))))


def _format_validation_error(err: pydantic.ValidationError) -> tuple[str, str]:
    """(where, message): the first error's field, and every error (up to five) in the message."""

    def one(e: dict) -> tuple[str, str]:
        loc = ".".join(str(x) for x in e["loc"]) or "(top level)"
        if e["type"] == "missing":
            return loc, "missing field"
        if e["type"] == "extra_forbidden":
            return loc, "unknown field (check the spelling and the unit in the name)"
        return loc, e["msg"]

    errors = [one(e) for e in err.errors()]
    where, msg = errors[0]
    if len(errors) > 1:
        others = "; ".join(f"{w}: {m}" for w, m in errors[1:5])
        more = f"; and {len(errors) - 5} more" if len(errors) > 5 else ""
        msg += f"; also {others}{more}"
    return where, msg


def spec_from_dict(data: Any, *, file: str | Path | None = None,
                   base_dir: Path | None = None) -> BladeSpec:
    """Validate a parsed YAML mapping as a :class:`BladeSpec` (raises :class:`SpecError`)."""
    if not isinstance(data, dict):
        raise SpecError("a blade spec must be a YAML mapping of fields", file=file,
                        hint="see docs/blade-spec.md")
    prof = data.get("profile")
    if base_dir is not None and isinstance(prof, dict) and isinstance(prof.get("csv"), str):
        csv = Path(prof["csv"])
        if not csv.is_absolute():
            data = {**data, "profile": {**prof, "csv": str((base_dir / csv).resolve())}}
    try:
        spec = BladeSpec.model_validate(data)
    except pydantic.ValidationError as err:
        where, msg = _format_validation_error(err)
        raise SpecError(msg, file=file, where=where, hint="see docs/blade-spec.md") from None
    spec.check_category(file=file)
    return spec


def read_blade_spec(path: str | Path, *, category: str | None = None,
                    check: bool = True) -> BladeSpec:
    """Read and validate a blade spec YAML file.

    Parameters
    ----------
    path
        YAML file. A ``profile.csv`` path is taken relative to the spec file.
    category
        Select this stiffness category (default: the file's ``category``).
    check
        Also build the blade once, so that geometric problems (sole not under the blade,
        self-intersecting segmentation, joint on a missing segment) raise here.

    Raises
    ------
    InputFileError
        Missing file or invalid YAML.
    SpecError
        Invalid content; the message names the field.
    """
    path = Path(path)
    data = read_yaml(path, what="blade spec")
    spec = spec_from_dict(data, file=path, base_dir=path.parent)
    if category is not None:
        spec = spec.with_category(category)
    if check:
        try:
            spec.build()
        except BladelabError as err:
            if err.file is None:
                err = type(err)(err.message, file=path, where=err.where, hint=err.hint)
            raise err from None
    return spec
