"""Synthetic, physically consistent stances: a point-mass runner whose leg carries the blade.

The runner (MuJoCo, :func:`bladelab.sim.mujoco_engine.build_spec` with ``root="runner"``): a point
mass ``body_mass_kg`` at the hip, free in x and z; a rigid pylon from the hip down to the clamp;
the blade on the clamp. A stiff pitch servo at the hip keeps the pylon along the leg line, the
line from the planned contact point to the hip, rotated by the constant angle between that line
and the pylon in the blade's geometry: so the blade pivots over its sole and rolls along it as
the hip vaults over, instead of being dragged. The runner starts in flight shortly before
touch-down with a forward speed and a downward velocity; the free simulation of the whole
stance is recorded on a uniform time base and becomes the :class:`~bladelab.trial.stance.Stance`
(clamp pose, GRF, characteristic distance). The blade's K, D are the truth.

Optional measurement noise (seeded): white noise on clamp position [m] and pitch [deg] and on the
forces (fraction of peak vertical force).
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np
from numba import njit

from bladelab import units
from bladelab.blade.model import BladeModel
from bladelab.constants import STANDARD_GRAVITY
from bladelab.errors import ModelError, SimulationError
from bladelab.numba_cache import refresh_stale_caches
from bladelab.sim.chain import build_chain
from bladelab.sim.mujoco_engine import MujocoBlade, build_spec
from bladelab.trial.stance import Stance


@njit(cache=True)
def _runner_forces(qpos, qvel, qfrc, out, slip_acc, dt, qx, qz, qp, vp, jq, jd, K2, offset,
                   kp, kd, gain):
    """Pitch servo toward the leg line, quadratic spring term, slip bookkeeping.

    Returns whether any sole element is in contact.
    """
    hx = qpos[qx]
    hz = qpos[qz]
    vx = qvel[qx]
    vz = qvel[qz]
    target = math.atan2(hx, hz) + offset
    target_rate = (hz * vx - hx * vz) / (hx * hx + hz * hz)
    qfrc[:] = 0.0
    qfrc[vp] = gain * (-kp * (qpos[qp] - target) - kd * (qvel[vp] - target_rate))
    for j in range(jd.shape[0]):
        q = qpos[jq[j]]
        qfrc[jd[j]] = -K2[j] * q * abs(q)
    any_contact = False
    for e in range(out.shape[0]):
        if out[e, 1] > 0.0:
            any_contact = True
            slip_acc[e] += out[e, 3] * dt
    return any_contact


def _lowest_sole_point(blade: BladeModel, pitch: float) -> np.ndarray:
    """Clamp-frame point of the undeformed sole that is lowest at clamp pitch ``pitch`` [rad]."""
    best = None
    for s in blade.soles:
        psi = pitch + s.angle
        sn, cs = math.sin(psi), math.cos(psi)
        nrm = math.hypot(s.semi_axis_x * sn, s.semi_axis_z * cs)
        # lowest point in the lab orientation, then back to the clamp frame
        off_lab = np.array([sn * cs * (s.semi_axis_x**2 - s.semi_axis_z**2) / nrm, -nrm])
        c, sp = math.cos(pitch), math.sin(pitch)
        off = np.array([c * off_lab[0] - sp * off_lab[1], sp * off_lab[0] + c * off_lab[1]])
        p = np.asarray(s.center, float) + off
        z_lab = -sp * p[0] + c * p[1]
        if best is None or z_lab < best[0]:
            best = (z_lab, p)
    return best[1]


def generate_stance(
    blade: BladeModel,
    *,
    speed_mps: float = 8.0,
    body_mass_kg: float = 70.0,
    touchdown_angle_deg: float = -25.0,
    touchdown_vertical_speed_mps: float = -0.5,
    pylon_length_m: float = 0.45,
    stiffness: float | np.ndarray | None = None,
    damping: float | np.ndarray | None = None,
    dt: float = 5e-6,
    sample_rate: float = 1000.0,
    margin_s: float = 0.003,
    servo_stiffness: float = 3.0e4,
    servo_damping: float = 300.0,
    stance_servo_scale: float = 0.0,
    marker_noise_m: float = 0.0,
    pitch_noise_deg: float = 0.0,
    force_noise_frac: float = 0.0,
    seed: int | np.random.Generator | None = None,
    engine: str = "mujoco",
) -> tuple[Stance, dict[str, Any]]:
    """Simulate one running stance on ``blade`` and return it with its ground truth.

    Parameters
    ----------
    blade
        The blade (its contact model is used; K, D from the blade unless given).
    speed_mps
        Forward speed of the hip at touch-down [m/s].
    body_mass_kg
        Runner mass [kg], a point mass at the hip.
    touchdown_angle_deg
        Leg angle at touch-down [deg]: angle of the line contact point → hip from vertical,
        positive forward (negative: the foot lands ahead of the hip).
    touchdown_vertical_speed_mps
        Vertical hip velocity at touch-down [m/s] (negative: falling).
    pylon_length_m
        Hip-to-clamp length of the rigid pylon [m].
    stiffness, damping
        Joint K [N·m/rad], D [N·m·s/rad] per joint; None = the blade's own.
    dt
        MuJoCo step [s] (≤ 5e-6 s with friction).
    sample_rate
        Sampling rate of the returned stance [Hz].
    margin_s
        Time kept before touch-down and after toe-off [s].
    servo_stiffness, servo_damping
        Pitch servo gains [N·m/rad], [N·m·s/rad].
    marker_noise_m, pitch_noise_deg, force_noise_frac
        Standard deviations of white measurement noise added to clamp x/z [m], clamp pitch
        [deg] and the forces (fraction of the peak vertical force). Distance gets the marker
        noise too.
    seed
        Seed or Generator for the noise (only used when a noise level is > 0).
    engine
        ``"mujoco"`` (the only engine that simulates the free runner).

    Returns
    -------
    (Stance, dict)
        The stance (metadata names the source and truth) and the truth: ``K_Nm_per_rad``,
        ``D_Nms_per_rad`` (lists), ``K_Nm_per_deg``, ``D_Nms_per_deg``, ``contact_time_s``,
        ``peak_grf_z_N``, ``max_compression_m``, ``min_deflection_deg``, ``max_sole_slip_m``,
        ``pitch_touchdown_deg``, ``pitch_toeoff_deg``, ``clamp_mean_speed_mps``, and the clean
        signals ``deflection`` (n, n_joints) [rad], ``grf_x``, ``grf_z`` [N], ``distance`` [m],
        ``tip_x``, ``tip_z`` (blade tip in the lab frame) [m].

    Raises
    ------
    ModelError
        Unknown engine or inconsistent parameters.
    SimulationError
        The runner never touched down or did not leave the ground within 0.6 s.
    """
    if engine != "mujoco":
        raise ModelError(f"engine {engine!r} cannot simulate the free runner", where="engine",
                         hint="use engine='mujoco'")
    if not (body_mass_kg > 0 and speed_mps > 0 and pylon_length_m > 0 and dt > 0):
        raise ModelError("body mass, speed, pylon length and dt must be > 0",
                         where="generate_stance")
    chain = build_chain(blade)
    nj = chain.n_joints
    K = chain.stiffness if stiffness is None else np.broadcast_to(np.asarray(stiffness, float), (nj,))
    D = chain.damping if damping is None else np.broadcast_to(np.asarray(damping, float), (nj,))
    K2 = chain.stiffness_quadratic
    nsub = max(1, int(round(1.0 / (sample_rate * dt))))
    dt = 1.0 / (sample_rate * nsub)
    mj = MujocoBlade(blade, build_spec(blade, stiffness=K, damping=D, dt=dt, root="runner",
                                       body_mass=body_mass_kg, pylon_length=pylon_length_m))
    m, d = mj.model, mj.data
    contact = chain.contact

    # touch-down geometry: pitch θ = β + offset, offset = angle between the pylon and the line
    # from the lowest sole point to the hip (iterate: the lowest point depends on the pitch)
    beta = units.deg2rad(touchdown_angle_deg)
    offset = 0.0
    for _ in range(20):
        p = _lowest_sole_point(blade, beta + offset)
        offset = math.atan2(p[0], pylon_length_m - p[1])
    theta_td = beta + offset
    c, s = math.cos(theta_td), math.sin(theta_td)
    p_low = np.array([c * p[0] + s * p[1], -s * p[0] + c * p[1]])  # lab offset clamp -> sole
    clamp_td = -p_low + np.array([0.0, 0.0])  # sole lowest point at the pivot (0, 0)
    hip_td = clamp_td + np.array([s * pylon_length_m, c * pylon_length_m])
    lead = max(0.010, margin_s + 0.002)  # start in flight, before the kept margin
    g = STANDARD_GRAVITY
    v_td = np.array([speed_mps, touchdown_vertical_speed_mps])
    hip0 = hip_td - v_td * lead - np.array([0.0, 0.5 * g * lead**2])
    hip0[1] += 0.001  # 1 mm clearance
    v0 = v_td + np.array([0.0, g * lead])
    qx, qz, qp = (m.jnt_qposadr[m.joint(n).id] for n in ("root_x", "root_z", "pylon_pitch"))
    vp = m.jnt_dofadr[m.joint("pylon_pitch").id]
    d.qpos[qx], d.qpos[qz] = hip0
    d.qvel[qx], d.qvel[qz] = v0

    def _target(hx, hz, vx, vz):
        r2 = hx * hx + hz * hz
        return math.atan2(hx, hz) + offset, (hz * vx - hx * vz) / r2

    th0, thd0 = _target(*hip0, *v0)
    d.qpos[qp] = th0
    d.qvel[vp] = thd0
    jq, jd = mj.joint_qpos, mj.joint_dofs
    clamp_site, tip_site = mj.clamp_site, mj.tip_site
    rows = []
    slip_acc = np.zeros(len(blade.soles))
    touched = False
    last_contact = None
    max_steps = int(0.6 / dt)
    qpos, qvel, qfrc, out = d.qpos, d.qvel, d.qfrc_applied, mj.out
    jq = np.ascontiguousarray(jq)
    jd = np.ascontiguousarray(jd)
    K2 = np.asarray(K2, float)
    for i in range(max_steps):
        mujoco.mj_step1(m, d)
        mj.apply_contact(contact)
        in_contact = _runner_forces(qpos, qvel, qfrc, out, slip_acc, dt, qx, qz, qp, vp, jq, jd,
                                    K2, offset, servo_stiffness, servo_damping,
                                    stance_servo_scale if touched else 1.0)
        if i % nsub == 0:
            cl = d.site_xpos[clamp_site]
            tip = d.site_xpos[tip_site]
            rows.append((
                i * dt, cl[0], cl[2], qpos[qp], out[:, 0].sum(), out[:, 1].sum(),
                math.hypot(tip[0] - cl[0], tip[2] - cl[2]), *qpos[jq], qpos[qx], qpos[qz],
                *out[:, 1], *slip_acc, tip[0], tip[2],
            ))
        if in_contact:
            touched = True
            last_contact = i
        elif touched and (i - last_contact) * dt > margin_s + 2.0 / sample_rate:
            break
        mujoco.mj_step2(m, d)
        if i % 1000 == 0 and not np.all(np.isfinite(qpos)):
            raise SimulationError(f"the runner diverged at t = {i * dt:.4g} s",
                                  where="generate_stance", hint="reduce dt")
    else:
        raise SimulationError(
            "the runner did not complete a stance within 0.6 s" if touched else
            "the runner never touched down", where="generate_stance",
            hint="check speed, touch-down angle and pylon length",
        )
    rec = np.asarray(rows)
    ne = chain.n_soles
    t, cx, cz, pitch, fx, fz, dist = (rec[:, i] for i in range(7))
    defl = rec[:, 7:7 + nj]
    fz_el = rec[:, 9 + nj:9 + nj + ne]
    slip_cum = rec[:, 9 + nj + ne:9 + nj + 2 * ne]
    loaded = np.flatnonzero(fz > 1.0)
    n_margin = int(round(margin_s * sample_rate))
    i0 = max(0, loaded[0] - n_margin)
    i1 = min(len(t), loaded[-1] + n_margin + 1)
    sl = slice(i0, i1)
    # sole slip: range of the integrated slip velocity of each element while it bears load
    slip = 0.0
    for e in range(ne):
        on = np.flatnonzero(fz_el[:, e] > 0.05 * fz.max())
        if on.size:
            slip = max(slip, float(np.ptp(slip_cum[on, e])))
    rng = np.random.default_rng(seed)
    n = i1 - i0
    noisy = {
        "clamp_x": cx[sl] + (rng.normal(0, marker_noise_m, n) if marker_noise_m > 0 else 0.0),
        "clamp_z": cz[sl] + (rng.normal(0, marker_noise_m, n) if marker_noise_m > 0 else 0.0),
        "clamp_pitch": pitch[sl] + (rng.normal(0, units.deg2rad(pitch_noise_deg), n)
                                    if pitch_noise_deg > 0 else 0.0),
        "distance": dist[sl] + (rng.normal(0, marker_noise_m, n) if marker_noise_m > 0 else 0.0),
    }
    f_sd = force_noise_frac * float(fz.max())
    noisy["grf_x"] = fx[sl] + (rng.normal(0, f_sd, n) if f_sd > 0 else 0.0)
    noisy["grf_z"] = fz[sl] + (rng.normal(0, f_sd, n) if f_sd > 0 else 0.0)
    time = t[sl] - t[i0]
    K_deg = units.stiffness_per_rad_to_per_deg(np.asarray(K, float))
    D_deg = units.damping_per_rad_to_per_deg(np.asarray(D, float))
    stance = Stance(
        time=time, clamp_x=noisy["clamp_x"], clamp_y=np.zeros(n), clamp_z=noisy["clamp_z"],
        clamp_pitch=noisy["clamp_pitch"], grf_x=noisy["grf_x"], grf_y=np.zeros(n),
        grf_z=noisy["grf_z"], distance=noisy["distance"],
        metadata={
            "source": "bladelab.sim.generate_stance", "blade": blade.name,
            "speed_mps": speed_mps, "body_mass_kg": body_mass_kg,
            "K_Nm_per_deg": float(K_deg[0]), "D_Nms_per_deg": float(D_deg[0]),
        },
    )
    contact_time = (loaded[-1] - loaded[0] + 1) / sample_rate
    truth = {
        "K_Nm_per_rad": np.asarray(K, float).tolist(),
        "D_Nms_per_rad": np.asarray(D, float).tolist(),
        "K_Nm_per_deg": K_deg.tolist(),
        "D_Nms_per_deg": D_deg.tolist(),
        "contact_time_s": float(contact_time),
        "peak_grf_z_N": float(fz.max()),
        "max_compression_m": float(blade.rest_distance - dist[sl].min()),
        "min_deflection_deg": float(units.rad2deg(defl[sl].min())),
        "max_abs_deflection_deg": float(units.rad2deg(np.abs(defl[sl]).max())),
        "max_sole_slip_m": slip,
        "pitch_touchdown_deg": float(units.rad2deg(pitch[loaded[0]])),
        "pitch_toeoff_deg": float(units.rad2deg(pitch[loaded[-1]])),
        "clamp_mean_speed_mps": float((cx[loaded[-1]] - cx[loaded[0]]) / max(contact_time, 1e-9)),
        "hip_speed_toeoff_mps": float(np.gradient(rec[:, 7 + nj], t)[loaded[-1]]),
        "deflection": defl[sl].copy(),
        "grf_x": fx[sl].copy(),
        "grf_z": fz[sl].copy(),
        "distance": dist[sl].copy(),
        "tip_x": rec[sl, 9 + nj + 2 * ne].copy(),
        "tip_z": rec[sl, 10 + nj + 2 * ne].copy(),
    }
    return stance, truth


refresh_stale_caches(globals())
