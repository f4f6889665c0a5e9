"""Design point -> generated blade on an amputee runner -> predicted stride.

:class:`CollocationEvaluator` is the design study's evaluator ``"collocation"``
(``bladelab design --evaluator collocation``): for each design point it

1. generates the multi-link blade (:func:`~bladelab.design.blade_generator.generate_blade`);
2. builds the runner wearing it: the transfemoral runner (``build_runner("transfemoral",
   blade_model=…)``: intact leg, residual hip muscles, the passive 3S80-class knee, the
   blade's links, joints and soles) or the transtibial one (``"amputee"``: the residual knee
   and its muscles, the blade in place of the foot), by ``amputation``;
3. predicts one periodic stride at the prescribed speed (or, with ``max_speed``, the stride
   of the maximum-speed problem) by direct collocation
   (:func:`~bladelab.predict.collocation.solve.predict_stride`), warm-started from the
   design's own stride in ``start_strides`` (another study of the same designs) if given, then
   from the nearest designs already solved in ``solutions_dir`` (coded distance), then from
   ``start``;
   a start that does not converge to a stride without
   :meth:`~bladelab.predict.collocation.solution.CollocationSolution.gait_warnings` is
   followed by the next one; the last resort is ``start`` with a tracking stage first;
4. reads seed 002's responses off the stride
   (:func:`~bladelab.design.predicted.stride_responses`), with ``max_speed`` the stride's
   mean speed named ``max_speed_m_per_s``.

Every design's stride is written to ``solutions_dir/<point>.json`` (``bladelab report``
renders it) and read back instead of solved again when the design is evaluated again (a
resumed or re-fitted study), a failed one's best iterate to
``<point>.best_iterate.json``; a design point with no clean stride raises
:class:`~bladelab.errors.OptimizationError` naming IPOPT's status and the gait's defects
(the study stops there with the finished runs kept: never a NaN).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from bladelab.design.blade_generator import generate_blade
from bladelab.design.predicted import stride_responses
from bladelab.design.predicted_runner import (
    AMPUTATIONS,
    DEFAULT_AMPUTATION,
    DEFAULT_BODIES,
    DEFAULT_BODY,
    DEFAULT_DESIGN_SPEED_MPS,
    DEFAULT_SOLE_STIFFNESS_SCALE,
    DEFAULT_START,
    DEFAULT_STARTS,
    REFERENCE_DOFS,
    REFERENCE_DOFS_TRANSTIBIAL,
)
from bladelab.design.responses import MAX_SPEED_RESPONSE_UNITS, PREDICTED_RESPONSE_UNITS
from bladelab.design.start_continuation import continue_stride, read_clean_stride
from bladelab.design.stride_files import (
    point_file_stem,
    solved_from_text,
    start_identity,
    start_text,
    stored_neighbours,
)
from bladelab.errors import InputFileError, OptimizationError, SpecError
from bladelab.executors import say_to_stderr
from bladelab.predict import defaults as predict_defaults
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.stored import (
    check_athlete,
    check_model_spec,
    runner_from_spec,
)
from bladelab.runner.params import BODIES, default_runner_params
from bladelab.runner.scaling import athlete_params

__all__ = ["CollocationEvaluator", "DEFAULT_BODY", "DEFAULT_DESIGN_SPEED_MPS", "DEFAULT_START",
           "DEFAULT_STARTS", "REFERENCE_DOFS"]

#: Solved designs a new design may start from, nearest first, before the study's start
#: (a start that gives no clean stride is followed by the next; measured 2026-11-26: with the
#: technique kept, two axial designs got a 10-BW hop or no convergence from the centre, their
#: only neighbour then).
START_NEIGHBOURS = 3


@dataclass(frozen=True)
class CollocationEvaluator:
    """Design point -> predicted amputee stride -> seed 002's responses (module docstring).

    Attributes
    ----------
    speed_mps
        Prescribed mean speed of the stride [m/s]; None with ``max_speed``.
    max_speed
        Predict each design's stride of the maximum-speed problem instead (the speed free, the
        negative mean speed plus the effort terms minimised:
        :func:`~bladelab.predict.collocation.continuation.max_speed_settings`'s weights); its
        mean speed is the response ``max_speed_m_per_s``. With ``stride_time_people`` the
        stride time is held in people's band at the stride's own speed
        (``CollocationSettings.period_band``).
    start_strides
        A folder of strides of the same designs (another study's ``strides``, e.g. at a
        prescribed speed): each design starts from its own stride there first (the file named
        by its point), then from the neighbours and ``start``. None (default): no such folder.
    start
        A collocation solution (file) of the runner to start the first design from (any
        blade with the same number of links); default the runner's (:data:`DEFAULT_STARTS`).
    amputation
        ``"transfemoral"`` (:data:`DEFAULT_AMPUTATION`, seed 002's athlete: the passive
        prosthetic knee) or ``"transtibial"`` (the residual knee, the blade below it).
    body
        The runner body: ``"seed001"`` or ``"human"`` (predict's default body); None: the
        amputation's (:data:`DEFAULT_BODIES`). A runner without a built-in start
        (:data:`DEFAULT_STARTS`) needs ``start``.
    solutions_dir
        Folder of the designs' strides (the warm starts of the later designs); None: a
        ``strides`` folder is not kept and every design starts from ``start``.
    factor_ranges
        Factor -> (low, high) in its unit: the coding of the nearest-neighbour distance
        (default: relative differences).
    mesh_intervals, swing_clearance_m, max_iter
        Collocation settings
        (:class:`~bladelab.predict.collocation.settings.CollocationSettings`): mesh intervals,
        the swinging blade's minimum height [m], IPOPT's iteration limit.
    knee_moment_min_Nm
        Keep the prosthetic knee's external extension moment at or above this [N·m] in every
        design's stride (seed 002's knee-buckling constraint imposed on the predicted gait,
        ``CollocationSettings.knee_moment_min_nm``); None: a reported outcome only.
    knee_flexion_max_loaded_deg
        Keep the prosthetic knee within this flexion [deg] while its blade is loaded
        (``CollocationSettings.knee_flexion_max_loaded_deg``: the straight stance); None: free.
    blade_backward_euler
        Transcribe the blade's joints by backward Euler
        (``CollocationSettings.blade_backward_euler``: no node-to-node ringing of its links).
    sole_stiffness_scale
        Factor on the generated blade's sole contact stiffness
        (:data:`DEFAULT_SOLE_STIFFNESS_SCALE`).
    reference_weight
        Keep the athlete's own joints (:data:`REFERENCE_DOFS`, the transtibial runner's
        :data:`REFERENCE_DOFS_TRANSTIBIAL`) near the ``start`` stride's:
        this weight [1/rad²] × their time-averaged mean squared deviation is added to the
        objective (``CollocationSettings.reference_weight``), so that every blade is run with
        the same technique and its responses are the blade's (seed 002 imposed measured
        kinematics); 0 (default): the gait is predicted freely.
    step_phase_tolerance
        Keep every design's steps alternating: the prosthetic leg's stance half a stride ±
        this fraction of the stride after the intact leg's
        (``CollocationSettings.step_phase_tolerance``); None (default): free. Every
        converged transfemoral stride of both bodies gallops without it (docs/design.md).
    prosthetic_load_max_bw
        Keep the prosthetic leg's vertical ground force at or below this many body weights
        in every design's stride (``CollocationSettings.prosthetic_load_max_bw``: the load
        the residual limb tolerates in its socket); None (default): no limit.
    stride_time_range_s, stride_time_people
        Keep every design's stride time inside (lo, hi) [s], or inside measured runners' band
        at the speed (``CollocationSettings.stride_time_range_s`` /
        ``stride_time_people``): an athlete's cadence imposed, not predicted; free by default.
        At people's stride time more strides meet people's criteria, but a design's strides
        from different starts spread more than free ones (docs/design.md).
    people_weight
        Weight [1/rad²] of people's joint angles in the objective (the intact leg's hip, knee
        and ankle and the residual hip (and knee); ``CollocationSettings(reference="people")``,
        docs/collocation.md); None: the body's default
        (:func:`bladelab.predict.defaults.people_weight_for`: 10 on the human body, 0 on
        seed 001's), 0 with a ``reference_weight`` (the two terms exclude each other). The
        transtibial runner on the human body also keeps predict's swing knee
        (:func:`bladelab.predict.defaults.swing_knee_for`): its strides are predict's.
    athlete
        The runner scaled to this athlete: body mass [kg], height [m], muscle strength,
        maximum shortening velocity, segment and residual-limb lengths [m], the prosthesis's
        extra length [m] (``bladelab.runner.scaling.athlete_params``' fields, as predict's
        ``--body-mass`` … ``--prosthesis-extra-length``); None (default): the body's own.
        Every design's stride is of this athlete; the built-in start, of the default one, is
        only its first guess.
    generator
        Options of :func:`~bladelab.design.blade_generator.generate_blade`.
    """

    speed_mps: float | None = DEFAULT_DESIGN_SPEED_MPS
    max_speed: bool = False
    start_strides: str | None = None
    start: str | None = None
    solutions_dir: str | None = None
    factor_ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    mesh_intervals: int = 50
    swing_clearance_m: float = 0.02
    max_iter: int = 3000
    knee_moment_min_Nm: float | None = None
    knee_flexion_max_loaded_deg: float | None = None
    blade_backward_euler: bool = True
    sole_stiffness_scale: float = DEFAULT_SOLE_STIFFNESS_SCALE
    reference_weight: float = 0.0
    body: str | None = None
    amputation: str = DEFAULT_AMPUTATION
    people_weight: float | None = None
    step_phase_tolerance: float | None = None
    prosthetic_load_max_bw: float | None = None
    stride_time_range_s: tuple[float, float] | None = None
    stride_time_people: bool = False
    athlete: Mapping[str, float] | None = None
    generator: Mapping[str, Any] = field(default_factory=dict)

    #: What a study's ``evaluator.json`` written before a setting existed meant by it: the
    #: studies before the human body ran seed 001's body without people's angles, and
    #: those before the alternating-steps constraint and the prosthetic load limit ran
    #: without them; every study before the stride time option let it free.
    LEGACY_SETTINGS: ClassVar[dict[str, Any]] = {"body": "seed001", "people_weight": 0.0,
                                                 "step_phase_tolerance": None,
                                                 "prosthetic_load_max_bw": None,
                                                 "amputation": "transfemoral",
                                                 "stride_time_range_s": None,
                                                 "stride_time_people": False,
                                                 "max_speed": False, "start_strides": None,
                                                 "athlete": None}

    def __post_init__(self) -> None:
        if self.amputation not in AMPUTATIONS:
            raise SpecError(f"unknown amputation {self.amputation!r}", where="amputation",
                            hint=" or ".join(AMPUTATIONS))
        if self.body is None:
            object.__setattr__(self, "body", DEFAULT_BODIES[self.amputation])
        if not isinstance(self.max_speed, bool):
            raise SpecError(f"expected true or false, got {self.max_speed!r}",
                            where="max_speed")
        if self.max_speed:
            object.__setattr__(self, "speed_mps", None)
        elif self.speed_mps is None:
            raise SpecError("no speed: prescribe one, or pose the maximum-speed problem",
                            where="speed_mps", hint="speed_mps in m/s, or max_speed true")
        if self.start_strides is not None and not Path(self.start_strides).is_dir():
            raise InputFileError("no such folder of the designs' start strides",
                                 file=self.start_strides,
                                 hint="another study's strides folder (its designs' strides)")
        if self.body not in BODIES:
            raise SpecError(f"unknown body {self.body!r}", where="body", hint=" or ".join(BODIES))
        if self.athlete is not None:
            athlete = check_athlete(dict(self.athlete) if isinstance(self.athlete, Mapping)
                                    else self.athlete)
            # the athlete's limits on this body: a named error now, not per design
            athlete_params(default_runner_params(self.model, body=self.body), **athlete)
            object.__setattr__(self, "athlete", athlete or None)
        if self.start is None and (self.amputation, self.body) not in DEFAULT_STARTS:
            raise SpecError(f"no built-in start stride of the {self.amputation} runner on the "
                            f"{self.body} body", where="body",
                            hint=f"give the first design's start: a clean {self.amputation} "
                                 "stride of that body (a collocation solution file)")
        transfemoral_only = {"knee_moment_min_Nm": self.knee_moment_min_Nm,
                             "knee_flexion_max_loaded_deg": self.knee_flexion_max_loaded_deg}
        for name, value in transfemoral_only.items():
            if value is not None and self.amputation != "transfemoral":
                raise SpecError("a setting of the prosthetic knee: the transtibial runner has "
                                "the residual (biological) knee", where=name,
                                hint="leave it out, or amputation transfemoral")
        if self.reference_weight and self.people_weight:
            raise SpecError("people's joint angles and the start stride's technique are two "
                            "references of one objective term: give one weight",
                            where="people_weight", hint="people_weight 0 with a "
                                                        "reference_weight")
        self.settings()  # speed, mesh, clearance, knee moment: errors name the field
        if not (self.sole_stiffness_scale > 0 and math.isfinite(self.sole_stiffness_scale)):
            raise SpecError(f"sole_stiffness_scale must be > 0, got {self.sole_stiffness_scale}",
                            where="sole_stiffness_scale")
        start = self.start_file
        if not start.is_file():
            raise InputFileError("no such collocation solution (the first design's start)",
                                 file=start,
                                 hint=f"a solution.json of the {self.amputation} runner")

    @property
    def start_file(self) -> Path:
        """The first design's start (and the reference): ``start``, else the runner's
        (:data:`DEFAULT_STARTS`)."""
        if self.start is not None:
            return Path(self.start)
        return DEFAULT_STARTS[(self.amputation, self.body)]

    @property
    def model(self) -> str:
        """The runner model of the designs' strides (:data:`AMPUTATIONS`)."""
        return AMPUTATIONS[self.amputation]

    @property
    def people_weight_per_rad2(self) -> float:
        """The weight [1/rad²] of people's joint angles in every design's objective
        (``people_weight``, else the body's default; 0 with a ``reference_weight``)."""
        if self.reference_weight:
            return 0.0
        return float(predict_defaults.people_weight_for(self.body, self.people_weight))

    @property
    def units(self) -> dict[str, str]:
        units = dict(PREDICTED_RESPONSE_UNITS)
        if self.max_speed:  # the mean speed under its own name
            del units["avg_vx_m_per_s"]
            units.update(MAX_SPEED_RESPONSE_UNITS)
        return units

    @property
    def response_names(self) -> tuple[str, ...]:
        """The responses of a design: a stored run without all of them (an older library's)
        is evaluated again by the study, which reads its stored stride back."""
        return tuple(self.units)

    def responses(self, solution, runner) -> dict[str, float]:
        """A design's responses (:func:`~bladelab.design.predicted.stride_responses`; with
        ``max_speed`` the stride's mean speed is named ``max_speed_m_per_s`` [m/s] in place of
        ``avg_vx_m_per_s``: one response, not the same column twice)."""
        out = stride_responses(solution, runner)
        if self.max_speed:
            out.pop("avg_vx_m_per_s", None)
            out["max_speed_m_per_s"] = float(solution.mean_speed_mps)
        return out

    def to_dict(self) -> dict:
        d = asdict(self)
        d["generator"] = {k: str(v) if isinstance(v, Path) else v
                          for k, v in dict(self.generator).items()}
        d["factor_ranges"] = {k: list(v) for k, v in dict(self.factor_ranges).items()}
        d["start"] = str(self.start) if self.start else f"built-in {self.start_file.name}"
        d["people_weight"] = self.people_weight_per_rad2
        return {"evaluator": "collocation", **d}

    # -- starts ---------------------------------------------------------------------------
    def _neighbours(self, point: Mapping[str, float]) -> list[Path]:
        """Stride files of the other designs solved in ``solutions_dir``, nearest first."""
        if self.solutions_dir is None:
            return []
        return stored_neighbours(self.solutions_dir, point, self.factor_ranges)

    def _starts(self, point: Mapping[str, float]) -> list[Path]:
        """Solution files to start from: the :data:`START_NEIGHBOURS` nearest solved designs,
        nearest first, then ``start``; with a reference weight, ``start`` (the reference)
        first and the neighbours after it (every design from the same start: measured
        2026-11-26, a chain of neighbours carried a 0.59 s stride away from the reference's 0.53 s
        into a third of the box). With ``start_strides``, the design's own stride there
        comes first."""
        near = self._neighbours(point)[:START_NEIGHBOURS]
        starts = [self.start_file, *near] if self.reference_weight else [*near, self.start_file]
        own = self._own_start(point)
        return [own, *starts] if own is not None else starts

    def speed_floor(self, point: Mapping[str, float], current=None) -> float | None:
        """The maximum-speed problem's floor [m/s] for a design: the mean speed of its own
        stride in ``start_strides``, else of its stored stride ``current`` (strides of this
        blade); None (the start's own speed) without either, or with a prescribed speed. A
        neighbour's speed as the floor would pin the design to it (measured: 7 of 25 designs
        of a study at one neighbour's 4.972 m/s to the last digit)."""
        if not self.max_speed:
            return None
        own = self._own_start(point)
        if own is not None:
            return float(CollocationSolution.read(own).mean_speed_mps)
        return None if current is None else float(current.mean_speed_mps)

    def _own_start(self, point: Mapping[str, float]) -> Path | None:
        """The design's own stride in ``start_strides``, or None."""
        if self.start_strides is None:
            return None
        own = Path(self.start_strides) / f"{point_file_stem(point)}.json"
        return own if own.is_file() else None

    def solved_from(self, point: Mapping[str, float]) -> dict[str, str]:
        """{start file name: its identity} of the solve that gave this design's stored stride,
        when that was one solve from another stride as it is (no tracking stage, not
        continued); else {}."""
        own = self._stride_file(point)
        if own is None or not own.is_file():
            return {}
        return solved_from_text(CollocationSolution.read(own).guess_source)

    def _cheapest_other(self, point: Mapping[str, float], settings,
                        exclude: Sequence[Path]) -> Path | None:
        """The stored stride of another design of this problem with the lowest objective, not
        among ``exclude``; None when there is none."""
        best = None
        for path in self._neighbours(point):
            if path in exclude:
                continue
            sol = CollocationSolution.read(path)
            if not (sol.converged and sol.settings.same_problem(settings)):
                continue
            if best is None or sol.nlp.objective < best[0]:
                best = (float(sol.nlp.objective), path)
        return None if best is None else best[1]

    def settle(self, point: Mapping[str, float], neighbours: int = 2,
               cheapest: bool = False, known: Mapping[str, str] | None = None,
               say: Callable[[str], None] | None = None) -> dict:
        """Solve this design again from its ``neighbours`` nearest solved designs, its own
        stride in ``start_strides`` (if any) and, with ``cheapest``, the study's cheapest
        stride of another design (when it is not one of them), and keep the clean stride of
        lowest objective (rewriting its file). The cheapest stride reaches a branch the
        neighbours do not carry across the box (measured: from it five designs of a settled
        study went lower, one by 2.4 %, docs/design.md). Returns ``{"point", "before",
        "after"`` (objectives), ``"from"`` (the file that gave the kept stride, or None),
        ``"responses_before"`` (the stored stride's responses) and ``"tries"``: per start,
        ``{"from", "converged", "status", "objective", "warnings", "responses"}`` (responses
        of a clean stride only) and ``"start"`` (:func:`start_identity` of the start stride).
        ``known``: start file name -> its identity when this design was last solved from it; a
        start still the same is not solved again (IPOPT would retrace the same path) and is
        listed under ``"unchanged"``. Every clean stride of a design is a local optimum of the
        same problem: their spread is what the start decides
        (:mod:`bladelab.design.start_spread`). ``say(line)`` gets one line per start (its
        outcome and wall time)."""
        point = {k: float(v) for k, v in point.items()}
        spec, settings = self.problem(point)
        current, _ = self._stored(point, spec, settings)
        if current is None or self.solutions_dir is None:
            raise SpecError("this design has no stored clean stride to settle",
                            where="settle", hint="evaluate the design first")
        runner = runner_from_spec(spec)
        best, source, tries, unchanged = current, None, [], []
        starts = self._neighbours(point)[:neighbours]
        own = self._own_start(point)
        if own is not None:
            starts.append(own)
        if cheapest and (far := self._cheapest_other(point, settings, starts)) is not None:
            starts.append(far)
        name = point_file_stem(point)
        floor = self.speed_floor(point, current)
        for k, path in enumerate(starts, 1):
            start = CollocationSolution.read(path)
            identity = start_identity(start, floor)
            head = f"{name}: start {k} of {len(starts)} ({path.name})"
            if (known or {}).get(path.name) == identity:
                unchanged.append(path.name)
                if say is not None:
                    say(f"{head}: unchanged since this design was solved from it, skipped")
                continue
            guess = start.to_guess(start_text(path, start, floor))
            t0 = time.perf_counter()
            sol = predict_stride(runner, settings, guess, model_spec=spec, track=False,
                                 speed_floor=floor)
            warnings = sol.gait_warnings() if sol.converged else []
            clean = sol.converged and not warnings
            if say is not None:
                said = (f"objective {sol.nlp.objective:.5g} (stored {current.nlp.objective:.5g})"
                        if clean else f"IPOPT {sol.nlp.status}" if not sol.converged
                        else "flagged: " + "; ".join(warnings))
                say(f"{head}: {said}, {time.perf_counter() - t0:.0f} s")
            tries.append({"from": path.name, "start": identity,
                          "converged": bool(sol.converged), "status": str(sol.nlp.status),
                          "objective": float(sol.nlp.objective) if sol.converged else None,
                          "warnings": list(warnings),
                          "responses": self.responses(sol, runner) if clean else None})
            if clean and sol.nlp.objective < best.nlp.objective:
                best, source = sol, path.name
        if source is not None:
            self._keep(best, point)
        return {"point": point, "before": float(current.nlp.objective),
                "after": float(best.nlp.objective), "from": source,
                "responses_before": self.responses(current, runner), "tries": tries,
                "unchanged": unchanged}

    def settings(self):
        """The :class:`~bladelab.predict.collocation.settings.CollocationSettings` of every
        design's stride (checked when the evaluator is made)."""
        reference = people_term(self.people_weight_per_rad2)
        if self.reference_weight:
            reference = {"reference": str(self.start_file),
                         "reference_weight": self.reference_weight,
                         "reference_dofs": (REFERENCE_DOFS if self.amputation == "transfemoral"
                                            else REFERENCE_DOFS_TRANSTIBIAL)}
        reference["swing_knee_min_deg"] = predict_defaults.swing_knee_for(
            self.body, None, self.model)
        return CollocationSettings(mesh_intervals=self.mesh_intervals,
                                   speed_m_per_s=self.speed_mps,
                                   swing_clearance_m=self.swing_clearance_m,
                                   knee_moment_min_nm=self.knee_moment_min_Nm,
                                   knee_flexion_max_loaded_deg=self.knee_flexion_max_loaded_deg,
                                   blade_backward_euler=self.blade_backward_euler,
                                   step_phase_tolerance=self.step_phase_tolerance,
                                   prosthetic_load_max_bw=self.prosthetic_load_max_bw,
                                   stride_time_range_s=self.stride_time_range_s,
                                   stride_time_people=self.stride_time_people,
                                   max_iter=self.max_iter, **reference)

    def problem(self, point: Mapping[str, float]) -> tuple[dict, Any]:
        """(model specification with the design's blade, collocation settings) of a design: the
        problem every start of this design is solved for."""
        blade = self.blade_spec(point)
        spec = {"model": self.model, "blade": blade["name"], "blade_spec": blade,
                "body": self.body}
        if self.athlete:
            spec["athlete"] = dict(self.athlete)
        return check_model_spec(spec), self.settings()

    def blade_spec(self, point: Mapping[str, float]) -> dict:
        """The design's blade file contents: the generated blade, its soles' contact stiffness
        times ``sole_stiffness_scale`` and their damping times its square root."""
        data = generate_blade(point, **dict(self.generator)).spec.model_dump(
            mode="json", exclude_none=True)
        contact = dict(data.get("contact", {}))
        for key in ("stiffness_N_per_m", "stiffness_N_per_m_pow_n"):
            if key in contact:
                contact[key] *= self.sole_stiffness_scale
        if "damping_Ns_per_m" in contact:
            contact["damping_Ns_per_m"] *= math.sqrt(self.sole_stiffness_scale)
        data["contact"] = contact
        return data

    def _stride_file(self, point: Mapping[str, float], suffix: str = "") -> Path | None:
        """``solutions_dir/<point><suffix>.json``, or None without a solutions folder."""
        if self.solutions_dir is None:
            return None
        return Path(self.solutions_dir) / f"{point_file_stem(point)}{suffix}.json"

    def _keep(self, solution, point: Mapping[str, float], suffix: str = "") -> None:
        """Write a design's stride (or, with ``suffix`` ".best_iterate", its failed solve's
        last iterate) to the solutions folder, if there is one."""
        path = self._stride_file(point, suffix)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            solution.write(path)

    def _replace(self, solution, point: Mapping[str, float]) -> None:
        """Write a design's new stride; a stride file it replaces that this problem could not
        use (flagged by a later gait check, or of other settings) is kept as
        ``<point>.previous.json``: results already computed are not lost."""
        own = self._stride_file(point)
        if own is not None and own.is_file():
            own.replace(self._stride_file(point, ".previous"))
        self._keep(solution, point)

    def _stored(self, point: Mapping[str, float], spec: dict, settings):
        """(stride, its file): this design's clean stride of this problem (same blade,
        speed, mesh, weights, constraints and transcription) from ``solutions_dir``, or the
        start file if it is one; else (None, None)."""
        own = self._stride_file(point)
        paths = [self.start_file]  # the start may be this very design's
        for path in ([own] if own is not None else []) + paths:
            sol = read_clean_stride(path, spec, settings)
            if sol is not None:
                return sol, path
        return None, None

    # -- one design -----------------------------------------------------------------------
    def prepare(self, point: Mapping[str, float], progress: bool = True) -> None:
        """Before a study's runs (:func:`~bladelab.design.study.run_design` calls it with its
        first design, the centre): at a prescribed speed more than
        :data:`~bladelab.design.start_continuation.CONTINUATION_STEP_MPS` from the start
        stride's, solve this design by speed continuation from the start
        (:func:`~bladelab.design.start_continuation.continue_stride`, the steps kept in
        ``solutions_dir/continuation``) and keep its stride, so that the other designs start
        near their own speed. Nothing to do for a stored design, one with its own stride in
        ``start_strides``, the maximum-speed problem or without a solutions folder; a chain
        that fails leaves the start as it is. A line per step on standard error with
        ``progress``."""
        point = {k: float(v) for k, v in point.items()}
        if self.max_speed or self.solutions_dir is None or self._own_start(point) is not None:
            return
        spec, settings = self.problem(point)
        if self._stored(point, spec, settings)[0] is not None:
            return
        sol = continue_stride(runner_from_spec(spec), spec, settings, self.start_file,
                              Path(self.solutions_dir) / "continuation", point_file_stem(point),
                              solve=predict_stride, say=say_to_stderr if progress else None)
        if sol is not None:
            self._replace(sol, point)

    def __call__(self, point: Mapping[str, float]) -> dict[str, float]:
        point = {k: float(v) for k, v in point.items()}
        spec, settings = self.problem(point)
        runner = runner_from_spec(spec)
        stored, source = self._stored(point, spec, settings)
        if stored is not None:  # solved before (an interrupted or refitted study), or the start
            own = self._stride_file(point)
            if own is not None and source != own:  # the start: a neighbour of the others
                self._replace(stored, point)
            return self.responses(stored, runner)
        # each start as it is, then the study's start with a tracking stage first
        plan = [(f, False) for f in self._starts(point)] + [
            (self.start_file, True)]
        tried, best = [], None
        t0 = time.perf_counter()
        floor = self.speed_floor(point)
        for path, track in plan:
            source = CollocationSolution.read(path)
            guess = source.to_guess(f"tracking collocation solution {path.name}" if track
                                    else start_text(path, source, floor))
            sol = predict_stride(runner, settings, guess, model_spec=spec, track=track,
                                 speed_floor=floor)
            if _continuable(sol):  # one more round from where the iteration limit stopped it
                sol = predict_stride(runner, settings, sol.to_guess(
                    f"collocation solution {path.name}, continued after {sol.nlp.iterations} "
                    "iterations"), model_spec=spec, track=False, speed_floor=floor)
            defects = sol.gait_warnings() if sol.converged else []
            if sol.converged and not defects:
                break
            tried.append(f"from {path.name}{' (tracking first)' if track else ''}: "
                         + (f"IPOPT {sol.nlp.status}" if not sol.converged
                            else "; ".join(defects)))
            best = best or sol
        else:
            self._keep(best, point, ".best_iterate")
            raise OptimizationError(
                f"no clean stride for this blade after {len(plan)} starts "
                f"({time.perf_counter() - t0:.0f} s): " + " | ".join(tried),
                where="collocation evaluator",
                hint="the last iterates are in the solutions folder; widen the box's centre "
                     "towards this point, or give a --start stride nearer to it")
        self._replace(sol, point)
        return self.responses(sol, runner)


#: Largest constraint violation of an iteration-limited solve that is continued from its last
#: iterate (:meth:`CollocationEvaluator.__call__`) rather than given up.
CONTINUE_MAX_VIOLATION = 1e-3


def _continuable(solution) -> bool:
    """True for a predictive solve stopped by IPOPT's iteration limit on a nearly feasible
    iterate: the knee-safe strides of the box's corners need 1900-2200 iterations where the
    free ones needed 600-1000, and an axial design stopped at 3000 with a violation of 1e-5
    (measured 2026-11-26)."""
    nlp = solution.nlp
    return (not solution.converged and solution.stage == "predictive"
            and nlp.status == "Maximum_Iterations_Exceeded"
            and math.isfinite(nlp.max_violation) and nlp.max_violation < CONTINUE_MAX_VIOLATION)
