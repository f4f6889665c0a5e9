"""Closed-loop simulation with the reflex controller, and the objective of seed 001 eq. 2.4–2.9.

``J = w_cot·J_cot + w_gait·J_gait + w_inj·J_inj + w_lean·J_lean`` (defaults 0.1, 100, 0.1, 0.1):

- ``J_cot = ∫Ė dt / (m·d)`` [J/(kg·m)]: Uchida 2016 gross metabolic energy
  (:mod:`bladelab.runner.metabolics`) over body mass and distance travelled (pelvis, ≥ 1 m);
- ``J_gait = 1 − Σ_s t_s·w_s / t_des`` (SCONE's GaitMeasure): steps s run from touch-down to
  touch-down (the first from t = 0; a touch-down: a leg's new contact at 0.1 body weight,
  more than 0.1 s after the last one, as SCONE's GaitMeasure: runner.closed_loop), ``w_s = max(0, 1 − Ψ(v_s, v_min, v_max)/(1 m/s))`` with the
  linear range penalty Ψ of eq. 2.8 and the step's mean pelvis speed ``v_s``; after a fall no more
  steps count, so falling early costs up to 1; with ``alternating_steps`` (default) a step by
  the same leg as the step before earns nothing (hops and gallops are not running), and one
  during which the other (swinging) foot strikes the ground within 0.1 s earns
  ``max(0, 1 − peak/strike_limit_bw)`` of its credit, ``peak`` the strike's vertical force
  [body weights] (a stumble; graded so the optimiser sees a lighter strike as better; our
  additions, docs/predictive.md);
- ``J_inj``: knee load (ligament torque [N·m] of each knee) outside ``knee_load_range``
  (−100…100), ``J_lean``: pelvis tilt [deg] outside ``pelvis_tilt_range_deg`` (−16…−2); both
  eq. 2.9, ``abs_penalty·|Err| + squared_penalty·Err²`` averaged over the simulated time.

The simulation starts from SCONE's gait state moving forward at ``initial_speed`` [m/s] (None:
the prescribed ``speed``). Seed 001 started every simulation from the same state (§2.2.2);
sweeps start every speed from the first speed's, so a solution warm-started at a higher speed
keeps running and its steps' speed penalty, not a fall, tells the optimiser to go faster.

The simulation stops early once the model has fallen (pelvis below 60 % of standing height).

Robust evaluation (``robust_samples`` = n > 1, :func:`bladelab.predict.reflex.optimize.evaluate_candidates`):
a candidate's cost is the mean over the nominal simulation and n − 1 copies with the
parameters jittered by ``robust_jitter`` (relative, seeded directions), and it counts as
fallen if any copy falls. A reflex gait is chaotic: without this, CMA-ES finds controllers that
survive only on the exact floating-point path and fall after a 1e-9 change (docs/predictive.md).
``robust_directions`` "fixed" draws the copies' directions once for the whole run;
"per-generation" draws new ones every generation (seeded by the run's seed and the generation,
so a resume is exact), so that a controller cannot learn to survive a handful of fixed copies
and no others. ``robust_speed_change`` s > 0 also starts the copies at (1 ± s) × the initial
speed, alternately (the stable-gait acceptance's ±5 % initial-speed test inside the objective).
``robust_push`` p > 0 pushes copy k once, at a time drawn from its seed in
:func:`push_window`: its forward (pelvis) speed times 1 + p (k even) or 1 − p (k odd) from
that instant (``push`` = (time [s], relative change) of one simulation). The start's first
steps test a gait's transient; a push in mid-run tests its basin of attraction (docs/predictive.md).
``robust_half_step`` runs the last copy at half the time step: a gait that survives only the
step it is optimised at lives on the discretisation (2026-11-27: the first Newmark gait to
run 10 s at 1 ms falls at 1.95 s at 0.5 ms).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path

import mujoco
import numpy as np

from bladelab.errors import InputFileError, SimulationError, SpecError
from bladelab.predict import defaults
from bladelab.predict.reflex.closed_loop import STEP_STATE_SIZE, run_closed_loop
from bladelab.predict.reflex.controller import (
    CONTROLLER_STATE_SIZE,
    ControllerLayout,
    controller_layout,
    history_length,
)
from bladelab.predict.reflex.tracking import cached_reference, stride_start, tracking_error
from bladelab.runner.implicit_setup import implicit_arrays, simulation_model, site_views
from bladelab.runner.kernel import mujoco_step_addresses, path_kinematics
from bladelab.runner.metabolics import metabolic_params
from bladelab.runner.model import RunnerModel, contact_heights
from bladelab.runner.muscle import equilibrium_fiber_lengths
from bladelab.runner.simulate import Recording, RunnerResult, initial_qpos
from bladelab.sim.compilation import announce_compilation

DEFAULT_PREDICT_DT = defaults.TIME_STEP_S
MAX_TOUCHDOWNS = 400
#: Sampling interval of the angles a tracking term compares [s].
TRACK_SAMPLE_S = 2e-3
#: How the robust copies' jitter directions are drawn (:class:`ObjectiveSettings`).
ROBUST_DIRECTIONS = ("fixed", "per-generation")


def check_robust_copies(directions: str, speed_change: float, push: float = 0.0,
                        duration: float = math.inf, *, half_step: bool = False,
                        samples: int = 1,
                        where: tuple[str, ...] = ("robust_directions", "robust_speed_change",
                                                  "robust_push", "duration",
                                                  "robust_half_step", "robust_samples"),
                        ) -> None:
    """Refuse robust-copy options :class:`ObjectiveSettings` cannot use: ``directions`` one
    of :data:`ROBUST_DIRECTIONS`, ``speed_change`` and ``push`` in [0, 0.5), a push only in a
    simulation of at least :data:`MIN_PUSH_DURATION` [s], a half-step copy only with at least
    one copy (``samples`` ≥ 2); ``where`` names them (the fields, or the command line's
    options)."""
    if directions not in ROBUST_DIRECTIONS:
        raise SpecError(f"unknown value {directions!r}", where=where[0],
                        hint=" or ".join(ROBUST_DIRECTIONS))
    for value, name in ((speed_change, where[1]), (push, where[2])):
        if not (math.isfinite(value) and 0 <= value < 0.5):
            raise SpecError(f"must be in [0, 0.5), got {value}", where=name)
    if push > 0 and duration < MIN_PUSH_DURATION:
        raise SpecError(f"a push needs a simulation of at least {MIN_PUSH_DURATION:g} s "
                        f"(after the start's first steps, with time to fall), got {duration:g} s",
                        where=where[3], hint=f"a longer {where[3]}, or no {where[2]}")
    if half_step and samples < 2:
        raise SpecError("the half-step run is one of the robust copies: there is none",
                        where=where[4], hint=f"{where[5]} of at least 2")


def push_window(duration: float) -> tuple[float, float]:
    """Times [s] between which a robust copy's push falls (``robust_push``): after the start's
    first steps (:data:`PUSH_AFTER` s) and early enough that a gait it fells falls before the
    end (:data:`PUSH_BEFORE_END` s before it; measured: 1–5 s after a 2 % push)."""
    return PUSH_AFTER, duration - PUSH_BEFORE_END


#: A robust copy's push (``robust_push``) comes this long [s] after the start ...
PUSH_AFTER = 2.0
#: ... and this long [s] before the end of the simulation.
PUSH_BEFORE_END = 4.0
#: The shortest simulation [s] a push fits into.
MIN_PUSH_DURATION = PUSH_AFTER + PUSH_BEFORE_END + 1.0


@dataclass(frozen=True)
class ObjectiveSettings:
    """Weights and ranges of the objective (seed 001 §2.2.1). Speeds [m/s], load [N·m], tilt
    [deg], times [s]. ``run_up``: the reflexes on the mean forward speed act from the start, as
    if the runner had moved at the initial velocity before it (else they wait for a full
    window of the run)."""

    speed: float = defaults.SPEED_M_PER_S
    speed_tolerance: float = 0.1
    duration: float = defaults.DURATION_S
    dt: float = DEFAULT_PREDICT_DT
    w_cot: float = 0.1
    w_gait: float = 100.0
    w_inj: float = 0.1
    w_lean: float = defaults.LEAN_WEIGHT_PER_DEG
    knee_load_range: tuple[float, float] = (-100.0, 100.0)
    pelvis_tilt_range_deg: tuple[float, float] = (-16.0, -2.0)
    abs_penalty: float = 1.0
    squared_penalty: float = 0.0
    robust_samples: int = defaults.ROBUST_SAMPLES
    robust_jitter: float = defaults.ROBUST_JITTER
    robust_directions: str = defaults.ROBUST_DIRECTIONS
    robust_speed_change: float = 0.0
    robust_push: float = 0.0
    robust_half_step: bool = False
    push: tuple[float, float] | None = None
    alternating_steps: bool = True
    strike_limit_bw: float = defaults.STRIKE_LIMIT_BW
    initial_speed: float | None = None
    run_up: bool = False
    integrator: str = defaults.INTEGRATOR
    track: str | None = None
    w_track: float = 0.0
    track_skip: float = 1.0
    start_stride: str | None = None

    def __post_init__(self) -> None:
        check_robust_copies(self.robust_directions, self.robust_speed_change,
                            self.robust_push, self.duration, half_step=self.robust_half_step,
                            samples=self.robust_samples)
        if self.push is not None:
            t, change = self.push
            if not (0 <= t <= self.duration and -0.5 < change < 0.5):
                raise SpecError(f"a push at {t} s changing the speed by {change} (relative) does "
                                f"not fit a {self.duration} s simulation", where="push")
        if self.w_track < 0 or not math.isfinite(self.w_track):
            raise SpecError(f"the tracking weight must be >= 0, got {self.w_track}",
                            where="w_track")
        if self.w_track > 0 and self.track is None:
            raise SpecError("a tracking weight needs a stride to track", where="track",
                            hint="a collocation solution file (bladelab predict --track)")

    @property
    def start_speed(self) -> float:
        """Forward speed of the initial state [m/s]: ``initial_speed``, else ``speed``."""
        return self.speed if self.initial_speed is None else self.initial_speed

    @classmethod
    def from_dict(cls, d: dict) -> ObjectiveSettings:
        """Settings from :meth:`to_dict`'s output (JSON lists back to tuples)."""
        d = dict(d)
        for key in ("knee_load_range", "pelvis_tilt_range_deg", "push"):
            if d.get(key) is not None:
                d[key] = tuple(d[key])
        return cls(**d)

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Evaluation:
    """One simulation's objective terms."""

    cost: float
    j_cot: float
    j_gait: float
    j_inj: float
    j_lean: float
    fell: bool
    duration: float
    distance: float
    mean_speed: float
    metabolic_energy: float
    n_steps: int
    j_track: float = 0.0
    track_strides: int = 0

    def to_dict(self, *, tracking: bool = True) -> dict:
        """The terms by name; ``tracking=False`` leaves out ``j_track`` and ``track_strides``
        (tables of runs that track nothing)."""
        skip = () if tracking else ("j_track", "track_strides")
        return {k: (float(v) if isinstance(v, float) else v) for k, v in asdict(self).items()
                if k not in skip}


