"""The collocation options that ``bladelab predict`` and ``bladelab sweep`` share: people's
angles and swing knee, alternating steps, and the athlete (body mass, height, strength, fibre
speed, segment and residual-limb lengths, the prosthesis's height, a static trial).
"""

from __future__ import annotations

import math
from pathlib import Path

import typer

from bladelab.errors import SpecError
from bladelab.predict import defaults

__all__ = ["ATHLETE_OPTIONS", "COLLOCATION", "alternating_steps_option", "athlete_from_options",
           "athlete_option", "people_weight_option", "static_option", "swing_knee_option"]

#: The help panel of the collocation options.
COLLOCATION = "Collocation"


def people_weight_option():
    """``--people-weight``, the same on ``predict`` and ``sweep`` (collocation)."""
    return typer.Option(
        None, "--people-weight", rich_help_panel=COLLOCATION, show_default=False,
        help="Weight [1/rad²] of people's measured hip, knee and ankle angles at 3.5 m/s in "
             "the objective (a tracking term of measured running, reported as such; "
             f"docs/collocation.md). Default: {defaults.PEOPLE_WEIGHT_PER_RAD2:g} on the human "
             "body, 0 on the others; 0: the gait is predicted freely.")


def swing_knee_option():
    """``--swing-knee``, the same on ``predict`` and ``sweep`` (collocation)."""
    return typer.Option(
        None, "--swing-knee", rich_help_panel=COLLOCATION, show_default=False,
        help="Keep every knee that is a person's flexed at least this much [deg] at its peak "
             "in swing (a constraint from measured running, reported as such; "
             "docs/collocation.md). Default: people's "
             f"{defaults.SWING_KNEE_MIN_DEG:g} on the human body, none on the others; 0: "
             "free.")


def alternating_steps_option():
    """``--alternating-steps``, the same on ``predict`` and ``sweep`` (collocation)."""
    return typer.Option(
        None, "--alternating-steps", rich_help_panel=COLLOCATION, show_default=False,
        help="Keep the steps alternating: the second leg's stance half a stride +- this "
             "fraction of the stride after the first leg's, e.g. 0.1 (rules out a gallop).")


#: The athlete's options: library field -> (option, help).
ATHLETE_OPTIONS = {
    "body_mass_kg": ("--body-mass", "The athlete's body mass [kg] (an amputee's with the "
                     "prosthesis); segment masses, inertias and muscle forces scale with it. "
                     "Default: the parameter set's (human body: able 75 kg, amputee 73.2 kg)."),
    "height_m": ("--height", "The athlete's height [m] (default 1.80 m); segment lengths, "
                 "inertias and muscle forces scale with it."),
    "muscle_strength": ("--muscle-strength", "The muscles' active force relative to the "
                        "body's (1: people's maximal strength; a sprinter's hip and knee "
                        "muscles are about 1.3 times larger); tendons stay as they are."),
    "max_shortening_velocity": ("--max-shortening-velocity", "Every muscle's maximum "
                                "shortening velocity [optimal fibre lengths/s] (default 10; "
                                "faster fibres, a larger fast-twitch share, raise it)."),
    "residual_limb_length_m": ("--residual-limb", "The transtibial amputee's residual limb "
                               "[m]: the residual tibia from the knee joint to its end "
                               "(default 60 % of the tibia, 0.258 m at 1.80 m); the "
                               "prosthesis below it keeps the leg's length."),
    "thigh_length_m": ("--thigh-length", "The athlete's thighs [m], hip to knee joint centre "
                       "(default 0.396 m at 1.80 m, scaled with the height); the femur's "
                       "joints and muscle points, and the muscles' fibre and tendon lengths, "
                       "follow it."),
    "shank_length_m": ("--shank-length", "The athlete's shanks [m], knee to ankle joint "
                       "centre (default 0.430 m at 1.80 m, scaled with the height)."),
    "prosthesis_extra_length_m": ("--prosthesis-extra-length", "How much longer the straight "
                                  "prosthetic leg stands than the intact one, knee to ground "
                                  "[m]: the blade's height as set (athletes: 0.02-0.08 m; "
                                  "default 0.03 m at 1.80 m, scaled with the height)."),
}


def static_option(panel: str = COLLOCATION):
    """``--static``: thigh and shank lengths from a static trial (in the help ``panel``)."""
    return typer.Option(None, "--static", rich_help_panel=panel, show_default=False,
                        help="A static (standing) C3D trial of the athlete: the thighs and "
                             "shanks from its joint centres (Harrington's hips, epicondyles, "
                             "malleoli; both sides' mean, the intact leg's shank for an "
                             "amputee), unless --thigh-length or --shank-length are given.")


def athlete_option(field: str, panel: str = COLLOCATION):
    """One of :data:`ATHLETE_OPTIONS` as a typer option (default: the body's own) in the help
    ``panel``."""
    flag, text = ATHLETE_OPTIONS[field]
    return typer.Option(None, flag, rich_help_panel=panel, show_default=False, help=text)


def athlete_from_options(static: Path | None = None, **fields: float | None) -> dict | None:
    """The athlete of the options (library field -> value; None when none is given), with the
    segment lengths of a ``static`` trial where no option gives them."""
    athlete = {k: v for k, v in fields.items() if v is not None}
    if static is not None:
        from bladelab.trial import read_c3d, segment_lengths  # deferred: reads C3D

        lengths = segment_lengths(read_c3d(static))
        for name, per_side in (("thigh_length_m", lengths.thigh_m),
                               ("shank_length_m", lengths.shank_m)):
            known = [v for v in per_side.values() if math.isfinite(v)]
            if name in athlete:
                continue
            if not known:
                raise SpecError(f"{static}: no {name.split('_')[0]} on either side (the knee "
                                "and ankle markers are missing)", where="--static",
                                hint="a static trial with the epicondyle (L.Knee, "
                                     "L.Knee.Medial) and malleolus (L.Ankle, L.Ankle.Medial) "
                                     "markers")
            athlete[name] = round(sum(known) / len(known), 4)
    return athlete or None
