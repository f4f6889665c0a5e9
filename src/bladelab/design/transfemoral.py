"""Kinematics-driven planar transfemoral-amputee runner with a multi-link blade (seed 002).

Model (MuJoCo, built by :func:`bladelab.runner.kinematic_transfemoral.build_kinematic_transfemoral`;
x forward, z up, pitch about +y):

- root: slide x, slide z (free) and the trunk pitch hinge at the hips; the pelvis carries the
  head-arms-trunk mass (``torso`` + ``pelvis`` of the runner parameters); the biological segment
  masses are scaled so that the whole model (with socket, knee and blade) weighs
  ``body_mass_kg``; a stiff *residual* servo holds the trunk pitch on the cycle's ``trunk_pitch`` (as the
  residual actuators of inverse-dynamics tools);
- sound leg: thigh, shank, foot (segment masses of :mod:`bladelab.runner.params`); hip, knee
  and ankle follow the gait cycle by stiff PD servos; two contact circles (heel, toe, radius
  3 cm) under the foot;
- prosthetic leg: residual thigh + socket (60 % of the thigh mass, + 1 kg socket), hip servo;
  the passive monocentric knee (:class:`~bladelab.runner.prosthetic_knee.ProstheticKnee`) at
  the sound knee's height; below it a short adapter to the blade clamp, sized so that the
  standing prosthetic leg (knee to the ground, blade undeformed) is ``extra_leg_length_m``
  longer than the sound one; the multi-link blade from its :class:`BladeModel` (passive joints
  with K, D, K2).
- contact: the project's contact law (:func:`bladelab.sim.mujoco_engine.contact_forces_3d`,
  the blade's ``ContactModel``) on the blade's sole ellipses and on the foot circles, applied as
  external forces; MuJoCo's own contact is off.

:func:`simulate_transfemoral` starts at prosthetic touch-down (the lowest sole point 1 mm above
the ground, vertical speed of the cycle's flight phase, forward speed ``speed_mps``) and
simulates one period. :class:`TransfemoralResult` holds GRF per leg, the centre of mass, the
prosthetic knee angle and its extension moment (COP of the blade's sole forces), and the blade
points over time; :meth:`TransfemoralResult.responses` gives the performance functions and the
two constraints. :class:`RunnerEvaluator` chains design point -> blade -> cycle -> responses.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numba import njit

from bladelab.blade.model import BladeModel
from bladelab.constants import STANDARD_GRAVITY
from bladelab.design import defaults
from bladelab.design.blade_generator import generate_blade
from bladelab.design.constraints import blade_clearance, knee_buckling, knee_extension_moment
from bladelab.design.gait_cycle import GaitCycle, default_gait_cycle, read_gait_csv
from bladelab.design.motion import as_motion_model
from bladelab.design.performance import cycle_performance
from bladelab.design.responses import RUNNER_RESPONSE_UNITS
from bladelab.errors import SimulationError, SpecError
from bladelab.numba_cache import refresh_stale_caches
from bladelab.runner.kinematic_transfemoral import (
    KinematicTransfemoral,
    build_kinematic_transfemoral,
)
from bladelab.runner.prosthetic_knee import ProstheticKnee, knee_torque
from bladelab.sim.chain import build_chain
from bladelab.sim.mujoco_engine import contact_forces_3d

__all__ = ["RunnerEvaluator", "TransfemoralResult", "simulate_transfemoral"]



def _joint_targets(cycle: GaitCycle, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Servo targets q [rad] and rates [rad/s] (MuJoCo signs) at times ``t``: (n, 5)."""
    a, ad = cycle.at(t), cycle.at(t, derivative=1)
    # MuJoCo hinge about +y: trunk +lean; hip + = extension; knee + = flexion; ankle + = plantar
    sign = {"trunk_pitch": 1.0, "hip_sound": -1.0, "knee_sound": 1.0, "ankle_sound": -1.0,
            "hip_prosthetic": -1.0}
    order = ("trunk_pitch", "hip_sound", "knee_sound", "ankle_sound", "hip_prosthetic")
    q = np.stack([sign[n] * a[n] for n in order], axis=1)
    qd = np.stack([sign[n] * ad[n] for n in order], axis=1)
    return q, qd


