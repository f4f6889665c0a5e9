"""Analyses of a runner simulation (seed 001 §1.1, §2.3, §2.4, Tables 3.3 and D.1).

- :func:`gait_events`, :func:`stances` and :func:`spatiotemporal`: touch-downs and lift-offs
  per leg (real steps: strikes of the swinging foot are :func:`swing_contacts`) and stride,
  step, contact, flight and swing times (§1.1);
- :func:`leg_grf` (N, body weights); :func:`joint_angles` (deg); :func:`joint_moments` (N·m);
  :func:`com_trajectory` (whole-body centre of mass);
- :func:`joint_powers`: hip, knee, ankle (muscle + ligament torque × angular velocity), socket,
  and the blade (power the blade contact delivers to the body);
- :func:`power_balance`: muscle, ligament, contact, gravity and kinetic power (eq. 2.10–2.18),
  and the residual ``P_external − P_kinetic``;
- :func:`stances`: the complete stances every per-stance analysis of
  :mod:`bladelab.runner.stance_mechanics` (K_leg, leg and blade energy) uses;
- :func:`summary`: the JSON summary of the CLI.

Powers are positive when delivered to the body segments. All tables are tidy DataFrames.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np
import pandas as pd

from bladelab.runner.layout import CP_BLADE, CP_LEG
from bladelab.runner.params import PROSTHETIC_KINDS
from bladelab.runner.simulate import (
    RC_FX,
    RC_FZ,
    RC_VX,
    RC_VZ,
    RunnerResult,
    leg_names,
)

CONTACT_THRESHOLD_N = 20.0
STEP_LOAD_BW = 0.1  # a leg is loaded at or above this vertical GRF [body weights] (SCONE)
MIN_STEP_S = 0.1  # a new contact sooner than this after the last step is not a step [s] (SCONE)
MIN_GAP_S = 0.05  # unloaded gaps shorter than this inside a stance are contact bounces [s]
MIN_CONTACT_S = 0.03  # loaded stretches shorter than this are brief touches, not stances [s]


def forward_pass(result: RunnerResult) -> dict[str, np.ndarray]:
    """Per sample of ``result`` (computed once, then cached on it): ``ek`` kinetic energy [J],
    ``com`` and ``comv`` the whole-body centre of mass's position [m] and velocity [m/s] (n, 3),
    ``qfrc_muscle`` the muscles' generalised forces (n, nv) [N or N·m]."""
    cached = getattr(result, "_fwd_cache", None)
    if cached is not None:
        return cached
    m = result.model.mj_analysis_model.__copy__()
    m.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    d = mujoco.MjData(m)
    n = len(result.time)
    ek = np.zeros(n)
    com = np.zeros((n, 3))
    comv = np.zeros((n, 3))
    qfa = np.zeros((n, m.nv))
    for i in range(n):
        d.qpos[:] = result.qpos[i]
        d.qvel[:] = result.qvel[i]
        d.ctrl[:] = -result.muscles[i, :, 3]
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        ek[i] = d.energy[1]
        com[i] = d.subtree_com[0]
        comv[i] = d.subtree_linvel[0]
        qfa[i] = d.qfrc_actuator
    out = {"ek": ek, "com": com, "comv": comv, "qfrc_muscle": qfa}
    object.__setattr__(result, "_fwd_cache", out)
    return out


def leg_vertical_force(result: RunnerResult, leg: int) -> np.ndarray:
    """Vertical ground force of leg 0 or 1 per sample [N], its contacts summed."""
    cols = result.model.contact_params[:, CP_LEG] == leg
    return result.contacts[:, cols, RC_FZ].sum(axis=1)


def com_trajectory(result: RunnerResult) -> pd.DataFrame:
    """Whole-body centre of mass (wide): time [s], x_m, z_m [m], vx_m_per_s, vz_m_per_s [m/s]."""
    fwd = forward_pass(result)
    com, v = fwd["com"], fwd["comv"]
    return pd.DataFrame({"time": result.time, "x_m": com[:, 0], "z_m": com[:, 2],
                         "vx_m_per_s": v[:, 0], "vz_m_per_s": v[:, 2]})


def leg_grf(result: RunnerResult) -> pd.DataFrame:
    """GRF per leg (tidy): time [s], leg, Fx, Fz [N], Fx_bw, Fz_bw [body weights]."""
    return result.leg_grf()


