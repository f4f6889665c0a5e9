"""Segmentation: split a blade profile into N rigid segments (seed 000 §2.2).

The profile is cut into N pieces of **equal arc length**; each rigid segment is the chord of its
piece. The geometric error of a segment is the area between its piece of the profile and its
chord divided by the piece's length, Aᵢ/sᵢ [mm²/mm] (the mean distance between profile and chord,
in mm). The error of the segmentation is the **worst segment's**:

    error = maxᵢ Aᵢ / sᵢ      [mm²/mm]

Aᵢ = ∫ |h| dt, with t the coordinate along the chord and h the distance of the profile from it
(exact for a piece that does not turn back relative to its chord). The worst segment is used,
rather than Σ Aᵢ / L, so that long straight parts (the clamp plate, a J blade's shank) cannot
hide a poor fit at the main curvature; ``mean_error`` (Σ Aᵢ / L) is reported as well. For an arc
of radius R cut into pieces of length s, Aᵢ/sᵢ ≈ s²/(12R): the error falls as 1/N².
:func:`segment_profile` picks the smallest N whose error is at most the threshold (seed 000:
1 mm²/mm gave 16 segments for both of its blades).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from bladelab._io import write_json
from bladelab.blade.profile import Profile, find_self_intersections
from bladelab.errors import ModelError

__all__ = ["Segmentation", "segment_profile", "segmentation_error", "write_segmentation_json"]

_MAX_SEGMENTS = 200


@dataclasses.dataclass(frozen=True, eq=False)
class Segmentation:
    """A profile cut into rigid segments.

    Attributes
    ----------
    n
        Number of segments N.
    error
        Geometric error [mm²/mm]: the largest ``segment_errors``.
    mean_error
        Total area between profile and chords divided by the profile length [mm²/mm].
    points
        (N+1, 2) segment end points (x, z) [m], clamp frame; on the profile.
    breaks
        (N+1,) arc-length positions [m] of the end points along the profile.
    segment_errors
        (N,) area between each piece and its chord divided by the piece length [mm²/mm].
    threshold
        The error threshold [mm²/mm] used to choose N (``None`` when N was given).
    profile_length
        Arc length of the profile [m].
    """

    n: int
    error: float
    mean_error: float
    points: np.ndarray
    breaks: np.ndarray
    segment_errors: np.ndarray
    threshold: float | None
    profile_length: float

    @property
    def chord_lengths(self) -> np.ndarray:
        """(N,) segment (chord) lengths [m]."""
        return np.hypot(*np.diff(self.points, axis=0).T)

    def to_dict(self) -> dict:
        """Plain dict; lengths in m, errors in mm²/mm."""
        return {
            "n_segments": int(self.n),
            "error_mm2_per_mm": float(self.error),
            "mean_error_mm2_per_mm": float(self.mean_error),
            "threshold_mm2_per_mm": self.threshold,
            "profile_length_m": float(self.profile_length),
            "points_x_m": self.points[:, 0].tolist(),
            "points_z_m": self.points[:, 1].tolist(),
        }


def _as_profile(points: Profile | np.ndarray) -> Profile:
    return points if isinstance(points, Profile) else Profile(np.asarray(points, dtype=float))


def _piece_areas(prof: Profile, s_all: np.ndarray, breaks: np.ndarray) -> np.ndarray:
    """Area [m²] between the profile and the chord of each piece [breaks[i], breaks[i+1]]."""
    areas = np.empty(len(breaks) - 1)
    ends = prof.at(breaks)
    lo = np.searchsorted(s_all, breaks[:-1], side="right")
    hi = np.searchsorted(s_all, breaks[1:], side="left")
    for i in range(len(breaks) - 1):
        pts = np.vstack([ends[i], prof.points[lo[i]:hi[i]], ends[i + 1]])
        chord = ends[i + 1] - ends[i]
        c = float(np.hypot(*chord))
        u = chord / c
        rel = pts - ends[i]
        t = rel @ u
        h = rel[:, 0] * u[1] - rel[:, 1] * u[0]
        areas[i] = _abs_trapezoid(t, h)
    return areas


def _abs_trapezoid(t: np.ndarray, h: np.ndarray) -> float:
    """∫|h| |dt| along a polyline, splitting pieces where h changes sign."""
    dt = np.abs(np.diff(t))
    h0, h1 = h[:-1], h[1:]
    same = h0 * h1 >= 0.0
    total = np.sum(np.where(same, 0.5 * (np.abs(h0) + np.abs(h1)) * dt, 0.0))
    # A piece crossing the chord: two triangles.
    cross = ~same
    if np.any(cross):
        a, b, d = np.abs(h0[cross]), np.abs(h1[cross]), dt[cross]
        total += np.sum(0.5 * d * (a * a + b * b) / (a + b))
    return float(total)


def segmentation_error(points: Profile | np.ndarray, n: int) -> float:
    """Geometric error [mm²/mm] of cutting a profile into ``n`` equal-arc-length segments.

    Parameters
    ----------
    points
        A :class:`Profile` or an (M, 2) polyline (x, z) [m].
    n
        Number of segments (≥ 1).
    """
    return _segment(_as_profile(points), n, threshold=None).error


def _segment(prof: Profile, n: int, threshold: float | None) -> Segmentation:
    s_all = prof.arc_length
    length = float(s_all[-1])
    breaks = np.linspace(0.0, length, n + 1)
    areas = _piece_areas(prof, s_all, breaks)
    piece = np.diff(breaks)
    return Segmentation(
        n=int(n),
        error=float(np.max(areas / piece) * 1e3),  # m²/m -> mm²/mm (= mm)
        mean_error=float(areas.sum() / length * 1e3),
        points=prof.at(breaks),
        breaks=breaks,
        segment_errors=areas / piece * 1e3,
        threshold=threshold,
        profile_length=length,
    )


def segment_profile(
    points: Profile | np.ndarray,
    *,
    max_error_mm2_per_mm: float = 1.0,
    n_segments: int | None = None,
    max_segments: int = _MAX_SEGMENTS,
    check_intersections: bool = True,
) -> Segmentation:
    """Cut a profile into the fewest equal-arc-length rigid segments meeting an error threshold.

    Parameters
    ----------
    points
        A :class:`Profile` or an (M, 2) polyline (x, z) [m] from the clamp to the toe.
    max_error_mm2_per_mm
        Threshold on the geometric error [mm²/mm] (worst segment, see the module docstring);
        the smallest N with ``error <= threshold`` is chosen.
    n_segments
        Use exactly this N instead of searching (the threshold is then ignored).
    max_segments
        Largest N tried before giving up.
    check_intersections
        Raise if the chain of segments intersects itself.

    Returns
    -------
    Segmentation

    Raises
    ------
    ModelError
        Bad threshold or N, no N up to ``max_segments`` meets the threshold, or the segmented
        chain intersects itself.
    """
    prof = _as_profile(points)
    if n_segments is not None:
        if int(n_segments) != n_segments or n_segments < 1:
            raise ModelError(f"number of segments must be a positive integer, got {n_segments}",
                             where="n_segments")
        seg = _segment(prof, int(n_segments), threshold=None)
    else:
        if not (max_error_mm2_per_mm > 0.0 and np.isfinite(max_error_mm2_per_mm)):
            raise ModelError(f"error threshold must be positive, got {max_error_mm2_per_mm} mm²/mm",
                             where="max_error_mm2_per_mm")
        seg = None
        for n in range(1, max_segments + 1):
            cand = _segment(prof, n, threshold=float(max_error_mm2_per_mm))
            if cand.error <= max_error_mm2_per_mm:
                seg = cand
                break
        if seg is None:
            raise ModelError(
                f"no segmentation with at most {max_segments} segments has an error below "
                f"{max_error_mm2_per_mm} mm²/mm", where=prof.name,
                hint="raise the threshold or check the profile units (metres)")
    if check_intersections:
        crossings = find_self_intersections(seg.points)
        if crossings:
            i, j = crossings[0]
            raise ModelError(
                f"the segmented blade intersects itself (segments {i + 1} and {j + 1} of {seg.n})",
                where=prof.name, hint="use more segments or a lower error threshold")
    return seg


def write_segmentation_json(segmentation: Segmentation, path: str | Path, *,
                            profile: str | Path = "") -> Path:
    """Write a segmentation (:meth:`Segmentation.to_dict`, lengths in m) as JSON, atomically,
    with the profile file it came from under ``profile``."""
    write_json(path, {"profile": str(profile), **segmentation.to_dict()})
    return Path(path)
