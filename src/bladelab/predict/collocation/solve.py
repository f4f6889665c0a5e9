"""Solving one stride: the settings, the two-stage solve and the output folder (issue 15).

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

The tracking stage is skipped when ``track_first`` is False or the guess is itself a
collocation solution (its ``source`` starts with :data:`COLLOCATION_SOURCE`, as
:meth:`~bladelab.predict.collocation.solution.CollocationSolution.to_guess` and
:meth:`~bladelab.predict.collocation.transcription.NLPSolution.to_guess` write it). A stage that
does not converge ends the solve: its last iterate is returned (``converged`` False) and is
never written as a solution. An interrupt (Ctrl-C, SIGTERM) during a stage raises
KeyboardInterrupt once IPOPT has returned: nothing is returned or written.

Deterministic: IPOPT with MUMPS (METIS ordering) on one thread; the same runner, settings and
guess give the same iterates, bit for bit.

:func:`predict_stride_in_folder` adds the output folder of ``bladelab predict --method
collocation``: ``solution.json`` only for a converged solve, ``best_iterate.json`` otherwise
(never both: the stale one is removed once the new file is in place); files are written
atomically, so an interruption leaves the previous state of the folder.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import time
import weakref
from collections.abc import Callable
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.transcription import StrideWeights

__all__ = [
    "BEST_ITERATE_FILE",
    "COLLOCATION_SOURCE",
    "CollocationSettings",
    "FolderResult",
    "HESSIANS",
    "SOLUTION_FILE",
    "SolveProgress",
    "TRACKING_RESTART_STATUSES",
    "TRACKING_WEIGHTS",
    "predict_stride",
    "predict_stride_in_folder",
    "warm_start_options",
]

#: The guess source prefix that marks a collocation solution (no tracking stage needed).
COLLOCATION_SOURCE = "collocation solution"
#: Effort weights of the tracking stage (no metabolic term).
TRACKING_WEIGHTS = StrideWeights(metabolic=0.0, activation=1.0, acceleration=0.01)
#: IPOPT statuses of a tracking stage that is solved once more from its last iterate.
TRACKING_RESTART_STATUSES = ("Infeasible_Problem_Detected", "Restoration_Failed")
#: IPOPT Hessian options (:meth:`StrideNLP.solve`).
HESSIANS = ("limited-memory", "exact")
#: File names in a ``bladelab predict --method collocation`` folder.
SOLUTION_FILE = "solution.json"
BEST_ITERATE_FILE = "best_iterate.json"


def _weights_from_dict(data, where: str) -> StrideWeights:
    if isinstance(data, StrideWeights):
        return data
    if not isinstance(data, dict):
        raise SpecError(f"expected a mapping of objective weights, got {type(data).__name__}",
                        where=where)
    known = {f.name for f in fields(StrideWeights)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise SpecError(f"unknown objective weight(s) {', '.join(unknown)}", where=where,
                        hint=f"known: {', '.join(sorted(known))}")
    try:
        return StrideWeights(**{k: float(v) for k, v in data.items()})
    except (TypeError, ValueError):
        raise SpecError("objective weights must be numbers", where=where) from None


@dataclass(frozen=True)
class CollocationSettings:
    """Settings of one stride solve.

    Attributes
    ----------
    mesh_intervals
        Mesh intervals n of the stride (trapezoidal collocation, n + 1 nodes).
    speed_m_per_s
        Prescribed mean speed [m/s]; None: the maximum-speed problem.
    weights
        Objective weights of the predictive stage (:class:`StrideWeights`); None: cost of
        transport 1, activation 1, acceleration 0.1 at a prescribed speed; speed 1,
        activation 1, acceleration 0.1 and no metabolic term for the maximum speed.
    tracking_weight
        Weight of the joint-angle tracking term of the tracking stage [1/rad²].
    grf_tracking_weight
        Weight of the tracking stage's vertical-ground-force term [1/BW²], used when the guess
        carries a force pattern (``StrideGuess.vertical_grf_bw``; every guess function gives
        one). Measured: with angles alone the stage met the Fukuchi angles with a one-legged
        hop and the template with 20-BW bounds; with the force pattern, alternating stances.
    track_first
        Run the tracking stage before the predictive one (module docstring).
    hessian
        IPOPT's Hessian: ``"limited-memory"`` (L-BFGS, adaptive barrier) or ``"exact"``.
    tol
        IPOPT's convergence tolerance [-].
    max_iter
        IPOPT's iteration limit per stage.
    warm_start_mu
        IPOPT's initial barrier parameter when the predictive stage starts from a collocation
        solution (a warm start: speed continuation, maximum speed, ``--guess solution.json``),
        with ``bound_push`` = ``bound_frac`` = 1e-8 so that the start is not pushed away from
        the bounds it sits on; None (default): IPOPT's defaults (mu_init 0.1, bound_push and
        bound_frac 0.01). Neither is better everywhere (measured 2026-11-25, mesh 50): amputee
        Cat6 4 → 4.2 m/s reached objective 2.708 with 1e-4 and 3.323 with the defaults; Cat5
        4 → 5 m/s reached a cost of transport of 3.33 with 1e-4 and 2.89 with the defaults,
        and the maximum speeds of Cat4/Cat5 were 6.99/7.32 m/s with 1e-4 against 7.53/7.71
        m/s. The landscape has local optima 15–25 % apart along a continuation; the two
        settings are two starts (docs/collocation.md).
    swing_clearance_m
        Keep every swinging foot or blade at least this high above the ground [m]: a path
        constraint on each contact while it moves forward faster than the pelvis
        (:func:`~bladelab.predict.collocation.dynamics.swing_clearance`); 0 (default): none.
        Issue 21's "toe clearance as a constraint" setting (the transfemoral runner's blade
        grazed the ground in swing without it).
    knee_moment_min_nm
        Keep the external extension moment of the prosthetic contacts' ground forces about the
        prosthetic knee at or above this [N·m] at every node (seed 002's knee-buckling
        constraint, :func:`~bladelab.predict.collocation.dynamics.knee_extension_moment`;
        at most 0, since the moment is 0 in swing); None (default): no constraint. Transfemoral
        runner only.
    knee_flexion_max_loaded_deg
        Keep the prosthetic knee within this flexion [deg] of straight while its blade
        carries load (a path constraint weighted by the blade's vertical force,
        :func:`~bladelab.predict.collocation.dynamics.knee_straight_while_loaded`): the
        straight stance from which ``knee_moment_min_nm`` at 0 becomes reachable
        (docs/design.md); None (default): no constraint. Transfemoral runner only.
    blade_backward_euler
        Transcribe a multi-link blade's joints by backward Euler instead of the trapezoidal
        rule (``StrideDynamics.backward_euler_dofs``): its links' modes (about 300 Hz) are
        resolved by no mesh, and with the trapezoidal rule they ring from node to node
        (measured 2026-11-26 on the transfemoral design stride: blade-joint accelerations
        alternating ±1500 rad/s², sole friction forces and the knee moment alternating in
        sign from node to node). Backward Euler damps them: first-order accurate, it lags and
        damps the blade's own motion by O(h) (docs/design.md). No effect without such a blade.
    pelvis_tilt_range_deg
        (lo, hi) [deg]: keep the pelvis tilt inside this range at every node (bounds; forward
        lean negative), e.g. seed 001's window (-16, -2) that issue 20 asks of a reflex gait;
        None (default): the coordinate's own bounds (-60, 30). A stride the reflex
        controller tracks (``bladelab predict --track``) passes its lean on: the Cat6 4 m/s
        stride without it leans -17.8° on average (docs/collocation.md).
    reference, reference_weight, reference_dofs
        A collocation solution file of the same runner whose joint angles the predictive
        stage stays near: ``reference_weight`` [1/rad²] × the time-averaged mean squared
        deviation of the coordinates ``reference_dofs`` (None: pelvis tilt and every joint)
        from the reference's, on the normalised stride, plus the same weight × ln(T/T_ref)²
        of the stride time T against the reference's (the cadence: measured session 15, with
        the angles alone the design strides split into 0.51 s and 0.59 s strides, both
        within 7° of the reference's angles). Weight 0 (default): none, the gait
        is predicted freely. The design study's "athlete keeps their technique" setting
        (docs/design.md): without it the optimum's split of the horizontal impulse between
        the legs is barely determined and depends on the start. The problem's identity
        (:meth:`same_problem`) holds the reference's file name, not its folder.
    """

    mesh_intervals: int = 50
    speed_m_per_s: float | None = 3.5
    weights: StrideWeights | None = None
    tracking_weight: float = 100.0
    grf_tracking_weight: float = 10.0
    track_first: bool = True
    hessian: str = "limited-memory"
    tol: float = 1e-4
    max_iter: int = 3000
    warm_start_mu: float | None = None
    swing_clearance_m: float = 0.0
    knee_moment_min_nm: float | None = None
    knee_flexion_max_loaded_deg: float | None = None
    blade_backward_euler: bool = False
    pelvis_tilt_range_deg: tuple[float, float] | None = None
    reference: str | None = None
    reference_weight: float = 0.0
    reference_dofs: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        n = self.mesh_intervals
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 4:
            raise SpecError(f"need an integer of at least 4 mesh intervals, got {n!r}",
                            where="mesh_intervals")
        object.__setattr__(self, "mesh_intervals", int(n))
        v = self.speed_m_per_s
        if v is not None:
            if isinstance(v, bool) or not isinstance(v, int | float) or not (
                    math.isfinite(v) and v > 0):
                raise SpecError(f"speed must be > 0 m/s or None (maximum speed), got {v!r}",
                                where="speed_m_per_s")
            object.__setattr__(self, "speed_m_per_s", float(v))
        if self.weights is None:
            w = (StrideWeights(metabolic=1.0, activation=1.0, acceleration=0.1)
                 if v is not None else
                 StrideWeights(metabolic=0.0, activation=1.0, acceleration=0.1, speed=1.0))
        else:
            w = _weights_from_dict(self.weights, "weights")
        object.__setattr__(self, "weights", w)
        self._check_weight("tracking_weight", "tracking weight")
        self._check_weight("grf_tracking_weight", "force tracking weight")
        if not isinstance(self.track_first, bool):
            raise SpecError(f"expected true or false, got {self.track_first!r}",
                            where="track_first")
        if self.hessian not in HESSIANS:
            raise SpecError(f"unknown Hessian option {self.hessian!r}", where="hessian",
                            hint=" or ".join(HESSIANS))
        if isinstance(self.tol, bool) or not isinstance(self.tol, int | float) or not (
                math.isfinite(self.tol) and self.tol > 0):
            raise SpecError(f"tolerance must be > 0, got {self.tol!r}", where="tol")
        object.__setattr__(self, "tol", float(self.tol))
        mi = self.max_iter
        if isinstance(mi, bool) or not isinstance(mi, int | np.integer) or mi < 1:
            raise SpecError(f"need at least 1 iteration, got {mi!r}", where="max_iter")
        object.__setattr__(self, "max_iter", int(mi))
        mu = self.warm_start_mu
        if mu is not None:
            if isinstance(mu, bool) or not isinstance(mu, int | float) or not (
                    math.isfinite(mu) and mu > 0):
                raise SpecError(f"the warm-start barrier must be > 0 or None, got {mu!r}",
                                where="warm_start_mu")
            object.__setattr__(self, "warm_start_mu", float(mu))

        sc = self.swing_clearance_m
        if isinstance(sc, bool) or not isinstance(sc, int | float) or not (
                math.isfinite(sc) and 0 <= sc < 0.5):
            raise SpecError(f"swing clearance must be within [0, 0.5) m, got {sc!r}",
                            where="swing_clearance_m")
        object.__setattr__(self, "swing_clearance_m", float(sc))
        km = self.knee_moment_min_nm
        if km is not None:
            if isinstance(km, bool) or not isinstance(km, int | float) or not (
                    math.isfinite(km) and km <= 0):
                raise SpecError(f"the knee moment minimum must be <= 0 N·m or None, got {km!r}",
                                where="knee_moment_min_nm",
                                hint="the moment is 0 while the prosthesis is off the ground")
            object.__setattr__(self, "knee_moment_min_nm", float(km))
        kf = self.knee_flexion_max_loaded_deg
        if kf is not None:
            if isinstance(kf, bool) or not isinstance(kf, int | float) or not (
                    math.isfinite(kf) and 0 <= kf <= 90):
                raise SpecError(f"the loaded knee's flexion limit must be within [0, 90] deg "
                                f"or None, got {kf!r}", where="knee_flexion_max_loaded_deg")
            object.__setattr__(self, "knee_flexion_max_loaded_deg", float(kf))
        if not isinstance(self.blade_backward_euler, bool):
            raise SpecError(f"expected true or false, got {self.blade_backward_euler!r}",
                            where="blade_backward_euler")
        self._check_tilt_range()
        self._check_reference()

    def _check_tilt_range(self) -> None:
        """``pelvis_tilt_range_deg``: None or (lo, hi) [deg] with lo < hi inside the pelvis
        tilt's own bounds, stored as a tuple of floats."""
        from bladelab.predict.collocation.dynamics import COORDINATE_BOUNDS_DEG

        tr = self.pelvis_tilt_range_deg
        if tr is None:
            return
        lo_all, hi_all = COORDINATE_BOUNDS_DEG["pelvis_tilt"]
        ok = (not isinstance(tr, str | bytes) and len(tr) == 2
              and all(isinstance(v, int | float) and not isinstance(v, bool)
                      and math.isfinite(v) for v in tr)
              and lo_all <= tr[0] < tr[1] <= hi_all)
        if not ok:
            raise SpecError(f"the pelvis tilt range must be (lo, hi) [deg] with {lo_all:g} <= "
                            f"lo < hi <= {hi_all:g}, got {tr!r}", where="pelvis_tilt_range_deg",
                            hint="seed 001's window is -16, -2 (forward lean negative)")
        object.__setattr__(self, "pelvis_tilt_range_deg", (float(tr[0]), float(tr[1])))

    def _check_weight(self, name: str, what: str) -> None:
        """A weight field: a finite number >= 0, stored as float."""
        w = getattr(self, name)
        if isinstance(w, bool) or not isinstance(w, int | float) or not (
                math.isfinite(w) and w >= 0):
            raise SpecError(f"{what} must be >= 0, got {w!r}", where=name)
        object.__setattr__(self, name, float(w))

    def _check_reference(self) -> None:
        self._check_weight("reference_weight", "the reference weight")
        rw = self.reference_weight
        if self.reference is not None:
            object.__setattr__(self, "reference", str(self.reference))
        if rw > 0 and self.reference is None:
            raise SpecError("a reference weight needs a reference solution", where="reference",
                            hint="give the solution file whose joint angles to stay near")
        dofs = self.reference_dofs
        if dofs is not None:
            if isinstance(dofs, str) or not all(isinstance(d, str) for d in dofs) or not dofs:
                raise SpecError(f"expected a list of coordinate names, got {dofs!r}",
                                where="reference_dofs")
            object.__setattr__(self, "reference_dofs", tuple(dofs))

    @property
    def max_speed(self) -> bool:
        """True for the maximum-speed problem."""
        return self.speed_m_per_s is None

    def to_dict(self) -> dict:
        out = asdict(self)
        out["weights"] = self.weights.to_dict()
        if self.reference_dofs is not None:
            out["reference_dofs"] = list(self.reference_dofs)
        if self.pelvis_tilt_range_deg is not None:
            out["pelvis_tilt_range_deg"] = list(self.pelvis_tilt_range_deg)
        return out

    @classmethod
    def from_dict(cls, data: dict) -> CollocationSettings:
        """Settings from :meth:`to_dict`'s mapping; an unknown key raises SpecError naming it
        (missing keys take their defaults)."""
        if not isinstance(data, dict):
            raise SpecError(f"expected a mapping of settings, got {type(data).__name__}",
                            where="settings")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise SpecError(f"unknown setting(s) {', '.join(unknown)}", where="settings",
                            hint=f"known: {', '.join(sorted(known))}")
        return cls(**data)

    def same_problem(self, other: CollocationSettings) -> bool:
        """True if ``other`` poses the same NLP (mesh, speed, weights, swing clearance, knee
        moment bound, loaded knee's flexion limit, blade transcription, pelvis tilt range);
        solver options
        (Hessian, tolerance, iterations) and the tracking stage may differ."""
        return self._problem() == other._problem()

    def _problem(self) -> tuple:
        return (self.mesh_intervals, self.speed_m_per_s, self.weights, self.swing_clearance_m,
                self.knee_moment_min_nm, self.knee_flexion_max_loaded_deg,
                self.blade_backward_euler, self.pelvis_tilt_range_deg) + self._reference_key()

    def _reference_key(self) -> tuple:
        """(reference file name, weight, coordinates), or () without a reference term."""
        if not self.reference_weight:
            return ()
        return (Path(self.reference).name, self.reference_weight, self.reference_dofs)


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
    import signal
    import threading

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
                 speed: float | None = None):
    """Solve one NLP with the settings' IPOPT options (:func:`warm_start_options` when
    ``warm``), reporting progress; an interrupt (Ctrl-C, SIGTERM) raises KeyboardInterrupt
    after IPOPT returns."""
    t0 = time.perf_counter()
    options = warm_start_options(settings) if warm else {}
    report = None
    if progress is not None:
        progress(SolveProgress(stage, "start", message=f"{nlp.n_vars} variables, "
                               f"{nlp.n_cons} constraints, {nlp.n} mesh intervals"))

        def report(it: int, obj: float, viol: float) -> None:
            progress(SolveProgress(stage, "iteration", it, obj, viol, time.perf_counter() - t0))

    with _interrupts_recorded():
        sol = nlp.solve(x0, max_iter=settings.max_iter, tol=settings.tol,
                        hessian=settings.hessian, options=options, speed=speed,
                        progress=report)
    if progress is not None:
        progress(SolveProgress(stage, "end", sol.iterations, sol.objective, sol.max_violation,
                               time.perf_counter() - t0, sol.status))
    return sol