def contact_mask(
    time: np.ndarray,
    loaded: np.ndarray,
    *,
    min_gap_s: float = MIN_GAP_S,
    min_contact_s: float = MIN_CONTACT_S,
    force: np.ndarray | None = None,
    min_peak_n: float = 0.0,
) -> np.ndarray:
    """Stance mask of one leg from its loaded samples (vertical GRF above the threshold).

    Unloaded gaps shorter than ``min_gap_s`` [s] between two loaded stretches (contact
    bounces) are filled, then loaded stretches shorter than ``min_contact_s`` [s] (a brief
    touch of the swinging foot) or, given the leg's vertical ``force`` [N] per sample, never
    reaching ``min_peak_n`` [N] (a scuff) are dropped; a stretch touching either end of the
    record is kept. ``time`` [s] and ``loaded`` (bool) are per sample.
    """
    on = np.asarray(loaded, dtype=bool).copy()
    time = np.asarray(time, dtype=float)
    for value, shortest in ((False, min_gap_s), (True, min_contact_s)):
        edges = np.flatnonzero(np.diff(on.astype(np.int8))) + 1
        bounds = np.concatenate([[0], edges, [len(on)]])
        for a, b in zip(bounds[:-1], bounds[1:], strict=True):
            if not (a > 0 and b < len(on)) or on[a] != value:
                continue
            weak = value and force is not None and np.max(force[a:b]) < min_peak_n
            if time[b] - time[a] < shortest or weak:
                on[a:b] = not value
    return on


def step_touchdowns(
    time: np.ndarray,
    leg_force: np.ndarray,
    body_weight: float,
    *,
    load_bw: float = STEP_LOAD_BW,
    min_step_s: float = MIN_STEP_S,
) -> list[tuple[float, int, float]]:
    """Steps as SCONE's GaitMeasure (and the objective, online) counts them: a new contact of a
    leg (vertical GRF ``leg_force`` (n, 2) [N] rising to ``load_bw`` body weights) more than
    ``min_step_s`` [s] after the previous step; a sooner new contact of the other leg marks the
    step as struck (the swinging foot hit the ground), with that contact's peak force. The
    force of sample i is seen at sample i + 1, as in the compiled loop. Returns (time [s], leg
    index, strike peak [body weights], 0 if not struck) per step."""
    loaded_prev = np.zeros(2, dtype=bool)
    last, last_leg, striking = -np.inf, -1, -1
    out: list[tuple[float, int, float]] = []
    for k in range(1, len(time)):
        for leg in (0, 1):
            loaded = leg_force[k - 1, leg] >= load_bw * body_weight
            if loaded and not loaded_prev[leg]:
                if time[k] - last > min_step_s:
                    out.append((float(time[k]), leg, 0.0))
                    last, last_leg, striking = time[k], leg, -1
                elif leg != last_leg and out:
                    striking = leg
            if striking == leg:
                if loaded:
                    peak = max(out[-1][2], float(leg_force[k - 1, leg] / body_weight))
                    out[-1] = (out[-1][0], out[-1][1], peak)
                else:
                    striking = -1
            loaded_prev[leg] = loaded
    return out


def _contacts(
    result: RunnerResult, threshold_n: float, min_gap_s: float, min_contact_s: float
) -> list[dict]:
    """Every cleaned contact of both legs (:func:`contact_mask`), each marked as a stance (a
    step of :func:`step_touchdowns` starts in it) or not (a swing contact)."""
    names = leg_names(result.model)
    bw = result.model.body_weight
    forces = np.stack([leg_vertical_force(result, leg) for leg in (0, 1)], axis=1)
    steps = step_touchdowns(result.time, forces, bw)
    dt = float(result.time[1] - result.time[0]) if len(result.time) > 1 else 0.0
    out = []
    for leg in (0, 1):
        fz = forces[:, leg]
        on = contact_mask(
            result.time,
            fz > threshold_n,
            min_gap_s=min_gap_s,
            min_contact_s=min_contact_s,
            force=fz,
            min_peak_n=STEP_LOAD_BW * bw if min_contact_s > 0 else 0.0,
        )
        edges = np.flatnonzero(np.diff(on.astype(np.int8))) + 1
        bounds = np.concatenate([[0], edges, [len(on)]])
        for a, b in zip(bounds[:-1], bounds[1:], strict=True):
            if not on[a]:
                continue
            t0, t1 = float(result.time[a]), float(result.time[b - 1])
            stance = any(side == leg and t0 - 1e-12 <= t <= t1 + dt + 1e-12 for t, side, _ in steps)
            out.append(
                {
                    "leg": names[leg],
                    "start": t0,
                    "end": float(result.time[min(b, len(on) - 1)]),
                    "peak_N": float(fz[a:b].max()),
                    "stance": stance,
                    "open": b == len(on),
                    "first": int(a),
                    "stop": int(b),
                }
            )
    return out