@njit(cache=True)
def _forces(qpos, qvel, qfrc, tq, tqd, sq, sd, kp, kd, kq, kdof, kpar, bq, bd, K2):
    for i in range(sq.shape[0]):
        qfrc[sd[i]] = -kp[i] * (qpos[sq[i]] - tq[i]) - kd[i] * (qvel[sd[i]] - tqd[i])
    qfrc[kdof] = knee_torque(kpar, qpos[kq], qvel[kdof])
    for j in range(bd.shape[0]):
        q = qpos[bq[j]]
        qfrc[bd[j]] = -K2[j] * q * abs(q)


@dataclass(frozen=True, eq=False)
class TransfemoralResult:
    """One simulated gait cycle (samples at ``sample_rate``).

    Attributes
    ----------
    time
        [s], from prosthetic touch-down.
    grf_prosthetic, grf_sound
        (n, 2) ground reaction force (x, z) on the runner per leg [N].
    com
        (n, 2) centre of mass (x, z) [m]; ``com_velocity`` (n, 2) [m/s].
    knee
        (n, 2) prosthetic knee axis (x, z) [m]; ``knee_angle`` flexion [rad].
    cop
        (n,) x of the centre of pressure under the blade [m] (NaN off the ground).
    knee_moment
        Extension moment of the blade's GRF about the prosthetic knee [N·m].
    blade_points
        (n, n_points, 2) blade segment points, tip and the lowest point of every sole ellipse.
    mass, period, speed
        Body mass [kg] (runner + blade), cycle period [s], touch-down speed [m/s].
    """

    time: np.ndarray
    grf_prosthetic: np.ndarray
    grf_sound: np.ndarray
    com: np.ndarray
    com_velocity: np.ndarray
    knee: np.ndarray
    knee_angle: np.ndarray
    cop: np.ndarray
    knee_moment: np.ndarray
    blade_points: np.ndarray
    mass: float
    period: float
    speed: float

    @property
    def prosthetic_stance(self) -> np.ndarray:
        return self.grf_prosthetic[:, 1] > 1.0

    def swing_mask(self, window: tuple[float, float] = (0.25, 0.75)) -> np.ndarray:
        """Middle part of the longest no-contact run of the blade (fractions of its length)."""
        off = ~self.prosthetic_stance
        best, start = (0, 0), None
        for i, o in enumerate(np.append(off, False)):
            if o and start is None:
                start = i
            elif not o and start is not None:
                if i - start > best[1] - best[0]:
                    best = (start, i)
                start = None
        mask = np.zeros(self.time.size, bool)
        a, b = best
        if b > a:
            n = b - a
            mask[a + int(window[0] * n):a + max(int(window[1] * n), int(window[0] * n) + 1)] = True
        return mask

    def responses(self, *, knee_margin: float = 0.0, clearance_threshold: float = 0.0,
                  swing_window: tuple[float, float] = (0.25, 0.75)) -> dict[str, float]:
        """Performance functions and constraints of the cycle (units: RUNNER_RESPONSE_UNITS).

        Δv_x, mean v_x and the impulses span the whole cycle; E, the knee moment, contact time,
        peak force and stance knee flexion refer to the prosthetic stance that starts the cycle.
        """
        fx = self.grf_prosthetic[:, 0] + self.grf_sound[:, 0]
        fz = self.grf_prosthetic[:, 1] + self.grf_sound[:, 1]
        on = self.prosthetic_stance
        if not on.any():
            raise SimulationError("the blade never touched the ground in this cycle",
                                  where="transfemoral runner",
                                  hint="check the gait cycle and the speed")
        # the stance that starts the cycle (a next touch-down may begin before T)
        st = np.zeros_like(on)
        i0 = int(np.argmax(on))
        i1 = i0 + int(np.argmin(on[i0:])) if not on[i0:].all() else on.size
        st[i0:i1] = True
        perf = cycle_performance(
            self.time, fx, fz, self.mass, stance_masks={"prosthetic": st},
            com_x=self.com[:, 0])
        kb = knee_buckling(self.time, self.knee_moment, stance_mask=st, margin=knee_margin)
        cl = blade_clearance(self.time, self.blade_points, swing_mask=self.swing_mask(swing_window),
                             threshold=clearance_threshold)
        dt = float(self.time[1] - self.time[0])
        return {
            "delta_vx_m_per_s": float(perf.delta_vx),
            "avg_vx_m_per_s": float(perf.mean_vx),
            "impulse_x_Ns": float(perf.impulse_x),
            "impulse_z_Ns": float(perf.impulse_z),
            "evaluation_E_m": float(perf.per_leg["prosthetic"]["evaluation"]),
            "peak_grf_z_prosthetic_N": float(self.grf_prosthetic[st, 1].max()),
            "contact_time_prosthetic_s": float(st.sum() * dt),
            "knee_moment_min_Nm": kb.min_moment,
            "swing_clearance_m": cl.min_clearance,
            "knee_flexion_max_stance_deg": float(np.degrees(self.knee_angle[st].max())),
        }


