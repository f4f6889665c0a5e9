"""Per-stance mechanics of a runner simulation (seed 001 §2.4, Tables 3.3 and D.1).

For each complete stance of :func:`bladelab.runner.analyses.stances` (strikes of the swinging
foot excluded): :func:`leg_stiffness` (K_leg, eq. 2.19–2.21), :func:`leg_energy` (the
GRF–vertical COM displacement loop, Table 3.3) and :func:`blade_energy` (what the blade contact
stores and returns, Table D.1). All tables are tidy DataFrames.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pandas as pd

from bladelab.runner.analyses import (
    CONTACT_THRESHOLD_N,
    forward_pass,
    leg_vertical_force,
    stances,
)
from bladelab.runner.layout import CP_BLADE, CP_EXP, CP_K, CP_LEG
from bladelab.runner.model import contact_heights
from bladelab.runner.simulate import RC_DEPTH, RC_FZ, RunnerResult, leg_names

__all__ = ["blade_energy", "leg_energy", "leg_stiffness"]


def _leg_stances(st: pd.DataFrame, leg_name: str) -> list[tuple[int, int]]:
    """The (first, stop) sample ranges of leg ``leg_name``'s stances in a :func:`stances`
    table."""
    st = st[st.leg == leg_name]
    return list(zip(st["first"].tolist(), st["stop"].tolist(), strict=True))


def _leg_length(result: RunnerResult, leg: int) -> float:
    """Standing leg length L0 [m]: hip joint height above the leg's lowest contact in the
    standing pose (a prosthetic leg longer by the athlete's ``prosthesis_extra_length_m``)."""
    model = result.model
    d = mujoco.MjData(model.mj_model)
    q = model.stand_qpos.copy()
    q[:] = 0.0
    d.qpos[:] = q
    mujoco.mj_kinematics(model.mj_model, d)
    side = "l" if leg == 0 else "r"
    hip = d.xanchor[model.mj_model.joint(f"hip_flexion_{side}").id, 2]
    h = contact_heights(model, q)
    cols = model.contact_params[:, CP_LEG] == leg
    return float(hip - h[cols].min())


def leg_stiffness(
    result: RunnerResult, *, threshold_n: float = CONTACT_THRESHOLD_N
) -> pd.DataFrame:
    """Leg stiffness per stance of :func:`stances` (seed 001 eq. 2.19–2.21): columns leg,
    touchdown [s], contact_time [s], F_peak [N], delta_y [m], L0 [m], theta_rad, delta_L [m],
    K_leg [N/m]. Strikes of the swinging foot are not stances and do not count."""
    fwd = forward_pass(result)
    names = leg_names(result.model)
    st = stances(result, threshold_n=threshold_n)
    rows = []
    for leg in (0, 1):
        l0 = _leg_length(result, leg)
        fz = leg_vertical_force(result, leg)
        for i0, i1 in _leg_stances(st, names[leg]):
            tc = result.time[i1] - result.time[i0]
            v = float(np.mean(fwd["comv"][i0:i1, 0]))
            dy = float(fwd["com"][i0, 2] - np.min(fwd["com"][i0:i1, 2]))
            theta = math.asin(min(abs(v) * tc / (2 * l0), 1.0))
            dl = dy + l0 * (1 - math.cos(theta))
            fp = float(np.max(fz[i0:i1]))
            rows.append(
                {
                    "leg": names[leg],
                    "touchdown": float(result.time[i0]),
                    "contact_time": tc,
                    "F_peak": fp,
                    "delta_y": dy,
                    "L0": l0,
                    "theta_rad": theta,
                    "delta_L": dl,
                    "K_leg": fp / dl if dl > 0 else math.nan,
                }
            )
    cols = ["leg", "touchdown", "contact_time", "F_peak", "delta_y", "L0", "theta_rad",
            "delta_L", "K_leg"]
    return pd.DataFrame(rows, columns=cols)


def leg_energy(result: RunnerResult, *, threshold_n: float = CONTACT_THRESHOLD_N) -> pd.DataFrame:
    """Energy per leg and stance of :func:`stances` (strikes of the swinging foot excluded) from
    the GRF–vertical COM displacement loop (Table 3.3 layout): columns leg, touchdown [s],
    E_stored [J] (work absorbed while the COM descends), E_generated [J] (work returned while
    it rises), hysteresis [J] = |stored − generated|, recoil_pct = 100·min/max."""
    fwd = forward_pass(result)
    names = leg_names(result.model)
    st = stances(result, threshold_n=threshold_n)
    rows = []
    for leg in (0, 1):
        fz = leg_vertical_force(result, leg)
        for i0, i1 in _leg_stances(st, names[leg]):
            dz = np.diff(fwd["com"][i0 : i1 + 1, 2])
            f = 0.5 * (fz[i0:i1] + fz[i0 + 1 : i1 + 1])
            stored = float(-np.sum(f * np.minimum(dz, 0.0)))
            generated = float(np.sum(f * np.maximum(dz, 0.0)))
            big = max(stored, generated)
            rows.append(
                {
                    "leg": names[leg],
                    "touchdown": float(result.time[i0]),
                    "E_stored": stored,
                    "E_generated": generated,
                    "hysteresis": abs(stored - generated),
                    "recoil_pct": 100.0 * min(stored, generated) / big if big > 0 else math.nan,
                }
            )
    return pd.DataFrame(
        rows, columns=["leg", "touchdown", "E_stored", "E_generated", "hysteresis", "recoil_pct"]
    )


def blade_energy(
    result: RunnerResult,
    *,
    compression: str = "penetration",
    threshold_n: float = CONTACT_THRESHOLD_N,
) -> pd.DataFrame:
    """Energy the blade contact stores and returns per prosthetic stance (seed 001 Table D.1).

    E_stored = ∫F·dδ while the blade compresses, E_returned = −∫F·dδ while it recovers, summed
    over the blade's contacts (the sphere, or a multi-link blade's soles), with F the contact's
    vertical (normal) force [N] and δ its compression [m], over each stance of
    :func:`stances` extended to the whole time the blade touches the ground.

    Parameters
    ----------
    result
        An amputee simulation (empty table for the able model).
    compression
        ``"penetration"``: δ is the simulated penetration of the contact (the energy the
        Hunt–Crossley law really stores and returns, dissipation included); ``"hertz"``: δ is
        computed back from the force by the elastic Hertz law ``δ = (F/k)^(1/n)`` (seed 001
        eq. 2.3 as its eq. 2.14 uses it). The second cannot show any dissipation: F(δ) is then
        one curve, and a loop along it encloses no area.
    threshold_n
        Vertical force [N] above which a leg is in contact (:func:`stances`).

    Returns
    -------
    DataFrame
        leg, touchdown_s, E_stored_J, E_returned_J, hysteresis_J (stored − returned),
        recoil_pct (100·returned/stored), peak_force_N, peak_compression_m.
    """
    if compression not in ("penetration", "hertz"):
        raise ValueError(f"compression must be 'penetration' or 'hertz', not {compression!r}")
    cols = ["leg", "touchdown_s", "E_stored_J", "E_returned_J", "hysteresis_J", "recoil_pct",
            "peak_force_N", "peak_compression_m"]
    cp = result.model.contact_params
    blade = np.flatnonzero(cp[:, CP_BLADE] == 1)
    if not len(blade):
        return pd.DataFrame(columns=cols)
    force = result.contacts[:, blade, RC_FZ]
    depth = result.contacts[:, blade, RC_DEPTH]
    if compression == "hertz":
        k, n = cp[blade, CP_K], cp[blade, CP_EXP]
        depth = (np.maximum(force, 0.0) / k) ** (1.0 / n)
        touching = (force > 0).any(axis=1)
    else:
        # penetrating; not 'force > 0': a smooth contact law (the collocation model's) pushes
        # with a small force above the ground too, which would join every stance into one
        # (the forward law's force is 0 without penetration: the same stances)
        touching = (depth > 0).any(axis=1)
    rows = []
    name = leg_names(result.model)[1]
    for i0, i1 in _leg_stances(stances(result, threshold_n=threshold_n), name):
        t0 = float(result.time[i0])
        while i0 > 0 and touching[i0 - 1]:
            i0 -= 1
        while i1 < len(touching) - 1 and touching[i1]:
            i1 += 1
        dd = np.diff(depth[i0 : i1 + 1], axis=0)
        f = 0.5 * (force[i0:i1] + force[i0 + 1 : i1 + 1])
        stored = float(np.sum(f * np.maximum(dd, 0.0)))
        returned = float(-np.sum(f * np.minimum(dd, 0.0)))
        rows.append({
            "leg": name,
            "touchdown_s": t0,
            "E_stored_J": stored,
            "E_returned_J": returned,
            "hysteresis_J": stored - returned,
            "recoil_pct": 100.0 * returned / stored if stored > 0 else math.nan,
            "peak_force_N": float(force[i0 : i1 + 1].sum(axis=1).max()),
            "peak_compression_m": float(depth[i0 : i1 + 1].max()),
        })
    return pd.DataFrame(rows, columns=cols)
