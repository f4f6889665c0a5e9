"""Solving one stride: the two-stage solve and the output folder (the settings:
:mod:`bladelab.predict.collocation.settings`).

:func:`predict_stride` runs the path that converges today (``docs/collocation.md``):

1. **tracking** — the muscle-driven stride NLP at the prescribed speed (the guess's own speed
   for a maximum-speed problem), minimising effort (:data:`TRACKING_WEIGHTS`) plus
   ``tracking_weight`` × the mean squared deviation [rad²] of the joint angles from the guess:
   a dynamically consistent stride near the guess;
2. **predictive** — the problem asked for (cost of transport + effort at the prescribed speed,
   or maximum speed + effort), warm-started from the tracking solution.

A tracking stage that ends in a local infeasibility (IPOPT's statuses in
:data:`TRACKING_RESTART_STATUSES`) is solved once more from its last iterate: the template
start of the able model at 4 m/s ended so on one host (violation 0.017 in the pelvis's
vertical velocity defects after 513 iterations) and converged in 574 more from there (IPOPT
restarts its barrier and its L-BFGS memory). The stage's ``tracking`` record then counts both
solves and names the first one's status (``restarted_after``).

A guess that is a solution of the same problem layout (mesh, model) and carries its
multipliers starts the predictive stage from its primal and dual values (IPOPT's warm start,
:data:`~bladelab.predict.collocation.ipopt_options.DUAL_WARM_START_OPTIONS`): a solution
solved again ends at once, a continuation step stays on its start's branch.

A predictive stage on L-BFGS that runs out of iterations near a feasible point is **polished**:
solved on from its last iterate and multipliers with the exact Hessian (stage ``"polish"``,
:attr:`~bladelab.predict.collocation.settings.CollocationSettings.polish_iter` iterations), and
the polished stride is kept if it converges. L-BFGS can stand thousands of iterations on a
feasible stride without meeting the optimality tolerance, where the exact Hessian, useless far
from a solution, finishes in about a hundred (measured: docs/collocation.md). The solution's
``timings`` record the polish.

The tracking stage keeps every swinging foot or blade :data:`TRACKING_SWING_CLEARANCE_M` above
the ground (:func:`~bladelab.predict.collocation.dynamics.swing_clearance`; the settings' own
clearance where larger), the predictive stage only the settings' own. A cold start from the
able runner's template otherwise ended in a stride with a second touch-down of a foot in 3 of 5
starts that differed by 10⁻⁶ rad; with the clearance in the tracking stage the predictive stage
starts from one contact per foot per stride (measured: docs/collocation.md, "The stride
NLP").

The tracking stage is skipped when ``track_first`` is False or the guess is itself a
collocation solution (its ``source`` starts with :data:`COLLOCATION_SOURCE`, as
:meth:`~bladelab.predict.collocation.solution.CollocationSolution.to_guess` and
:meth:`~bladelab.predict.collocation.nlp_solution.NLPSolution.to_guess` write it). A stage that
does not converge ends the solve: its last iterate is returned (``converged`` False) and is
never written as a solution. An interrupt (Ctrl-C, SIGTERM) during a stage raises
KeyboardInterrupt once IPOPT has returned: nothing is returned or written.

Deterministic: IPOPT with MUMPS (METIS ordering) on one thread; the same runner, settings and
guess give the same iterates, bit for bit.

The output folder of ``bladelab predict --method collocation`` is
:mod:`bladelab.predict.collocation.output_folder`'s.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import signal
import threading
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.dynamics import stride_dynamics
from bladelab.predict.collocation.ipopt_options import PREDICTIVE_LBFGS_OPTIONS
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.people import PROSTHETIC_JOINTS, people_reference
from bladelab.predict.collocation.settings import (
    PEOPLE_REFERENCE,
    POLISH_MAX_VIOLATION,
    CollocationSettings,
)
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import check_model_spec
from bladelab.predict.collocation.stride_guess import COLLOCATION_SOURCE
from bladelab.predict.collocation.stride_problem import StrideWeights
from bladelab.predict.collocation.swing_knee import biological_knees
from bladelab.predict.collocation.symmetry import mirror_permutation
from bladelab.predict.collocation.transcription import StrideNLP

__all__ = [
    "SolveProgress",
    "TRACKING_RESTART_STATUSES",
    "TRACKING_SWING_CLEARANCE_M",
    "TRACKING_WEIGHTS",
    "predict_stride",
    "warm_start_options",
]

#: Effort weights of the tracking stage (no metabolic term).
TRACKING_WEIGHTS = StrideWeights(metabolic=0.0, activation=1.0, acceleration=0.01)
#: Least height [m] of a swinging foot or blade above the ground in the tracking stage (module
#: docstring).
TRACKING_SWING_CLEARANCE_M = 0.01
#: IPOPT statuses of a tracking stage that is solved once more from its last iterate.
TRACKING_RESTART_STATUSES = ("Infeasible_Problem_Detected", "Restoration_Failed")


@dataclass(frozen=True)
class SolveProgress:
    """One progress report of :func:`predict_stride`.

    Attributes
    ----------
    stage
        ``"tracking"`` or ``"predictive"``.
    event
        ``"start"`` (with the problem's size in ``message``), ``"iteration"`` or ``"end"``.
    iteration
        IPOPT's iteration count so far.
    objective
        Objective value of the current iterate [-] (NaN at start).
    violation
        Largest constraint violation of the current iterate (scaled constraints) [-].
    elapsed_s
        Wall time since the stage started [s].
    message
        Problem size at start, IPOPT's status at the end.
    """

    stage: str
    event: str
    iteration: int = 0
    objective: float = math.nan
    violation: float = math.nan
    elapsed_s: float = 0.0
    message: str = ""


@contextlib.contextmanager
def _interrupts_recorded():
    """Record SIGINT/SIGTERM while IPOPT runs and raise KeyboardInterrupt after it returns.

    CasADi turns an interrupt inside IPOPT into the status ``NonIpopt_Exception_Thrown`` and
    returns normally; the caller would then take the interrupted iterate for a failed solve.
    The signals' previous handlers still run (the command line's SIGTERM handler marks the
    run as terminated)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    seen: list[int] = []
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}

    def record(signum, frame):
        seen.append(signum)
        handler = previous[signum]
        if callable(handler):
            handler(signum, frame)
        raise KeyboardInterrupt

    for sig in previous:
        signal.signal(sig, record)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if seen:
        raise KeyboardInterrupt