def simulate_transfemoral(
    blade: BladeModel,
    *,
    cycle: GaitCycle | None = None,
    speed_mps: float = defaults.RUNNER_SPEED_MPS,
    body_mass_kg: float = defaults.BODY_MASS_KG,
    height_m: float = 1.75,
    knee: ProstheticKnee | None = None,
    extra_leg_length_m: float = 0.02,
    knee_offset_m: float = 0.0,
    servo_stiffness: float = 2.0e4,
    servo_damping: float = 200.0,
    dt: float = 2e-5,
    sample_rate: float = 1000.0,
    n_cycles: float = 1.0,
) -> TransfemoralResult:
    """Simulate the kinematics-driven transfemoral runner over ``n_cycles`` gait cycles.

    Parameters
    ----------
    blade
        The multi-link blade (K, D, K2 and contact from the model).
    cycle
        Joint angles; default :func:`~bladelab.design.gait_cycle.default_gait_cycle`.
    speed_mps
        Forward speed at prosthetic touch-down [m/s].
    body_mass_kg, height_m
        Runner (segment masses and lengths scaled from the runner parameters) [kg], [m].
    knee
        Prosthetic knee parameters.
    extra_leg_length_m
        Standing prosthetic leg minus sound leg (knee to ground) [m].
    knee_offset_m
        Forward offset of the clamp relative to the knee axis [m] (alignment: a positive value
        puts the knee axis behind the blade's load line).
    servo_stiffness, servo_damping
        PD gains of the joint servos [N·m/rad], [N·m·s/rad] (the ankle and trunk use 1/10 and
        5× of them).
    dt, sample_rate
        MuJoCo step [s], output rate [Hz].
    """
    if not (speed_mps > 0 and body_mass_kg > 0 and height_m > 0 and dt > 0 and n_cycles > 0):
        raise SpecError("speed, body mass, height, dt and n_cycles must be > 0",
                        where="simulate_transfemoral")
    cycle = cycle or default_gait_cycle()
    knee = knee or ProstheticKnee()
    chain = build_chain(blade)
    b = build_kinematic_transfemoral(blade, body_mass_kg, height_m, knee, extra_leg_length_m,
                                     dt, knee_offset_m)
    m = b.model
    d = mujoco.MjData(m)
    nsub = max(1, int(round(1.0 / (sample_rate * dt))))
    n_steps = int(round(n_cycles * cycle.period / dt))
    t_all = np.arange(n_steps + 1) * dt
    tq, tqd = _joint_targets(cycle, t_all)
    scale = np.array([5.0, 1.0, 1.0, 0.1, 1.0])
    kp, kd = servo_stiffness * scale, servo_damping * scale
    # initial pose: targets at t = 0, passive knee from the cycle, blade undeformed
    d.qpos[b.servo_q] = tq[0]
    d.qvel[b.servo_d] = tqd[0]
    a0, ad0 = cycle.at(0.0), cycle.at(0.0, derivative=1)
    d.qpos[b.knee_q] = float(a0["knee_prosthetic"])
    d.qvel[b.knee_d] = float(ad0["knee_prosthetic"])
    mujoco.mj_kinematics(m, d)
    low = _lowest(d, b, soles_only=True)
    d.qpos[m.jnt_qposadr[m.joint("root_z").id]] = -low + 0.001
    # flight before touch-down: half of (half period − contact) at the landing speed
    contact_guess = 0.23 * cycle.period
    t_flight = max(0.5 * cycle.period - contact_guess, 0.0)
    d.qvel[m.jnt_dofadr[m.joint("root_x").id]] = speed_mps
    d.qvel[m.jnt_dofadr[m.joint("root_z").id]] = -0.5 * STANDARD_GRAVITY * t_flight
    contact = chain.contact
    ns = len(b.sites)
    out = np.zeros((ns, 7))
    K2 = np.array([j.stiffness_quadratic for j in blade.joints], float)
    kpar = knee.as_array()
    rootid = np.ascontiguousarray(m.body_rootid)
    rec_t, rec = [], []
    acc = np.zeros((ns, 2))  # forces summed since the last sample (mean force per interval)
    for i in range(n_steps + 1):
        mujoco.mj_step1(m, d)
        contact_forces_3d(contact, d.site_xpos, d.site_xmat, b.sites, b.axes, b.site_body,
                          d.cvel, d.subtree_com, rootid, d.xipos, 0.0, d.xfrc_applied, out)
        _forces(d.qpos, d.qvel, d.qfrc_applied, tq[i], tqd[i], b.servo_q, b.servo_d, kp, kd,
                b.knee_q, b.knee_d, kpar, b.blade_q, b.blade_d, K2)
        if i > 0:
            acc += out[:, :2]
        if i % nsub == 0:
            mean = out[:, :2] if i == 0 else acc / nsub
            rec_t.append(i * dt)
            rec.append(_sample(d, b, out, mean))
            acc[:] = 0.0
        if i == n_steps:
            break
        mujoco.mj_step2(m, d)
        if i % 2000 == 0 and not np.all(np.isfinite(d.qpos)):
            raise SimulationError(f"the transfemoral runner diverged at t = {i * dt:.3g} s",
                                  where="simulate_transfemoral", hint="reduce dt")
    return _result(np.asarray(rec_t), rec, b, m, speed_mps, cycle.period)


