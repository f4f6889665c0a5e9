"""Smooth (C∞) replacements of the forward model's switches, and their settings.

The forward model (:mod:`bladelab.runner.kernel`, :mod:`bladelab.runner.muscle`,
:func:`bladelab.contact.hunt_crossley_force`) uses ``max``, ``if`` and ``|x|``: fine for time
stepping, but IPOPT needs twice-differentiable functions. Every switch is replaced by one of
three primitives, each with a width parameter in :class:`Smoothing` (SI units, or normalised
as stated); the error each causes is stated in ``docs/collocation.md`` and measured by
``tests/test_collocation_model.py``.

- :func:`smooth_max0` ``½(x + √(x² + ε²))``: ≥ max(x, 0), off by ε/2 at x = 0 and by less
  than ε²/(4|x|) elsewhere (hyperbolic; used where a small positive floor is harmless);
- :func:`softplus` ``w·ln(1 + e^{x/w})``: off by w·ln 2 at 0 and by less than w·e^{−|x|/w}
  elsewhere (exponentially exact away from the switch; invertible, :func:`softplus_inverse`);
- :func:`sigmoid` ``½(1 + tanh(x/(2w)))``: the derivative of :func:`softplus`, a step.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import casadi as ca

from bladelab.errors import SpecError


@dataclass(frozen=True)
class Smoothing:
    """Widths of the smooth approximations (defaults: the values the stated bounds assume).

    Attributes
    ----------
    contact_depth_m
        ε of the smooth positive part of a Hunt–Crossley sphere's penetration [m].
    contact_damping
        ε of the smooth positive part of the damping factor ``1 + 1.5·c·δ̇`` [-].
    spring_damper_depth_m
        ε of the depth and width of the onset gate of smooth spring–damper contacts (stiff,
        linear: multi-link blade soles) [m].
    contact_force_n
        ε of the smooth positive part of a spring–damper contact force [N].
    friction_velocity_mps
        v_t of the friction ``−μ·Fn·tanh(v/v_t)`` [m/s].
    ligament_angle_rad
        w of the softplus of a ligament's excursion beyond its limit [rad]; a stiff limit gets
        a narrower one (:meth:`ligament_width`).
    ligament_offset_nm
        Largest torque the softplus adds at a limit, ``k·w·ln 2`` [N·m]: a limit stiffer than
        ``ligament_offset_nm / (ligament_angle_rad·ln 2)`` (3.6 kN·m/rad) gets ``w = offset /
        (k·ln 2)`` (the prosthetic knee's 20 kN·m/rad stop: 0.36 mrad; measured, the
        0.002 rad width left 24 N·m of dynamics residual at the stop).
    ligament_torque_nm
        ε of the smooth positive part of a ligament torque [N·m].
    socket_angle_rad
        ε of ``|q| ≈ √(q² + ε²)`` in the quadratic socket (and blade-joint) spring [rad].
    tendon_strain
        w of the softplus of the tendon strain in the tendon force–strain curve [-].
    passive_length
        w of the softplus of ``l̃ − 1`` in the passive fibre force [-] (l̃ in optimal lengths).
    force_velocity
        w of the blend of the shortening and lengthening force–velocity branches [-] (fibre
        velocity in v_max).
    activation
        w of the switch between activation and deactivation rates [-] (``u − a``).
    damping_switch_rad_s
        w of the switch between a joint's flexion and extension damping (a hydraulic
        prosthetic knee) [rad/s]: off by at most 0.28·w·|D_flex − D_ext| [N·m].
    """

    contact_depth_m: float = 2.5e-4  # 1 mm gave a 3.4 % dynamics residual, 0.25 mm 0.55 %
    contact_damping: float = 0.05
    spring_damper_depth_m: float = 1.0e-4
    contact_force_n: float = 1.0
    friction_velocity_mps: float = 0.03
    ligament_angle_rad: float = 0.002  # 0.01 gave the amputee a 2.6 % dynamics residual, 0.002 0.47 %
    ligament_torque_nm: float = 0.5
    ligament_offset_nm: float = 5.0
    socket_angle_rad: float = 1.0e-3
    tendon_strain: float = 1.0e-3
    passive_length: float = 0.01
    force_velocity: float = 0.005
    activation: float = 0.005
    damping_switch_rad_s: float = 0.01

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not value > 0.0:
                raise SpecError(f"must be positive, got {value}", where=f"Smoothing.{name}")

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    def ligament_width(self, stiffness: float) -> float:
        """The softplus width [rad] of a ligament limit of ``stiffness`` [N·m/rad]."""
        if stiffness <= 0.0:
            return self.ligament_angle_rad
        return min(self.ligament_angle_rad,
                   self.ligament_offset_nm / (stiffness * math.log(2.0)))


def smooth_max0(x, eps: float):
    """Smooth ``max(x, 0)``: ``½(x + √(x² + ε²))`` (same units as ``x`` and ``ε``)."""
    return 0.5 * (x + ca.sqrt(x * x + eps * eps))


def softplus(x, width: float):
    """Smooth ``max(x, 0)``: ``w·ln(1 + e^{x/w})``, evaluated without overflow."""
    return ca.fmax(x, 0.0) + width * ca.log1p(ca.exp(-ca.fabs(x) / width))


def softplus_inverse(s, width: float):
    """The ``x`` with ``softplus(x, w) = s`` for ``s > 0``: ``s + w·ln(1 − e^{−s/w})``."""
    return s + width * ca.log(-ca.expm1(-s / width))


def sigmoid(x, width: float):
    """Smooth step ``½(1 + tanh(x/(2w)))``, the derivative of :func:`softplus` in ``x``."""
    return 0.5 * (1.0 + ca.tanh(x / (2.0 * width)))