def warm_start_options(settings: CollocationSettings) -> dict:
    """IPOPT options of a stage warm-started from a collocation solution
    (:attr:`CollocationSettings.warm_start_mu`); empty when it is None."""
    if settings.warm_start_mu is None:
        return {}
    return {"ipopt.mu_init": settings.warm_start_mu, "ipopt.bound_push": 1e-8,
            "ipopt.bound_frac": 1e-8}


def _solve_stage(nlp, x0: np.ndarray, settings: CollocationSettings, stage: str,
                 progress: Callable[[SolveProgress], None] | None, *, warm: bool = False,
                 speed: float | None = None, multipliers=None):
    """Solve one NLP with the settings' IPOPT options (:func:`warm_start_options` when
    ``warm``; with ``multipliers``, the primal-dual warm start of
    :meth:`~bladelab.predict.collocation.transcription.StrideNLP.solve`, its barrier start
    :attr:`CollocationSettings.warm_start_mu` where set; with L-BFGS, every stage but the
    tracking stage with ``PREDICTIVE_LBFGS_OPTIONS``), reporting progress; an interrupt
    (Ctrl-C, SIGTERM) raises KeyboardInterrupt after IPOPT returns."""
    t0 = time.perf_counter()
    if multipliers is not None:
        options = ({} if settings.warm_start_mu is None
                   else {"ipopt.mu_init": settings.warm_start_mu})
    else:
        options = warm_start_options(settings) if warm else {}
    if settings.hessian == "limited-memory" and stage != "tracking":
        options = {**PREDICTIVE_LBFGS_OPTIONS, **options}
    report = None
    if progress is not None:
        progress(SolveProgress(stage, "start", message=f"{nlp.n_vars} variables, "
                               f"{nlp.n_cons} constraints, {nlp.n} mesh intervals"))

        def report(it: int, obj: float, viol: float) -> None:
            progress(SolveProgress(stage, "iteration", it, obj, viol, time.perf_counter() - t0))

    with _interrupts_recorded():
        sol = nlp.solve(x0, max_iter=settings.max_iter, tol=settings.tol,
                        hessian=settings.hessian, options=options, speed=speed,
                        progress=report, multipliers=multipliers)
    if progress is not None:
        progress(SolveProgress(stage, "end", sol.iterations, sol.objective, sol.max_violation,
                               time.perf_counter() - t0, sol.status))
    return sol


