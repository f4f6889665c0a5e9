"""A monocentric hydraulic prosthetic knee, 3S80 class (seed 002): passive, no stance lock.

The knee angle q [rad] is flexion-positive (the shank turns back relative to the thigh). Torque
on the shank about the knee [N·m]:

τ = −c_f·q̇ (q̇ > 0, flexing) or −c_e·q̇ (q̇ < 0, extending)   hydraulic damping
    − k_a·(q − q_a0)                                             extension assist spring
    − k_s·(q − q_s) − d_s·q̇   only while q < q_s                 hyperextension stop

Default values are illustrative for a sprint setting (the 3S80's resistances are adjustable and
not published as numbers): c_f 1.5, c_e 0.8 N·m·s/rad, k_a 8 N·m/rad about q_a0 = 0, the stop at
0° with k_s 2e4 N·m/rad and d_s 100 N·m·s/rad (a stiff bumper).

The transfemoral runner (:func:`bladelab.runner.build_runner` ``"transfemoral"``) uses the same
knee in its own sign convention (``knee_angle_r``: 0 straight, negative flexes):
:meth:`ProstheticKnee.joint_row` gives its row of ``RunnerModel.joint_params``; there the stop is
the joint's upper ligament limit (with a flexion stop at :attr:`ProstheticKnee.flexion_limit`)
and the runner's ligament law applies (the stop pushes, never pulls).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from bladelab.errors import SpecError
from bladelab.numba_cache import refresh_stale_caches

__all__ = ["ProstheticKnee", "knee_torque"]


@dataclass(frozen=True)
class ProstheticKnee:
    """Parameters of the passive knee (SI: N·m/rad, N·m·s/rad, rad, kg).

    Attributes
    ----------
    flexion_damping, extension_damping
        Hydraulic damping c_f while flexing and c_e while extending [N·m·s/rad].
    assist_stiffness, assist_rest_angle
        Extension-assist spring k_a [N·m/rad] and its rest angle q_a0 [rad].
    stop_angle, stop_stiffness, stop_damping
        Hyperextension stop q_s [rad], k_s [N·m/rad], d_s [N·m·s/rad].
    mass
        Knee mechanism mass [kg] (on the shank below the axis) of the design evaluator's
        runner; the transfemoral runner of :mod:`bladelab.runner` counts it in its
        ``prosthesis_r`` segment instead.
    flexion_limit
        Mechanical flexion stop [rad] (flexion-positive), with the stop's stiffness and
        damping (the transfemoral runner only; 140°, about the 3S80's range).
    """

    flexion_damping: float = 1.5
    extension_damping: float = 0.8
    assist_stiffness: float = 8.0
    assist_rest_angle: float = 0.0
    stop_angle: float = 0.0
    stop_stiffness: float = 2.0e4
    stop_damping: float = 100.0
    mass: float = 1.2
    flexion_limit: float = math.radians(140.0)

    def __post_init__(self) -> None:
        for name, v in asdict(self).items():
            if not math.isfinite(v):
                raise SpecError(f"{name} must be finite", where=f"prosthetic knee: {name}")
            if name not in ("assist_rest_angle", "stop_angle") and v < 0:
                raise SpecError(f"{name} must be >= 0, got {v}", where=f"prosthetic knee: {name}")

    def as_array(self):
        """(c_f, c_e, k_a, q_a0, q_s, k_s, d_s) for :func:`knee_torque`."""
        return np.array([self.flexion_damping, self.extension_damping, self.assist_stiffness,
                         self.assist_rest_angle, self.stop_angle, self.stop_stiffness,
                         self.stop_damping], float)

    def torque(self, q: float, qd: float) -> float:
        """Knee torque [N·m] at flexion angle ``q`` [rad] and rate ``qd`` [rad/s]."""
        return float(knee_torque(self.as_array(), q, qd))

    def to_dict(self) -> dict:
        return asdict(self)

    def joint_row(self):
        """This knee as a row of ``RunnerModel.joint_params`` (columns ``JP_*`` of
        :mod:`bladelab.runner.layout`) for a knee coordinate that is negative in flexion:
        ligament limits (−flexion_limit, −stop_angle) with the stop's stiffness and damping,
        the assist spring as the joint spring (about 0, so ``assist_rest_angle`` must be 0),
        flexion damping while q̇ < 0 and extension damping while q̇ > 0."""
        if self.assist_rest_angle != 0.0:
            raise SpecError("the runner's knee spring acts about 0: assist_rest_angle must be 0",
                            where="prosthetic knee: assist_rest_angle")
        return np.array([-self.flexion_limit, -self.stop_angle, self.stop_stiffness,
                         self.stop_damping, self.assist_stiffness, 0.0, self.flexion_damping,
                         self.extension_damping, 0.0, 0.0])


@njit(cache=True)
def knee_torque(p, q, qd):
    """Torque of the knee with parameters ``p`` (see :meth:`ProstheticKnee.as_array`)."""
    c = p[0] if qd > 0.0 else p[1]
    tau = -c * qd - p[2] * (q - p[3])
    if q < p[4]:
        tau += -p[5] * (q - p[4]) - p[6] * qd
    return tau


refresh_stale_caches(globals())
