"""Identification formulations: how the measured stance drives the model.

A *formulation* names the way the simulated blade is tied to the measured stance during
identification; it maps to a clamp :class:`bladelab.sim.Drive`:

==========================  =====================================================================
formulation                 model
==========================  =====================================================================
``"seed"``                  seed 000 exactly: the clamp follows the measured pose, the sole has
                            the smooth spring-damper contact with stick-slip friction.
``"utilised-friction"``     the clamp follows the measured pose; the friction force of each loaded
                            sole element is r(t)·Fn,e with r = measured Fx/Fz (the utilised
                            friction), instead of the stick-slip law.
``"grf-driven"``            the clamp follows the measured pose and the measured GRF is applied to
                            the sole (split over the elements by the model's normal forces); the
                            cost is the distance only (the simulated GRF is the measured one).
                            Kernel only.
==========================  =====================================================================

Why (``docs/robust-identification.md``): in its stick regime the stick-slip law acts as a damper
of ~4e4 N·s/m on the sole's slip velocity, so millimetre errors of a filtered 100–250 Hz clamp
path become arbitrary horizontal forces and, through the hinge's height above the sole, wrong
hinge moments that K and D absorb. Taking the horizontal force from the force plate removes that
path. The default is ``"utilised-friction"`` (measured on 40 degraded MuJoCo stances).
"""

from __future__ import annotations

from bladelab.errors import OptimizationError
from bladelab.sim.api import Drive

FORMULATIONS: dict[str, Drive] = {
    "seed": Drive.PRESCRIBED,
    "utilised-friction": Drive.UTILISED_FRICTION,
    "grf-driven": Drive.GRF_DRIVEN,
}
# formulations whose cost is the distance only (their simulated GRF is the measured one)
DISTANCE_ONLY = frozenset({"grf-driven"})
DEFAULT_FORMULATION = "utilised-friction"

__all__ = ["DEFAULT_FORMULATION", "DISTANCE_ONLY", "FORMULATIONS", "formulation_drive"]


def formulation_drive(formulation: str) -> Drive:
    """The clamp drive of an identification formulation.

    Raises
    ------
    OptimizationError
        Unknown formulation name.
    """
    try:
        return FORMULATIONS[formulation]
    except (KeyError, TypeError):
        raise OptimizationError(
            f"unknown formulation {formulation!r}", where="formulation",
            hint="one of " + ", ".join(FORMULATIONS)) from None