def _ellipse_low(xpos, xmat, a, c):
    exz, ezz = xmat[6], xmat[8]
    nrm = math.hypot(a * exz, c * ezz)
    ct, st = -a * exz / nrm, -c * ezz / nrm
    return (xpos[0] + a * ct * xmat[0] + c * st * xmat[2],
            xpos[2] + a * ct * xmat[6] + c * st * xmat[8])


def _lowest(d, b: KinematicTransfemoral, *, soles_only: bool = False) -> float:
    zs = [_ellipse_low(d.site_xpos[s], d.site_xmat[s], *b.axes[e])[1]
          for e, s in enumerate(b.sites[:b.n_soles])]
    if not soles_only:
        zs += list(d.xpos[b.seg_bodies, 2]) + [d.site_xpos[b.tip_site, 2]]
    return float(min(zs))


def _sample(d, b: KinematicTransfemoral, out: np.ndarray, mean: np.ndarray):
    ne = b.n_soles
    lows = [_ellipse_low(d.site_xpos[s], d.site_xmat[s], *b.axes[e])
            for e, s in enumerate(b.sites[:ne])]
    pts = [(x, z) for x, _, z in d.xpos[b.seg_bodies]]
    pts.append((d.site_xpos[b.tip_site, 0], d.site_xpos[b.tip_site, 2]))
    pts += lows
    fz = out[:ne, 1]
    cop = float(np.dot([p[0] for p in lows], fz) / fz.sum()) if fz.sum() > 1e-9 else math.nan
    com = d.subtree_com[1]
    return (mean[:ne, 0].sum(), mean[:ne, 1].sum(), mean[ne:, 0].sum(), mean[ne:, 1].sum(),
            com[0], com[2],
            d.xpos[b.knee_body, 0], d.xpos[b.knee_body, 2], d.qpos[b.knee_q], cop, pts)