def gait_events(
    result: RunnerResult,
    *,
    threshold_n: float = CONTACT_THRESHOLD_N,
    min_gap_s: float = MIN_GAP_S,
    min_contact_s: float = MIN_CONTACT_S,
    steps_only: bool = True,
) -> pd.DataFrame:
    """Touch-downs and lift-offs per leg: columns leg, event (touchdown/liftoff), time [s].

    A leg is in contact while its vertical GRF exceeds ``threshold_n`` [N], with bounces, brief
    touches and scuffs (contacts never reaching 0.1 body weight, SCONE's step load) cleaned by
    :func:`contact_mask` (``min_contact_s=0`` keeps every contact). With ``steps_only``, only
    stances count: contacts in which a step (:func:`step_touchdowns`, SCONE's definition)
    starts; the others, a swinging foot striking the ground, are :func:`swing_contacts`.
    """
    rows = []
    for c in _contacts(result, threshold_n, min_gap_s, min_contact_s):
        if steps_only and not c["stance"]:
            continue
        if c["start"] > result.time[0]:
            rows.append({"leg": c["leg"], "event": "touchdown", "time": c["start"]})
        if not c["open"]:
            rows.append({"leg": c["leg"], "event": "liftoff", "time": c["end"]})
    return pd.DataFrame(rows, columns=["leg", "event", "time"]).sort_values(
        "time", ignore_index=True
    )


def swing_contacts(
    result: RunnerResult,
    *,
    threshold_n: float = CONTACT_THRESHOLD_N,
    min_gap_s: float = MIN_GAP_S,
    min_contact_s: float = MIN_CONTACT_S,
) -> pd.DataFrame:
    """Contacts that are not stances (no step starts in them: a swinging foot striking or
    scuffing the ground): leg, start [s], duration [s], peak vertical force [N]."""
    rows = [
        {
            "leg": c["leg"],
            "start": c["start"],
            "duration": c["end"] - c["start"],
            "peak_N": c["peak_N"],
        }
        for c in _contacts(result, threshold_n, min_gap_s, min_contact_s)
        if not c["stance"]
    ]
    return pd.DataFrame(rows, columns=["leg", "start", "duration", "peak_N"])


def spatiotemporal(
    result: RunnerResult, *, threshold_n: float = CONTACT_THRESHOLD_N
) -> pd.DataFrame:
    """Mean stride, step, contact, flight and swing times [s] per leg (seed 001 §1.1).

    Tidy: columns leg, variable, value (mean [s]), sd (standard deviation over the cycles [s]),
    n (number of complete cycles used). Only stances with both a touch-down and a lift-off
    inside the simulation count; NaN where there are none.
    """
    ev = gait_events(result, threshold_n=threshold_n)
    names = leg_names(result.model)
    rows = []
    for leg, other in ((names[0], names[1]), (names[1], names[0])):
        td = ev.time[(ev.leg == leg) & (ev.event == "touchdown")].to_numpy()
        lo = ev.time[(ev.leg == leg) & (ev.event == "liftoff")].to_numpy()
        td_other = ev.time[(ev.leg == other) & (ev.event == "touchdown")].to_numpy()
        contact, flight, step = [], [], []
        for t in td:
            after = lo[lo > t]
            if len(after):
                contact.append(after[0] - t)
                nxt = td_other[td_other > after[0]]
                if len(nxt):
                    flight.append(nxt[0] - after[0])
            nxt = td_other[td_other > t]
            if len(nxt):
                step.append(nxt[0] - t)
        stride = np.diff(td)
        swing = [td[k + 1] - td[k] - contact[k] for k in range(min(len(stride), len(contact)))]
        mean_contact = float(np.mean(contact)) if contact else math.nan
        mean_stride = float(np.mean(stride)) if len(stride) else math.nan
        values = {
            "stride_time": (mean_stride, stride),
            "step_time": (float(np.mean(step)) if step else math.nan, step),
            "contact_time": (mean_contact, contact),
            "flight_time": (float(np.mean(flight)) if flight else math.nan, flight),
            "swing_time": (mean_stride - mean_contact, swing),
        }
        for var, (val, xs) in values.items():
            sd = float(np.std(xs, ddof=1)) if len(xs) > 1 else math.nan
            rows.append({"leg": leg, "variable": var, "value": val, "sd": sd, "n": len(xs)})
    return pd.DataFrame(rows)