def initial_state(
    model: RunnerModel, layout: ControllerLayout, x: np.ndarray, speed: float
) -> tuple[np.ndarray, np.ndarray]:
    """SCONE's gait state with the controller's initial-state offsets, moving at ``speed``."""
    pose = {}
    q0, _ = initial_qpos(model, "gait")
    for i, name in enumerate(layout.names):
        if name.endswith(".offset"):
            dof = name[: -len(".offset")]
            pose[dof] = q0[model.dof(dof)] + x[i]
    q, v = initial_qpos(model, "gait")
    for dof, val in pose.items():
        q[model.dof(dof)] = val
    q[model.dof("pelvis_tz")] -= contact_heights(model, q).min()
    v[model.dof("pelvis_tx")] = speed
    return q, v


def simulate_controlled(
    model: RunnerModel,
    x: np.ndarray,
    *,
    layout: ControllerLayout | None = None,
    settings: ObjectiveSettings | None = None,
    record_every: int = 0,
) -> tuple[Evaluation, RunnerResult | None]:
    """Simulate the runner under the reflex controller with parameters ``x``.

    Parameters
    ----------
    model
        The runner.
    x
        Controller parameter vector (:func:`~bladelab.predict.reflex.controller.controller_layout`).
    settings
        Speed [m/s], duration [s], time step [s] and objective weights.
    record_every
        Record a :class:`RunnerResult` sample every this many steps (0: no recording, faster).

    Returns
    -------
    (Evaluation, RunnerResult or None)
    """
    settings = settings or ObjectiveSettings()
    layout = layout or controller_layout(model)
    # a C-contiguous copy: a strided view (a column of a population) would make numba compile
    # another version of the closed loop
    x = np.array(x, dtype=float, order="C")
    if x.shape != (layout.size,):
        raise SimulationError(
            f"expected {layout.size} controller parameters, got {x.shape}", where="parameters"
        )
    dt = settings.dt
    m, own_sites = simulation_model(model, settings.integrator)
    m.opt.timestep = dt
    d = mujoco.MjData(m)
    v_start = settings.start_speed
    if settings.start_stride is not None:
        q0, v0 = stride_initial_state(model, settings.start_stride, v_start)
    else:
        q0, v0 = initial_state(model, layout, x, v_start)
    d.qpos[:] = q0
    d.qvel[:] = v0
    announce_compilation(run_closed_loop, "the reflex controller's simulation loop")
    mujoco.mj_forward(m, d)
    imp = implicit_arrays(model, m, d, settings.integrator, own_sites)
    mj = site_views(d, imp, oriented=False)
    nm = len(model.muscle_names)
    mp = model.muscle_params
    mb = metabolic_params(model)
    ms = np.zeros((nm, 4))
    ms[:, 0] = 0.05
    path, pstart = model.path_points, model.path_start
    mtu = np.zeros((nm, 2))
    seg_u = np.zeros((path.shape[0], 3))
    path_kinematics(mj[2], d.cvel, d.subtree_com[1].copy(), path, pstart, mtu, seg_u)
    ms[:, 1] = equilibrium_fiber_lengths(mp, mtu[:, 0], ms[:, 0])
    u = np.zeros(nm)
    table = layout.table_for(dt)
    hist = np.zeros((history_length(layout, dt), 3 * nm + 2 * m.nq))
    cs = np.zeros(CONTROLLER_STATE_SIZE)
    cs[4] = 1.0 if settings.run_up else 0.0
    cs[0] = 3.0  # start in swing; the first contact starts a stance
    cs[1] = 3.0
    cp = model.contact_params
    cstate = np.zeros((cp.shape[0], 1))
    crec = np.zeros((cp.shape[0], 7))
    lig = np.zeros(m.nv)
    jp = model.joint_params
    ix = model.dof("pelvis_tx")
    iz = model.dof("pelvis_tz")
    itilt = model.dof("pelvis_tilt")
    knee_idx = np.array([model.dof(n) for n in ("knee_angle_l", "knee_angle_r")], dtype=np.int64)
    thresholds = np.array([x[layout.index(name + side)] for name in
                           ("stance_load_threshold_", "liftoff_load_margin_") for side in "lr"])
    leg_length = float(model.stand_qpos[iz])
    fall_height = 0.6 * leg_length
    ranges = np.array([*settings.knee_load_range, *settings.pelvis_tilt_range_deg], dtype=float)
    pen = np.array([settings.abs_penalty, settings.squared_penalty])
    acc = np.zeros(4)
    td = np.zeros((MAX_TOUCHDOWNS, 4))
    steps = np.zeros(STEP_STATE_SIZE)
    steps[2] = -1e9  # no step yet
    steps[3] = -1.0
    bw, mass = model.body_weight, model.total_mass
    n_steps = int(round(settings.duration / dt))
    reference = _tracked_stride(settings.track) if settings.track is not None else None
    if reference is not None:
        reference.check_model(model.kind, model.params.blade if model.kind == "amputee" else None,
                              "track", dof_names=tuple(model.dof_names))
    if record_every > 0:
        every = record_every
    elif reference is not None:
        every = max(1, int(round(TRACK_SAMPLE_S / dt)))
    else:
        every = n_steps + 1
    rec = Recording(model, n_steps, every)
    push = np.array([-1.0, 1.0, ix])
    if settings.push is not None:
        push[:2] = round(settings.push[0] / dt), 1.0 + settings.push[1]
    f1, f2 = mujoco_step_addresses()
    arrays = (mp, ms, mtu, seg_u, u, path, pstart, cp, cstate, jp, crec, lig)
    control = (
        table,
        x,
        hist,
        cs,
        mb,
        ix,
        thresholds,
        bw,
        mass,
        leg_length,
        acc,
        td,
        steps,
        knee_idx,
        itilt,
        ranges,
        pen,
    )
    k, k_rec, fell = run_closed_loop(
        f1,
        f2,
        m._address,
        d._address,
        n_steps,
        every,
        dt,
        iz,
        fall_height,
        mj,
        arrays,
        rec.arrays,
        control,
        imp,
        push,
    )
    qpos = d.qpos
    t_end = k * dt
    distance = float(qpos[ix] - q0[ix]) if math.isfinite(qpos[ix]) else 0.0
    touchdowns = td[: int(acc[3])]
    result = rec.result(k_rec, dt, bool(fell), settings.duration) if every <= n_steps else None
    track = (0.0, 0)
    if reference is not None:
        index = np.array([model.dof(name) for name in reference.dof_names], dtype=np.int64)
        track = tracking_error(result.time, result.qpos, touchdowns, reference, index,
                               settings.track_skip, settings.duration)
    ev = _evaluate(settings, acc, touchdowns, t_end, distance, bool(fell), mass, q0[ix], track)
    return ev, (result if record_every > 0 else None)


