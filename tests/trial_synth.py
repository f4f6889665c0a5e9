"""Synthetic trials with known answers, for the trial tests (written with write_c3d).

The ground truth is analytic: a half-sine vertical force with a known contact, a braking →
propulsion horizontal force, a COP moving along the plate, and clamp/tip markers built from a
known clamp origin path, pitch and tip offset.
"""

from __future__ import annotations

import numpy as np

from bladelab.trial.c3d import plate_corners, write_c3d

MARKER_RATE = 200.0
ANALOG_RATE = 1000.0
DURATION = 1.0
TD, TO = 0.30, 0.42  # touch-down, toe-off [s]
PEAK = 2000.0  # N
HALF_CLAMP = 0.05  # m: clamp markers ±5 cm along the clamp x axis
TIP_OFFSET = np.array([0.15, 0.0, -0.40])  # tip in the clamp frame, unloaded [m]


def grf(t: np.ndarray) -> np.ndarray:
    """(n, 3) GRF [N]: half-sine Fz on [TD, TO], Fx = −0.15·Fz·cos(π τ) (braking then propulsion)."""
    tau = np.clip((t - TD) / (TO - TD), 0.0, 1.0)
    on = (t >= TD) & (t <= TO)
    fz = np.where(on, PEAK * np.sin(np.pi * tau), 0.0)
    fx = np.where(on, -0.15 * fz * np.cos(np.pi * tau), 0.0)
    fy = np.where(on, 0.02 * fz, 0.0)
    return np.column_stack([fx, fy, fz])


def clamp_origin(t: np.ndarray) -> np.ndarray:
    """(n, 3) clamp origin [m]: forward at 4 m/s, slight vertical dip during contact."""
    return np.column_stack(
        [-1.0 + 4.0 * t, np.full_like(t, 0.12), 0.50 - 0.03 * np.sin(2 * np.pi * 1.5 * t)]
    )


def clamp_pitch(t: np.ndarray) -> np.ndarray:
    """Clamp pitch [rad]: −30° → +40° sweep (smooth)."""
    return np.deg2rad(5.0 + 35.0 * np.sin(2 * np.pi * 1.2 * (t - 0.36)))


def compression_scale(t: np.ndarray) -> np.ndarray:
    """Tip offset scale (1 − 15 % at mid-stance): d(t) = scale · |TIP_OFFSET|."""
    return 1.0 - 0.15 * np.exp(-(((t - 0.36) / 0.05) ** 2))


def _rot_y(theta: np.ndarray, v: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    # R_y(θ) v = (c vx + s vz, vy, −s vx + c vz)
    return np.column_stack([c * v[..., 0] + s * v[..., 2], v[..., 1] * np.ones_like(c), -s * v[..., 0] + c * v[..., 2]])


def markers(t: np.ndarray) -> dict[str, np.ndarray]:
    """CLAMP_ANT, CLAMP_POST, BLADE_TIP and a static REF marker [m]."""
    o = clamp_origin(t)
    th = clamp_pitch(t)
    ax = _rot_y(th, np.array([HALF_CLAMP, 0.0, 0.0]))
    tip = o + _rot_y(th, TIP_OFFSET) * compression_scale(t)[:, None]
    return {
        "CLAMP_ANT": o + ax,
        "CLAMP_POST": o - ax,
        "BLADE_TIP": tip,
        "REF": np.tile([0.0, 0.0, 0.01], (len(t), 1)),
    }


def cop(t: np.ndarray, x0: float = 0.45, x1: float = 0.60) -> np.ndarray:
    tau = np.clip((t - TD) / (TO - TD), 0.0, 1.0)
    return np.column_stack([x0 + (x1 - x0) * tau, np.full_like(t, 0.1), np.zeros_like(t)])


def write_single_plate(path, *, point_units: str = "mm", metadata=None, origin=(0.0, 0.0, 0.04)):
    """One plate centred at x = 0.5 m; returns (marker time, analog time)."""
    tm = np.arange(int(DURATION * MARKER_RATE)) / MARKER_RATE
    ta = np.arange(int(DURATION * ANALOG_RATE)) / ANALOG_RATE
    write_c3d(
        path,
        markers=markers(tm),
        marker_rate=MARKER_RATE,
        analog_rate=ANALOG_RATE,
        platforms=[
            {
                "force": grf(ta),
                "cop": cop(ta),
                "free_moment": np.where(grf(ta)[:, 2] > 0, 3.0, 0.0),
                "corners": plate_corners((0.5, 0.0, 0.0), 0.9, 0.6),
                "origin": np.asarray(origin),
            }
        ],
        metadata=metadata or {"athlete": "TT1", "side": "right", "blade": "xtreme", "category": 5,
                              "speed_pct_pb": 95.0},
        point_units=point_units,
    )
    return tm, ta


def write_two_plates_one_foot(path):
    """The foot crosses from plate 1 (x < 0.6) to plate 2; load shifts linearly."""
    tm = np.arange(int(DURATION * MARKER_RATE)) / MARKER_RATE
    ta = np.arange(int(DURATION * ANALOG_RATE)) / ANALOG_RATE
    f = grf(ta)
    w = np.clip(1.0 - (ta - TD) / (TO - TD), 0.0, 1.0)[:, None]
    c1 = np.column_stack([np.full_like(ta, 0.55), np.full_like(ta, 0.1), np.zeros_like(ta)])
    c2 = np.column_stack([np.full_like(ta, 0.65), np.full_like(ta, 0.1), np.zeros_like(ta)])
    write_c3d(
        path,
        markers=markers(tm),
        marker_rate=MARKER_RATE,
        analog_rate=ANALOG_RATE,
        platforms=[
            {"force": f * w, "cop": c1, "corners": plate_corners((0.3, 0.0, 0.0), 0.6, 0.6)},
            {"force": f * (1 - w), "cop": c2, "corners": plate_corners((0.9, 0.0, 0.0), 0.6, 0.6)},
        ],
    )
    return f, ta