def joint_angles(result: RunnerResult) -> pd.DataFrame:
    """Joint angles in degrees (tidy): time [s], joint, angle_deg (rotational coordinates)."""
    model = result.model
    frames = []
    for j, name in enumerate(model.dof_names):
        if name in ("pelvis_tx", "pelvis_tz"):
            continue
        frames.append(
            pd.DataFrame(
                {"time": result.time, "joint": name, "angle_deg": np.degrees(result.qpos[:, j])}
            )
        )
    return pd.concat(frames, ignore_index=True)


def _joint_torque(result: RunnerResult) -> np.ndarray:
    """(n, n_dof) muscle + ligament (and socket/blade spring) generalized force [N·m]."""
    return forward_pass(result)["qfrc_muscle"] + result.ligament


_ACTUATED = ("hip", "knee", "ankle", "socket")


def joint_moments(result: RunnerResult) -> pd.DataFrame:
    """Joint moments [N·m] (tidy): time [s], joint, moment_Nm: muscle + ligament torque about
    each hip, knee, ankle and the socket (positive in the coordinate's positive sense, e.g. a
    hip flexion moment)."""
    torque = _joint_torque(result)
    frames = [
        pd.DataFrame({"time": result.time, "joint": name, "moment_Nm": torque[:, j]})
        for j, name in enumerate(result.model.dof_names)
        if name.startswith(_ACTUATED)
    ]
    return pd.concat(frames, ignore_index=True)


def joint_powers(result: RunnerResult) -> pd.DataFrame:
    """Joint powers [W] (tidy): time, joint, power. Joints: hip/knee/ankle per side (muscle +
    ligament torque × angular velocity), ``socket_r`` and ``blade_r`` (amputee)."""
    model = result.model
    torque = _joint_torque(result)
    frames = []
    for j, name in enumerate(model.dof_names):
        if name.startswith(_ACTUATED):
            frames.append(
                pd.DataFrame(
                    {"time": result.time, "joint": name, "power": torque[:, j] * result.qvel[:, j]}
                )
            )
    blade = model.contact_params[:, CP_BLADE] == 1
    if blade.any():
        c = result.contacts[:, blade, :]
        p = (c[:, :, RC_FX] * c[:, :, RC_VX] + c[:, :, RC_FZ] * c[:, :, RC_VZ]).sum(axis=1)
        frames.append(pd.DataFrame({"time": result.time, "joint": "blade_r", "power": p}))
    return pd.concat(frames, ignore_index=True)


def power_balance(result: RunnerResult) -> pd.DataFrame:
    """Power balance (seed 001 eq. 2.10–2.18), wide: time [s], muscle, ligament, contact,
    gravity, external (their sum), kinetic (dE_kin/dt from the simulated motion), residual [W].

    Muscle power is Σ F_t·(−v_mtu), ligament power Σ τ·q̇, contact power Σ F·v of the body point
    at each contact, gravity power −M·g·v_com,z; the kinetic power is the time derivative of the
    kinetic energy computed by MuJoCo from the recorded states, independently of the forces.
    """
    fwd = forward_pass(result)
    p_m = -(result.muscles[:, :, 3] * result.mtu[:, :, 1]).sum(axis=1)
    p_l = (result.ligament * result.qvel).sum(axis=1)
    c = result.contacts
    p_c = (c[:, :, RC_FX] * c[:, :, RC_VX] + c[:, :, RC_FZ] * c[:, :, RC_VZ]).sum(axis=1)
    p_g = -result.model.total_mass * result.model.gravity * fwd["comv"][:, 2]
    p_ext = p_m + p_l + p_c + p_g
    p_k = np.gradient(fwd["ek"], result.time) if len(result.time) > 2 else np.zeros_like(p_ext)
    return pd.DataFrame(
        {
            "time": result.time,
            "muscle": p_m,
            "ligament": p_l,
            "contact": p_c,
            "gravity": p_g,
            "external": p_ext,
            "kinetic": p_k,
            "residual": p_ext - p_k,
        }
    )


