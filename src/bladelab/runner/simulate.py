"""Forward simulation of the runner: MuJoCo multibody step + bladelab's numba force kernel.

Each step: ``mj_step1`` (positions, velocities), then one numba call
(:func:`bladelab.runner.kernel.forces`) that computes the muscle path lengths and velocities,
advances the muscles (:mod:`bladelab.runner.muscle`), computes ligament, socket and ground
contact forces (Hunt–Crossley normal force, elastic–plastic friction capped at μ·Fn) and writes
them to MuJoCo's ``xfrc_applied`` (muscle and contact point forces) and ``qfrc_applied``
(ligaments, socket), then ``mj_step2`` (semi-implicit Euler). With constant excitations the
whole loop runs in compiled code (:func:`bladelab.runner.kernel.run_loop`).

A controller is any callable ``controller(t, state) -> excitations`` (one value in [0, 1] per
muscle, in ``RunnerModel.muscle_names`` order), called every ``control_interval`` steps with a
:class:`ControllerState` of live arrays: muscle states (activation, fibre length [m], fibre
velocity [m/s], tendon force [N]), MTU lengths [m] and velocities [m/s], qpos, qvel, and the
contact forces (Fx, Fz [N] per contact). Instead of a controller, constant excitations may be
given.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
import pandas as pd

from bladelab.errors import SimulationError
from bladelab.runner.implicit import INTEGRATORS, NEWMARK, implicit_advance
from bladelab.runner.implicit_setup import (
    explicit_step_limit,
    implicit_arrays,
    simulation_model,
    site_views,
)
from bladelab.runner.kernel import (
    mujoco_step_addresses,
    path_kinematics,
    record_sample,
    run_loop,
    step_forces,
)
from bladelab.runner.model import DEFAULT_DT, RunnerModel, contact_heights
from bladelab.runner.muscle import equilibrium_fiber_lengths
from bladelab.runner.params import PROSTHETIC_KINDS
from bladelab.sim.compilation import announce_compilation

# Record columns per contact: Fx, Fz [N], contact point x, z [m], point velocity vx, vz [m/s],
# compression δ [m].
RC_FX, RC_FZ, RC_PX, RC_PZ, RC_VX, RC_VZ, RC_DEPTH = range(7)


@dataclass(frozen=True)
class ControllerState:
    """Live views handed to a controller (do not keep references between calls)."""

    muscles: np.ndarray  # (n_muscles, 4): activation, l_ce [m], v_ce [m/s], F_t [N]
    mtu_length: np.ndarray  # [m]
    mtu_velocity: np.ndarray  # [m/s]
    qpos: np.ndarray
    qvel: np.ndarray
    contacts: np.ndarray  # (n_contacts, 7), columns RC_*


# SCONE's InitStateGait10.zml (H0918, Apache-2.0): a gait state at 1 m/s, OpenSim names [rad].
GAIT_INITIAL_STATE = {
    "pelvis_tilt": (-0.0336387, -0.572135),
    "hip_flexion_r": (0.165239, -0.576377),
    "knee_angle_r": (-0.0888009, 0.175894),
    "ankle_angle_r": (0.0197104, 0.988937),
    "hip_flexion_l": (0.232604, 4.90666),
    "knee_angle_l": (-1.22703, -3.59786),
    "ankle_angle_l": (-0.167279, 0.633253),
}


@dataclass(frozen=True, eq=False)
class RunnerResult:
    """A forward simulation, sampled every ``record_every`` steps.

    Arrays have one row per sample: ``time`` [s]; ``qpos``, ``qvel`` (``model.dof_names``);
    ``muscles`` (n, n_muscles, 4): activation, fibre length [m], fibre velocity [m/s], tendon
    force [N]; ``mtu`` (n, n_muscles, 2): MTU length [m] and velocity [m/s]; ``excitation``
    (n, n_muscles); ``contacts`` (n, n_contacts, 7): Fx, Fz [N], contact point x, z [m], its
    velocity vx, vz [m/s], compression [m]; ``ligament`` (n, n_dof): ligament and socket
    torques [N·m] (forces [N] for the pelvis translations, always 0).
    """

    model: RunnerModel
    time: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    muscles: np.ndarray
    mtu: np.ndarray
    excitation: np.ndarray
    contacts: np.ndarray
    ligament: np.ndarray
    dt: float
    fell: bool
    requested_duration: float

    @property
    def duration(self) -> float:
        """Simulated time [s] (shorter than requested after a fall)."""
        return float(self.time[-1]) if len(self.time) else 0.0

    def leg_grf(self) -> pd.DataFrame:
        """Tidy GRF per leg: columns time [s], leg (intact/prosthetic or left/right), Fx, Fz [N],
        Fx_bw, Fz_bw [body weights]."""
        bw = self.model.body_weight
        names = leg_names(self.model)
        frames = []
        for leg in (0, 1):
            cols = self.model.contact_params[:, 7 - 1] == leg  # CP_LEG
            fx = self.contacts[:, cols, RC_FX].sum(axis=1)
            fz = self.contacts[:, cols, RC_FZ].sum(axis=1)
            frames.append(
                pd.DataFrame(
                    {
                        "time": self.time,
                        "leg": names[leg],
                        "Fx": fx,
                        "Fz": fz,
                        "Fx_bw": fx / bw,
                        "Fz_bw": fz / bw,
                    }
                )
            )
        return pd.concat(frames, ignore_index=True)

    def states(self) -> pd.DataFrame:
        """Coordinates as a wide table: time [s] and one column per dof (rad or m)."""
        df = pd.DataFrame(self.qpos, columns=list(self.model.dof_names))
        df.insert(0, "time", self.time)
        return df

    def muscle_states(self) -> pd.DataFrame:
        """Tidy muscle states: time, muscle, excitation, activation, l_ce [m], v_ce [m/s],
        force [N], l_mtu [m], v_mtu [m/s]."""
        n, m = self.excitation.shape
        return pd.DataFrame(
            {
                "time": np.repeat(self.time, m),
                "muscle": np.tile(np.array(self.model.muscle_names), n),
                "excitation": self.excitation.ravel(),
                "activation": self.muscles[:, :, 0].ravel(),
                "l_ce": self.muscles[:, :, 1].ravel(),
                "v_ce": self.muscles[:, :, 2].ravel(),
                "force": self.muscles[:, :, 3].ravel(),
                "l_mtu": self.mtu[:, :, 0].ravel(),
                "v_mtu": self.mtu[:, :, 1].ravel(),
            }
        )

    def to_dict(self) -> dict:
        return {
            "model": self.model.kind,
            "fell": self.fell,
            "duration_s": self.duration,
            "requested_duration_s": self.requested_duration,
            "dt_s": self.dt,
            "samples": int(len(self.time)),
        }


def leg_names(model: RunnerModel) -> tuple[str, str]:
    """Names of the left and right legs in tables: (intact, prosthetic) or (left, right)."""
    return ("intact", "prosthetic") if model.kind in PROSTHETIC_KINDS else ("left", "right")


def initial_qpos(model: RunnerModel, state: str | dict = "stand") -> tuple[np.ndarray, np.ndarray]:
    """Initial (qpos, qvel): ``"stand"`` (every contact touching, at rest), ``"gait"`` (SCONE's
    1 m/s gait state, lowest contact touching) or a mapping ``{dof: value}`` on the standing pose.
    """
    q = model.stand_qpos.copy()
    v = np.zeros(model.mj_model.nv)
    if state == "stand":
        return q, v
    if state == "gait":
        q[:] = 0.0
        for name, (val, vel) in GAIT_INITIAL_STATE.items():
            if name in model.dof_names:
                q[model.dof(name)], v[model.dof(name)] = val, vel
        v[model.dof("pelvis_tx")] = 1.0
    elif isinstance(state, dict):
        for name, val in state.items():
            q[model.dof(name)] = val
    else:
        raise SimulationError(
            f"unknown initial state {state!r}", hint="use 'stand', 'gait' or a dict"
        )
    q[model.dof("pelvis_tz")] -= contact_heights(model, q).min()
    return q, v


#: Time step [s] of the Newmark integrator where :func:`integrator_for` chooses it.
NEWMARK_DT = 1e-3
#: Default time step [s] per integrator: the explicit scheme's 0.25 ms, the linearly implicit
#: ones' 1 ms.
DEFAULT_TIME_STEPS = {"explicit": DEFAULT_DT, "implicit": NEWMARK_DT, "newmark": NEWMARK_DT}


def integrator_for(model: RunnerModel) -> tuple[str, float]:
    """The integrator and time step [s] a forward simulation of ``model`` takes by default:
    ``("explicit", DEFAULT_DT)`` where the explicit scheme integrates every joint damper at
    that step (:func:`~bladelab.runner.implicit_setup.explicit_step_limit`: seed 001's rigid
    feet, the toes body's 0.03 N·m·s/rad hinge), else ``("newmark", NEWMARK_DT)`` (the human
    body's 2 N·m·s/rad on the toes' small inertia would need a step below 0.1 ms)."""
    name = "explicit" if explicit_step_limit(model) >= DEFAULT_DT else "newmark"
    return name, DEFAULT_TIME_STEPS[name]


def simulate_runner(
    model: RunnerModel,
    *,
    controller: Callable[[float, ControllerState], np.ndarray] | None = None,
    excitations: np.ndarray | float | None = None,
    duration: float = 10.0,
    dt: float = DEFAULT_DT,
    initial_state: str | dict = "stand",
    initial_speed: float = 0.0,
    drop_height: float = 0.0,
    hold_pose: bool = False,
    control_interval: int = 1,
    record_every: int = 2,
    fall_height: float | None = None,
    initial_activation: float | None = 0.01,
    integrator: str = "explicit",
) -> RunnerResult:
    """Simulate the runner forward.

    Parameters
    ----------
    model
        A :class:`RunnerModel` (``build_runner``).
    controller
        ``controller(t, state) -> excitations`` (n_muscles values in [0, 1]); overrides
        ``excitations``.
    excitations
        Constant excitations: one value for all muscles or one per muscle (default 0.05).
    duration
        Requested simulated time [s].
    dt
        Time step [s] (default ``DEFAULT_DT`` = 0.25 ms; 0.5 ms is unstable under running loads).
    initial_state
        ``"stand"``, ``"gait"`` or ``{dof: value}`` (see :func:`initial_qpos`).
    initial_speed
        Forward pelvis speed at t = 0 [m/s] (added to the state's).
    drop_height
        Lift the model by this much [m] before release (drop test).
    hold_pose
        Hold every joint at its initial angle with stiff springs and the pelvis at its initial
        x and tilt (MuJoCo joint springs; for drop tests of contact and mass).
    control_interval
        Call the controller every this many steps.
    record_every
        Store a sample every this many steps.
    initial_activation
        Muscle activation at t = 0 (default 0.01, muscles then activate with their dynamics);
        None starts at the initial excitations.
    fall_height
        Stop when the pelvis COM is below this height [m] (default: 60 % of standing height).
    integrator
        ``"explicit"`` (default: every bladelab force at the step's start, MuJoCo's
        semi-implicit Euler), ``"newmark"``: contacts, ligaments and the socket linearly
        implicit in Newmark's trapezoidal rule, muscle fibres by BDF2
        (:mod:`bladelab.runner.implicit`), stable at a 1 ms step and there more accurate than
        the explicit scheme at 0.25 ms, or ``"implicit"``: its first-order predecessor
        (semi-implicit Euler, kept for runs made with it).
    """
    if not (duration > 0 and dt > 0 and math.isfinite(duration) and math.isfinite(dt)):
        raise SimulationError("duration and dt must be positive", where="duration/dt")
    if dt > 2e-3:
        raise SimulationError(
            f"time step {dt} s is too large for the contact and muscle laws",
            where="dt",
            hint=f"use at most 1e-3 s (default {DEFAULT_DT:g} s)",
        )
    if integrator not in INTEGRATORS:
        raise SimulationError(f"unknown integrator {integrator!r}", where="integrator",
                              hint=f"use one of {', '.join(INTEGRATORS)}")
    if int(record_every) < 1 or int(control_interval) < 1:
        raise SimulationError("must be at least 1", where="record_every/control_interval")
    m, own_sites = simulation_model(model, integrator, compiled_loop=controller is None)
    nm = len(model.muscle_names)
    if hold_pose:
        m = _held_copy(model, m)
    m.opt.timestep = dt
    d = mujoco.MjData(m)
    q0, v0 = initial_qpos(model, initial_state)
    q0[model.dof("pelvis_tz")] += drop_height
    v0[model.dof("pelvis_tx")] += initial_speed
    if hold_pose:
        m.qpos_spring[:] = q0
    d.qpos[:] = q0
    d.qvel[:] = v0
    u = np.full(nm, 0.05)
    if excitations is not None:
        exc = np.asarray(excitations, dtype=float)
        if exc.ndim > 1 or (exc.ndim == 1 and exc.shape[0] != nm):
            raise SimulationError(
                f"expected one excitation or {nm} (one per muscle), got shape {exc.shape}",
                where="excitations",
                hint=f"muscles: {', '.join(model.muscle_names)}",
            )
        if not np.all((exc >= 0) & (exc <= 1)):
            raise SimulationError("excitations must be in [0, 1]", where="excitations")
        u[:] = exc
    ms = np.zeros((nm, 4))
    if controller is None:
        announce_compilation(run_loop, "the runner's simulation loop")
    else:
        announce_compilation(step_forces, "the runner's force functions")
    mujoco.mj_forward(m, d)
    imp = implicit_arrays(model, m, d, integrator, own_sites)
    mj = site_views(d, imp)
    mp = model.muscle_params
    path, pstart = model.path_points, model.path_start
    mtu = np.zeros((nm, 2))
    seg_u = np.zeros((path.shape[0], 3))
    path_kinematics(mj[2], d.cvel, d.subtree_com[1].copy(), path, pstart, mtu, seg_u)
    ms[:, 0] = np.clip(u, 0.01, 1.0) if initial_activation is None else initial_activation
    ms[:, 1] = equilibrium_fiber_lengths(mp, mtu[:, 0], ms[:, 0])
    cp = model.contact_params
    cstate = np.zeros((cp.shape[0], 1))
    crec = np.zeros((cp.shape[0], 7))
    lig = np.zeros(m.nv)
    jp = model.joint_params
    n_steps = int(round(duration / dt))
    rec = Recording(model, n_steps, record_every)
    if fall_height is None:
        fall_height = 0.6 * model.stand_qpos[model.dof("pelvis_tz")]
    iz = model.dof("pelvis_tz")
    arrays = (mp, ms, mtu, seg_u, u, path, pstart, cp, cstate, jp, crec, lig)
    if controller is None:
        f1, f2 = mujoco_step_addresses()
        _, k_rec, fell = run_loop(
            f1,
            f2,
            m._address,
            d._address,
            n_steps,
            record_every,
            dt,
            iz,
            float(fall_height),
            mj,
            arrays,
            rec.arrays,
            imp,
        )
    else:
        k_rec, fell = _python_loop(
            m,
            d,
            controller,
            control_interval,
            n_steps,
            record_every,
            dt,
            iz,
            fall_height,
            mj,
            arrays,
            rec.arrays,
            imp,
        )
    return rec.result(k_rec, dt, fell, duration)


def _python_loop(
    m,
    d,
    controller,
    control_interval,
    n_steps,
    record_every,
    dt,
    iz,
    fall_height,
    mj,
    arrays,
    rec,
    imp,
):
    """The time loop with a Python controller called every ``control_interval`` steps."""
    qpos, qvel, sxp, _, cvel, scom = mj[:6]
    _, ms, mtu, seg_u, u, path, pstart, _, _, _, crec, _ = arrays
    root_com = np.zeros(3)
    state = ControllerState(ms, mtu[:, 0], mtu[:, 1], qpos, qvel, crec)
    step1, step2 = mujoco.mj_step1, mujoco.mj_step2
    k_rec = 0
    for k in range(n_steps + 1):
        step1(m, d)
        root_com[:] = scom[1]
        if k % control_interval == 0:
            path_kinematics(sxp, cvel, root_com, path, pstart, mtu, seg_u)
            u[:] = np.clip(controller(k * dt, state), 0.0, 1.0)
        step_forces(mj, arrays, imp, root_com, dt)
        if k % record_every == 0:
            record_sample(rec, k_rec, k * dt, mj, arrays)
            k_rec += 1
        if not qpos[iz] >= fall_height:
            return k_rec, True
        if k == n_steps:
            break
        if imp[0][0] == NEWMARK:
            implicit_advance(mj, imp, dt)
        else:
            step2(m, d)
    return k_rec, False


class Recording:
    """Preallocated arrays of a simulation's samples (``arrays``: the tuple the compiled loops
    fill, :func:`bladelab.runner.kernel.record_sample`). Left uninitialised: :meth:`result`
    hands out only the samples recorded (zeroing the ~8 MB of a 10 s run: ~0.2 ms)."""

    def __init__(self, model: RunnerModel, n_steps: int, every: int) -> None:
        m = model.mj_model
        nm = len(model.muscle_names)
        nc = model.contact_params.shape[0]
        n = n_steps // every + 1
        self.model = model
        self.arrays = (
            np.empty(n),  # time [s]
            np.empty((n, m.nq)),
            np.empty((n, m.nv)),
            np.empty((n, nm, 4)),
            np.empty((n, nm, 2)),
            np.empty((n, nm)),
            np.empty((n, nc, 7)),
            np.empty((n, m.nv)),
        )

    def result(self, n: int, dt: float, fell: bool, duration: float) -> RunnerResult:
        """The first ``n`` samples as a :class:`RunnerResult`."""
        t, q, v, ms, mtu, u, c, lig = (a[:n] for a in self.arrays)
        return RunnerResult(
            model=self.model,
            time=t,
            qpos=q,
            qvel=v,
            muscles=ms,
            mtu=mtu,
            excitation=u,
            contacts=c,
            ligament=lig,
            dt=dt,
            fell=fell,
            requested_duration=duration,
        )


def _held_copy(model: RunnerModel, base: mujoco.MjModel) -> mujoco.MjModel:
    """A copy of ``base`` (the runner's MuJoCo model or its site-free dynamics model) whose
    joints (all but pelvis_tz) have stiff springs."""
    m = base.__copy__()
    for j, name in enumerate(model.dof_names):
        if name == "pelvis_tz":
            continue
        m.jnt_stiffness[j] = 2e5 if name == "pelvis_tx" else 2e4
        m.dof_damping[j] = 2e3 if name == "pelvis_tx" else 2e2
    return m