def stride_initial_state(model: RunnerModel, path: str, speed: float, *,
                         where: str = "settings.start_stride") -> tuple[np.ndarray, np.ndarray]:
    """The collocation stride ``path``'s state at leg 0's touch-down
    (:func:`~bladelab.predict.reflex.tracking.stride_start`) as the initial (qpos, qvel) of
    ``model``: the pelvis at x = 0, its forward speed shifted so that the stride's mean speed
    becomes ``speed`` [m/s]; the controller's initial-state offsets do not apply. A stride of
    a runner with other coordinates is refused (errors name ``where``)."""
    if not Path(path).is_file():
        raise InputFileError("the stride this run starts from is not there", file=path,
                             where=where,
                             hint="a collocation solution file; a relative path is read from "
                                  "the current folder")
    start = stride_start(str(path))
    if set(start.dof_names) != set(model.dof_names):
        lacks = [n for n in model.dof_names if n not in start.dof_names]
        extra = [n for n in start.dof_names if n not in model.dof_names]
        raise InputFileError(
            "the stride's runner has other coordinates than the controller's"
            + (f" (the stride lacks {', '.join(lacks)})" if lacks else "")
            + (f" (the stride has {', '.join(extra)} too)" if extra else ""), file=path,
            where=where, hint="start from a stride of the same runner and body")
    q = np.zeros(model.mj_model.nq)
    v = np.zeros(model.mj_model.nv)
    for j, name in enumerate(start.dof_names):
        q[model.dof(name)], v[model.dof(name)] = start.qpos[j], start.qvel[j]
    q[model.dof("pelvis_tx")] = 0.0
    v[model.dof("pelvis_tx")] += speed - start.speed_mps
    return q, v


