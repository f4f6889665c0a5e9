"""The legs' segment lengths from a static (standing) trial's anatomical markers.

- **Hip joint centre**: Harrington et al. (2007, J Biomech 40:595)'s regression from the pelvis
  landmarks. Pelvic width PW = the distance between the two ASIS markers, pelvic depth PD =
  from the PSIS' midpoint to the ASIS' midpoint; in the pelvis frame at the ASIS' midpoint
  (x anterior, y superior, z to the right): x = −0.24·PD − 9.9 mm, y = −0.30·PW − 10.9 mm,
  z = ±(0.33·PW + 7.3) mm. Their MRI of eight adults put its errors at up to 3 cm.
- **Knee joint centre**: midway between the lateral and medial femoral epicondyle markers.
- **Ankle joint centre**: midway between the lateral and medial malleolus markers.
- **Thigh** = hip to knee joint centre, **shank** = knee to ankle joint centre [m], from the
  markers' means over the static trial's frames (gaps left out).

The default marker names are the Fukuchi et al. (2017) data set's (``RBDS001static.c3d``:
``L.ASIS``, ``L.PSIS``, ``L.Knee``, ``L.Knee.Medial``, ``L.Ankle``, ``L.Ankle.Medial`` and
the same with ``R.``); :class:`SegmentMarkerMap` names others (``{side}`` is replaced by the
side's prefix). A side without knee or ankle markers (an amputee's prosthetic side) has no
segment lengths of its own.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from pydantic import BaseModel, ConfigDict

from bladelab.errors import DataError
from bladelab.trial.trial import Trial

__all__ = ["SegmentLengths", "SegmentMarkerMap", "segment_lengths"]

# Harrington et al. (2007), single-variable regressions [mm]: (slope, intercept)
_HJC_ANTERIOR = (-0.24, -9.9)  # of pelvic depth
_HJC_SUPERIOR = (-0.30, -10.9)  # of pelvic width
_HJC_LATERAL = (0.33, 7.3)  # of pelvic width


class SegmentMarkerMap(BaseModel):
    """Marker names of the landmarks (``{side}``: the side's prefix)."""

    model_config = ConfigDict(extra="forbid")
    asis: str = "{side}.ASIS"
    psis: str = "{side}.PSIS"
    knee_lateral: str = "{side}.Knee"
    knee_medial: str = "{side}.Knee.Medial"
    ankle_lateral: str = "{side}.Ankle"
    ankle_medial: str = "{side}.Ankle.Medial"
    sides: dict[str, str] = {"left": "L", "right": "R"}


@dataclasses.dataclass(frozen=True)
class SegmentLengths:
    """Segment lengths per side [m] (NaN where the side lacks the markers) and the pelvis's
    dimensions [m] that placed the hip joint centres."""

    thigh_m: dict[str, float]
    shank_m: dict[str, float]
    pelvic_width_m: float
    pelvic_depth_m: float
    source: str | None = None

    def to_dict(self) -> dict:
        """JSON-serialisable, every length in metres."""
        return dataclasses.asdict(self)


def _mean(trial: Trial, label: str) -> np.ndarray:
    if label not in trial.markers:
        raise DataError(f"no marker named {label!r}", file=trial.source, where=f"marker {label}",
                        hint="a static trial with the pelvis (ASIS, PSIS), knee (epicondyles) "
                             "and ankle (malleoli) markers; other names: SegmentMarkerMap")
    xyz = trial.marker(label)
    if not np.isfinite(xyz).all(axis=1).any():
        raise DataError("has no valid frame", file=trial.source, where=f"marker {label}",
                        hint="a static trial needs each landmark visible in some frame")
    return np.nanmean(xyz, axis=0)


def _hip_centres(trial: Trial, names: SegmentMarkerMap) -> tuple[dict, float, float]:
    """Hip joint centres [m] per side, pelvic width and depth [m]."""
    left, right = names.sides["left"], names.sides["right"]
    asis = {s: _mean(trial, names.asis.format(side=p)) for s, p in (("left", left),
                                                                    ("right", right))}
    psis = [_mean(trial, names.psis.format(side=p)) for p in (left, right)]
    origin = 0.5 * (asis["left"] + asis["right"])
    lateral = asis["right"] - asis["left"]
    width = float(np.linalg.norm(lateral))
    z = lateral / width
    back = 0.5 * (psis[0] + psis[1])
    forward = origin - back
    x = forward - np.dot(forward, z) * z
    depth = float(np.linalg.norm(forward))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pw_mm, pd_mm = 1000.0 * width, 1000.0 * depth
    ax = (_HJC_ANTERIOR[0] * pd_mm + _HJC_ANTERIOR[1]) / 1000.0
    ay = (_HJC_SUPERIOR[0] * pw_mm + _HJC_SUPERIOR[1]) / 1000.0
    az = (_HJC_LATERAL[0] * pw_mm + _HJC_LATERAL[1]) / 1000.0
    centres = {side: origin + ax * x + ay * y + sign * az * z
               for side, sign in (("left", -1.0), ("right", 1.0))}
    return centres, width, depth


def segment_lengths(trial: Trial, names: SegmentMarkerMap | None = None) -> SegmentLengths:
    """Thigh and shank lengths [m] of each side from a static trial (module docstring).

    Raises
    ------
    DataError
        A pelvis landmark is missing, or a landmark is never visible (the message names the
        marker and the file). A side without both knee markers has neither length, a side
        with its knee but not both ankle markers (a residual limb) its thigh alone.
    """
    names = names or SegmentMarkerMap()
    hips, width, depth = _hip_centres(trial, names)
    thigh, shank = {}, {}
    for side, prefix in names.sides.items():
        knee_labels = [names.knee_lateral.format(side=prefix),
                       names.knee_medial.format(side=prefix)]
        ankle_labels = [names.ankle_lateral.format(side=prefix),
                        names.ankle_medial.format(side=prefix)]
        has_knee = all(label in trial.markers for label in knee_labels)
        has_ankle = all(label in trial.markers for label in ankle_labels)
        if not has_knee:
            thigh[side] = shank[side] = math.nan
            continue
        knee = 0.5 * (_mean(trial, knee_labels[0]) + _mean(trial, knee_labels[1]))
        thigh[side] = float(np.linalg.norm(hips[side] - knee))
        if has_ankle:
            ankle = 0.5 * (_mean(trial, ankle_labels[0]) + _mean(trial, ankle_labels[1]))
            shank[side] = float(np.linalg.norm(knee - ankle))
        else:
            shank[side] = math.nan
    return SegmentLengths(thigh_m=thigh, shank_m=shank, pelvic_width_m=width,
                          pelvic_depth_m=depth, source=trial.source)