def _stage_info(sol) -> dict:
    return {"success": bool(sol.success), "status": sol.status, "iterations": int(sol.iterations),
            "wall_s": float(sol.wall_s), "objective": float(sol.objective),
            "max_violation": float(sol.max_violation)}


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
                     pelvis_tilt_range_deg: tuple[float, float] | None = None):
    """(collocation model, stride dynamics) of ``runner``, built once (per swing clearance,
    knee moment bound, loaded knee's flexion limit and blade transcription; a pelvis tilt
    range narrows the bounds of the dynamics built without it)."""
    from bladelab.predict.collocation.dynamics import stride_dynamics
    from bladelab.predict.collocation.model import build_collocation_model

    built = _BUILT.setdefault(runner, {"dyn": {}, "nlps": {}})
    if "cm" not in built:
        built["cm"] = build_collocation_model(runner)
    key = (swing_clearance_m, knee_moment_min_nm, blade_backward_euler,
           knee_flexion_max_loaded_deg)
    if key not in built["dyn"]:
        built["dyn"][key] = stride_dynamics(built["cm"], swing_clearance_m=swing_clearance_m,
                                            knee_moment_min_nm=knee_moment_min_nm,
                                            knee_flexion_max_loaded_deg=(
                                                knee_flexion_max_loaded_deg),
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


def _reference_tracking(runner, settings: CollocationSettings) -> tuple:
    """The predictive stage's reference terms (:attr:`CollocationSettings.reference`):
    ``((q_ref, weight, dofs) on the mesh, (T_ref, weight))``, or (None, None)."""
    if not settings.reference_weight:
        return None, None
    from bladelab.predict.collocation.solution import CollocationSolution

    path = Path(settings.reference)
    if not path.is_file():
        raise InputFileError("no such reference solution", file=path,
                             hint="the collocation solution whose joint angles the gait stays "
                                  "near (settings: reference)")
    ref = CollocationSolution.read(path).to_guess(f"{COLLOCATION_SOURCE} {path.name}")
    q = ref.on_model(runner).resample(settings.mesh_intervals).q
    return (q, settings.reference_weight, settings.reference_dofs), (
        ref.period, settings.reference_weight)


def _predictive_nlp(runner, dyn, settings: CollocationSettings):
    """The predictive :class:`~bladelab.predict.collocation.transcription.StrideNLP` of the
    settings' mesh, problem (prescribed speed, or maximum speed), weights and reference term,
    built once per runner (the reference file is read only then); the speed itself is a
    parameter of each solve."""
    from bladelab.predict.collocation.transcription import StrideNLP

    n, speed = settings.mesh_intervals, settings.speed_m_per_s
    nlps = _BUILT[runner]["nlps"]
    key = (n, speed is None, settings.weights, id(dyn), settings._reference_key())
    if key not in nlps:
        while len(nlps) >= MAX_NLPS_PER_RUNNER:
            nlps.pop(next(iter(nlps)))
        tracking, period_tracking = _reference_tracking(runner, settings)
        nlps[key] = StrideNLP(dyn, n=n, speed=speed, weights=settings.weights,
                              tracking=tracking, period_tracking=period_tracking)
    else:
        nlps[key] = nlps.pop(key)  # most recently used last
    return nlps[key]


def predict_stride(runner, settings: CollocationSettings, guess, *, model_spec: dict,
                   progress: Callable[[SolveProgress], None] | None = None,
                   track: bool | None = None):
    """Solve one periodic stride of ``runner`` (module docstring): tracking, then predictive.

    Parameters
    ----------
    runner
        The forward model (:func:`bladelab.runner.build_runner`).
    settings
        :class:`CollocationSettings`.
    guess
        Initial guess (:class:`~bladelab.predict.collocation.guess.StrideGuess`), resampled to
        the mesh; scaled to the prescribed speed (same period) if it runs at another one.
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

    Returns
    -------
    CollocationSolution
        ``converged`` True only if the predictive stage converged; otherwise the last iterate
        of the stage that did not (``stage`` names it).
    """
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.predict.collocation.stored import check_model_spec
    from bladelab.predict.collocation.transcription import StrideNLP

    spec = check_model_spec(model_spec)
    if runner.kind != spec["model"]:
        raise SpecError(f"the runner is the {runner.kind} model, model_spec says "
                        f"{spec['model']}", where="model_spec")
    if not isinstance(settings, CollocationSettings):
        raise SpecError(f"expected CollocationSettings, got {type(settings).__name__}",
                        where="settings")
    cm, dyn = _model_functions(runner, settings.swing_clearance_m, settings.knee_moment_min_nm,
                               settings.blade_backward_euler,
                               settings.knee_flexion_max_loaded_deg,
                               settings.pelvis_tilt_range_deg)
    n = settings.mesh_intervals
    g = guess.on_model(runner).resample(n)
    speed = settings.speed_m_per_s
    if speed is not None and not math.isclose(g.speed, speed, rel_tol=1e-12):
        g = g.with_speed(speed)
    warm = str(guess.source).startswith(COLLOCATION_SOURCE)
    tracking_stage = (settings.track_first and not warm) if track is None else bool(track)
    common = {"settings": settings, "model_spec": spec, "guess_source": str(guess.source),
              "cm": cm}
    tracking = None
    start = g
    if tracking_stage:
        grf = None
        if g.vertical_grf_bw is not None and settings.grf_tracking_weight > 0:
            grf = (g.vertical_grf_bw * runner.body_weight, settings.grf_tracking_weight)
        nlp_t = StrideNLP(dyn, n=n, speed=speed if speed is not None else g.speed,
                          weights=TRACKING_WEIGHTS, tracking=(g.q, settings.tracking_weight),
                          grf_tracking=grf)
        sol_t = _solve_stage(nlp_t, nlp_t.initial_vector(g), settings, "tracking", progress)
        tracking = _stage_info(sol_t)
        if not sol_t.success and sol_t.status in TRACKING_RESTART_STATUSES:
            first = tracking
            sol_t = _solve_stage(nlp_t, nlp_t.initial_vector(sol_t.to_guess("tracking restart")),
                                 settings, "tracking", progress)
            tracking = _stage_info(sol_t) | {
                "iterations": first["iterations"] + int(sol_t.iterations),
                "wall_s": first["wall_s"] + float(sol_t.wall_s),
                "restarted_after": first["status"]}
        if not sol_t.success:
            return CollocationSolution.from_nlp(
                runner, sol_t, stage="tracking", tracking=tracking,
                metabolic_energy_J=nlp_t.energy_and_distance(sol_t)[0], **common)
        start = sol_t.to_guess(f"{COLLOCATION_SOURCE} (tracking stage)")
    nlp_p = _predictive_nlp(runner, dyn, settings)
    sol = _solve_stage(nlp_p, nlp_p.initial_vector(start), settings, "predictive", progress,
                       warm=warm and not tracking_stage, speed=speed)
    return CollocationSolution.from_nlp(
        runner, sol, stage="predictive", tracking=tracking,
        metabolic_energy_J=nlp_p.energy_and_distance(sol)[0], **common)


@dataclass(frozen=True)
class FolderResult:
    """What :func:`predict_stride_in_folder` did.

    Attributes
    ----------
    solution
        The solution (or best iterate) found or read back.
    path
        The file it is in (``solution.json`` or ``best_iterate.json``).
    solved
        False when a converged solution was already in the folder (``resume``) and nothing was
        solved.
    """

    solution: object
    path: Path
    solved: bool


def _held(out: Path) -> list[str]:
    return [n for n in (SOLUTION_FILE, BEST_ITERATE_FILE) if (out / n).exists()]


def predict_stride_in_folder(
    out: str | Path,
    runner,
    settings: CollocationSettings,
    make_guess: Callable[[], object],
    *,
    model_spec: dict,
    resume: bool = False,
    force: bool = False,
    progress: Callable[[SolveProgress], None] | None = None,
) -> FolderResult:
    """:func:`predict_stride` writing its result into the folder ``out`` (module docstring).

    Parameters
    ----------
    out
        Output folder (created if needed).
    runner, settings, model_spec, progress
        As :func:`predict_stride`.
    make_guess
        Returns the initial guess; not called when resuming.
    resume
        Continue from the folder: a converged ``solution.json`` of the same problem (model,
        mesh, speed, weights) is returned as it is; a ``best_iterate.json`` of it is the warm
        start of the predictive stage.
    force
        Start over in a folder that holds a solve (its files are replaced once the new result
        is written).

    Raises
    ------
    InputFileError
        ``out`` holds a solve and neither ``resume`` nor ``force`` is given; ``resume`` without
        a solve in the folder, or with one of another problem.
    """
    from bladelab.predict.collocation.stored import check_model_spec, read_stored, write_solve

    out = Path(out)
    spec = check_model_spec(model_spec)
    if out.exists() and not out.is_dir():
        raise InputFileError("is a file, not a folder", file=out, hint="give a folder for --out")
    held = _held(out) if out.is_dir() else []
    if resume and force:
        raise SpecError("give --resume or --force, not both", where="--resume/--force")
    if held and not (resume or force):
        raise InputFileError(
            f"the output folder holds a collocation solve ({', '.join(held)})", file=out,
            hint="--resume continues it, --force starts over in it, or choose another --out")
    guess = None
    ok, best = out / SOLUTION_FILE, out / BEST_ITERATE_FILE
    if resume:
        if not held:
            raise InputFileError("no collocation solve to resume from", file=out,
                                 hint="run without --resume first, with the same --out")
        done, iterate = read_stored(ok, best, spec, settings)
        if done is not None:
            return FolderResult(done, ok, False)
        guess = iterate.to_guess()
    if guess is None:
        guess = make_guess()
    sol = predict_stride(runner, settings, guess, model_spec=spec, progress=progress)
    target = write_solve(sol, ok, best)
    return FolderResult(sol, target, True)

