"""Blade profiles: the blade's side-view centre line as a polyline in the clamp frame.

A profile runs from the clamp origin (first point) to the toe tip (last point). Coordinates are
(x, z) in metres in the **clamp frame**: origin at the clamp origin, z up along the pylon, x
forward; the profile hangs below the clamp (z < 0). Profiles come from straight and circular
elements (:func:`profile_from_elements`, used by the built-in blades) or from a CSV polyline
exported from CAD (:func:`read_profile_csv`, format in ``docs/blade-spec.md``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab.errors import DataError, InputFileError, ModelError

__all__ = [
    "Profile",
    "ProfileElement",
    "profile_from_elements",
    "read_profile_csv",
    "find_self_intersections",
]

# Spacing [m] of the points that discretise circular arcs.
_ARC_STEP = 5.0e-4


@dataclasses.dataclass(frozen=True)
class ProfileElement:
    """One element of a parametric profile: a straight line or a circular arc.

    Attributes
    ----------
    length
        Arc length [m] of the element (> 0).
    turn
        Change of heading [rad] along the element; 0 for a straight line. Positive turns
        counter-clockwise in a side view with x to the right and z up (a blade going down that
        bends forward has a positive turn).
    """

    length: float
    turn: float = 0.0

    @property
    def radius(self) -> float:
        """Radius of curvature [m] (``inf`` for a straight line)."""
        return math.inf if self.turn == 0.0 else self.length / abs(self.turn)


@dataclasses.dataclass(frozen=True, eq=False)
class Profile:
    """A blade profile: polyline from the clamp origin to the toe tip, clamp frame [m].

    Attributes
    ----------
    points
        (M, 2) points (x, z) [m], M ≥ 2, consecutive points distinct.
    name
        Where it came from (file name or blade name).
    """

    points: np.ndarray
    name: str = "profile"

    def __post_init__(self) -> None:
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ModelError(f"profile points must be an (M, 2) array of (x, z), got shape {pts.shape}",
                             where=self.name)
        if len(pts) < 2:
            raise ModelError(f"a profile needs at least two points, got {len(pts)}", where=self.name,
                             hint="give the polyline from the clamp origin to the toe tip")
        if not np.all(np.isfinite(pts)):
            raise ModelError("profile points contain NaN or infinite values", where=self.name)
        if np.any(np.hypot(*np.diff(pts, axis=0).T) <= 0.0):
            raise ModelError("profile has repeated consecutive points (zero-length piece)",
                             where=self.name, hint="remove duplicated rows")
        pts.setflags(write=False)
        object.__setattr__(self, "points", pts)

    @property
    def arc_length(self) -> np.ndarray:
        """(M,) cumulative arc length [m] at each point, starting at 0."""
        return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(self.points, axis=0).T))])

    @property
    def length(self) -> float:
        """Total arc length [m]."""
        return float(self.arc_length[-1])

    @property
    def height(self) -> float:
        """Build height [m]: from the clamp origin (z = 0) down to the lowest profile point."""
        return float(-np.min(self.points[:, 1]))

    @property
    def toe_length(self) -> float:
        """Toe length [m]: from the clamp axis (x = 0) forward to the most forward profile point."""
        return float(np.max(self.points[:, 0]))

    @property
    def lowest_point(self) -> np.ndarray:
        """(x, z) [m] of the lowest profile point."""
        return self.points[int(np.argmin(self.points[:, 1]))].copy()

    def at(self, s: np.ndarray | float) -> np.ndarray:
        """Points (x, z) [m] at arc lengths ``s`` [m] (linear interpolation, clipped to the ends)."""
        s_all = self.arc_length
        s = np.clip(np.asarray(s, dtype=float), 0.0, s_all[-1])
        return np.stack([np.interp(s, s_all, self.points[:, 0]),
                         np.interp(s, s_all, self.points[:, 1])], axis=-1)

    def densified(self, step: float = _ARC_STEP) -> Profile:
        """A copy with extra points so that no piece is longer than ``step`` [m].

        The original points are kept, so the polyline is unchanged geometrically.
        """
        pieces = [self.points[:1]]
        for a, b in zip(self.points[:-1], self.points[1:], strict=True):
            n = max(1, math.ceil(float(np.hypot(*(b - a))) / step))
            t = np.arange(1, n + 1)[:, None] / n
            pieces.append(a + t * (b - a))
        return Profile(np.vstack(pieces), name=self.name)

    def to_dict(self) -> dict:
        """Summary in SI units (no point list)."""
        low = self.lowest_point
        return {
            "name": self.name,
            "n_points": int(len(self.points)),
            "length_m": self.length,
            "height_m": self.height,
            "toe_length_m": self.toe_length,
            "lowest_point_x_m": float(low[0]),
            "lowest_point_z_m": float(low[1]),
        }


def profile_from_elements(
    elements: Sequence[ProfileElement],
    *,
    start_heading: float = -math.pi / 2,
    start: tuple[float, float] = (0.0, 0.0),
    name: str = "profile",
) -> Profile:
    """Build a profile from consecutive straight lines and circular arcs.

    Parameters
    ----------
    elements
        Elements in order from the clamp to the toe.
    start_heading
        Direction [rad] of the tangent at the first point, measured from +x toward +z
        (−π/2: straight down the pylon axis).
    start
        First point (x, z) [m]; the clamp origin by default.
    name
        Name stored in the profile.

    Returns
    -------
    Profile
        Arcs are discretised with points about 0.5 mm apart (exact chords of the circle).
    """
    if len(elements) == 0:
        raise ModelError("a parametric profile needs at least one element", where=name)
    pts = [np.asarray(start, dtype=float)]
    heading = float(start_heading)
    for i, el in enumerate(elements):
        if not (el.length > 0.0 and math.isfinite(el.length)):
            raise ModelError(f"element length must be positive, got {el.length} m",
                             where=f"{name}: elements[{i}]")
        p0 = pts[-1]
        if el.turn == 0.0:
            pts.append(p0 + el.length * np.array([math.cos(heading), math.sin(heading)]))
            continue
        n = max(2, math.ceil(el.length / _ARC_STEP))
        radius = el.length / abs(el.turn)
        sign = math.copysign(1.0, el.turn)
        # Centre on the side the element turns toward.
        centre = p0 + radius * sign * np.array([-math.sin(heading), math.cos(heading)])
        phi = heading + el.turn * np.arange(1, n + 1) / n
        arc = centre + radius * sign * np.stack([np.sin(phi), -np.cos(phi)], axis=1)
        pts.extend(arc)
        heading += el.turn
    return Profile(np.vstack(pts), name=name)


def read_profile_csv(path: str | Path) -> Profile:
    """Read a profile polyline from CSV (clamp frame).

    The file has a header row and two numeric columns, ``x_m,z_m`` (metres) or ``x_mm,z_mm``
    (millimetres); one row per point, from the clamp origin end to the toe tip. Lines starting
    with ``#`` are comments. See ``docs/blade-spec.md``.

    Parameters
    ----------
    path
        CSV file.

    Returns
    -------
    Profile
        Points in metres.

    Raises
    ------
    InputFileError
        The file is missing or not a CSV with the expected columns.
    DataError
        Non-numeric or missing values, fewer than two points, repeated consecutive points, or a
        self-intersecting polyline.
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError("profile CSV not found", file=path)
    try:
        df = pd.read_csv(path, comment="#", skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as err:
        raise InputFileError(f"cannot parse as CSV ({err})", file=path,
                             hint="expected a header 'x_m,z_m' and one row per point") from None
    df.columns = [str(c).strip() for c in df.columns]
    if {"x_m", "z_m"} <= set(df.columns):
        cols, scale = ("x_m", "z_m"), 1.0
    elif {"x_mm", "z_mm"} <= set(df.columns):
        cols, scale = ("x_mm", "z_mm"), 1e-3
    else:
        raise InputFileError(f"missing columns: expected 'x_m,z_m' or 'x_mm,z_mm', got {list(df.columns)}",
                             file=path, hint="add a header row naming the columns with their unit")
    values = {}
    for c in cols:
        v = pd.to_numeric(df[c], errors="coerce").to_numpy(dtype=float)
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise DataError(f"non-numeric or missing value in row {int(bad[0]) + 1}", file=path, where=c)
        values[c] = v
    pts = np.stack([values[cols[0]], values[cols[1]]], axis=1) * scale
    if len(pts) < 2:
        raise DataError(f"a profile needs at least two points, got {len(pts)}", file=path,
                        hint="give the polyline from the clamp origin to the toe tip")
    step = np.hypot(*np.diff(pts, axis=0).T)
    if np.any(step <= 0.0):
        i = int(np.flatnonzero(step <= 0.0)[0])
        raise DataError(f"rows {i + 1} and {i + 2} are the same point", file=path,
                        hint="remove duplicated rows")
    crossings = find_self_intersections(pts)
    if crossings:
        i, j = crossings[0]
        raise DataError(f"the polyline intersects itself (pieces {i + 1} and {j + 1})", file=path,
                        hint="the points must follow the blade once, from clamp to toe")
    return Profile(pts, name=path.name)


def find_self_intersections(points: np.ndarray, *, tol: float = 1e-12) -> list[tuple[int, int]]:
    """Pairs (i, j), i < j, of pieces of a polyline that intersect or overlap.

    Piece i runs from ``points[i]`` to ``points[i + 1]``. Adjacent pieces share an end point,
    which does not count, unless they fold back onto each other (overlap along a line).

    Parameters
    ----------
    points
        (M, 2) polyline.
    tol
        Tolerance on the cross products [m²].

    Returns
    -------
    list of (int, int)
        Empty when the polyline is simple.
    """
    p = np.asarray(points, dtype=float)
    a, b = p[:-1], p[1:]
    n = len(a)
    if n < 2:
        return []
    # Bounding-box prefilter, then exact orientation tests on the candidates.
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    out: list[tuple[int, int]] = []
    for i in range(n - 1):
        j = np.arange(i + 1, n)
        cand = j[np.all(lo[j] <= hi[i] + tol, axis=1) & np.all(hi[j] >= lo[i] - tol, axis=1)]
        for jj in cand:
            jj = int(jj)
            if jj == i + 1:
                if _folds_back(a[i], b[i], b[jj], tol):
                    out.append((i, jj))
            elif _segments_intersect(a[i], b[i], a[jj], b[jj], tol):
                out.append((i, jj))
    return out


def _cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def _on_segment(p: np.ndarray, q: np.ndarray, r: np.ndarray, tol: float) -> bool:
    """Whether r, collinear with p-q, lies within the box of p-q."""
    return (min(p[0], q[0]) - tol <= r[0] <= max(p[0], q[0]) + tol
            and min(p[1], q[1]) - tol <= r[1] <= max(p[1], q[1]) + tol)


def _segments_intersect(p1, p2, p3, p4, tol: float) -> bool:
    d1, d2 = _cross(p3, p4, p1), _cross(p3, p4, p2)
    d3, d4 = _cross(p1, p2, p3), _cross(p1, p2, p4)
    if ((d1 > tol and d2 < -tol) or (d1 < -tol and d2 > tol)) and (
            (d3 > tol and d4 < -tol) or (d3 < -tol and d4 > tol)):
        return True
    return ((abs(d1) <= tol and _on_segment(p3, p4, p1, tol))
            or (abs(d2) <= tol and _on_segment(p3, p4, p2, tol))
            or (abs(d3) <= tol and _on_segment(p1, p2, p3, tol))
            or (abs(d4) <= tol and _on_segment(p1, p2, p4, tol)))


def _folds_back(a: np.ndarray, b: np.ndarray, c: np.ndarray, tol: float) -> bool:
    """Adjacent pieces a-b and b-c overlap: collinear and c goes back toward a."""
    u, v = b - a, c - b
    return abs(float(u[0] * v[1] - u[1] * v[0])) <= tol and float(u @ v) < 0.0
