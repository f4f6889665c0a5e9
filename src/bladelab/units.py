"""Unit conversions: the only place in bladelab where they live.

Inside the package everything is SI (m, s, N, rad, N·m/rad, N·m·s/rad). The literature reports
torsional stiffness K* in N·m/deg and damping D* in N·m·s/deg; convert at the edges only.
"""

from __future__ import annotations

import math

import numpy as np

from bladelab.constants import STANDARD_GRAVITY

DEG_PER_RAD = 180.0 / math.pi
RAD_PER_DEG = math.pi / 180.0


def _scale(value, factor: float):
    """Multiply a scalar (returns float) or array-like (returns ndarray) by ``factor``."""
    if isinstance(value, (int, float, np.floating, np.integer)):
        return float(value) * factor
    return np.asarray(value, dtype=float) * factor


def deg2rad(angle_deg):
    """Angle [deg] -> [rad]; works on scalars and arrays."""
    return _scale(angle_deg, RAD_PER_DEG)


def rad2deg(angle_rad):
    """Angle [rad] -> [deg]; works on scalars and arrays."""
    return _scale(angle_rad, DEG_PER_RAD)


def stiffness_per_deg_to_per_rad(k_nm_per_deg):
    """Torsional stiffness [N·m/deg] -> [N·m/rad] (multiply by 180/π)."""
    return _scale(k_nm_per_deg, DEG_PER_RAD)


def stiffness_per_rad_to_per_deg(k_nm_per_rad):
    """Torsional stiffness [N·m/rad] -> [N·m/deg] (multiply by π/180)."""
    return _scale(k_nm_per_rad, RAD_PER_DEG)


# Damping converts like stiffness: N·m·s/deg <-> N·m·s/rad.
damping_per_deg_to_per_rad = stiffness_per_deg_to_per_rad
damping_per_rad_to_per_deg = stiffness_per_rad_to_per_deg


def mm_to_m(length_mm):
    """Length [mm] -> [m]."""
    return _scale(length_mm, 1e-3)


def body_weight(mass_kg: float) -> float:
    """Body weight [N] of a mass [kg] under standard gravity."""
    return float(mass_kg) * STANDARD_GRAVITY
