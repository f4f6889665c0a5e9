"""The vocabulary of a blade joint's parameters: one place for their names, units and keys.

Inside bladelab, K, D and K2 are SI (N·m/rad, N·m·s/rad, N·m/rad²); at the edges (JSON keys,
CSV columns, blade specs, the command line, reports) they are in the literature's degrees.
Identification, blade specs, the CLI and reports take names, keys, units and conversions from
:data:`JOINT_PARAMETERS`; the conversion factors themselves live in :mod:`bladelab.units`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bladelab import units
from bladelab.errors import SpecError

__all__ = ["JOINT_PARAMETERS", "JointParameter", "joint_parameter"]


@dataclass(frozen=True)
class JointParameter:
    """One compliant-joint parameter.

    Attributes
    ----------
    name
        ``"K"``, ``"D"`` or ``"K2"``.
    description
        What it is.
    si_unit, edge_unit
        Units inside (per radian) and at the edges (per degree).
    edge_key, ci_key
        JSON/CSV keys of the value and of its confidence interval (edge units).
    degree_power
        How many times the unit has "per angle": 1 for K and D, 2 for K2.
    """

    name: str
    description: str
    si_unit: str
    edge_unit: str
    edge_key: str
    ci_key: str
    degree_power: int

    def to_edge(self, value_si):
        """SI (per radian) -> edge units (per degree); a scalar gives a float, an array-like
        an ndarray."""
        return _times(value_si, units.RAD_PER_DEG**self.degree_power)

    def from_edge(self, value_edge):
        """Edge units (per degree) -> SI (per radian); scalars and arrays as :meth:`to_edge`."""
        return _times(value_edge, units.DEG_PER_RAD**self.degree_power)


def _times(value, factor: float):
    if np.ndim(value) == 0:
        return float(value) * factor
    return np.asarray(value, dtype=float) * factor


JOINT_PARAMETERS: dict[str, JointParameter] = {
    "K": JointParameter("K", "torsional stiffness", "N·m/rad", "N·m/deg", "K_Nm_per_deg",
                        "K_ci_Nm_per_deg", 1),
    "D": JointParameter("D", "torsional damping", "N·m·s/rad", "N·m·s/deg", "D_Nms_per_deg",
                        "D_ci_Nms_per_deg", 1),
    "K2": JointParameter("K2", "quadratic stiffness (τ = −(K·q + K2·q·|q|))", "N·m/rad²",
                         "N·m/deg²", "K2_Nm_per_deg2", "K2_ci_Nm_per_deg2", 2),
}


def joint_parameter(name: str) -> JointParameter:
    """The parameter called ``name`` (``K``, ``D`` or ``K2``)."""
    try:
        return JOINT_PARAMETERS[name]
    except KeyError:
        raise SpecError(f"unknown joint parameter {name!r}", where="parameter",
                        hint=f"use one of {', '.join(JOINT_PARAMETERS)}") from None
