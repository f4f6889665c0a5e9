"""Scaling a runner parameter set's body to an athlete, and the muscles' strength it gives.

A parameter set's segment tables are for its reference athlete (1.80 m; seed 001 Table 2.1).
Segment masses and inertias scale by ``m/m_ref`` (inertias also by ``(h/h_ref)²``), all lengths
by ``h/h_ref``, the total muscle volume by ``m/m_ref`` (:func:`scale_ratios`); the thighs and
shanks may have their own length factors, and the transtibial residual tibia its own length
(:func:`residual_tibia_factors`). Muscle strength follows seed 001 eq. 2.1:
``Fmax = σ·φ·V_total / l_opt`` (σ in N/cm², V in cm³, l_opt in cm; :func:`muscle_max_force`).
:func:`athlete_params` gives the parameter set of another athlete (mass [kg], height [m],
muscle strength, fibre speed, segment lengths [m]).
"""

from __future__ import annotations

import math

from bladelab.errors import SpecError
from bladelab.runner.geometry import (
    ANKLE_TO_SOLE_M,
    RESIDUAL_TIBIA_FRACTION,
    THIGH_LENGTH_M,
    TIBIA_LENGTH_M,
)
from bladelab.runner.params import (
    MAX_SHORTENING_VELOCITY_RANGE,
    PROSTHESIS_EXTRA_LENGTH_RANGE_M,
    RESIDUAL_TIBIA_FRACTION_RANGE,
    SEGMENT_LENGTH_FACTOR_RANGE,
    RunnerParams,
    runner_params_from_dict,
)


def muscle_max_force(params: RunnerParams, muscle_type: str) -> float:
    """Fmax [N] of a muscle type for the (scaled) athlete: seed 001 eq. 2.1 from its volume
    fraction, or its table force times the mass ratio over the length ratio."""
    mt = params.muscle_types[muscle_type]
    mass_ratio, length_ratio = scale_ratios(params)
    if mt.max_isometric_force_N is not None:
        return mt.max_isometric_force_N * mass_ratio / length_ratio
    volume = params.total_muscle_volume_cm3 * mass_ratio
    l_opt_cm = mt.optimal_fiber_length_m * length_ratio * 100.0
    return params.specific_tension_N_per_cm2 * mt.volume_fraction * volume / l_opt_cm


def active_strength(params: RunnerParams) -> float:
    """The active force over Fmax [-]: the active over the set's specific tension (1 when the
    set gives no active specific tension)."""
    active = params.active_specific_tension_N_per_cm2
    return 1.0 if active is None else active / params.specific_tension_N_per_cm2


def residual_tibia_factors(params: RunnerParams) -> tuple[float, float]:
    """(mass factor, inertia factor) [-] of the transtibial residual tibia against the
    segment table's ``tibia_res_r`` (which is 60 % of the tibia long): its mass in proportion
    to its length, its inertia to mass × length² (a uniform rod's rule); (1, 1) for the
    other kinds and for the table's own length."""
    if params.kind != "amputee":
        return 1.0, 1.0
    k = params.residual_tibia_fraction / RESIDUAL_TIBIA_FRACTION
    return k, k**3


def leg_length_factor(params: RunnerParams) -> float:
    """The standing leg's length (hip joint to the sole) over the height-scaled model's [-]:
    1 unless the thighs or shanks have their own length factors."""
    scaled = (params.thigh_length_factor * THIGH_LENGTH_M
              + params.shank_length_factor * TIBIA_LENGTH_M + ANKLE_TO_SOLE_M)
    return scaled / (THIGH_LENGTH_M + TIBIA_LENGTH_M + ANKLE_TO_SOLE_M)


def scale_ratios(params: RunnerParams) -> tuple[float, float]:
    """(mass ratio, length ratio) of the athlete to the parameter set's segment tables: the
    muscles' forces scale with them (:func:`muscle_max_force`)."""
    table_mass = sum(s.mass_kg for s in params.segments.values())
    return params.athlete.body_mass_kg / table_mass, params.athlete.height_m / 1.80


def segment_mass_ratio(params: RunnerParams) -> float:
    """The segments' mass ratio [-]: the athlete's mass over the segment table's with the
    residual tibia at its own length (:func:`residual_tibia_factors`), so that the model
    weighs what the athlete does; :func:`scale_ratios`'s mass ratio for the table's
    residual tibia."""
    table_mass = sum(s.mass_kg for s in params.segments.values())
    if "tibia_res_r" in params.segments:
        table_mass += ((residual_tibia_factors(params)[0] - 1.0)
                       * params.segments["tibia_res_r"].mass_kg)
    return params.athlete.body_mass_kg / table_mass