def _stalled(sol, settings: CollocationSettings) -> bool:
    """True for an L-BFGS stage that ran out of iterations near a feasible point
    (:attr:`CollocationSettings.polish_iter`, :data:`POLISH_MAX_VIOLATION`)."""
    return (settings.polish_iter > 0 and settings.hessian == "limited-memory"
            and sol.status == "Maximum_Iterations_Exceeded"
            and sol.max_violation <= POLISH_MAX_VIOLATION and sol.multipliers is not None)


def _polish(nlp, sol, settings: CollocationSettings,
            progress: Callable[[SolveProgress], None] | None, speed: float | None):
    """Solve ``nlp`` on from a stalled stage's last iterate and multipliers with the exact
    Hessian (stage ``"polish"``, at most ``settings.polish_iter`` iterations). Returns the
    polished solution if it converged, else ``sol``; either way its ``timings`` count the
    polish (``polish_iterations``, ``polish_s``, and ``polished`` 1 or 0) and its
    ``iterations`` and ``wall_s`` are the two solves' together."""
    exact = dataclasses.replace(settings, hessian="exact", max_iter=settings.polish_iter)
    nlp = nlp.interpreted()  # the exact Hessian needs the interpreted node function
    polished = _solve_stage(nlp, nlp.initial_vector(sol.to_guess("the stalled stage")), exact,
                            "polish", progress, speed=speed, multipliers=sol.multipliers)
    kept = polished if polished.success else sol
    timings = {**kept.timings, "polish_iterations": float(polished.iterations),
               "polish_s": float(polished.wall_s), "polished": float(polished.success)}
    return dataclasses.replace(kept, iterations=sol.iterations + polished.iterations,
                               wall_s=sol.wall_s + polished.wall_s, timings=timings)


def _stage_info(sol) -> dict:
    return {"success": bool(sol.success), "status": sol.status, "iterations": int(sol.iterations),
            "wall_s": float(sol.wall_s), "objective": float(sol.objective),
            "max_violation": float(sol.max_violation),
            "ipopt_own_s": float(sol.timings.get("ipopt_own_s", 0.0))}


