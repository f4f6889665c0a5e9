"""The running blade of the planar runner: its stiffness categories and its contact sphere.

The built-in categories (Flex-Run Cat4–Cat7, ``bladelab/data/runner/categories.yaml``) hold seed
001 Table 2.3 (stiffness [kN/m], the seed's plane-strain modulus E [N/m²]) and Table 1.1 (body
mass range [kg]). The blade touches the ground as a Hertz sphere (seed 001 eq. 2.3,
``F = 4/3·E·√R·δ^1.5``) of radius :data:`BLADE_RADIUS_M` whose E makes its tangent stiffness at
the athlete's body weight the category's (:func:`blade_modulus`; docs/runner-model.md). Lengths
in m, angles in degrees, at the reference athlete (1.80 m) where they scale.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import yaml

from bladelab.contact import hertz_sphere_stiffness
from bladelab.errors import SpecError

#: The blade categories' file (``bladelab/data/runner/``).
CATEGORIES_FILE = Path(__file__).resolve().parents[1] / "data" / "runner" / "categories.yaml"
BLADE_RADIUS_M = 0.1464
BLADE_OFFSET_A_M = 0.069
BLADE_OFFSET_B_M = 0.0693
BLADE_ALIGNMENT_DEG = 9.0
BLADE_EXTRA_LENGTH_M = 0.03
BLADE_FRICTION = 0.9
BLADE_DISSIPATION_S_PER_M = 0.2


@dataclass(frozen=True)
class BladeCategory:
    """One stiffness category of the catalogue (seed 001 Table 2.3 / Table 1.1)."""

    name: str
    stiffness_n_per_m: float
    e_table: float
    body_mass_range_kg: tuple[float, float]

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "stiffness_kN_per_m": self.stiffness_n_per_m / 1e3,
            "E_table_N_per_m2": self.e_table,
            "body_mass_kg": list(self.body_mass_range_kg),
        }


@lru_cache(maxsize=1)
def blade_catalogue() -> dict[str, BladeCategory]:
    """The built-in blade categories, by name (Cat4, Cat5, Cat6, Cat6High, Cat7)."""
    text = CATEGORIES_FILE.read_text()
    out = {}
    for name, row in yaml.safe_load(text).items():
        out[name] = BladeCategory(
            name=name,
            stiffness_n_per_m=float(row["stiffness_kN_per_m"]) * 1e3,
            e_table=float(row["E_table_N_per_m2"]),
            body_mass_range_kg=(float(row["body_mass_kg"][0]), float(row["body_mass_kg"][1])),
        )
    return out


def blade_category(name: str) -> BladeCategory:
    """Look up a category by name (case-insensitive); unknown names raise :class:`SpecError`."""
    cat = blade_catalogue()
    for key, value in cat.items():
        if key.lower() == str(name).lower():
            return value
    raise SpecError(
        f"unknown blade category {name!r}",
        where="blade",
        hint=f"use one of {', '.join(cat)}",
    )


def blade_modulus(
    stiffness_n_per_m: float, load_n: float, *, radius: float = BLADE_RADIUS_M
) -> float:
    """Plane-strain modulus E [N/m²] whose Hertz sphere (eq. 2.3) has the tangent stiffness
    ``stiffness_n_per_m`` [N/m] at the static load ``load_n`` [N].

    With ``F = k·δ^1.5`` and ``k = 4/3·E·√R``: ``dF/dδ = 1.5·F/δ``, so the compression at the load
    is ``δ = 1.5·F/K`` and ``E = F / (4/3·√R·δ^1.5)``.
    """
    delta = 1.5 * load_n / stiffness_n_per_m
    return load_n / (hertz_sphere_stiffness(radius, 1.0) * delta**1.5)


def hertz_compression(force_n: float, modulus: float, radius: float) -> float:
    """Static compression δ [m] of a Hertz sphere (eq. 2.3) under ``force_n`` [N]."""
    return (
        (force_n / hertz_sphere_stiffness(radius, modulus)) ** (2.0 / 3.0) if force_n > 0 else 0.0
    )


__all__ = [
    "BLADE_ALIGNMENT_DEG",
    "BLADE_DISSIPATION_S_PER_M",
    "BLADE_EXTRA_LENGTH_M",
    "BLADE_FRICTION",
    "BLADE_OFFSET_A_M",
    "BLADE_OFFSET_B_M",
    "BLADE_RADIUS_M",
    "CATEGORIES_FILE",
    "BladeCategory",
    "blade_catalogue",
    "blade_category",
    "blade_modulus",
    "hertz_compression",
]