#: The parameter set's fields that :func:`athlete_params` changes (the same body scaled to
#: another athlete has the same parameters but these).
ATHLETE_PARAM_FIELDS = frozenset({"athlete", "active_specific_tension_N_per_cm2",
                                  "max_shortening_velocity_lopt_per_s",
                                  "residual_tibia_fraction", "thigh_length_factor",
                                  "shank_length_factor", "prosthesis_extra_length_m"})
#: Fields of an athlete that :func:`athlete_params` changes, with their units.
ATHLETE_FIELDS = {"body_mass_kg": "kg", "height_m": "m", "muscle_strength": "-",
                  "max_shortening_velocity": "l_opt/s", "residual_limb_length_m": "m",
                  "thigh_length_m": "m", "shank_length_m": "m",
                  "prosthesis_extra_length_m": "m"}


def athlete_params(params: RunnerParams, *, body_mass_kg: float | None = None,
                   height_m: float | None = None,
                   muscle_strength: float | None = None,
                   max_shortening_velocity: float | None = None,
                   residual_limb_length_m: float | None = None,
                   thigh_length_m: float | None = None,
                   shank_length_m: float | None = None,
                   prosthesis_extra_length_m: float | None = None) -> RunnerParams:
    """The parameter set scaled to another athlete (None keeps the set's value).

    ``body_mass_kg`` [kg] and ``height_m`` [m] replace :class:`Athlete`'s: segment masses
    scale with the mass, lengths with the height over 1.80 m, inertias with mass times
    length squared, maximum isometric forces with mass over length (seed 001 eq. 2.1's rule;
    :func:`scale_ratios`). For an amputee the mass is the runner's with the prosthesis.
    ``muscle_strength`` [-] multiplies the fibres' active force (the active specific tension)
    and leaves the tendons and passive tissue as they are: 1 is the set's strength (on the
    human body, people's voluntary maxima times about 1.1); a trained sprinter's hip and knee
    muscles are about 1.3 times larger for their height and mass (Handsfield et al. 2017).
    ``max_shortening_velocity`` [optimal fibre lengths/s] replaces every muscle's maximum
    shortening velocity (:attr:`RunnerParams.max_shortening_velocity_lopt_per_s`, 10 unless
    set): the fibres' speed, which a larger fast-twitch share raises.
    ``residual_limb_length_m`` [m] is the transtibial amputee's residual tibia, knee joint to
    its distal end (:attr:`RunnerParams.residual_tibia_fraction` of the athlete's tibia,
    0.258 m at 1.80 m unless set). ``thigh_length_m`` and ``shank_length_m`` [m] are the
    athlete's thighs (hip to knee joint centre) and shanks (knee to ankle joint centre), e.g.
    from a static trial (:func:`bladelab.trial.segment_lengths`); unless set, 0.396 m and
    0.430 m times the height over 1.80 m. The residual limb's length is a fraction of the
    shank given here. ``prosthesis_extra_length_m`` [m] is how much longer the straight
    prosthetic leg stands than the intact one, knee to ground (the blade's height as the
    prosthetist sets it; 3 cm at 1.80 m unless set, scaled with the height).
    """
    data = params.model_dump()
    athlete = dict(data["athlete"])
    for name, value in (("body_mass_kg", body_mass_kg), ("height_m", height_m)):
        if value is not None:
            athlete[name] = value
    data["athlete"] = athlete
    if muscle_strength is not None:
        if not (isinstance(muscle_strength, int | float) and math.isfinite(muscle_strength)
                and muscle_strength > 0):
            raise SpecError(f"muscle strength must be a number > 0, got {muscle_strength!r}",
                            where="muscle_strength", hint="1 is the body's own strength")
        active = params.active_specific_tension_N_per_cm2 or params.specific_tension_N_per_cm2
        data["active_specific_tension_N_per_cm2"] = active * float(muscle_strength)
    if max_shortening_velocity is not None:
        lo, hi = MAX_SHORTENING_VELOCITY_RANGE
        if not _number_within(max_shortening_velocity, lo, hi):
            raise SpecError(f"the maximum shortening velocity must be within {lo:g}–{hi:g} "
                            f"optimal fibre lengths/s, got {max_shortening_velocity!r}",
                            where="athlete.max_shortening_velocity",
                            hint="10 is the body's own")
        data["max_shortening_velocity_lopt_per_s"] = float(max_shortening_velocity)
    ratio = athlete["height_m"] / 1.80
    for name, value, reference in (("thigh", thigh_length_m, THIGH_LENGTH_M),
                                   ("shank", shank_length_m, TIBIA_LENGTH_M)):
        if value is not None:
            data[f"{name}_length_factor"] = _length_factor(name, value, reference * ratio)
    if prosthesis_extra_length_m is not None:
        data["prosthesis_extra_length_m"] = _prosthesis_extra(
            params.kind, prosthesis_extra_length_m, ratio)
    if residual_limb_length_m is not None:
        tibia = TIBIA_LENGTH_M * ratio * data["shank_length_factor"]
        data["residual_tibia_fraction"] = _residual_fraction(
            params.kind, residual_limb_length_m, tibia, athlete["height_m"])
    return runner_params_from_dict(data, source="athlete")