def power_balance_residual_pct(result: RunnerResult, *, skip_times: Sequence[float] = ()) -> float:
    """RMS of the power-balance residual in % of the peak |P_kinetic|, over the samples with a
    neighbour on each side, less those within two samples of each of ``skip_times`` [s] (e.g.
    a push that changes the kinetic energy without external work).

    The kinetic power at a sample is a central difference, ``(E_{k+1} − E_{k−1})/2h``: the
    mean power over the two sample intervals around it. The external power is averaged over
    the same window (Simpson's rule, ``(P_{k−1} + 4·P_k + P_{k+1})/6``) before the two are
    compared, so the residual measures the simulation, not the sampling: comparing the central
    difference with the power at the sample itself has an error of ``h²·P''/6``, which under
    running loads sampled every 1 ms is ~0.46 % of the peak for any time step (measured on the
    seed 001's amputee reflex gait, 2026-11-27; explicit 0.0625 ms: 0.46 % against 0.13 %
    sampled every step). Until then this was that comparison."""
    pb = power_balance(result)
    if len(pb) < 3:
        return 0.0
    ext = pb.external.to_numpy()
    kinetic = pb.kinetic.to_numpy()[1:-1]
    residual = (ext[:-2] + 4.0 * ext[1:-1] + ext[2:]) / 6.0 - kinetic
    keep = np.ones(len(residual), dtype=bool)
    if len(skip_times):
        spacing = float(result.time[1] - result.time[0])
        centre = pb.time.to_numpy()[1:-1]
        for t in skip_times:
            keep &= np.abs(centre - t) > 2.5 * spacing
    if not keep.any():
        return 0.0
    peak = float(np.max(np.abs(kinetic[keep])))
    if peak == 0.0:
        return 0.0
    return float(np.sqrt(np.mean(residual[keep] ** 2)) / peak * 100.0)


def stances(
    result: RunnerResult,
    *,
    threshold_n: float = CONTACT_THRESHOLD_N,
    min_gap_s: float = MIN_GAP_S,
    min_contact_s: float = MIN_CONTACT_S,
) -> pd.DataFrame:
    """The complete stances of both legs: the contacts of :func:`gait_events` (a step of
    :func:`step_touchdowns` starts in each; strikes of the swinging foot excluded) with both the
    touch-down and the lift-off inside the record.

    Returns a DataFrame with columns leg, first, stop (sample indices: the stance is
    ``first:stop``, ``stop`` the first unloaded sample), touchdown_s, liftoff_s, contact_time_s.
    Every per-stance analysis of :mod:`bladelab.runner.stance_mechanics` uses these stances.
    """
    rows = [
        {
            "leg": c["leg"],
            "first": c["first"],
            "stop": c["stop"],
            "touchdown_s": c["start"],
            "liftoff_s": c["end"],
            "contact_time_s": c["end"] - c["start"],
        }
        for c in _contacts(result, threshold_n, min_gap_s, min_contact_s)
        if c["stance"] and not c["open"] and c["first"] > 0
    ]
    cols = ["leg", "first", "stop", "touchdown_s", "liftoff_s", "contact_time_s"]
    return pd.DataFrame(rows, columns=cols).sort_values("touchdown_s", ignore_index=True)


def _blade_name(model) -> str | None:
    if model.kind not in PROSTHETIC_KINDS:
        return None
    return model.blade_model.name if model.blade_model is not None else model.params.blade


def summary(result: RunnerResult) -> dict:
    """The JSON summary: fell, duration_s, mean_speed_mps, contact times per leg,
    power_balance_residual_pct, and the spatiotemporal means."""
    fwd = forward_pass(result)
    names = leg_names(result.model)
    st = spatiotemporal(result)
    dur = result.duration
    speed = float((fwd["com"][-1, 0] - fwd["com"][0, 0]) / dur) if dur > 0 else 0.0

    def _val(leg: str, var: str) -> float | None:
        v = st.value[(st.leg == leg) & (st.variable == var)]
        return None if v.empty or not np.isfinite(v.iloc[0]) else float(v.iloc[0])

    out = {
        "model": result.model.kind,
        "blade": _blade_name(result.model),
        "fell": bool(result.fell),
        "duration_s": dur,
        "mean_speed_mps": speed,
        f"contact_time_{names[0]}_s": _val(names[0], "contact_time"),
        f"contact_time_{names[1]}_s": _val(names[1], "contact_time"),
        "power_balance_residual_pct": power_balance_residual_pct(result),
        "peak_grf_bw": {
            leg: float(np.max(leg_vertical_force(result, i)) / result.model.body_weight)
            for i, leg in enumerate(names)
        },
        "spatiotemporal_s": {
            f"{r.leg}.{r.variable}": (None if not np.isfinite(r.value) else float(r.value))
            for r in st.itertuples()
        },
    }
    if result.model.kind == "able":
        out["contact_time_intact_s"] = out[f"contact_time_{names[0]}_s"]
        out["contact_time_prosthetic_s"] = None
    return out
