"""The catalogue of built-in blades and the entry points that load a blade by name or file.

Built-in specs live in ``bladelab/data/blades/<family>.yaml``; each family lists stiffness
categories, so the loadable names are ``<family>-<category>`` (``xtreme-cat5``) or the bare family
name for its default category.
"""

from __future__ import annotations

import dataclasses
from importlib import resources
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab import units
from bladelab.blade.model import BladeModel, CompliantJoint
from bladelab.blade.spec import BladeSpec, read_blade_spec
from bladelab.errors import ModelError, SpecError

__all__ = ["blade_catalogue", "list_blades", "load_blade", "multilink_blade"]


def _builtin_dir() -> Path:
    return Path(str(resources.files("bladelab") / "data" / "blades"))


def _families() -> dict[str, Path]:
    d = _builtin_dir()
    return {p.stem: p for p in sorted(d.glob("*.yaml"))} if d.is_dir() else {}


def list_blades() -> list[str]:
    """Names of the built-in blades, one per family and category (``xtreme-cat5``).

    The bare family name (``xtreme``) also loads, with the family's default category.
    """
    names = []
    for family, path in _families().items():
        spec = read_blade_spec(path, check=False)
        if spec.categories:
            names.extend(f"{family}-{c}" for c in spec.categories)
        else:
            names.append(family)
    return names


def _looks_like_path(name: str) -> bool:
    return name.endswith((".yaml", ".yml")) or "/" in name or "\\" in name


def load_blade(name_or_path: str | Path, *, category: str | None = None) -> BladeSpec:
    """Load a blade spec: a built-in name (see :func:`list_blades`) or a YAML file.

    Parameters
    ----------
    name_or_path
        ``"xtreme-cat5"``, ``"xceed"`` (default category), or a path to a spec file.
    category
        Select this stiffness category (overrides the one in the name).

    Returns
    -------
    BladeSpec
        Validated, including a trial build (geometric checks); ``.build()`` gives the model.

    Raises
    ------
    SpecError
        Unknown name or category, or an invalid spec.
    InputFileError
        A spec file that is missing or not YAML.
    """
    if isinstance(name_or_path, Path) or _looks_like_path(str(name_or_path)) \
            or Path(str(name_or_path)).is_file():
        return read_blade_spec(name_or_path, category=category)
    name = str(name_or_path).strip().lower().replace("_", "-")
    families = _families()
    family, cat = name, None
    if family not in families and "-" in name:
        family, cat = name.rsplit("-", 1)
    if family not in families:
        raise SpecError(f"unknown blade {str(name_or_path)!r}", where="blade",
                        hint=f"built-in blades: {', '.join(list_blades())}; or give a spec file")
    spec = read_blade_spec(families[family], check=False)
    chosen = category or cat
    if chosen is not None:
        spec = spec.with_category(chosen)
    spec.build()  # geometric checks
    return spec


def blade_catalogue() -> pd.DataFrame:
    """Tidy table of the built-in blades: one row per name, key numbers with units in columns."""
    rows = []
    for name in list_blades():
        spec = load_blade(name)
        s = spec.summary()
        rows.append({
            "name": name,
            "family": spec.name,
            "category": spec.category,
            "K_Nm_per_deg": s["joints"][0]["K_Nm_per_deg"],
            "D_Nms_per_deg": s["joints"][0]["D_Nms_per_deg"],
            "n_joints": len(s["joints"]),
            "mass_kg": s["mass_kg"],
            "height_m": s["height_m"],
            "toe_length_m": s["toe_length_m"],
            "n_segments": s["n_segments"],
            "description": spec.description,
        })
    return pd.DataFrame(rows)


def multilink_blade(
    blade: str | Path | BladeSpec,
    *,
    n_links: int = 6,
    K_Nm_per_deg: float | np.ndarray | None = None,
    D_Nms_per_deg: float | np.ndarray | None = None,
) -> BladeModel:
    """A multi-link blade (seed 002: 6 rigid links joined by 5 spring-dampers) from a spec.

    The spec's segmentation is kept (so the geometry, masses and soles are unchanged); its
    compliant joints are replaced by ``n_links - 1`` joints at the segment ends nearest to equal
    fractions of the profile's arc length, so the segments group into ``n_links`` rigid links.

    Parameters
    ----------
    blade
        A built-in name, a spec file or a :class:`BladeSpec`.
    n_links
        Number of rigid links (2 ≤ n_links ≤ number of segments).
    K_Nm_per_deg
        Stiffness per joint [N·m/deg]: one value for all or one per joint. Default: (n_links−1)
        times the spec's (first) nominal K, so that equal springs in series under one moment
        are as compliant as the spec's single joint (a crude nominal value; identify it).
    D_Nms_per_deg
        Damping per joint [N·m·s/deg]; default scaled from the spec's D in the same way.

    Returns
    -------
    BladeModel
        Named ``<name>-<n_links>link``.
    """
    spec = blade if isinstance(blade, BladeSpec) else load_blade(blade)
    base = spec.build()
    n_seg = base.n_segments
    if not (2 <= int(n_links) <= n_seg) or int(n_links) != n_links:
        raise ModelError(f"n_links must be an integer from 2 to {n_seg}, got {n_links}",
                         where="n_links")
    n_j = int(n_links) - 1
    # Hinge points: segment ends closest to equal arc-length fractions (distinct, in order).
    seg_len = np.hypot(*np.diff(base.points, axis=0).T)
    s_pts = np.concatenate([[0.0], np.cumsum(seg_len)])
    points: list[int] = []
    for k in range(1, n_j + 1):
        target = k / n_links * s_pts[-1]
        order = np.argsort(np.abs(s_pts[1:-1] - target)) + 1
        points.append(int(next(p for p in order if p not in points)))
    points.sort()
    k_nom = units.stiffness_per_rad_to_per_deg(base.joints[0].stiffness) * n_j
    d_nom = units.damping_per_rad_to_per_deg(base.joints[0].damping) * n_j
    try:
        ks = np.broadcast_to(np.asarray(k_nom if K_Nm_per_deg is None else K_Nm_per_deg, float),
                             (n_j,))
        ds = np.broadcast_to(np.asarray(d_nom if D_Nms_per_deg is None else D_Nms_per_deg, float),
                             (n_j,))
    except ValueError:
        raise ModelError(f"give one K and D value for all joints or one per joint ({n_j})",
                         where="K_Nm_per_deg / D_Nms_per_deg") from None
    if np.any(ks <= 0) or np.any(ds < 0) or not (np.all(np.isfinite(ks)) and np.all(np.isfinite(ds))):
        raise ModelError("joint stiffness must be positive and damping non-negative",
                         where="K_Nm_per_deg / D_Nms_per_deg")
    joints = tuple(
        CompliantJoint(point=p, stiffness=float(units.stiffness_per_deg_to_per_rad(k)),
                       damping=float(units.damping_per_deg_to_per_rad(d)))
        for p, k, d in zip(points, ks, ds, strict=True)
    )
    return dataclasses.replace(base, name=f"{base.name}-{n_links}link", joints=joints)
