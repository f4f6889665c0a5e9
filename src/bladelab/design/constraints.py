"""Safety constraints of seed 002: knee buckling and tripping.

**Knee buckling.** A transfemoral runner's prosthetic knee (no stance lock) buckles when the
ground reaction force passes behind it during weight bearing, i.e. when the external moment
flexes the knee. In the sagittal (x–z) plane, with the GRF F = (F_x, F_z) acting at the centre of
pressure (COP), the external knee *extension* moment is

    M = (x_COP − x_knee)·F_z − (z_COP − z_knee)·F_x     [N·m],

which is minus the y-component of r × F (r = COP − knee): M > 0 when the GRF line passes in front
of the knee (extension), M = 0 when it passes through the knee, M < 0 behind it (flexion:
buckling risk). The constraint is min M over prosthetic stance ≥ a margin.

**Tripping.** The minimum height of the blade above the ground over the prosthetic swing phase
must stay above a threshold.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from bladelab.errors import DataError

__all__ = [
    "knee_extension_moment",
    "KneeBucklingResult",
    "knee_buckling",
    "ClearanceResult",
    "blade_clearance",
]


def _arr(name: str, value, n: int | None = None) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim == 0 and n is not None:
        a = np.full(n, float(a))
    a = a.reshape(-1)
    if n is not None and a.size != n:
        raise DataError(f"has {a.size} samples, expected {n}", where=name)
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise DataError(f"non-finite value at sample {int(bad[0])}", where=name)
    return a


def knee_extension_moment(
    cop_x: np.ndarray,
    cop_z: np.ndarray | float,
    knee_x: np.ndarray,
    knee_z: np.ndarray,
    grf_x: np.ndarray,
    grf_z: np.ndarray,
) -> np.ndarray:
    """External knee extension moment of the GRF [N·m], positive = extension.

    Parameters
    ----------
    cop_x, cop_z
        Centre of pressure [m] (``cop_z`` may be a scalar: the ground height).
    knee_x, knee_z
        Knee joint centre [m].
    grf_x, grf_z
        Ground reaction force on the runner [N].

    Returns
    -------
    numpy.ndarray
        M = (x_COP − x_knee)·F_z − (z_COP − z_knee)·F_x per sample.
    """
    fx = _arr("grf_x", grf_x)
    n = fx.size
    cx, cz = _arr("cop_x", cop_x, n), _arr("cop_z", cop_z, n)
    kx, kz = _arr("knee_x", knee_x, n), _arr("knee_z", knee_z, n)
    fz = _arr("grf_z", grf_z, n)
    return (cx - kx) * fz - (cz - kz) * fx


@dataclass(frozen=True)
class KneeBucklingResult:
    """Knee-buckling check over prosthetic stance.

    Attributes
    ----------
    min_moment
        Minimum extension moment over stance [N·m].
    time_of_min
        When it occurs [s].
    margin
        Required minimum [N·m].
    slack
        min_moment − margin [N·m]; ≥ 0 when satisfied.
    satisfied
        ``slack >= 0``.
    """

    min_moment: float
    time_of_min: float
    margin: float
    slack: float
    satisfied: bool

    def to_dict(self) -> dict:
        return asdict(self)


def knee_buckling(
    time: np.ndarray,
    moment: np.ndarray,
    *,
    stance_mask: np.ndarray,
    margin: float = 0.0,
) -> KneeBucklingResult:
    """Minimum knee extension moment over the prosthetic stance samples vs a margin.

    Parameters
    ----------
    time
        Samples [s].
    moment
        Knee extension moment [N·m] (:func:`knee_extension_moment`).
    stance_mask
        True during prosthetic stance (weight bearing).
    margin
        Required minimum extension moment [N·m] (0: the GRF must never pass behind the knee).
    """
    t = _arr("time", time)
    m = _arr("knee moment", moment, t.size)
    mask = np.asarray(stance_mask, dtype=bool).reshape(-1)
    if mask.size != t.size:
        raise DataError(f"has {mask.size} samples, time has {t.size}", where="stance mask")
    if not mask.any():
        raise DataError(
            "no prosthetic stance samples", where="stance mask",
            hint="the knee-buckling constraint needs the prosthetic leg on the ground",
        )
    idx = np.flatnonzero(mask)
    i = idx[int(np.argmin(m[idx]))]
    slack = float(m[i] - margin)
    return KneeBucklingResult(float(m[i]), float(t[i]), float(margin), slack, slack >= 0.0)


@dataclass(frozen=True)
class ClearanceResult:
    """Tripping check over swing.

    Attributes
    ----------
    min_clearance
        Smallest height of any blade point above the ground over swing [m].
    time_of_min
        When it occurs [s].
    point_index
        Which blade point (column of the trajectory) is lowest then.
    threshold
        Required minimum clearance [m].
    slack
        min_clearance − threshold [m].
    satisfied
        ``slack >= 0``.
    """

    min_clearance: float
    time_of_min: float
    point_index: int
    threshold: float
    slack: float
    satisfied: bool

    def to_dict(self) -> dict:
        return asdict(self)


def blade_clearance(
    time: np.ndarray,
    points: np.ndarray,
    *,
    swing_mask: np.ndarray,
    ground: float | Callable[[np.ndarray], np.ndarray] = 0.0,
    threshold: float = 0.0,
    radius: float = 0.0,
) -> ClearanceResult:
    """Minimum clearance of the blade over swing.

    Parameters
    ----------
    time
        Samples [s], length n.
    points
        Blade points over time [m], shape (n, n_points, 2) as (x, z) or (n, n_points, 3) as
        (x, y, z); (n, 2|3) for a single point.
    swing_mask
        True during the prosthetic swing phase.
    ground
        Ground height [m], a constant or a function of x (array -> array).
    threshold
        Required minimum clearance [m].
    radius
        Subtracted from every point's height (e.g. the radius of sole contact spheres) [m].
    """
    t = _arr("time", time)
    p = np.asarray(points, dtype=float)
    if p.ndim == 2:
        p = p[:, None, :]
    if p.ndim != 3 or p.shape[0] != t.size or p.shape[2] not in (2, 3):
        raise DataError(
            f"blade trajectory must have shape (n_samples, n_points, 2 or 3), got {p.shape}",
            where="blade points",
        )
    if not np.all(np.isfinite(p)):
        raise DataError("non-finite blade point coordinates", where="blade points")
    mask = np.asarray(swing_mask, dtype=bool).reshape(-1)
    if mask.size != t.size:
        raise DataError(f"has {mask.size} samples, time has {t.size}", where="swing mask")
    if not mask.any():
        raise DataError("no swing samples", where="swing mask")
    x, z = p[..., 0], p[..., -1]
    gz = np.asarray(ground(x), dtype=float) if callable(ground) else np.full_like(z, float(ground))
    if gz.shape != z.shape:
        raise DataError("ground(x) must return one height per point", where="ground")
    clearance = z - gz - float(radius)
    c = np.where(mask[:, None], clearance, np.inf)
    i, j = np.unravel_index(int(np.argmin(c)), c.shape)
    slack = float(clearance[i, j] - threshold)
    return ClearanceResult(
        float(clearance[i, j]), float(t[i]), int(j), float(threshold), slack, slack >= 0.0
    )
