"""Prescribed clamp motion: a stance's clamp samples made smooth and differentiable.

Each channel (x, z, pitch) is interpolated by a quintic B-spline through the samples (C⁴), so the
positions, velocities and accelerations the engines see are derivatives of one function.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.interpolate import make_interp_spline

from bladelab.errors import DataError
from bladelab.trial.stance import Stance


@dataclasses.dataclass(frozen=True, eq=False)
class ClampMotion:
    """Clamp pose x, z [m], pitch [rad] as splines of time [s] (planar x–z).

    ``belt_speed`` [m/s] (treadmill) is added to the forward motion: x(t) = x_stance(t) +
    belt_speed·(t − t0), which is the same as a ground moving backwards.
    """

    t0: float
    t1: float
    splines: tuple
    belt_speed: float = 0.0

    @classmethod
    def from_stance(cls, stance: Stance, *, belt_speed: float = 0.0, degree: int = 5) -> ClampMotion:
        """Fit the interpolating splines to a stance's clamp samples."""
        t = np.asarray(stance.time, float)
        if len(t) <= degree:
            raise DataError(f"only {len(t)} samples; the clamp spline needs more than {degree}",
                            where="stance.time")
        if np.any(np.diff(t) <= 0):
            raise DataError("time is not strictly increasing", where="stance.time")
        channels = (stance.clamp_x, stance.clamp_z, stance.clamp_pitch)
        for name, y in zip(("clamp_x", "clamp_z", "clamp_pitch"), channels, strict=True):
            bad = np.flatnonzero(~np.isfinite(y))
            if bad.size:
                raise DataError(
                    f"{bad.size} missing or non-finite value(s), first at t = {t[bad[0]]:.4g} s",
                    where=f"stance.{name}", hint="fill or interpolate gaps before simulating",
                )
        splines = tuple(make_interp_spline(t, np.asarray(y, float), k=degree) for y in channels)
        return cls(t0=float(t[0]), t1=float(t[-1]), splines=splines, belt_speed=float(belt_speed))

    def evaluate(self, t: np.ndarray) -> np.ndarray:
        """(len(t), 11): x, z, θ, ẋ, ż, θ̇, ẍ, z̈, θ̈, cos θ, sin θ at times ``t`` [s] (SI)."""
        t = np.asarray(t, float)
        out = np.empty((len(t), 11))
        for c, spl in enumerate(self.splines):
            out[:, c] = spl(t)
            out[:, 3 + c] = spl(t, 1)
            out[:, 6 + c] = spl(t, 2)
        out[:, 0] += self.belt_speed * (t - self.t0)
        out[:, 3] += self.belt_speed
        out[:, 9] = np.cos(out[:, 2])
        out[:, 10] = np.sin(out[:, 2])
        return out
