"""From the runner's geometry tables to the MjSpec body frames.

The geometry (:mod:`bladelab.runner.geometry`, SCONE H0918) gives every point relative to the
centre of mass of its body in OpenSim axes (x forward, y up, z right) [m] and every inertia as
its principal moments about those axes [kg·m²]; the MuJoCo bodies of
:func:`bladelab.runner.model.build_runner` have their frames at their joints in the lab axes
(x forward, y left, z up). Lengths scale with the athlete's height (and a segment's length
factor), inertias with mass times length squared.
"""

from __future__ import annotations

from bladelab.runner import geometry as geo

__all__ = ["difference", "lab_inertia", "lab_vector"]


def lab_vector(p: tuple[float, float, float], s: float) -> list[float]:
    """The OpenSim-axes vector ``p`` [m] in lab axes, scaled by ``s`` [-]."""
    return list(geo.to_lab(p, s))


def lab_inertia(ixx: float, iyy: float, izz: float, factor: float) -> list[float]:
    """Principal inertias in lab axes; the sagittal one (lab y = OpenSim z) is kept exact, the
    out-of-plane x one is raised if needed to satisfy the triangle inequality (it has no effect
    in the planar model; the prosthesis of Table 2.1 violates it)."""
    ix, iy, iz = ixx * factor, izz * factor, iyy * factor
    if ix + iz < iy:
        ix = iy - iz + 1e-6
    return [ix, iy, iz]


def difference(
    a: tuple[float, float, float], b: tuple[float, float, float]
) -> tuple[float, float, float]:
    """``a − b`` [m], component by component (a point relative to another)."""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])