def _tracked_stride(path: str):
    """The run's tracked stride (``settings.track``); a missing file names the setting."""
    if not Path(path).is_file():
        raise InputFileError(
            "the stride this run tracks is not there", file=path, where="settings.track",
            hint="a relative path is read from the current folder: run from the folder the "
            "run was made in (for the committed runs, the repository root)")
    return cached_reference(path)


def _evaluate(settings, acc, td, t_end, distance, fell, mass, x0,
              track: tuple[float, int] = (0.0, 0)) -> Evaluation:
    s = settings
    v_min, v_max = s.speed - s.speed_tolerance, s.speed + s.speed_tolerance
    times = np.concatenate([[0.0], td[:, 0]])
    xs = np.concatenate([[x0], td[:, 1]])
    legs = np.concatenate([[-1.0], td[:, 2]])
    strike = np.concatenate([[0.0], td[:, 3]])
    credit = 0.0
    for i in range(1, len(times)):
        ts = times[i] - times[i - 1]
        if ts <= 0:
            continue
        weight = 1.0
        if s.alternating_steps:
            if i > 1 and legs[i] == legs[i - 1]:
                continue  # the same leg again: a hop or gallop
            if strike[i] > 0.0:  # the other foot struck the ground
                weight = max(0.0, 1.0 - strike[i] / s.strike_limit_bw) if s.strike_limit_bw > 0 else 0.0
        v = (xs[i] - xs[i - 1]) / ts
        psi = v_min - v if v < v_min else (v - v_max if v > v_max else 0.0)
        credit += ts * weight * max(0.0, 1.0 - psi)
    j_gait = max(0.0, 1.0 - credit / s.duration)
    t = max(t_end, s.dt)
    j_cot = acc[0] / (mass * max(distance, 1.0))
    j_inj = acc[1] / t
    j_lean = acc[2] / t
    if not all(math.isfinite(v) for v in (j_cot, j_inj, j_lean)):
        j_cot, j_inj, j_lean = 1e3, 1e3, 1e3
    cost = s.w_cot * j_cot + s.w_gait * j_gait + s.w_inj * j_inj + s.w_lean * j_lean
    cost += s.w_track * track[0]
    return Evaluation(
        cost=float(cost),
        j_cot=float(j_cot),
        j_gait=float(j_gait),
        j_inj=float(j_inj),
        j_lean=float(j_lean),
        fell=bool(fell),
        duration=float(t_end),
        distance=float(distance),
        mean_speed=float(distance / t) if t > 0 else 0.0,
        metabolic_energy=float(acc[0]),
        n_steps=int(len(td)),
        j_track=float(track[0]),
        track_strides=int(track[1]),
    )


def evaluate(
    model: RunnerModel,
    x: np.ndarray,
    *,
    layout: ControllerLayout | None = None,
    settings: ObjectiveSettings | None = None,
) -> Evaluation:
    """The objective of parameters ``x`` (one closed-loop simulation, no recording)."""
    return simulate_controlled(model, x, layout=layout, settings=settings)[0]


__all__ = [
    "ROBUST_DIRECTIONS",
    "Evaluation",
    "ObjectiveSettings",
    "check_robust_copies",
    "evaluate",
    "initial_state",
    "stride_initial_state",
    "simulate_controlled",
]