#: Per runner (weakly held): its collocation model, its stride dynamics and the predictive
#: NLPs built for it, so that a continuation, a sweep or several starts build each NLP and its
#: IPOPT solver once (14–20 s at mesh 50) instead of once per solve.
_BUILT: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: Predictive NLPs kept per runner (the oldest is dropped; each holds up to
#: ``StrideNLP.MAX_SOLVERS`` expanded solvers).
MAX_NLPS_PER_RUNNER = 2


def _model_functions(runner, swing_clearance_m: float = 0.0,
                     knee_moment_min_nm: float | None = None, blade_backward_euler: bool = False,
                     knee_flexion_max_loaded_deg: float | None = None,
                     pelvis_tilt_range_deg: tuple[float, float] | None = None,
                     prosthetic_load_max_bw: float | None = None):
    """(collocation model, stride dynamics) of ``runner``, built once (per swing clearance,
    knee moment bound, loaded knee's flexion limit, prosthetic load limit and blade
    transcription; a pelvis tilt range narrows the bounds of the dynamics built without
    it)."""
    built = _BUILT.setdefault(runner, {"dyn": {}, "nlps": {}})
    if "cm" not in built:
        built["cm"] = build_collocation_model(runner)
    key = (swing_clearance_m, knee_moment_min_nm, blade_backward_euler,
           knee_flexion_max_loaded_deg, prosthetic_load_max_bw)
    if key not in built["dyn"]:
        built["dyn"][key] = stride_dynamics(built["cm"], swing_clearance_m=swing_clearance_m,
                                            knee_moment_min_nm=knee_moment_min_nm,
                                            knee_flexion_max_loaded_deg=(
                                                knee_flexion_max_loaded_deg),
                                            prosthetic_load_max_bw=prosthetic_load_max_bw,
                                            blade_backward_euler=blade_backward_euler)
    if pelvis_tilt_range_deg is None:
        return built["cm"], built["dyn"][key]
    narrowed = (*key, tuple(pelvis_tilt_range_deg))
    if narrowed not in built["dyn"]:
        dyn = built["dyn"][key]
        q_bounds = dyn.q_bounds.copy()
        q_bounds[dyn.dof_names.index("pelvis_tilt")] = np.radians(pelvis_tilt_range_deg)
        built["dyn"][narrowed] = dataclasses.replace(dyn, q_bounds=q_bounds)
    return built["cm"], built["dyn"][narrowed]


def _reference_phase(runner, settings: CollocationSettings, start) -> float | None:
    """The phase [fraction of the stride] of people's angles for a solve from ``start`` (the
    guess on the mesh): the start's own (``StrideGuess.reference_phase``, a stride solved
    against them), else the phase that fits the start best; None without people's
    reference."""
    if not settings.reference_weight or settings.reference != PEOPLE_REFERENCE:
        return None
    if start.reference_phase is not None:
        return float(start.reference_phase) % 1.0
    return people_reference(runner.dof_names, start.q, settings.reference_dofs,
                            exclude=PROSTHETIC_JOINTS.get(runner.kind, ()))[2]


def _reference_tracking(runner, settings: CollocationSettings, start,
                        phase: float | None) -> tuple:
    """The predictive stage's reference terms (:attr:`CollocationSettings.reference`):
    ``((q_ref, weight, dofs) on the mesh, (T_ref, weight) or None)``, or (None, None).
    People's angles (``reference="people"``) at ``phase`` (:func:`_reference_phase`) have no
    stride-time term; a solution file's have its stride time's."""
    if not settings.reference_weight:
        return None, None
    if settings.reference == PEOPLE_REFERENCE:
        q, dofs, _ = people_reference(runner.dof_names, start.q, settings.reference_dofs,
                                      exclude=PROSTHETIC_JOINTS.get(runner.kind, ()),
                                      phase=phase)
        return (q, settings.reference_weight, dofs), None
    path = Path(settings.reference)
    if not path.is_file():
        raise InputFileError("no such reference solution", file=path,
                             hint="the collocation solution whose joint angles the gait stays "
                                  f"near (settings: reference), or '{PEOPLE_REFERENCE}'")
    ref = CollocationSolution.read(path).to_guess(f"{COLLOCATION_SOURCE} {path.name}")
    q = ref.on_model(runner).resample(settings.mesh_intervals).q
    return (q, settings.reference_weight, settings.reference_dofs), (
        ref.period, settings.reference_weight)


def _compiled(settings: CollocationSettings) -> bool | None:
    """The NLP's ``compiled`` argument: the default (compiled unless turned off) with L-BFGS,
    False with the exact Hessian (which needs the interpreted node function)."""
    return False if settings.hessian == "exact" else None


def _knee_flexion_min(runner, settings: CollocationSettings) -> dict[str, float] | None:
    """{knee coordinate: minimum peak flexion [rad]} of the settings' swing knee on the
    runner's biological knees, or None."""
    if settings.swing_knee_min_deg is None:
        return None
    minimum = math.radians(settings.swing_knee_min_deg)
    return {k: minimum for k in biological_knees(runner.dof_names, runner.kind)} or None


def _predictive_nlp(runner, dyn, settings: CollocationSettings, start, phase: float | None):
    """The predictive :class:`~bladelab.predict.collocation.transcription.StrideNLP` of the
    settings' mesh, problem (prescribed speed, or maximum speed), weights, reference term,
    alternating steps, symmetry and stride time range,
    built once per runner and reference (the reference file is read only then; people's
    angles once per ``phase``, :func:`_reference_phase` of the guess ``start``); the speed
    itself is a parameter of each solve."""
    n, speed = settings.mesh_intervals, settings.speed_m_per_s
    nlps = _BUILT[runner]["nlps"]
    key = (n, speed is None, settings.weights, id(dyn), settings.reference_key(), phase,
           settings.step_phase_tolerance, settings.symmetric, settings.period_bounds_s,
           settings.period_band, settings.swing_knee_min_deg, settings.hessian)
    if key not in nlps:
        while len(nlps) >= MAX_NLPS_PER_RUNNER:
            nlps.pop(next(iter(nlps)))
        tracking, period_tracking = _reference_tracking(runner, settings, start, phase)
        nlps[key] = StrideNLP(dyn, n=n, speed=speed, weights=settings.weights,
                              tracking=tracking, period_tracking=period_tracking,
                              step_phase_tolerance=settings.step_phase_tolerance,
                              symmetric=settings.symmetric,
                              period_bounds=settings.period_bounds_s,
                              period_band=settings.period_band,
                              knee_flexion_min=_knee_flexion_min(runner, settings),
                              compiled=_compiled(settings))
    else:
        nlps[key] = nlps.pop(key)  # most recently used last
    return nlps[key]


def predict_stride(runner, settings: CollocationSettings, guess, *, model_spec: dict,
                   progress: Callable[[SolveProgress], None] | None = None,
                   track: bool | None = None, speed_floor: float | None = None):
    """Solve one periodic stride of ``runner`` (module docstring): tracking, then predictive.

    Parameters
    ----------
    runner
        The forward model (:func:`bladelab.runner.build_runner`).
    settings
        :class:`CollocationSettings`.
    guess
        Initial guess (:class:`~bladelab.predict.collocation.stride_guess.StrideGuess`),
        resampled to the mesh; scaled to the prescribed speed (same period) if it runs at
        another one, unless it starts the predictive stage from its multipliers (then its own
        point is the start).
    model_spec
        ``{"model": "able" | "amputee", "blade": "Cat6" | None}``: how ``runner`` was built,
        stored with the solution (:func:`~bladelab.predict.collocation.stored.runner_from_spec`
        builds it again).
    progress
        Called with a :class:`SolveProgress` at each stage's start, every IPOPT iteration and
        each stage's end.
    track
        Force (True) or skip (False) the tracking stage; None: ``settings.track_first`` unless
        the guess is a collocation solution.
    speed_floor
        The maximum-speed problem only: the mean speed [m/s] the stride must at least reach, a
        speed at which ``runner`` is known to have a stride. None: that of the collocation
        stride it starts from, which holds only if that stride is of this runner (a stride
        of another blade as the start would otherwise pin the answer to its speed).

    Returns
    -------
    CollocationSolution
        ``converged`` True only if the predictive stage converged; otherwise the last iterate
        of the stage that did not (``stage`` names it).
    """
    spec = check_model_spec(model_spec)
    if speed_floor is not None and (settings.speed_m_per_s is not None or not (
            speed_floor >= 0 and math.isfinite(speed_floor))):
        raise SpecError(f"a speed floor ({speed_floor!r} m/s) needs the maximum-speed problem "
                        "and a finite speed >= 0", where="speed_floor",
                        hint="leave it out with a prescribed speed")
    if runner.kind != spec["model"]:
        raise SpecError(f"the runner is the {runner.kind} model, model_spec says "
                        f"{spec['model']}", where="model_spec")
    if not isinstance(settings, CollocationSettings):
        raise SpecError(f"expected CollocationSettings, got {type(settings).__name__}",
                        where="settings")
    if settings.symmetric:  # refused before any stage runs (the legs: when the NLP is built)
        mirror_permutation(runner.dof_names)
        mirror_permutation(runner.muscle_names)
    others = (settings.knee_moment_min_nm, settings.blade_backward_euler,
              settings.knee_flexion_max_loaded_deg, settings.pelvis_tilt_range_deg,
              settings.prosthetic_load_max_bw)
    cm, dyn = _model_functions(runner, settings.swing_clearance_m, *others)
    n = settings.mesh_intervals
    g = guess.on_model(runner).resample(n)
    speed = settings.speed_m_per_s
    warm = str(guess.source).startswith(COLLOCATION_SOURCE)
    tracking_stage = (settings.track_first and not warm) if track is None else bool(track)
    warm_predictive = warm and not tracking_stage
    phase = _reference_phase(runner, settings, g)
    duals = (_predictive_nlp(runner, dyn, settings, g, phase).initial_multipliers(g)
             if warm_predictive else None)
    # a primal-dual start stays at the solution's own point, whose one violated constraint is
    # then the speed: scaled to the speed it starts off its branch (measured: 843 iterations
    # and a stride 18 % dearer against 224, docs/collocation.md "Warm starts")
    if duals is None and speed is not None and not math.isclose(g.speed, speed, rel_tol=1e-12):
        g = g.with_speed(speed)
    common = {"settings": settings, "model_spec": spec, "guess_source": str(guess.source),
              "cm": cm}
    tracking = None
    start = g
    if tracking_stage:
        grf = None
        if g.vertical_grf_bw is not None and settings.grf_tracking_weight > 0:
            grf = (g.vertical_grf_bw * runner.body_weight, settings.grf_tracking_weight)
        _, dyn_t = _model_functions(
            runner, max(settings.swing_clearance_m, TRACKING_SWING_CLEARANCE_M), *others)
        nlp_t = StrideNLP(dyn_t, n=n, speed=speed if speed is not None else g.speed,
                          weights=TRACKING_WEIGHTS, tracking=(g.q, settings.tracking_weight),
                          grf_tracking=grf, period_bounds=settings.period_bounds_s,
                          compiled=_compiled(settings))
        sol_t = _solve_stage(nlp_t, nlp_t.initial_vector(g), settings, "tracking", progress)
        tracking = _stage_info(sol_t)
        if not sol_t.success and sol_t.status in TRACKING_RESTART_STATUSES:
            first = tracking
            sol_t = _solve_stage(nlp_t, nlp_t.initial_vector(sol_t.to_guess("tracking restart")),
                                 settings, "tracking", progress)
            again = _stage_info(sol_t)
            both = {key: first[key] + again[key] for key in ("iterations", "wall_s", "ipopt_own_s")}
            tracking = again | both | {"restarted_after": first["status"]}
        if not sol_t.success:
            return CollocationSolution.from_nlp(
                runner, sol_t, stage="tracking", tracking=tracking,
                metabolic_energy_J=nlp_t.energy_and_distance(sol_t)[0], **common)
        start = sol_t.to_guess(f"{COLLOCATION_SOURCE} (tracking stage)")
    nlp_p = _predictive_nlp(runner, dyn, settings, g, phase)  # built once, then looked up
    # the prescribed speed; of a maximum speed, its floor: the caller's, else that of a
    # collocation stride it starts from (a stride that exists)
    stage_speed = (speed if speed is not None else speed_floor if speed_floor is not None
                   else g.speed if warm else None)
    sol = _solve_stage(nlp_p, nlp_p.initial_vector(start), settings, "predictive", progress,
                       warm=warm_predictive, speed=stage_speed, multipliers=duals)
    if _stalled(sol, settings):
        sol = _polish(nlp_p, sol, settings, progress, stage_speed)
    return CollocationSolution.from_nlp(
        runner, sol, stage="predictive", tracking=tracking,
        metabolic_energy_J=nlp_p.energy_and_distance(sol)[0], reference_phase=phase,
        speed_floor_mps=stage_speed if speed is None else None,
        **common)
