"""How far the smooth collocation laws may be from the forward model's (numeric, no CasADi).

Closed-form bounds of the differences caused by :class:`~.smooth.Smoothing`, per evaluation;
``tests/test_collocation_model.py`` checks the collocation model against the forward model with
them and ``docs/collocation.md`` tabulates them at the default widths. Notation:
``m0(x; ε) = ½(x + √(x² + ε²))`` (:func:`~.smooth.smooth_max0`), which exceeds ``max(x, 0)`` by
``ε²/(2(√(x² + ε²) + |x|)) ≤ min(ε/2, ε²/(4|x|))``.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from bladelab.contact import smoothstep
from bladelab.predict.collocation.smooth import Smoothing


def smooth_max0_excess(x: float, eps: float) -> float:
    """``m0(x; ε) − max(x, 0)`` ≥ 0 (same units as x)."""
    return eps * eps / (2.0 * (math.sqrt(x * x + eps * eps) + abs(x)))


@lru_cache(maxsize=16)
def depth_power_excess(exponent: float) -> float:
    """``sup_δ |m0(δ; 1)ⁿ − max(δ, 0)ⁿ|`` [-] for 1 ≤ n ≤ 2: the largest excess of the smoothed
    penetration power, per ``εⁿ`` (0.3875 for Hertz n = 1.5, 0.5 for n = 1)."""
    t = np.linspace(0.0, 200.0, 400_001)
    excess = (0.5 * (t + np.sqrt(t * t + 1.0))) ** exponent - t**exponent
    return float(excess.max())


def hunt_crossley_bound(
    depth: float, depth_rate: float, stiffness: float, exponent: float, dissipation: float,
    smoothing: Smoothing,
) -> float:
    """Largest |smooth − forward| Hunt–Crossley normal force [N] at this state.

    The smooth force ``k·m0(δ; ε_d)ⁿ·m0(x; ε_x)`` with ``x = 1 + 1.5·c·δ̇`` differs from the
    forward ``k·max(δ, 0)ⁿ·max(x, 0)`` by at most
    ``k·E_n·ε_dⁿ·m0(x; ε_x) + k·max(δ, 0)ⁿ·(m0(x; ε_x) − max(x, 0))``.

    Parameters
    ----------
    depth, depth_rate
        Penetration δ [m] and its rate δ̇ [m/s] (positive while penetrating further).
    stiffness, exponent, dissipation
        k [N/mⁿ], n [-], c [s/m] (``RunnerModel.contact_params`` columns).
    """
    eps_d, eps_x = smoothing.contact_depth_m, smoothing.contact_damping
    x = 1.0 + 1.5 * dissipation * depth_rate
    xs = max(x, 0.0) + smooth_max0_excess(x, eps_x)
    return stiffness * (
        depth_power_excess(exponent) * eps_d**exponent * xs
        + max(depth, 0.0) ** exponent * smooth_max0_excess(x, eps_x)
    )


def spring_damper_bound(
    depth: float, depth_rate: float, stiffness: float, damping: float, width: float,
    smoothing: Smoothing,
) -> float:
    """Largest |smooth − forward| spring–damper normal force [N] at ``depth`` [m]: at any depth
    for a forward onset of width w > 0, from ε' on for a sharp one (w = 0).

    Smooth ``smoothstep(δ/w)·m0(k·δ + c·δ̇; ε_F)`` against ``smoothstep(δ/w)·max(k·δ + c·δ̇,
    0)``: the same onset, so the outer smooth max alone differs, ``smoothstep·(m0 − max)``.

    Parameters
    ----------
    depth, depth_rate
        Penetration δ [m] and its rate [m/s].
    stiffness, damping, width
        k [N/m], c [N·s/m], transition width w [m] (``RunnerModel.contact_params``).
    """
    eps = smoothing.spring_damper_depth_m
    if width <= 0 and depth < eps:
        raise ValueError(f"a sharp onset's bound holds from {eps} m on, got depth {depth} m")
    w = width if width > 0 else eps
    x = stiffness * depth + damping * depth_rate
    return smoothstep(depth / w) * smooth_max0_excess(x, smoothing.contact_force_n)


def sliding_friction_bound(slip_velocity: float, normal_force: float, friction: float,
                           smoothing: Smoothing) -> float:
    """|smooth − forward| friction [N] while the forward bristle slides, from the tanh alone:
    ``μ·Fn·(1 − tanh(|v|/v_t))`` (add μ times the normal-force bound for the total)."""
    return friction * normal_force * (1.0 - math.tanh(abs(slip_velocity)
                                                      / smoothing.friction_velocity_mps))


def ligament_bound(margin: float, velocity: float, stiffness: float, damping: float,
                   smoothing: Smoothing) -> float:
    """|smooth − forward| ligament torque [N·m] at least ``margin`` [rad] from every limit.

    Each limit's softplus excursion and sigmoid damping gate differ from the forward switch by
    at most ``(K·w + D·|q̇|)·e^{−margin/w}``; the smooth max adds at most ε_τ/2 per limit.
    """
    w, eps = smoothing.ligament_width(stiffness), smoothing.ligament_torque_nm
    return eps + 2.0 * (stiffness * w + damping * abs(velocity)) * math.exp(-margin / w)


def socket_bound(stiffness_quadratic: float, smoothing: Smoothing) -> float:
    """|smooth − forward| socket torque [N·m]: ``K2·|q|·(√(q² + ε²) − |q|) ≤ K2·ε²/2``."""
    return 0.5 * stiffness_quadratic * smoothing.socket_angle_rad**2


def damping_switch_bound(damping_negative: float, damping_positive: float,
                         smoothing: Smoothing) -> float:
    """|smooth − forward| torque [N·m] of a joint damped differently in its two senses (a
    hydraulic knee): the sigmoid gate between the two dampings costs at most
    ``|ΔD|·|q̇|·σ(−|q̇|/w)``, whose maximum over q̇ is ``0.2785·w·|ΔD|``."""
    return 0.2785 * smoothing.damping_switch_rad_s * abs(damping_negative - damping_positive)
