"""Parameter sets of the planar runner: athlete, segments, muscles and the blade category.

A parameter set is a YAML file validated by pydantic (:class:`RunnerParams`). The built-in ones,
``able`` and ``amputee``, hold the tables of seed 001 (Table 2.1 segment masses and inertias,
Table 2.2 muscle parameters) in ``bladelab/data/runner/``; the blade catalogue
(``categories.yaml``, :mod:`bladelab.runner.blade_categories`) holds Table 2.3 and Table 1.1.

Muscle strength (seed 001 eq. 2.1) and the scaling of a set's body to an athlete:
:mod:`bladelab.runner.scaling`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from bladelab._io import read_yaml
from bladelab.errors import InputFileError, SpecError
from bladelab.runner.blade_categories import (
    BLADE_DISSIPATION_S_PER_M,
    BLADE_EXTRA_LENGTH_M,
    blade_category,
)
from bladelab.runner.geometry import (
    LEG_MUSCLES,
    RESIDUAL_TIBIA_FRACTION,
    SHANK_MUSCLES,
    TORSO_MUSCLES,
)
from bladelab.runner.muscle import V_MAX_OPT_PER_S
from bladelab.runner.prosthetic_knee import ProstheticKnee

#: Folder of the runner models' data files (parameter sets, categories, stored strides,
#: reflex starts).
RUNNER_DATA_DIR = Path(__file__).resolve().parents[1] / "data" / "runner"
#: The reflex controller's starting points: SCONE's parameters and seed 001's two gaits (warm
#: starts, not accepted solutions; its README).
REFLEX_STARTS_DIR = RUNNER_DATA_DIR / "reflex-starts"
FOOT_PLANE_STRAIN_MODULUS = 2.7e6
FOOT_FRICTION = 0.9
FOOT_DISSIPATION_S_PER_M = 1.0


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Athlete(_Strict):
    """Body mass [kg] and height [m] of the athlete (the model is scaled to them)."""

    body_mass_kg: float = Field(gt=0)
    height_m: float = Field(gt=0.5, lt=2.6)


class Segment(_Strict):
    """Mass [kg] and principal inertia [kg·m²] (OpenSim axes Ixx, Iyy, Izz) of one segment."""

    mass_kg: float
    inertia_kg_m2: tuple[float, float, float]

    @field_validator("mass_kg")
    @classmethod
    def _positive_mass(cls, v: float) -> float:
        if not v > 0:
            raise ValueError(f"mass must be positive, got {v} kg")
        return v

    @field_validator("inertia_kg_m2")
    @classmethod
    def _positive_inertia(cls, v: tuple[float, float, float]) -> tuple[float, float, float]:
        if min(v) <= 0:
            raise ValueError(f"inertias must be positive, got {v}")
        return v


class MuscleType(_Strict):
    """Muscle–tendon parameters of one muscle type (lengths in m, pennation in rad).

    The strength is either a share of the total muscle volume (``volume_fraction``, seed 001
    eq. 2.1 with the set's specific tension) or the maximum isometric force of a published
    model (``max_isometric_force_N``, for the parameter set's own segment table; scaled to the
    athlete as eq. 2.1 scales: by the mass ratio over the length ratio). Exactly one is given.
    """

    volume_fraction: float | None = Field(default=None, gt=0, lt=1)
    max_isometric_force_N: float | None = Field(default=None, gt=0)
    optimal_fiber_length_m: float = Field(gt=0)
    tendon_slack_length_m: float = Field(gt=0)
    pennation_rad: float = Field(ge=0, lt=1.2)
    #: Tendon strain at Fmax [-] (the tendon curve is ``(ε/ε_ref)²``). Default: Geyer & Herr
    #: (2010)'s 4 %, which seed 001's model uses for every muscle.
    tendon_strain_at_fmax: float = Field(default=0.04, gt=0.005, lt=0.2)
    #: Fibre strain at which the passive fibre force reaches Fmax [-] (e₀ of the curve
    #: ``((l̃ − 1)/e₀)²``). Default: 0.6, the curve of seed 001's model.
    passive_strain_at_fmax: float = Field(default=0.6, gt=0.1, le=3.0)

    @model_validator(mode="after")
    def _one_strength(self) -> MuscleType:
        if (self.volume_fraction is None) == (self.max_isometric_force_N is None):
            raise ValueError("give exactly one of volume_fraction and max_isometric_force_N")
        return self


class FootContact(_Strict):
    """The Hunt–Crossley law of the foot's contact spheres (heel, ball, toe tip)."""

    #: Plane-strain modulus E [N/m²] of the Hertz law ``F = 4/3·E·√R·δ^1.5``.
    plane_strain_modulus_N_per_m2: float = Field(default=FOOT_PLANE_STRAIN_MODULUS, gt=0)
    #: Hunt–Crossley dissipation c [s/m].
    dissipation_s_per_m: float = Field(default=FOOT_DISSIPATION_S_PER_M, ge=0)
    #: Friction coefficient [-].
    friction: float = Field(default=FOOT_FRICTION, gt=0)


class CapsuleMoment(_Strict):
    """A joint's passive moment within its range, ``M(q) = M₀·exp(r·q)`` [N·m] (q in degrees):
    the capsule and ligaments, which the muscles' passive fibre forces do not include (e.g.
    the hip capsule that resists extension; Riener & Edrich 1999)."""

    #: Moment at q = 0 [N·m], positive along the coordinate.
    moment_at_zero_Nm: float
    #: Rate r [1/deg] (negative: growing as q decreases, i.e. into extension for a hip).
    rate_per_deg: float = Field(ge=-0.5, le=0.5)


class ToeHinge(_Strict):
    """The passive metatarsophalangeal hinge of ``RunnerParams.foot = "toes"``: a linear
    spring and damper about the neutral pose, ``−K·q − D·q̇`` (docs/runner-model.md, "The toe
    segment"). Defaults: Sasaki, Neptune & Kautz (2009), as OpenSim's gait models have it."""

    #: Rotational stiffness K [N·m/rad].
    stiffness_Nm_per_rad: float = Field(default=25.0, ge=0)
    #: Damping D [N·m·s/rad]. 0.03 leaves the light toe segment (about 2·10⁻⁴ kg·m² about its
    #: hinge) ringing at about 50 Hz; PredSim's passive toes (Falisse, Afschrift & De Groote
    #: 2022) use 2.
    damping_Nms_per_rad: float = Field(default=0.03, ge=0)


class ArchSpring(_Strict):
    """The foot's longitudinal arch as a midtarsal hinge with a passive spring and damper
    (docs/runner-model.md, "The arch"): the calcaneus carries the heel, the forefoot the ball
    and the toes. The moment about the hinge is ``−K·q − D·q̇`` (q > 0: the forefoot turned up
    against the rearfoot, the arch compressed)."""

    #: Rotational stiffness K [N·m/rad]. Default 1,000: the arch then stores about 16 J under
    #: a 2,000 N load on the ball (Ker et al. 1987 measured 17 J at 4.5 m/s).
    stiffness_Nm_per_rad: float = Field(default=1000.0, gt=0)
    #: Damping D [N·m·s/rad]. Default 3: about 22 % of the stored energy lost over a 0.25 s
    #: stance (Ker et al. 1987: the arch returned 78 %).
    damping_Nms_per_rad: float = Field(default=3.0, ge=0)


#: Coordinates (both legs) that may carry a capsule moment.
CAPSULE_COORDINATES = ("hip_flexion", "knee_angle", "ankle_angle")


#: The model kinds: seed 001's able-bodied and transtibial ("amputee") runners, and the
#: transfemoral runner (docs/runner-model.md, "The transfemoral runner").
KINDS = ("able", "amputee", "transfemoral")
#: The kinds with a prosthetic right leg (a blade, no shank muscles on that side).
PROSTHETIC_KINDS = ("amputee", "transfemoral")
#: Muscles of the transfemoral runner's residual limb: the monoarticular hip muscles, whose
#: attachments the amputation keeps (the biarticular hamstrings and rectus femoris lose their
#: tibial insertion; :data:`MYODESIS_MUSCLES` with ``RunnerParams.myodesis``).
RESIDUAL_THIGH_MUSCLES = ("glut_max", "iliopsoas")
#: The biarticular thigh muscles that a myodesis re-attaches to the distal end of the residual
#: femur, where they become monoarticular hip muscles (``RunnerParams.myodesis``).
MYODESIS_MUSCLES = ("hamstrings", "rect_fem")


#: The range of a muscle's maximum shortening velocity [optimal fibre lengths/s] a parameter
#: set may give: wide enough for a sensitivity study over the physiological range (Miller,
#: Umberger & Caldwell 2012 varied it so), around the models' usual 10.
MAX_SHORTENING_VELOCITY_RANGE = (2.0, 30.0)

#: The range of the transtibial residual tibia's length [fraction of the tibia, knee to
#: ankle] a parameter set may give: from a short residual limb (about 9 cm at 1.80 m) to a
#: long one that leaves the socket 4 cm above the ankle.
RESIDUAL_TIBIA_FRACTION_RANGE = (0.2, 0.9)

#: The range of a segment length factor (thigh, shank) a parameter set may give, relative to
#: the height-scaled model's segment: people of one height differ by about ±10 % in each.
SEGMENT_LENGTH_FACTOR_RANGE = (0.8, 1.3)

#: The range of the prosthetic leg's extra length [m, at 1.80 m] a parameter set may give:
#: athletes' running-specific prostheses are set so that the prosthetic leg stands 2–8 cm
#: taller than the intact one (Taboga et al. 2020, Sci Rep 10:1763), and a little more.
PROSTHESIS_EXTRA_LENGTH_RANGE_M = (0.0, 0.10)


class RunnerParams(_Strict):
    """A runner parameter set (one YAML file)."""

    kind: Literal["able", "amputee", "transfemoral"]
    blade: str = "Cat6"
    athlete: Athlete
    specific_tension_N_per_cm2: float = Field(gt=0)
    total_muscle_volume_cm3: float = Field(gt=0)
    #: Specific tension of the fibres' active force [N/cm²]; None: ``specific_tension``. The
    #: muscles' Fmax (eq. 2.1 or the table's forces, at ``specific_tension``) normalises their
    #: tendon and passive curves; the active force is stronger by the ratio of the two
    #: (:func:`~bladelab.runner.scaling.active_strength`), so that a literature specific
    #: tension does not stiffen the tendons or the passive tissue.
    active_specific_tension_N_per_cm2: float | None = Field(default=None, gt=0)
    #: Every muscle's maximum shortening velocity [optimal fibre lengths/s]: the force–velocity
    #: curve's zero and the metabolic model's velocity scale. 10 (Zajac 1989; OpenSim's
    #: default) unless set; faster fibres (a sprinter's larger fast-twitch share) raise it.
    max_shortening_velocity_lopt_per_s: float = Field(
        default=V_MAX_OPT_PER_S, ge=MAX_SHORTENING_VELOCITY_RANGE[0],
        le=MAX_SHORTENING_VELOCITY_RANGE[1])
    #: The transtibial runner's residual tibia: its length as a fraction of the tibia (knee to
    #: ankle) [-]. 0.6 unless set (seed 001's model; the segment table's ``tibia_res_r`` is
    #: this residual tibia). Its mass follows its length, its inertia mass × length²
    #: (:func:`~bladelab.runner.scaling.residual_tibia_factors`); the prosthesis below it keeps
    #: the leg's length. Ignored by the other kinds.
    residual_tibia_fraction: float = Field(
        default=RESIDUAL_TIBIA_FRACTION, ge=RESIDUAL_TIBIA_FRACTION_RANGE[0],
        le=RESIDUAL_TIBIA_FRACTION_RANGE[1])
    #: Both thighs' length (hip to knee joint centre) over the height-scaled model's
    #: (``THIGH_LENGTH_M``, 0.396 m at 1.80 m) [-]: the femur's joints, muscle points and inertia
    #: scale with it (its mass stays), and every muscle's optimal fibre and tendon slack lengths
    #: follow its muscle–tendon length standing straight (OpenSim's scaling rule).
    thigh_length_factor: float = Field(default=1.0, ge=SEGMENT_LENGTH_FACTOR_RANGE[0],
                                       le=SEGMENT_LENGTH_FACTOR_RANGE[1])
    #: The same for both shanks (knee to ankle joint centre, the tibia's
    #: ``TIBIA_LENGTH_M`` at 1.80 m; the residual tibia keeps its fraction of it) [-].
    shank_length_factor: float = Field(default=1.0, ge=SEGMENT_LENGTH_FACTOR_RANGE[0],
                                       le=SEGMENT_LENGTH_FACTOR_RANGE[1])
    #: How much longer the straight prosthetic leg is than the intact one, knee to ground
    #: [m, at 1.80 m; scaled with the height]: the blade's height as the prosthetist sets it.
    #: 0.03 unless set (seed 001's athlete); the transtibial and transfemoral runners'.
    #: Ignored by the able runner.
    prosthesis_extra_length_m: float = Field(
        default=BLADE_EXTRA_LENGTH_M, ge=PROSTHESIS_EXTRA_LENGTH_RANGE_M[0],
        le=PROSTHESIS_EXTRA_LENGTH_RANGE_M[1])
    segments: dict[str, Segment]
    muscle_types: dict[str, MuscleType]
    #: Gravity of this model [m/s²]: 9.81, the value the seed-001 runner and its shipped reflex
    #: solutions were built with (not bladelab.constants.STANDARD_GRAVITY; a change would make
    #: those fragile solutions fall).
    gravity_m_per_s2: float = Field(default=9.81, gt=0)
    #: Hunt–Crossley dissipation c [s/m] of the blade sphere. Default: seed 001's 0.2 s/m, with
    #: which seed 001's reflex gaits (the reflex starts) were optimised; the sphere then returns about 54 % of
    #: the energy it stores per prosthetic stance (docs/runner-model.md, "Blade energy return").
    #: 0.02 s/m returns about 94 %, 0 s/m 100 % (an elastic blade, as seed 001's Table D.1
    #: reports). Opt-in: a change makes those fragile solutions fall.
    blade_dissipation_s_per_m: float = Field(default=BLADE_DISSIPATION_S_PER_M, ge=0)
    #: The foot: ``"rigid"`` (seed 001: one calcaneus segment with a heel and a ball sphere) or
    #: ``"toes"`` (a toe segment on a passive metatarsophalangeal hinge, with a toe-tip sphere;
    #: docs/runner-model.md, "The toe segment"). Changes the model's coordinates.
    foot: Literal["rigid", "toes"] = "rigid"
    #: The foot's arch (:class:`ArchSpring`): a midtarsal hinge between the calcaneus and the
    #: forefoot, only with ``foot = "toes"``; None (the default): the calcaneus and forefoot
    #: are one rigid segment. Changes the model's coordinates.
    arch: ArchSpring | None = None
    #: The toes' passive hinge (:class:`ToeHinge`), only with ``foot = "toes"``.
    toe_hinge: ToeHinge = Field(default_factory=ToeHinge)
    #: The foot's contact law.
    foot_contact: FootContact = Field(default_factory=FootContact)
    #: Flexion [deg] at which the knee ligament engages: seed 001's 90°; people flex the knee
    #: to about 140° (the swing of sprinting comes close to it).
    knee_flexion_limit_deg: float = Field(default=90.0, gt=30.0, le=170.0)
    #: The lumbar joint's passive torque: ``"ligament"`` (seed 001: a soft limit at 0° both
    #: ways, 500 N·m/rad and 5 N·m·s/rad, that pushes back and never pulls, so that its damping
    #: jumps by 5 N·m·s/rad × q̇ where the trunk crosses 0°) or ``"spring"`` (the same stiffness
    #: and damping as a linear spring–damper about 0°: smooth, and the same law in the forward
    #: model and the collocation twin, which has to smooth the ligament's jump).
    lumbar_passive: Literal["ligament", "spring"] = "ligament"
    #: Passive capsule moments by coordinate (:data:`CAPSULE_COORDINATES`, both legs; not on
    #: a prosthetic joint); none by default (seed 001's model).
    capsule_moments: dict[str, CapsuleMoment] = Field(default_factory=dict)
    #: The prosthetic knee of the transfemoral runner (ignored by the other kinds).
    prosthetic_knee: ProstheticKnee = Field(default_factory=ProstheticKnee)
    #: The transfemoral runner's residual limb: False (the monoarticular hip muscles only,
    #: :data:`RESIDUAL_THIGH_MUSCLES`) or True (a myodesis: the hamstrings and rectus femoris
    #: also act at the hip, anchored on the distal femur where their tibial insertion was with
    #: the knee straight; :data:`MYODESIS_MUSCLES`). Ignored by the other kinds.
    myodesis: bool = False
    #: The transfemoral runner's residual limb: a factor on the maximal isometric force of
    #: each of its muscles, by type (:data:`RESIDUAL_THIGH_MUSCLES`, :data:`MYODESIS_MUSCLES`);
    #: a type not named keeps the intact leg's force (factor 1: an upper bound for a
    #: residual limb). Fmax scales the active, passive and tendon forces and the metabolic
    #: muscle mass alike (an atrophied muscle has a smaller cross-section). Ignored by the
    #: other kinds.
    residual_muscle_strength: dict[str, float] = Field(default_factory=dict)
    #: The muscles' metabolic energy model: ``"uchida2016"`` (seed 001 eq. 2.5: Umberger 2003
    #: as modified by Uchida et al. 2016; :mod:`bladelab.runner.metabolics`) or
    #: ``"bhargava2004"`` (Bhargava et al. 2004, as PredSim computes it).
    metabolic_model: Literal["uchida2016", "bhargava2004"] = "uchida2016"

    @field_validator("residual_muscle_strength")
    @classmethod
    def _residual_muscles(cls, value: dict[str, float]) -> dict[str, float]:
        known = RESIDUAL_THIGH_MUSCLES + MYODESIS_MUSCLES
        unknown = sorted(set(value) - set(known))
        if unknown:
            raise ValueError(f"unknown residual limb muscle(s) {', '.join(unknown)}; known: "
                             f"{', '.join(known)}")
        bad = {k: v for k, v in value.items() if not (math.isfinite(v) and 0 < v <= 2)}
        if bad:
            raise ValueError(f"a strength factor must be within (0, 2], got {bad}")
        return value

    @model_validator(mode="after")
    def _arch_needs_toes(self) -> RunnerParams:
        if self.arch is not None and self.foot != "toes":
            raise ValueError('arch: a midtarsal hinge needs the toe segment (foot: toes)')
        return self

    @model_validator(mode="after")
    def _known_capsules(self) -> RunnerParams:
        unknown = sorted(set(self.capsule_moments) - set(CAPSULE_COORDINATES))
        if unknown:
            raise ValueError(f"capsule_moments: unknown coordinate(s) {', '.join(unknown)}; "
                             f"known: {', '.join(CAPSULE_COORDINATES)}")
        return self


def required_segments(kind: str) -> tuple[str, ...]:
    """Segment names a parameter set of this kind must have."""
    common = ("torso", "pelvis", "femur_l", "tibia_l", "calcn_l", "femur_r")
    if kind == "amputee":
        return common + ("tibia_res_r", "prosthesis_r")
    if kind == "transfemoral":
        return common + ("prosthesis_r",)
    return common + ("tibia_r", "calcn_r")


def muscle_names(kind: str, myodesis: bool = False) -> tuple[str, ...]:
    """The model's muscle–tendon units in order: intact/left leg, right leg, torso
    (``myodesis``: see :attr:`RunnerParams.myodesis`)."""
    left = tuple(f"{m}_l" for m in LEG_MUSCLES)
    if kind == "transfemoral":
        residual = RESIDUAL_THIGH_MUSCLES + (MYODESIS_MUSCLES if myodesis else ())
        right_types = [m for m in LEG_MUSCLES if m in residual]
    else:
        right_types = [m for m in LEG_MUSCLES if kind == "able" or m not in SHANK_MUSCLES]
    right = tuple(f"{m}_r" for m in right_types)
    torso = tuple(f"{m}_{s}" for m in TORSO_MUSCLES for s in ("r", "l"))
    return left + right + torso


def _check(params: RunnerParams, source: str | None) -> RunnerParams:
    missing = [s for s in required_segments(params.kind) if s not in params.segments]
    if missing:
        raise SpecError(
            f"missing segment(s) {', '.join(missing)} for a {params.kind} model",
            file=source,
            where="segments",
            hint=f"a {params.kind} model needs {', '.join(required_segments(params.kind))}",
        )
    extra = [s for s in params.segments if s not in required_segments(params.kind)]
    if extra:
        raise SpecError(
            f"unknown segment(s) {', '.join(extra)} for a {params.kind} model",
            file=source,
            where="segments",
            hint=f"use {', '.join(required_segments(params.kind))}",
        )
    types = set(LEG_MUSCLES) | set(TORSO_MUSCLES)
    missing = sorted(types - set(params.muscle_types))
    if missing:
        raise SpecError(
            f"missing muscle(s) {', '.join(missing)}",
            file=source,
            where="muscle_types",
            hint=f"the model needs parameters for {', '.join(sorted(types))}",
        )
    unknown = sorted(set(params.muscle_types) - types)
    if unknown:
        raise SpecError(
            f"unknown muscle(s) {', '.join(unknown)}",
            file=source,
            where="muscle_types",
            hint=f"known muscles: {', '.join(sorted(types))}",
        )
    return params


def runner_params_from_dict(data: dict, *, source: str | None = None) -> RunnerParams:
    """Validate a parameter dictionary; errors name the field and how to fix it."""
    try:
        params = RunnerParams.model_validate(data)
    except ValidationError as err:
        first = err.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise SpecError(
            first["msg"],
            file=source,
            where=where,
            hint="see bladelab/data/runner/amputee.yaml for a complete parameter set",
        ) from None
    if params.kind in PROSTHETIC_KINDS:
        try:
            blade_category(params.blade)
        except SpecError as err:
            raise SpecError(err.message, file=source, where="blade", hint=err.hint) from None
    return _check(params, source)


def read_runner_yaml(path: str | Path, *, _seen: tuple[Path, ...] = ()) -> dict:
    """A runner parameter YAML file as a dictionary, ``extends`` resolved: a file that names
    another (``extends: able.yaml``, a path relative to its own folder) is that file's
    parameters with this file's top-level keys replacing the other's (so a variant states only
    what differs: e.g. the amputee's athlete and segments; its muscles are the able runner's)."""
    path = Path(path)
    data = read_yaml(path, what="runner parameter file")
    if not isinstance(data, dict):
        raise InputFileError("expected a mapping of parameters", file=path)
    base = data.pop("extends", None)
    if base is None:
        return data
    if not isinstance(base, str) or not base:
        raise SpecError("expected the name of another parameter file", file=str(path),
                        where="extends", hint="e.g. extends: able.yaml (beside this file)")
    target = (path.parent / base).resolve()
    if target in _seen or target == path.resolve():
        raise SpecError(f"{base} extends this file again (a loop)", file=str(path),
                        where="extends")
    if not target.is_file():
        raise InputFileError(f"the file it extends, {base}, does not exist", file=path,
                             hint="name a parameter file beside this one")
    return {**read_runner_yaml(target, _seen=(*_seen, path.resolve())), **data}


def load_runner_params(path: str | Path) -> RunnerParams:
    """Read and validate a runner parameter YAML file (``extends`` resolved:
    :func:`read_runner_yaml`)."""
    return runner_params_from_dict(read_runner_yaml(path), source=str(path))


#: Named bodies of the built-in parameter sets. ``human``: segments and leg
#: muscles of SCONE's H0918 gait model (gait10dof18musc), tendons as compliant as people's, a
#: toe segment, the knee flexing to 140° (``bladelab/data/runner/human/``;
#: docs/runner-model.md, "The human body"). ``seed001``: seed 001's model as published (rigid
#: foot, every tendon at 4 % strain at Fmax). ``toes``: seed 001's body with a toe segment on a
#: passive metatarsophalangeal hinge and triceps-surae (Achilles) tendons at 8 % strain at Fmax
#: (docs/runner-model.md, "The toe segment and the Achilles tendon").
BODIES = ("human", "seed001", "toes")
#: Tendon strain at Fmax [-] of the ``toes`` body, per muscle type (others keep 4 %).
TOES_BODY_TENDON_STRAIN = {"soleus": 0.08, "gastroc": 0.08}


def default_runner_params(
    kind: str = "amputee", *, blade: str | None = None, body: str = "seed001"
) -> RunnerParams:
    """The built-in parameter set of a model kind (``able``, ``amputee`` or ``transfemoral``)
    with a body of :data:`BODIES`, optionally wearing another blade category."""
    if kind not in KINDS:
        raise SpecError(f"unknown model {kind!r}", where="model",
                        hint="use " + ", ".join(repr(k) for k in KINDS))
    if body not in BODIES:
        raise SpecError(f"unknown body {body!r}", where="body", hint=" or ".join(BODIES))
    folder = RUNNER_DATA_DIR / "human" if body == "human" else RUNNER_DATA_DIR
    data = read_runner_yaml(folder / f"{kind}.yaml")
    if blade is not None:
        data["blade"] = blade
    if body == "toes":
        data["foot"] = "toes"
        for name, strain in TOES_BODY_TENDON_STRAIN.items():
            data["muscle_types"][name]["tendon_strain_at_fmax"] = strain
    return runner_params_from_dict(data, source=f"built-in {kind} parameters ({body} body)")


__all__ = [
    "ArchSpring",
    "ToeHinge",
    "BODIES",
    "FootContact",
    "KINDS",
    "PROSTHETIC_KINDS",
    "REFLEX_STARTS_DIR",
    "RUNNER_DATA_DIR",
    "Athlete",
    "RunnerParams",
    "default_runner_params",
    "load_runner_params",
    "read_runner_yaml",
    "muscle_names",
    "runner_params_from_dict",
]