def _number_within(value, lo: float, hi: float) -> bool:
    """Whether ``value`` is a number (not a bool) within ``lo``–``hi`` (NaN is not)."""
    return (isinstance(value, int | float) and not isinstance(value, bool)
            and lo <= value <= hi)


def _length_factor(name: str, length_m, model_m: float) -> float:
    """The length factor of a segment ``length_m`` [m] long against the model's ``model_m``
    [m]; a clear error outside :data:`SEGMENT_LENGTH_FACTOR_RANGE`."""
    lo, hi = (f * model_m for f in SEGMENT_LENGTH_FACTOR_RANGE)
    if not _number_within(length_m, lo, hi):
        raise SpecError(f"the {name}'s length must be within {lo:.3f}–{hi:.3f} m (80–130 % of "
                        f"the model's {model_m:.3f} m at this height), got {length_m!r}",
                        where=f"athlete.{name}_length_m",
                        hint=f"the {name} from the hip to the knee joint centre"
                        if name == "thigh" else "the shank from the knee to the ankle joint "
                        "centre")
    return float(length_m) / model_m


def _prosthesis_extra(kind: str, length_m, ratio: float) -> float:
    """The prosthetic leg's extra length at 1.80 m [m] for ``length_m`` [m] on an athlete
    ``ratio`` times 1.80 m tall; a clear error outside the accepted range or for the able
    runner."""
    where = "athlete.prosthesis_extra_length_m"
    if kind == "able":
        raise SpecError("the able runner has no prosthesis", where=where,
                        hint="the prosthetic leg's extra length is an amputee's")
    lo, hi = (x * ratio for x in PROSTHESIS_EXTRA_LENGTH_RANGE_M)
    if not _number_within(length_m, lo, hi):
        raise SpecError(f"the prosthetic leg's extra length must be within {lo:g}–{hi:.3g} m, "
                        f"got {length_m!r}", where=where,
                        hint="athletes' prostheses stand 0.02–0.08 m taller than the intact "
                             "leg; 0.03 m at 1.80 m is the body's own")
    return float(length_m) / ratio


def _residual_fraction(kind: str, length_m, tibia: float, height_m: float) -> float:
    """The residual tibia's fraction of the athlete's ``tibia`` [m] for a residual limb
    ``length_m`` [m] of an athlete ``height_m`` [m] tall; a clear error outside the accepted
    range or for a runner without a residual tibia."""
    where = "athlete.residual_limb_length_m"
    if kind != "amputee":
        raise SpecError(f"the {kind} runner has no residual tibia", where=where,
                        hint="the residual limb's length is the transtibial amputee's "
                             "(model amputee)")
    lo, hi = (f * tibia for f in RESIDUAL_TIBIA_FRACTION_RANGE)
    if not _number_within(length_m, lo, hi):
        raise SpecError(f"the residual limb's length must be within {lo:.3f}–{hi:.3f} m "
                        f"(20–90 % of the tibia of a {height_m:g} m athlete), got {length_m!r}",
                        where=where, hint=f"{RESIDUAL_TIBIA_FRACTION * tibia:.3f} m is the "
                        "body's own (60 % of the tibia)")
    return float(length_m) / tibia


__all__ = [
    "ATHLETE_FIELDS",
    "ATHLETE_PARAM_FIELDS",
    "active_strength",
    "athlete_params",
    "leg_length_factor",
    "muscle_max_force",
    "residual_tibia_factors",
    "scale_ratios",
    "segment_mass_ratio",
]
