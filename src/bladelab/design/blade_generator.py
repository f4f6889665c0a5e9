"""Design point -> multi-link blade spec.

:func:`generate_blade` turns the four design factors of seed 002 into a multi-link blade (default
6 rigid links joined by 5 spring-dampers, as seed 002), starting from a base blade spec with a
parametric profile (default the built-in ``xtreme``):

- **geometry**: the height factor changes the length of the proximal straight element (default:
  the first straight element), the toe-length factor the length of the distal arc (the last
  element, at constant radius); both lengths are solved together so that the built profile has
  exactly the requested build height and toe length (``Profile.height``, ``Profile.toe_length``);
- **segmentation**: ``n_segments`` equal-arc-length segments (default min(200, max(8·n_links, 48))); the
  ``n_links − 1`` hinges sit at the segment ends nearest to the centres of equal arc-length cells,
  (k − ½)/(n_links − 1) of the length;
- **springs from beam theory**: each hinge lumps the bending compliance of its cell (between the
  midpoints to its neighbouring hinges; the first and last cells reach the clamp and the tip):
  1/k_j = ∫_cell ds / (E·I(s)) with I = w·t(s)³/12 (t from the spec's thickness table, or
  ``thickness_mm``), i.e. k_j = E·I_j/ℓ_j for a uniform cell;
- **target stiffness** (``mode="target"``, when the point has a stiffness factor): all springs
  are scaled by one factor so that the virtual compression test
  (:func:`~bladelab.design.compression.vertical_stiffness`, load at the mount, support held
  horizontally) gives the target vertical stiffness; ``mode="beam"`` keeps the beam-theory values
  (then stiffness follows E, w and t: doubling the width doubles it);
- **damping** proportional to stiffness, D_j = β·K_j with β = D/K of the base spec's first joint
  unless ``damping_ratio_s`` is given;
- **width** scales the mass (and so the segment inertias) and the contact stiffness and damping
  by w / ``reference_width_m`` (the base spec does not state its width; 0.065 m assumed); mass
  also scales with the profile length.

The result holds the validated :class:`~bladelab.blade.spec.BladeSpec` (write it with
``spec.to_yaml()``) and the built :class:`~bladelab.blade.model.BladeModel`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import optimize

from bladelab import units
from bladelab.blade.catalogue import load_blade
from bladelab.blade.model import BladeModel
from bladelab.blade.profile import ProfileElement, profile_from_elements
from bladelab.blade.spec import BladeSpec, spec_from_dict
from bladelab.design import defaults
from bladelab.design.compression import vertical_stiffness
from bladelab.errors import ModelError, SpecError

__all__ = ["DEFAULT_FACTOR_ROLES", "GeneratedBlade", "generate_blade", "lumped_beam_stiffness"]

#: Which factor name plays which role (the names of :func:`default_design_space`).
DEFAULT_FACTOR_ROLES: dict[str, str] = {
    "stiffness": "stiffness_kN_per_m",
    "width": "width_m",
    "height": "height_m",
    "toe_length": "toe_length_m",
}

_DEFAULT_E_PA = 70e9  # flexural modulus of a carbon/epoxy laminate (assumed)
_DEFAULT_THICKNESS_MM = 12.0


@dataclass(frozen=True, eq=False)
class GeneratedBlade:
    """A blade generated from a design point.

    Attributes
    ----------
    spec
        The validated blade spec (multi-link joints, K in N·m/deg).
    model
        ``spec.build()``.
    vertical_stiffness
        Its virtual-compression-test stiffness [N/m].
    beam_vertical_stiffness
        The stiffness with the unscaled beam-theory springs [N/m].
    scale
        Factor applied to the beam-theory springs (1 in beam mode).
    height, toe_length, width
        Geometry of the generated blade [m].
    """

    spec: BladeSpec
    model: BladeModel
    vertical_stiffness: float
    beam_vertical_stiffness: float
    scale: float
    height: float
    toe_length: float
    width: float

    def to_dict(self) -> dict:
        return {
            "name": self.model.name,
            "vertical_stiffness_N_per_m": self.vertical_stiffness,
            "beam_vertical_stiffness_N_per_m": self.beam_vertical_stiffness,
            "scale": self.scale,
            "height_m": self.height,
            "toe_length_m": self.toe_length,
            "width_m": self.width,
            "mass_kg": self.model.mass,
            "joints": [
                {"point": j.point,
                 "K_Nm_per_deg": float(units.stiffness_per_rad_to_per_deg(j.stiffness)),
                 "D_Nms_per_deg": float(units.damping_per_rad_to_per_deg(j.damping))}
                for j in self.model.joints
            ],
        }


def _elements(spec: BladeSpec) -> list[tuple[float, float]]:
    if spec.profile.elements is None:
        raise ModelError(
            "the blade generator needs a base blade with a parametric profile (elements)",
            where=f"{spec.name}: profile",
            hint="use a built-in blade (xtreme, xceed) or a spec with profile.elements",
        )
    return [(e.length_mm, e.turn_deg) for e in spec.profile.elements]


def _profile(elements: list[tuple[float, float]], heading_deg: float):
    els = [ProfileElement(length * 1e-3, units.deg2rad(turn)) for length, turn in elements]
    return profile_from_elements(els, start_heading=units.deg2rad(heading_deg))


def _fit_geometry(
    elements: list[tuple[float, float]],
    heading_deg: float,
    height: float | None,
    toe_length: float | None,
    height_element: int,
    toe_element: int,
) -> list[tuple[float, float]]:
    """Element list with the height and toe elements resized to hit the targets."""
    els = [list(e) for e in elements]
    free: list[int] = []
    targets: list[float] = []
    if height is not None:
        free.append(height_element)
        targets.append(height)
    if toe_length is not None:
        free.append(toe_element)
        targets.append(toe_length)
    if not free:
        return [tuple(e) for e in els]
    curv = {i: els[i][1] / els[i][0] for i in free}  # deg per mm: constant radius

    def make(lengths_mm):
        new = [list(e) for e in els]
        for i, length in zip(free, lengths_mm, strict=True):
            new[i] = [float(length), float(curv[i] * length)]
        return new

    def resid(lengths_mm):
        prof = _profile(make(lengths_mm), heading_deg)
        out = []
        if height is not None:
            out.append(prof.height - height)
        if toe_length is not None:
            out.append(prof.toe_length - toe_length)
        return np.array(out) * 1e3  # mm

    x0 = np.array([els[i][0] for i in free], dtype=float)
    # diff_step: the profile is a polyline of arc points; tiny steps see its discreteness
    sol = optimize.least_squares(resid, x0, bounds=(np.full(len(free), 5.0), np.inf),
                                 xtol=1e-12, ftol=1e-12, gtol=1e-12, diff_step=1e-4)
    if np.max(np.abs(sol.fun)) > 1e-3:  # 1 µm
        raise ModelError(
            "the base profile cannot reach this height and toe length "
            f"(height {height}, toe length {toe_length} m; off by "
            f"{np.max(np.abs(sol.fun)):.1f} mm)",
            where="blade generator",
            hint="narrow the factor ranges around the base blade's geometry",
        )
    return [tuple(e) for e in make(sol.x)]


def _hinge_points(n_seg: int, n_links: int) -> list[int]:
    n_j = n_links - 1
    pts: list[int] = []
    for k in range(1, n_j + 1):
        target = (k - 0.5) / n_j * n_seg
        cand = sorted(range(1, n_seg), key=lambda p: (abs(p - target), p))
        pts.append(next(p for p in cand if p not in pts))
    return sorted(pts)


def _move_sole(sole: dict, n_seg0: int, n_seg: int) -> dict:
    """The same sole at the same arc-length fraction on a blade cut into ``n_seg`` segments."""
    frac = (sole["segment"] - 1 + sole.get("position", 0.5)) / n_seg0
    seg = min(n_seg, int(math.floor(frac * n_seg)) + 1)
    return {**sole, "segment": seg, "position": float(min(1.0, max(0.0, frac * n_seg - seg + 1)))}


def lumped_beam_stiffness(
    hinge_s: np.ndarray,
    length: float,
    *,
    youngs_modulus: float,
    width: float,
    thickness: np.ndarray | float,
    n_quad: int = 2000,
) -> np.ndarray:
    """Lumped rotational spring stiffness [N·m/rad] of each hinge from beam theory.

    Parameters
    ----------
    hinge_s
        Arc-length positions of the hinges [m], increasing.
    length
        Profile length L [m].
    youngs_modulus
        E [Pa].
    width
        Blade width w [m].
    thickness
        Constant thickness [m], or an (m, 2) table of (arc-length fraction, thickness [m]).
    n_quad
        Quadrature points over the blade.

    Returns
    -------
    numpy.ndarray
        k_j = 1 / ∫_cell ds/(E·I(s)), I = w·t³/12; cells end half-way between hinges, the
        first at the clamp and the last at the tip.
    """
    s_h = np.asarray(hinge_s, dtype=float)
    bounds = np.concatenate([[0.0], 0.5 * (s_h[1:] + s_h[:-1]), [length]])
    s = np.linspace(0.0, length, n_quad + 1)
    mid = 0.5 * (s[1:] + s[:-1])
    if np.ndim(thickness) == 0:
        t = np.full_like(mid, float(thickness))
    else:
        tab = np.asarray(thickness, dtype=float)
        t = np.interp(mid / length, tab[:, 0], tab[:, 1])
    flex = np.diff(s) / (youngs_modulus * width * t**3 / 12.0)  # ds / EI per piece
    cum = np.concatenate([[0.0], np.cumsum(flex)])
    at = np.interp(bounds, s, cum)
    return 1.0 / np.diff(at)


def generate_blade(
    point: Mapping[str, float],
    *,
    base: str | Path | BladeSpec = defaults.BASE_BLADE,
    n_links: int = 6,
    mode: str = "target",
    roles: Mapping[str, str] | None = None,
    youngs_modulus_Pa: float = _DEFAULT_E_PA,
    reference_width_m: float = 0.065,
    thickness_mm: float | None = None,
    damping_ratio_s: float | None = None,
    n_segments: int | None = None,
    height_element: int | None = None,
    toe_element: int = -1,
    alignment_deg: float = 0.0,
    tip: str = "held",
    name: str | None = None,
) -> GeneratedBlade:
    """A multi-link blade for a design point.

    Parameters
    ----------
    point
        ``{factor: value}`` in the factors' units; the factors named in ``roles`` are used:
        stiffness [kN/m] (target vertical stiffness), width [m], height [m], toe length [m].
        Missing factors keep the base blade's value (width: ``reference_width_m``).
    base
        Base blade (built-in name, spec file or spec) with a parametric profile.
    n_links
        Rigid links (``n_links − 1`` spring-dampers), 2 ≤ n_links ≤ n_segments.
    mode
        ``"target"``: scale the springs to the target stiffness (if the point has one);
        ``"beam"``: keep the beam-theory springs.
    roles
        Role -> factor name; default :data:`DEFAULT_FACTOR_ROLES`.
    youngs_modulus_Pa
        Flexural modulus E [Pa] of the laminate (cancels out in target mode).
    reference_width_m
        The base blade's width [m]; mass and contact scale with width / this.
    thickness_mm
        Constant laminate thickness [mm]; default the base spec's thickness table (else 12 mm).
    damping_ratio_s
        β = D/K [s]; default the base spec's first joint's D/K.
    n_segments
        Segments of the built blade; default min(200, max(8·n_links, 48)).
    height_element, toe_element
        Indices of the profile elements resized for height (default: the first straight
        element, else element 0) and toe length (default: the last).
    alignment_deg, tip
        Set-up of the virtual compression test used for the target.
    name
        Name of the generated blade.
    """
    roles = {**DEFAULT_FACTOR_ROLES, **(roles or {})}
    if mode not in ("target", "beam"):
        raise SpecError(f"mode must be 'target' or 'beam', got {mode!r}", where="mode")
    known = set(roles.values())
    unknown = [k for k in point if k not in known]
    if unknown:
        raise SpecError(
            f"the blade generator does not know factor(s) {unknown}",
            where="design point",
            hint=f"its roles are {roles}; pass roles= to map your factor names",
        )
    values = {role: float(point[fname]) for role, fname in roles.items() if fname in point}
    for role, v in values.items():
        if not math.isfinite(v) or v <= 0:
            raise SpecError(f"{roles[role]} must be positive, got {v}", where="design point")
    spec0 = base if isinstance(base, BladeSpec) else load_blade(base)
    n_links = int(n_links)
    n_seg = int(n_segments) if n_segments is not None else min(200, max(8 * n_links, 48))
    if not 2 <= n_links <= n_seg or n_seg > 200:
        raise ModelError(
            f"need 2 <= n_links <= n_segments <= 200, got n_links={n_links}, n_segments={n_seg}",
            where="n_links",
        )
    els0 = _elements(spec0)
    heading = spec0.profile.start_heading_deg
    if height_element is None:
        straight = [i for i, (_, turn) in enumerate(els0) if turn == 0.0]
        height_element = straight[0] if straight else 0
    toe_i = toe_element % len(els0)
    if height_element % len(els0) == toe_i and "height" in values and "toe_length" in values:
        raise ModelError("height and toe length need two different profile elements",
                         where="height_element")
    els = _fit_geometry(els0, heading, values.get("height"), values.get("toe_length"),
                        height_element % len(els0), toe_i)
    prof0 = _profile(els0, heading)
    prof = _profile(els, heading)
    width = values.get("width", reference_width_m)
    w_ratio = width / reference_width_m

    # joints, springs
    hinge_pts = _hinge_points(n_seg, n_links)
    length = prof.length
    hinge_s = np.array(hinge_pts, dtype=float) / n_seg * length
    if thickness_mm is not None:
        thick: np.ndarray | float = float(thickness_mm) * 1e-3
    elif spec0.thickness_mm is not None:
        thick = np.asarray(spec0.thickness_mm, dtype=float) * np.array([1.0, 1e-3])
    else:
        thick = _DEFAULT_THICKNESS_MM * 1e-3
    k_beam = lumped_beam_stiffness(hinge_s, length, youngs_modulus=youngs_modulus_Pa,
                                   width=width, thickness=thick)
    j0 = spec0.joints[0]
    k0 = spec0.joint_stiffness_Nm_per_deg()[0]
    beta = damping_ratio_s if damping_ratio_s is not None else j0.D_Nms_per_deg / k0

    data = spec0.model_dump(mode="json", exclude_none=True)
    data["name"] = name or f"{spec0.name}-design-{n_links}link"
    data["description"] = f"generated from {spec0.name} for design point {dict(point)}"
    data["profile"] = {"start_heading_deg": heading,
                       "elements": [{"length_mm": a, "turn_deg": b} for a, b in els]}
    data["segmentation"] = {"n_segments": n_seg}
    data["mass_kg"] = float(spec0.mass_kg * w_ratio * length / prof0.length)
    data.pop("categories", None)
    data.pop("category", None)
    n_seg0 = spec0.segmentation_result().n
    data["soles"] = [_move_sole(s.model_dump(mode="json"), n_seg0, n_seg) for s in spec0.soles]
    contact = dict(data.get("contact", {}))
    for key in ("stiffness_N_per_m", "stiffness_N_per_m_pow_n", "damping_Ns_per_m"):
        if key in contact:
            contact[key] = float(contact[key]) * w_ratio
    if "stiffness_N_per_m" not in contact and contact.get("law", "spring_damper") == "spring_damper":
        contact["stiffness_N_per_m"] = 1.0e6 * w_ratio
    data["contact"] = contact

    def with_k(k_rad: np.ndarray) -> BladeSpec:
        k_deg = units.stiffness_per_rad_to_per_deg(k_rad)
        data["joints"] = [
            {"between_segments": [p, p + 1], "K_Nm_per_deg": float(k),
             "D_Nms_per_deg": float(beta * k), "K2_Nm_per_deg2": 0.0}
            for p, k in zip(hinge_pts, k_deg, strict=True)
        ]
        return spec_from_dict(data)

    spec_beam = with_k(k_beam)
    model_beam = spec_beam.build()
    k_v_beam = vertical_stiffness(model_beam, alignment_deg=alignment_deg, tip=tip)
    scale = 1.0
    if mode == "target" and "stiffness" in values:
        scale = values["stiffness"] * 1e3 / k_v_beam
    spec = with_k(k_beam * scale) if scale != 1.0 else spec_beam
    model = model_beam.with_joint_parameters(  # = spec.build(), without building twice
        np.array([j.stiffness for j in model_beam.joints]) * scale,
        np.array([j.damping for j in model_beam.joints]) * scale,
    )
    k_v = vertical_stiffness(model, alignment_deg=alignment_deg, tip=tip)
    return GeneratedBlade(
        spec=spec, model=model, vertical_stiffness=float(k_v),
        beam_vertical_stiffness=float(k_v_beam), scale=float(scale), height=prof.height,
        toe_length=prof.toe_length, width=float(width),
    )
