"""Contact laws: normal force and friction between a body and the ground.

All functions are compiled with numba (``njit``) so that simulation kernels can call them in
their inner loop; they are plain functions of scalars and can also be called from Python.

Sign conventions: ``depth`` [m] is the penetration of the body into the ground (positive in
contact), ``depth_rate`` [m/s] its time derivative (positive while penetrating further).
``slip_velocity`` [m/s] is the tangential velocity of the contact point relative to the ground;
the friction force opposes it. Normal forces are never negative (no adhesion).

Laws
----
- :func:`smooth_spring_damper_force` — Simscape Multibody "Smooth spring-damper" normal law, used
  by seed 000: ``F = s(depth, w) · (k·depth + c·depth_rate)``, with ``s`` a cubic step from 0 to 1
  over the transition width ``w``.
- :func:`hunt_crossley_force` — Hunt & Crossley (1975): ``F = k·depth**n · (1 + 3/2·c·depth_rate)``;
  with ``n = 3/2`` and ``k = 4/3·E·sqrt(R)`` it is the Hertz sphere of seed 001 eq. 2.2–2.3.
- :func:`stick_slip_friction_coefficient` — Simscape "Smooth stick-slip" friction: ``μ`` rises
  linearly with slip velocity to ``μ_s`` at the critical velocity, then blends to ``μ_k``.
"""

from __future__ import annotations

import math

from numba import njit

from bladelab.numba_cache import refresh_stale_caches


@njit(cache=True, fastmath=False)
def smoothstep(x: float) -> float:
    """Cubic step: 0 for x <= 0, 1 for x >= 1, 3x² − 2x³ between (C¹-continuous)."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    return x * x * (3.0 - 2.0 * x)


@njit(cache=True)
def smooth_spring_damper_force(
    depth: float,
    depth_rate: float,
    stiffness: float,
    damping: float,
    transition_width: float,
) -> float:
    """Normal force [N] of the smooth spring-damper law.

    Parameters
    ----------
    depth
        Penetration [m]; no force when <= 0.
    depth_rate
        Penetration rate [m/s].
    stiffness
        Contact stiffness k [N/m].
    damping
        Contact damping c [N·s/m].
    transition_width
        Width w [m] over which the law is blended in (0 for a sharp onset).
    """
    if depth <= 0.0:
        return 0.0
    scale = 1.0 if transition_width <= 0.0 else smoothstep(depth / transition_width)
    force = scale * (stiffness * depth + damping * depth_rate)
    return force if force > 0.0 else 0.0


@njit(cache=True)
def hunt_crossley_force(
    depth: float,
    depth_rate: float,
    stiffness: float,
    exponent: float,
    dissipation: float,
) -> float:
    """Normal force [N] of the Hunt–Crossley law ``k·δⁿ·(1 + 1.5·c·δ̇)``.

    Parameters
    ----------
    depth
        Penetration δ [m]; no force when <= 0.
    depth_rate
        Penetration rate δ̇ [m/s].
    stiffness
        k [N/mⁿ]; for a Hertz sphere use :func:`hertz_sphere_stiffness`.
    exponent
        n [-]; 1.5 for Hertz, 1.0 for a linear spring.
    dissipation
        c [s/m] (seed 001: 1 s/m for the foot, 0.2 s/m for the blade).
    """
    if depth <= 0.0:
        return 0.0
    force = stiffness * depth**exponent * (1.0 + 1.5 * dissipation * depth_rate)
    return force if force > 0.0 else 0.0


@njit(cache=True)
def hertz_sphere_stiffness(radius: float, plane_strain_modulus: float) -> float:
    """Hertz stiffness k = 4/3·E·√R [N/m^1.5] of a sphere of radius R [m] on a rigid plane.

    ``plane_strain_modulus`` E [N/m²] (seed 001 eq. 2.3).
    """
    return 4.0 / 3.0 * plane_strain_modulus * math.sqrt(radius)


@njit(cache=True)
def stick_slip_friction_coefficient(
    slip_velocity: float,
    static_coefficient: float,
    kinetic_coefficient: float,
    critical_velocity: float,
) -> float:
    """Signed friction coefficient of the smooth stick-slip law (multiply by the normal force).

    ``|v| <= v_c``: μ = μ_s·v/v_c (stick, acts as a viscous damper); ``v_c < |v| < 1.5·v_c``:
    a cubic blend from μ_s to μ_k; beyond: μ_k. Returns a value with the sign of
    ``slip_velocity``; the friction force is ``-μ·F_n`` (it opposes slip).

    Parameters
    ----------
    slip_velocity
        Tangential velocity of the contact point relative to the ground [m/s].
    static_coefficient, kinetic_coefficient
        μ_s and μ_k [-].
    critical_velocity
        v_c [m/s] (> 0).
    """
    speed = abs(slip_velocity)
    if speed <= critical_velocity:
        mu = static_coefficient * speed / critical_velocity
    elif speed >= 1.5 * critical_velocity:
        mu = kinetic_coefficient
    else:
        blend = smoothstep((speed - critical_velocity) / (0.5 * critical_velocity))
        mu = static_coefficient + (kinetic_coefficient - static_coefficient) * blend
    return mu if slip_velocity >= 0.0 else -mu


@njit(cache=True)
def stribeck_friction_coefficient(
    slip_velocity: float,
    static_coefficient: float,
    dynamic_coefficient: float,
    transition_velocity: float,
) -> float:
    """Signed friction coefficient of the Hunt–Crossley/Simbody friction law.

    μ = min(|v|/v_t, 1)·(μ_d + 2(μ_s − μ_d)/(1 + (|v|/v_t)²)), signed like ``slip_velocity``.
    Used with :func:`hunt_crossley_force` in the runner (seed 001: μ_s = μ_d = 0.9).
    """
    ratio = abs(slip_velocity) / transition_velocity
    mu = min(ratio, 1.0) * (
        dynamic_coefficient + 2.0 * (static_coefficient - dynamic_coefficient) / (1.0 + ratio * ratio)
    )
    return mu if slip_velocity >= 0.0 else -mu


refresh_stale_caches(globals())