def _result(t, rec, b: KinematicTransfemoral, m, speed: float, period: float) -> TransfemoralResult:
    arr = np.array([r[:10] for r in rec], float)
    pts = np.array([r[10] for r in rec], float)
    com = arr[:, 4:6]
    vel = np.gradient(com, t, axis=0)
    fxp, fzp = arr[:, 0], arr[:, 1]
    cop = arr[:, 9].copy()
    for i in range(1, cop.size):  # a sample whose mean force is on but instantaneous is off
        if not math.isfinite(cop[i]):
            cop[i] = cop[i - 1]
    st = (fzp > 1.0) & np.isfinite(cop)
    moment = np.zeros(t.size)
    if st.any():
        moment[st] = knee_extension_moment(cop[st], 0.0, arr[st, 6], arr[st, 7], fxp[st], fzp[st])
    mass = float(np.sum(m.body_mass))
    return TransfemoralResult(
        time=t, grf_prosthetic=arr[:, 0:2], grf_sound=arr[:, 2:4], com=com, com_velocity=vel,
        knee=arr[:, 6:8], knee_angle=arr[:, 8], cop=cop, knee_moment=moment, blade_points=pts,
        mass=mass, period=period, speed=speed,
    )


@dataclass(frozen=True)
class RunnerEvaluator:
    """Design point -> generated blade -> one transfemoral gait cycle -> responses.

    Attributes
    ----------
    gait
        Gait-cycle CSV path (default: the built-in template).
    speed_mps, body_mass_kg, height_m
        Runner settings (:func:`simulate_transfemoral`).
    knee_margin_Nm, clearance_threshold_m
        Constraint thresholds recorded with the responses.
    dt
        Simulation step [s].
    generator
        Options of :func:`~bladelab.design.blade_generator.generate_blade`.
    motion
        Motion adaptation (seed 002): a :class:`~bladelab.design.motion_model.MotionModel` or a
        motion file (:func:`bladelab.design.motion.load_motion_model`, fitted once here); each
        design then runs its predicted cycle and gets the response ``predicted_period_s``.
        Exclusive with ``gait``.
    """

    gait: str | None = None
    speed_mps: float = defaults.RUNNER_SPEED_MPS
    body_mass_kg: float = defaults.BODY_MASS_KG
    height_m: float = 1.75
    knee_margin_Nm: float = 0.0
    clearance_threshold_m: float = 0.0
    dt: float = 2e-5
    generator: Mapping[str, Any] = field(default_factory=dict)
    motion: Any = None

    def __post_init__(self) -> None:
        if self.motion is not None:
            if self.gait is not None:
                raise SpecError("give either gait (one cycle for every design) or motion (a "
                                "predicted cycle per design), not both", where="runner evaluator")
            object.__setattr__(self, "motion", as_motion_model(self.motion))

    @property
    def units(self) -> dict[str, str]:
        u = dict(RUNNER_RESPONSE_UNITS)
        if self.motion is not None:
            u["predicted_period_s"] = "s"
        return u

    def to_dict(self) -> dict:
        d = asdict(replace(self, motion=None))
        d["generator"] = {k: str(v) if isinstance(v, Path) else v
                          for k, v in dict(self.generator).items()}
        d["motion"] = None if self.motion is None else self.motion.to_dict()
        return {"evaluator": "runner", **d}

    def __call__(self, point: Mapping[str, float]) -> dict[str, float]:
        blade = generate_blade(point, **dict(self.generator)).model
        if self.motion is not None:
            cycle = self.motion.predict_point(point)
        else:
            cycle = read_gait_csv(self.gait) if self.gait else default_gait_cycle()
        res = simulate_transfemoral(blade, cycle=cycle, speed_mps=self.speed_mps,
                                    body_mass_kg=self.body_mass_kg, height_m=self.height_m,
                                    dt=self.dt)
        out = res.responses(knee_margin=self.knee_margin_Nm,
                            clearance_threshold=self.clearance_threshold_m)
        if self.motion is not None:
            out["predicted_period_s"] = float(cycle.period)
        return out


refresh_stale_caches(globals())
