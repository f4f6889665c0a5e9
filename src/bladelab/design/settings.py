"""The evaluator of a design study from the settings a user gives.

:class:`EvaluatorSettings` holds what a user may set of an evaluator (its kind, speed, body
mass, time step, base blade, and the settings of one kind only); a setting left at None keeps
the evaluator's own default (:mod:`bladelab.design.defaults`). :func:`build_evaluator` checks
that each given setting applies to the kind (:data:`APPLIES_TO`), adds what the study decides
(the collocation evaluator's stride folder and factor ranges), fits the motion model of a motion
file, and builds the evaluator (:func:`~bladelab.design.evaluators.make_evaluator`).
``bladelab design`` calls it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path

from bladelab.design import defaults
from bladelab.design.evaluators import make_evaluator
from bladelab.design.motion import load_motion_model
from bladelab.design.space import DesignSpace
from bladelab.errors import InputFileError, SpecError

__all__ = ["APPLIES_TO", "EVALUATORS", "EvaluatorSettings", "build_evaluator"]

#: The evaluators by name.
EVALUATORS = ("blade", "runner", "collocation")
#: The evaluators each kind-specific setting of :class:`EvaluatorSettings` applies to.
APPLIES_TO: dict[str, tuple[str, ...]] = {
    "body_mass_kg": ("blade", "runner", "collocation"),
    "dt_s": ("blade", "runner"),
    "gait": ("runner",),
    "motion": ("runner",),
    "motion_model": ("runner",),
    "start": ("collocation",),
    "knee_moment_min_Nm": ("collocation",),
    "knee_flexion_max_loaded_deg": ("collocation",),
    "reference_weight": ("collocation",),
    "body": ("collocation",),
    "amputation": ("collocation",),
    "people_weight": ("collocation",),
    "step_phase_tolerance": ("collocation",),
    "prosthetic_load_max_bw": ("collocation",),
    "stride_time_range_s": ("collocation",),
    "stride_time_people": ("collocation",),
    "max_speed": ("collocation",),
    "start_strides": ("collocation",),
    "athlete": ("collocation",),
    "mesh_intervals": ("collocation",),
}


@dataclass(frozen=True)
class EvaluatorSettings:
    """A design study's evaluator as a user sets it; None: the evaluator's own default.

    Attributes
    ----------
    kind
        ``"blade"`` (one passive stance), ``"runner"`` (a template transfemoral gait cycle) or
        ``"collocation"`` (a predicted amputee stride per design).
    speed_mps
        Touch-down speed [m/s] (blade: :data:`~bladelab.design.defaults.BLADE_SPEED_MPS`,
        runner: :data:`~bladelab.design.defaults.RUNNER_SPEED_MPS`); the stride's mean speed
        (collocation: :data:`~bladelab.design.defaults.COLLOCATION_SPEED_MPS`).
    body_mass_kg
        Body mass [kg] (blade and runner: :data:`~bladelab.design.defaults.BODY_MASS_KG`;
        collocation: the athlete's, default the body's).
    dt_s
        Simulation step [s] (blade and runner).
    base
        Built-in blade (or blade file) that the generator reshapes to each design.
    gait, motion, motion_model
        Runner: a gait-cycle CSV for every design, or a motion file (cycles with their blades)
        whose fitted motion model predicts each design's cycle, and that model's terms
        (``auto``, ``quadratic``, ``linear`` or terms; default: the file's ``model:``).
    start, knee_moment_min_Nm, knee_flexion_max_loaded_deg, reference_weight
        Collocation: the first design's start stride (a solution file), the prosthetic knee's
        smallest extension moment [N·m], its largest flexion while loaded [deg], and the
        weight [1/rad²] that keeps the athlete's own joints near the start stride's
        (:class:`~bladelab.design.collocation_evaluator.CollocationEvaluator`).
    amputation, body, people_weight
        Collocation: the runner's amputation (``"transfemoral"``, the default, or
        ``"transtibial"``), its body (``"seed001"`` or ``"human"``; default the amputation's:
        seed 001's for the transfemoral runner, the human body for the transtibial one) and
        the weight [1/rad²] of people's joint angles in the objective (default: the body's).
    step_phase_tolerance
        Collocation: keep every design's steps alternating within this fraction of the stride
        of half a stride (``CollocationSettings.step_phase_tolerance``); None: free.
    prosthetic_load_max_bw
        Collocation: keep the prosthetic leg's vertical ground force at or below this many
        body weights (``CollocationSettings.prosthetic_load_max_bw``); None: no limit.
    stride_time_range_s, stride_time_people
        Collocation: keep every design's stride time inside (lo, hi) [s], or (True) inside
        measured runners' band at the speed; None: free.
    max_speed, start_strides
        Collocation: predict each design's maximum-speed stride instead of one at
        ``speed_mps`` (which it excludes), and a folder of strides of the same designs (another
        study's) that each design starts from first.
    athlete
        Collocation: the runner scaled to this athlete (height, muscle strength, maximum
        shortening velocity, segment and residual-limb lengths, the prosthesis's extra length:
        ``CollocationEvaluator.athlete``; the body mass is ``body_mass_kg``); None: the body's.
    mesh_intervals
        Collocation: mesh intervals of every design's stride (default 50; read a stride above
        5 m/s on 100, docs/collocation.md).
    """

    kind: str = "blade"
    speed_mps: float | None = None
    body_mass_kg: float | None = None
    dt_s: float | None = None
    base: str = defaults.BASE_BLADE
    gait: str | Path | None = None
    motion: str | Path | None = None
    motion_model: str | None = None
    start: str | Path | None = None
    knee_moment_min_Nm: float | None = None
    knee_flexion_max_loaded_deg: float | None = None
    reference_weight: float | None = None
    body: str | None = None
    amputation: str | None = None
    people_weight: float | None = None
    step_phase_tolerance: float | None = None
    prosthetic_load_max_bw: float | None = None
    stride_time_range_s: tuple[float, float] | None = None
    stride_time_people: bool | None = None
    max_speed: bool | None = None
    start_strides: str | Path | None = None
    athlete: Mapping[str, float] | None = None
    mesh_intervals: int | None = None

    def __post_init__(self) -> None:
        if self.kind not in EVALUATORS:
            raise SpecError(f"unknown evaluator {self.kind!r}", where="kind",
                            hint=", ".join(EVALUATORS))
        for f in fields(self):
            applies = APPLIES_TO.get(f.name)
            if applies and self.kind not in applies and getattr(self, f.name) is not None:
                raise SpecError(f"does not apply to the {self.kind} evaluator", where=f.name,
                                hint=f"a setting of the {' and '.join(applies)} evaluator")
        if self.dt_s is not None and not (self.dt_s > 0 and math.isfinite(self.dt_s)):
            raise SpecError(f"the time step must be > 0 s, got {self.dt_s}", where="dt_s")
        if self.gait is not None and self.motion is not None:
            raise SpecError("a gait cycle (one cycle for every design) and a motion file (a "
                            "predicted cycle per design) exclude each other", where="gait",
                            hint="give one of them")
        if self.motion_model is not None and self.motion is None:
            raise SpecError("a motion model needs a motion file", where="motion_model")
        if self.max_speed and self.speed_mps is not None:
            raise SpecError("a prescribed speed and the maximum-speed problem exclude each other",
                            where="max_speed", hint="give one of them")
        if self.gait is not None and not Path(self.gait).is_file():
            raise InputFileError("no such gait-cycle file", file=self.gait,
                                 hint="a CSV with time_s and the joint angles (docs/design.md)")

    def options(self, space: DesignSpace, out: str | Path) -> dict:
        """The keyword options of the evaluator of a study of ``space`` in the folder ``out``
        (the motion file not yet fitted: :func:`build_evaluator` does that)."""
        options: dict = {"generator": {"base": self.base}}
        if self.kind == "collocation":
            options["solutions_dir"] = str(Path(out) / "strides")
            options["factor_ranges"] = {f.name: (f.low, f.high) for f in space.factors}
            if self.start is not None:
                options["start"] = str(self.start)
            if self.start_strides is not None:
                options["start_strides"] = str(self.start_strides)
            for name in ("knee_moment_min_Nm", "knee_flexion_max_loaded_deg",
                         "reference_weight", "body", "amputation", "people_weight",
                         "step_phase_tolerance", "prosthetic_load_max_bw",
                         "stride_time_range_s", "stride_time_people", "max_speed",
                         "mesh_intervals"):
                if getattr(self, name) is not None:
                    options[name] = getattr(self, name)
            athlete = dict(self.athlete or {})
            if self.body_mass_kg is not None:
                athlete["body_mass_kg"] = self.body_mass_kg
            if athlete:
                options["athlete"] = athlete
        elif self.body_mass_kg is not None:
            options["body_mass_kg"] = self.body_mass_kg
        if self.speed_mps is not None:
            options["speed_mps"] = self.speed_mps
        if self.dt_s is not None:
            options["dt"] = self.dt_s
        if self.gait is not None:
            options["gait"] = str(self.gait)
        return options


def build_evaluator(settings: EvaluatorSettings, space: DesignSpace, out: str | Path, *,
                    progress: bool = False):
    """The evaluator of a study of ``space`` in the folder ``out`` (module docstring); a motion
    file's model is fitted here (``progress``: show its fit)."""
    options = settings.options(space, out)
    if settings.motion is not None:
        options["motion"] = load_motion_model(settings.motion, space=space,
                                              model=settings.motion_model, progress=progress)
    return make_evaluator(settings.kind, **options)
