"""Speed continuation and maximum speed of one model.

Two drivers on top of :func:`~bladelab.predict.collocation.solve.predict_stride`:

- :func:`speed_continuation` solves the stride at a sequence of prescribed speeds [m/s], in the
  order given, each warm-started from the previous converged solution (from its primal and
  dual values at its own point where it carries its multipliers, else scaled to the new mean
  speed: same period and joint curves, pelvis_tx and its speed scaled; a collocation guess
  skips the tracking stage; docs/collocation.md, "Warm starts"). The
  first speed starts from ``first_guess`` (template, trial, reflex solution, or a collocation
  solution), through the tracking stage unless it is a collocation solution.
- :func:`max_speed` solves the maximum-speed problem (``CollocationSettings(speed_m_per_s=
  None)``: the mean speed maximised with an effort term), warm-started from the fastest
  converged solution of the continuation.

The category sweep that runs both for several models is
:func:`bladelab.predict.collocation.sweep.collocation_sweep`.

Files (JSON of :class:`~bladelab.predict.collocation.solution.CollocationSolution`, written
atomically as soon as a solve ends, so results already computed are never lost):
``speed-<v>.json`` (``<v>`` as ``f"{v:g}"``: ``speed-3.5.json``, ``speed-4.json``) for a
converged solve, ``speed-<v>.best_iterate.json`` for one that did not converge (never both: the
stale one is removed once the new file is in place); ``max-speed.json`` and
``max-speed.best_iterate.json`` likewise.

Failure: a speed that does not converge from the previous converged one is tried again after
an intermediate speed halfway between them (``speed-<mid>.json``, a record of its own), down
to steps of 1/2^``refinements`` of the first step towards that prescribed speed (default
:data:`DEFAULT_REFINEMENTS` = 2: quarter steps; measured on
2026-11-25: the amputee Cat4 stride warm-started from 4 to 5 m/s was still infeasible after
800 iterations). A speed that still does not converge is recorded (its best-iterate file,
IPOPT's status in the table) and the continuation stops there;
:attr:`ContinuationResult.last_converged_speed` reports the last speed that converged.

Resuming: running again with the same folder reads a converged file of the same problem (model,
mesh, speed, objective weights: :meth:`CollocationSettings.same_problem`) back instead of
solving it; a best iterate of the same problem warm-starts that speed's predictive stage (as
``bladelab predict --resume``). A file of another problem is an error naming it, unless
``force`` (start over: existing files are neither read nor trusted, and are replaced).

Table rows (:meth:`~bladelab.predict.collocation.continuation_records.SolveRecord.row`, units in
the names): ``model``, ``blade``, ``problem`` (``speed`` or ``max-speed``),
``prescribed_speed_mps`` (empty for the maximum speed), ``converged``, ``status``,
``mean_speed_mps``, ``cost_of_transport_J_per_kg_m``, ``stride_time_s``, ``contact_time_s``
(mean of the legs), ``contact_time_<leg>_s``, ``peak_vertical_grf_<leg>_bw`` [body weights],
``flight_fraction``, ``dynamics_residual_pct``, ``iterations``, ``wall_s`` (of the solve, both
stages; the stored value for a file read back), ``mesh_intervals`` and ``file``; the maximum
speed's also ``speed_floor_mps`` and ``on_speed_floor``
(:func:`~bladelab.predict.collocation.continuation_records.speed_floor_columns`: a maximum speed
on its floor is the floor's, not the model's). Legs are left/right (able) or intact/prosthetic
(amputee).

Several starts (``starts`` K > 1, :mod:`bladelab.predict.collocation.starts`): each problem is
solved from up to K starts (the warm start above, its barrier start, the template, the
previous-but-one solution), every start's file kept (``speed-4.json`` for the warm start,
``speed-4.<start>.json`` for the others); the record is the kept start's (lowest converged
objective without gait warnings), the continuation goes on from it, and its row adds
``start``, ``starts``, ``objective``, ``objective_<start>`` and ``spread_pct``. Resuming reads
every start's converged file back; a start's best iterate is read back too when another start
of the problem converged, and warm-starts that start again otherwise (as with one start).

Other models' strides as starts (``extra_starts``, the sweep's settling pass): each problem
(:func:`problem_key`) may get further starts from solution files of other models (a
neighbouring blade category's stride at the same speed), labelled by the caller
(``from-Cat5``), solved after the K starts from the solution's primal and dual values, and
kept like any start. At the maximum speed such a start is held at the model's own floor (the
speed of the stride its warm start came from), not at the other stride's speed, so that every
start solves the same problem and a faster neighbour cannot pin the model to its speed.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Sequence
from pathlib import Path

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.continuation_records import (
    ContinuationProgress,
    ContinuationResult,
    SolveRecord,
)
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.output_folder import read_stored, write_solve
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starts import (
    MAX_STARTS,
    Start,
    check_starts,
    plan_starts,
    solve_starts,
    warm_guess,
)
from bladelab.predict.collocation.stored import (
    check_model_spec,
    model_label,
    runner_from_spec,
    same_model_spec,
)
from bladelab.predict.collocation.stride_guess import COLLOCATION_SOURCE

__all__ = [
    "MAX_SPEED_BEST_ITERATE_FILE",
    "MAX_SPEED_FILE",
    "DEFAULT_REFINEMENTS",
    "LazyRunner",
    "check_speeds",
    "max_speed",
    "max_speed_settings",
    "model_folder",
    "problem_key",
    "speed_continuation",
    "speed_file",
]

#: File names of the maximum-speed solve in a model's folder.
MAX_SPEED_FILE = "max-speed.json"
MAX_SPEED_BEST_ITERATE_FILE = "max-speed.best_iterate.json"


def speed_file(speed: float, *, converged: bool = True) -> str:
    """The file name of the solve at ``speed`` [m/s]: ``speed-<v:g>.json``, or
    ``speed-<v:g>.best_iterate.json`` when it did not converge."""
    return f"speed-{float(speed):g}" + (".json" if converged else ".best_iterate.json")


def problem_key(speed: float | None) -> str:
    """The key of a model's problem in ``extra_starts``: the prescribed speed as
    ``f"{v:g}"`` [m/s], ``"max-speed"`` for the maximum speed (``speed`` None)."""
    return "max-speed" if speed is None else f"{float(speed):g}"


def _solution_start(label: str, settings: CollocationSettings, path: Path) -> Start:
    """A start from the stride in solution file ``path`` (another model's), labelled
    ``label``: its primal and dual values (:func:`warm_guess`)."""
    def guess():
        return warm_guess(CollocationSolution.read(path), f" ({label}: {Path(path).name})")

    return Start(label, settings, guess, f"from {label.removeprefix('from-')}'s stride "
                                         f"{Path(path).parent.name}/{Path(path).name}")


def _extra(extra_starts, speed: float | None, settings: CollocationSettings) -> list[Start]:
    """The ``extra_starts`` of the problem at ``speed`` (None: the maximum speed)."""
    return [_solution_start(label, settings, Path(path))
            for label, path in (extra_starts or {}).get(problem_key(speed), ())]


def model_folder(spec: dict) -> str:
    """A model's subfolder in a sweep: ``able`` or ``amputee-<blade>``, with ``-<body>`` for
    a body other than seed 001's (``able-toes``)."""
    spec = check_model_spec(spec)
    return "-".join(p for p in (spec["model"], spec["blade"], spec.get("body")) if p)


# -- helpers ------------------------------------------------------------------------------
class LazyRunner:
    """The runner of a model specification, built on the first call unless given.

    ``LazyRunner(runner, spec)()`` returns ``runner``; if it is None, the runner built from
    ``spec`` (:func:`~bladelab.predict.collocation.stored.runner_from_spec`), once; if it is a
    callable that is not a runner (e.g. another :class:`LazyRunner`), what it returns."""

    def __init__(self, runner, spec: dict) -> None:
        self._runner, self._spec = runner, spec

    def __call__(self):
        if self._runner is None:
            self._runner = runner_from_spec(self._spec)
        elif callable(self._runner) and not hasattr(self._runner, "dof_names"):
            self._runner = self._runner()
        return self._runner


def _stored(ok: Path, best: Path, settings: CollocationSettings, *, spec: dict, force: bool):
    """(converged solution, best iterate) in ``ok`` / ``best``
    (:func:`~bladelab.predict.collocation.output_folder.read_stored`); ``force`` ignores both."""
    return (None, None) if force else read_stored(ok, best, spec, settings)


def _solve(get_runner, spec: dict, watched: bool, settings: CollocationSettings, guess,
           ok: Path, best: Path, report: Callable[..., None], speed_floor=None):
    """:func:`_solve_and_write` with the runner of ``get_runner`` (for
    :func:`~bladelab.predict.collocation.starts.solve_starts`)."""
    return _solve_and_write(get_runner(), settings, guess, spec=spec, ok=ok, best=best,
                            report=report, watched=watched, speed_floor=speed_floor)


def _solve_and_write(runner, settings: CollocationSettings, guess, *, spec: dict, ok: Path,
                     best: Path, report: Callable[..., None], watched: bool,
                     speed_floor: float | None = None):
    """Solve, write the solution (or best iterate) and remove the stale other file; the
    solver's progress goes to ``report`` when ``watched``; ``speed_floor`` [m/s] as
    :func:`~bladelab.predict.collocation.solve.predict_stride`."""
    sol = predict_stride(runner, settings, guess, model_spec=spec, speed_floor=speed_floor,
                         progress=(lambda p: report("solve", solve=p)) if watched else None)
    target = write_solve(sol, ok, best)
    s = sol.summary()
    if sol.converged:
        report("converged", path=target,
               message=f"mean speed {sol.mean_speed_mps:.4g} m/s, cost of transport "
                       f"{sol.cost_of_transport_J_per_kg_m:.4g} J/(kg·m), "
                       f"{s['iterations']} iterations, {s['wall_s']:.1f} s")
    else:
        report("failed", path=target,
               message=f"not converged: IPOPT status {sol.nlp.status} in the {sol.stage} stage "
                       f"after {sol.nlp.iterations} iterations; best iterate in {target.name}")
    return sol, target


def _template(get_runner, speed: float, n: int):
    return template_guess(get_runner(), speed=speed, n=n)


def check_speeds(speeds) -> tuple[float, ...]:
    """The prescribed speeds [m/s] as a tuple of floats: each > 0, none twice (as
    ``f"{v:g}"``); a single number is one speed. Raises SpecError naming ``speeds``."""
    if isinstance(speeds, int | float):
        speeds = [speeds]
    out = []
    for v in speeds:
        if isinstance(v, bool) or not isinstance(v, int | float) or not (
                math.isfinite(v) and v > 0):
            raise SpecError(f"speeds must be > 0 m/s, got {v!r}", where="speeds")
        out.append(float(v))
    if not out:
        raise SpecError("no speed given", where="speeds")
    names = [f"{v:g}" for v in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise SpecError(f"speed(s) {', '.join(dup)} m/s given twice", where="speeds")
    return tuple(out)


#: Halvings of the speed step allowed (:func:`speed_continuation`): steps down to a quarter.
DEFAULT_REFINEMENTS = 2


# -- drivers ------------------------------------------------------------------------------
def speed_continuation(runner, speeds: Sequence[float], settings: CollocationSettings,
                       first_guess, *, model_spec: dict, out_dir: str | Path,
                       progress: Callable[[ContinuationProgress], None] | None = None,
                       force: bool = False,
                       refinements: int = DEFAULT_REFINEMENTS,
                       starts: int = 1, extra_starts=None) -> ContinuationResult:
    """Solve the stride at each prescribed speed in order, each warm-started from the previous
    converged solution (module docstring); files ``out_dir/speed-<v>.json``.

    Parameters
    ----------
    runner
        The forward model (:func:`bladelab.runner.build_runner`); None (or a callable returning
        it): built from ``model_spec`` when a solve is needed (a rerun that only reads files
        back builds nothing).
    speeds
        Prescribed mean speeds [m/s], solved in this order.
    settings
        :class:`CollocationSettings` of a prescribed-speed problem (mesh, weights, solver
        options); each speed replaces its ``speed_m_per_s``.
    first_guess
        Initial guess of the first speed (:class:`StrideGuess`), or a callable
        ``first_guess(runner) -> StrideGuess``, called only when it is needed.
    model_spec
        ``{"model": "able" | "amputee", "blade": name | None}``: how ``runner`` is built.
    out_dir
        Folder of the files (created if needed).
    progress
        Called with :class:`ContinuationProgress` reports.
    force
        Solve every speed, ignoring (and then replacing) files already in ``out_dir``; files of
        speeds not reached stay (:func:`sweep_model_task` removes them).
    refinements
        Halvings of the speed step allowed when a solve does not converge from the previous
        speed: the smallest step is the first step towards a prescribed speed / 2^refinements
        (0: stop at the first failure).
    starts
        Starts per speed, 1 to 5 (module docstring; :mod:`~bladelab.predict.collocation.starts`):
        1 the warm start only; more, the best of several kept and continued from.
    extra_starts
        ``{problem_key(v): [(label, solution file), ...]}``: further starts of a speed from
        other models' strides (module docstring); None: none.

    Returns
    -------
    ContinuationResult
        One record per speed reached; the continuation stops at the first speed that does not
        converge.

    Raises
    ------
    SpecError
        No speed, a speed that is not > 0, a speed given twice, maximum-speed settings, or a
        number of starts out of range.
    InputFileError
        A file in ``out_dir`` holds another problem (without ``force``).
    """
    spec = check_model_spec(model_spec)
    speeds = check_speeds(speeds)
    starts = check_starts(starts)
    if not isinstance(settings, CollocationSettings):
        raise SpecError(f"expected CollocationSettings, got {type(settings).__name__}",
                        where="settings")
    if settings.max_speed:
        raise SpecError("the speed continuation needs the settings of a prescribed-speed "
                        "problem", where="settings",
                        hint="give speed_m_per_s (each speed of the continuation replaces it)")
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputFileError("is a file, not a folder", file=out_dir, hint="give a folder")
    get_runner = LazyRunner(runner, spec)
    label = model_label(spec)
    records: list[SolveRecord] = []
    prev = prev2 = None  # the previous converged (kept) solution, and the one before it
    pending = list(speeds)  # speeds still to solve, intermediate ones inserted in front
    prescribed = {f"{v:g}" for v in speeds}
    min_step = None  # smallest step [m/s] allowed towards the current prescribed speed
    restart: set[str] = set()  # speeds whose stored best iterate is stale (a step was refined)
    first: list = []  # the first guess, once made

    def first_start():
        if not first:
            first.append(first_guess(get_runner()) if callable(first_guess) else first_guess)
        return first[0]

    while pending:
        v = pending[0]
        problem = f"{v:g} m/s"

        def report(event: str, *, path=None, message: str = "", solve=None,
                   _problem=problem) -> None:
            if progress is not None:
                progress(ContinuationProgress(label, _problem, event, path, message, solve))

        s_v = dataclasses.replace(settings, speed_m_per_s=v)
        template = Start("template", s_v, functools.partial(
            _template, get_runner, v, settings.mesh_intervals))
        if prev is None:
            warm = Start("warm", s_v, first_start)
            plan = [warm] if starts == 1 else plan_starts(
                starts, warm, warm_source=str(first_start().source), template=template,
                previous=None, restart_start=starts == MAX_STARTS)
        else:
            warm = Start("warm", s_v, functools.partial(warm_guess, prev),
                         f"warm start from the {prev.settings.speed_m_per_s:g} m/s solution")
            previous = None if prev2 is None else Start(
                "previous-but-one", s_v,
                functools.partial(warm_guess, prev2, " (the previous but one)"),
                f"warm start from the {prev2.settings.speed_m_per_s:g} m/s solution (the "
                "previous but one)")
            plan = plan_starts(starts, warm, warm_source=COLLOCATION_SOURCE, template=template,
                               previous=previous, restart_start=starts == MAX_STARTS)
        extra = _extra(extra_starts, v, s_v)
        ok, best = out_dir / speed_file(v), out_dir / speed_file(v, converged=False)
        kept, outcomes = solve_starts(
            plan + extra, ok=ok, best=best, report=report, retry=f"{v:g}" not in restart,
            several=starts > 1 or bool(extra),
            read=functools.partial(_stored, spec=spec, force=force),
            solve=functools.partial(_solve, get_runner, spec, progress is not None))
        sol, path = kept.solution, kept.path
        solved = kept.solved or any(o.solved for o in outcomes)
        rec = SolveRecord("speed", v, sol, path, solved, outcomes)
        if sol.converged:
            records.append(rec)
            prev2, prev = prev, sol
            pending.pop(0)
            if f"{v:g}" in prescribed:
                min_step = None
            continue
        mid = None
        if prev is not None:
            v_prev = float(prev.settings.speed_m_per_s)
            if min_step is None:
                min_step = abs(v - v_prev) / 2**refinements
            mid = round(0.5 * (v_prev + v), 4)
            if (abs(v - v_prev) / 2 < min_step - 1e-9
                    or f"{mid:g}" in (f"{v_prev:g}", f"{v:g}")):
                mid = None
        if mid is None:
            records.append(rec)
            break
        restart.add(f"{v:g}")
        report("refine", path=path, message=f"not converged from {v_prev:g} m/s; "
                                            f"{mid:g} m/s first, then {v:g} m/s again")
        pending.insert(0, mid)
    return ContinuationResult(speeds, tuple(records))


def max_speed_settings(settings: CollocationSettings) -> CollocationSettings:
    """The maximum-speed problem with the mesh and solver options of ``settings``: speed None,
    the default maximum-speed weights (speed 1, activation 1, acceleration 0.1), the stride
    time free of people's band (``stride_time_people``: the band moves with the speed, which
    this problem predicts)."""
    return dataclasses.replace(settings, speed_m_per_s=None, weights=None,
                               stride_time_people=False)


def max_speed(runner, settings: CollocationSettings, guess, *, model_spec: dict,
              out_dir: str | Path,
              progress: Callable[[ContinuationProgress], None] | None = None,
              force: bool = False, starts: int = 1, previous=None,
              extra_starts=None) -> SolveRecord:
    """Solve the maximum-speed problem warm-started from ``guess`` (the fastest converged
    solution of :func:`speed_continuation`, a :class:`CollocationSolution` or its
    ``to_guess()``); file ``out_dir/max-speed.json`` (``max-speed.best_iterate.json`` if it
    does not converge). A converged file of the same problem is read back; a best iterate of
    it is the warm start instead of ``guess`` (module docstring).

    ``settings`` must pose the maximum-speed problem (``speed_m_per_s=None``;
    :func:`max_speed_settings`). ``runner``, ``model_spec``, ``progress``, ``force`` and
    ``starts`` as :func:`speed_continuation`; with several starts the template is the template
    guess at the warm start's speed, and ``previous`` (the second-fastest converged solution,
    a :class:`CollocationSolution`, or None) the previous-but-one start; ``extra_starts`` as
    :func:`speed_continuation` (key ``"max-speed"``).
    """
    spec = check_model_spec(model_spec)
    starts = check_starts(starts)
    if not isinstance(settings, CollocationSettings):
        raise SpecError(f"expected CollocationSettings, got {type(settings).__name__}",
                        where="settings")
    if not settings.max_speed:
        raise SpecError(f"the maximum-speed problem needs speed_m_per_s None, got "
                        f"{settings.speed_m_per_s:g} m/s", where="settings",
                        hint="max_speed_settings(settings) gives it")
    label = model_label(spec)
    for sol, what in ((guess, "warm start"), (previous, "previous-but-one start")):
        if isinstance(sol, CollocationSolution) and not same_model_spec(sol.model_spec, spec):
            raise SpecError(f"the {what} is a solution of {model_label(sol.model_spec)}, not "
                            f"{label}", where="guess" if sol is guess else "previous")
    out_dir = Path(out_dir)

    def report(event: str, *, path=None, message: str = "", solve=None) -> None:
        if progress is not None:
            progress(ContinuationProgress(label, "maximum speed", event, path, message, solve))

    get_runner = LazyRunner(runner, spec)
    if isinstance(guess, CollocationSolution):
        warm = Start("warm", settings, functools.partial(warm_guess, guess))
    else:
        warm = Start("warm", settings, lambda: guess)
    plan = [warm]
    if starts > 1:
        template = Start("template", settings, lambda: _template(
            get_runner, warm.guess().speed, settings.mesh_intervals))
        prev = None if previous is None else Start(
            "previous-but-one", settings,
            functools.partial(warm_guess, previous, " (the previous but one)"))
        source = COLLOCATION_SOURCE if isinstance(guess, CollocationSolution) else guess.source
        plan = plan_starts(starts, warm, warm_source=str(source), template=template,
                           previous=prev, restart_start=starts == MAX_STARTS)
    extra = _extra(extra_starts, None, settings)
    if extra:  # another model's stride: held at this model's own floor, not at its speed
        own_floor = warm.guess().speed
        extra = [dataclasses.replace(s, speed_floor=own_floor) for s in extra]
    ok, best = out_dir / MAX_SPEED_FILE, out_dir / MAX_SPEED_BEST_ITERATE_FILE
    kept, outcomes = solve_starts(
        plan + extra, ok=ok, best=best, report=report, several=starts > 1 or bool(extra),
        read=functools.partial(_stored, spec=spec, force=force),
        solve=functools.partial(_solve, get_runner, spec, progress is not None))
    solved = kept.solved or any(o.solved for o in outcomes)
    return SolveRecord("max-speed", None, kept.solution, kept.path, solved, outcomes)
