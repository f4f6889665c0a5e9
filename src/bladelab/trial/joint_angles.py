"""Sagittal joint angles from markers, and which leg each stance belongs to.

Segments (marker roles, names configurable with a :class:`JointMarkerMap`; ``{side}`` in a
name is replaced by the side's prefix, ``L`` or ``R`` by default; a role with several markers
uses their mean). The defaults fit the marker set of the Fukuchi et al. (2017) running data set
(``RBDS001runT35.c3d``: pelvis landmarks and 4-marker thigh and shank clusters, heel and
metatarsal markers):

=====================  ===================================  ===================================
role                   default markers                      meaning
=====================  ===================================  ===================================
pelvis_anterior        ``L.ASIS``, ``R.ASIS``               front of the pelvis
pelvis_posterior       ``L.PSIS``, ``R.PSIS``               back of the pelvis
thigh_proximal         ``{side}.Thigh.Top.Lateral/Medial``  upper end of the thigh axis
thigh_distal           ``{side}.Thigh.Bottom.Lateral/...``  lower end of the thigh axis
shank_proximal         ``{side}.Shank.Top.Lateral/Medial``  upper end of the shank axis
shank_distal           ``{side}.Shank.Bottom.Lateral/...``  lower end of the shank axis
foot_posterior         ``{side}.Heel.Top``                  back of the foot axis
foot_anterior          ``{side}.MT1``, ``{side}.MT5``       front of the foot axis
contact                heel markers, MT1, MT5               over the centre of pressure in stance
=====================  ===================================  ===================================

``left`` / ``right`` override roles for one side (an amputee's prosthetic side: the pylon or
blade markers as ``shank_*`` and ``contact``; a side without foot markers has no ankle angle).

Angles (sagittal plane = the lab x–z plane; x forward, z up), from segment orientations
φ = atan2(d_x, −d_z) of each proximal→distal axis d (0 hanging straight down, positive when
the distal end is ahead):

- trunk pitch θ = pelvis forward lean, atan2(−a_z, a_x) of a = anterior − posterior (a
  rotation about +y turning +z toward +x, the project's pitch convention);
- hip flexion = φ_thigh + θ (thigh relative to the pelvis);
- knee flexion = φ_thigh − φ_shank;
- ankle dorsiflexion = α_foot − φ_shank with α_foot = atan2(f_z, f_x) of the foot axis f.

Neutral offsets: with a static (standing) trial, each angle's mean in the static trial is
subtracted, so standing upright is 0 for every joint and for the trunk (what the runner model's
zero posture is). Without one, the angles are those of the marker axes (they depend on where the
clusters sit: a pelvis with ASIS below PSIS reads about 10° of lean).

Markers are low-pass filtered before the angles (zero-lag Butterworth, 20 Hz, as seed 002) after
filling short gaps; longer gaps stay NaN.

Leg of each stance (:func:`stance_legs`): the side whose ``contact`` markers are closer
(horizontally, median over the middle half of the contact) to the force platform's centre of
pressure.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from pydantic import BaseModel, ConfigDict

from bladelab.errors import DataError, SpecError
from bladelab.trial.events import StanceEvent, combined_grf
from bladelab.trial.filters import lowpass
from bladelab.trial.kinematics import read_marker_yaml, validated_marker_map
from bladelab.trial.trial import Trial

__all__ = [
    "JOINT_ROLES",
    "JointAngles",
    "JointMarkerMap",
    "load_joint_marker_map",
    "sagittal_angles",
    "stance_legs",
]

JOINT_ROLES: tuple[str, ...] = (
    "pelvis_anterior",
    "pelvis_posterior",
    "thigh_proximal",
    "thigh_distal",
    "shank_proximal",
    "shank_distal",
    "foot_posterior",
    "foot_anterior",
    "contact",
)
SIDES: tuple[str, ...] = ("left", "right")
_PELVIS = ("pelvis_anterior", "pelvis_posterior")


class JointMarkerMap(BaseModel):
    """Which markers define the segments (see the module docstring); YAML with the same keys."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    pelvis_anterior: tuple[str, ...] = ("L.ASIS", "R.ASIS")
    pelvis_posterior: tuple[str, ...] = ("L.PSIS", "R.PSIS")
    thigh_proximal: tuple[str, ...] = ("{side}.Thigh.Top.Lateral", "{side}.Thigh.Top.Medial")
    thigh_distal: tuple[str, ...] = ("{side}.Thigh.Bottom.Lateral", "{side}.Thigh.Bottom.Medial")
    shank_proximal: tuple[str, ...] = ("{side}.Shank.Top.Lateral", "{side}.Shank.Top.Medial")
    shank_distal: tuple[str, ...] = ("{side}.Shank.Bottom.Lateral", "{side}.Shank.Bottom.Medial")
    foot_posterior: tuple[str, ...] = ("{side}.Heel.Top",)
    foot_anterior: tuple[str, ...] = ("{side}.MT1", "{side}.MT5")
    contact: tuple[str, ...] = ("{side}.Heel.Top", "{side}.Heel.Bottom", "{side}.MT1", "{side}.MT5")
    side_prefix: dict[str, str] = {"left": "L", "right": "R"}
    left: dict[str, tuple[str, ...]] = {}
    right: dict[str, tuple[str, ...]] = {}

    def names(self, role: str, side: str | None = None) -> tuple[str, ...]:
        """Marker names of ``role`` (on ``side`` for a leg role), ``{side}`` substituted."""
        if role not in JOINT_ROLES:
            raise SpecError(
                f"unknown marker role {role!r}",
                where="marker map",
                hint=f"roles: {', '.join(JOINT_ROLES)}",
            )
        over = getattr(self, side) if side in SIDES else {}
        names = over.get(role, getattr(self, role))
        prefix = self.side_prefix.get(side, "") if side else ""
        return tuple(n.replace("{side}", prefix) for n in names)


def load_joint_marker_map(path: str | Path) -> JointMarkerMap:
    """Read a YAML joint marker map (keys: the roles, ``side_prefix``, ``left``, ``right``).

    Raises
    ------
    InputFileError
        Missing file or invalid YAML.
    SpecError
        Unknown keys or wrong types.
    """
    path = Path(path)
    data = read_marker_yaml(path, "a marker map is a mapping role: [marker names]")
    data = {k: ([v] if isinstance(v, str) else v) for k, v in data.items()}
    for side in SIDES:
        if isinstance(data.get(side), dict):
            bad = [k for k in data[side] if k not in JOINT_ROLES]
            if bad:
                raise SpecError(
                    f"unknown roles {bad}",
                    file=path,
                    where=side,
                    hint=f"roles: {', '.join(JOINT_ROLES)}",
                )
            data[side] = {k: ([v] if isinstance(v, str) else v) for k, v in data[side].items()}
    return validated_marker_map(
        JointMarkerMap,
        data,
        path,
        f"keys: {', '.join(JOINT_ROLES)}, side_prefix, left, right",
    )


@dataclasses.dataclass(frozen=True, eq=False)
class JointAngles:
    """Sagittal joint angles on the marker time base.

    Attributes
    ----------
    time
        [s], shape (n,).
    angles
        ``trunk_pitch``, ``hip_left``, ``knee_left``, ``ankle_left``, ``hip_right`` ... [rad]
        (flexion / dorsiflexion / forward lean positive), shape (n,) each; NaN in marker gaps.
    offsets
        The static trial's mean of each angle [rad] that was subtracted (empty without one).
    source
        The trial's file.
    """

    time: np.ndarray
    angles: Mapping[str, np.ndarray]
    offsets: Mapping[str, float]
    source: str | None = None

    def to_frame(self) -> pd.DataFrame:
        """``time_s`` and ``<angle>_deg`` columns."""
        df = pd.DataFrame({"time_s": self.time})
        for k, v in self.angles.items():
            df[f"{k}_deg"] = np.degrees(v)
        return df

    def to_dict(self) -> dict[str, Any]:
        """Summary: source, samples, angle names, offsets in degrees."""
        return {
            "source": self.source,
            "n_samples": int(self.time.size),
            "angles": list(self.angles),
            "offsets_deg": {k: float(np.degrees(v)) for k, v in self.offsets.items()},
        }


def _mean_marker(trial: Trial, names: Sequence[str], role: str, side: str | None) -> np.ndarray:
    missing = [n for n in names if n not in trial.markers]
    if missing or not names:
        what = f"{role}" + (f" ({side})" if side else "")
        raise DataError(
            f"marker {missing[0] if missing else '(none)'} for {what} is not in the trial; it has: "
            f"{', '.join(trial.markers) or '(none)'}",
            file=trial.source,
            where=f"marker {missing[0] if missing else role}",
            hint="map the role to existing markers with --markers MAP.yaml (docs/design.md)",
        )
    return np.mean([trial.markers[n] for n in names], axis=0)


def _segment(d: np.ndarray) -> np.ndarray:
    """Orientation of a proximal->distal axis from straight down, positive forward [rad]."""
    return np.arctan2(d[:, 0], -d[:, 2])


def _raw_angles(
    trial: Trial, markers: JointMarkerMap, cutoff_hz: float | None, sides: Sequence[str]
) -> dict[str, np.ndarray]:
    cache: dict[tuple, np.ndarray] = {}

    def pos(role: str, side: str | None) -> np.ndarray:
        names = markers.names(role, side)
        key = names
        if key not in cache:
            xyz = _mean_marker(trial, names, role, side)
            if cutoff_hz is not None and cutoff_hz < trial.marker_rate / 2:
                xyz = lowpass(
                    xyz,
                    trial.marker_rate,
                    cutoff_hz,
                    where=f"{role} ({'+'.join(names)})",
                    file=trial.source,
                )
            cache[key] = xyz
        return cache[key]

    a = pos("pelvis_anterior", None) - pos("pelvis_posterior", None)
    lean = np.arctan2(-a[:, 2], a[:, 0])
    out = {"trunk_pitch": lean}
    for side in sides:
        thigh = _segment(pos("thigh_distal", side) - pos("thigh_proximal", side))
        shank = _segment(pos("shank_distal", side) - pos("shank_proximal", side))
        out[f"hip_{side}"] = thigh + lean
        out[f"knee_{side}"] = thigh - shank
        over = getattr(markers, side)
        has_foot = not (
            ("foot_anterior" in over and not over["foot_anterior"])
            or ("foot_posterior" in over and not over["foot_posterior"])
        )
        if has_foot:
            f = pos("foot_anterior", side) - pos("foot_posterior", side)
            out[f"ankle_{side}"] = np.arctan2(f[:, 2], f[:, 0]) - shank
    return out


def sagittal_angles(
    trial: Trial,
    *,
    markers: JointMarkerMap | None = None,
    static: Trial | None = None,
    cutoff_hz: float | None = 20.0,
    sides: Sequence[str] = SIDES,
) -> JointAngles:
    """Sagittal trunk, hip, knee and ankle angles of a trial (see the module docstring).

    Parameters
    ----------
    trial
        The trial (lab frame).
    markers
        Marker roles (default :class:`JointMarkerMap`, the Fukuchi marker set).
    static
        A standing trial of the same person and marker set, in the same lab frame (read it with
        the running trial's ``axes``); its mean angles become zero.
    cutoff_hz
        Low-pass of the marker trajectories [Hz] (None: no filtering).
    sides
        Legs to compute (``left``, ``right``); a side whose map sets the foot roles to ``[]``
        has no ankle angle.

    Returns
    -------
    JointAngles

    Raises
    ------
    DataError
        A marker is missing (the message names it, the role and the file), or the static trial
        has no valid frame.
    """
    markers = markers or JointMarkerMap()
    bad = [s for s in sides if s not in SIDES]
    if bad:
        raise SpecError(f"unknown side {bad[0]!r}", where="sides", hint="left or right")
    raw = _raw_angles(trial, markers, cutoff_hz, sides)
    offsets: dict[str, float] = {}
    if static is not None:
        st = _raw_angles(static, markers, None, sides)
        for k in raw:
            v = st[k][np.isfinite(st[k])]
            if v.size == 0:
                raise DataError(
                    f"no frame of the static trial has the markers of {k}",
                    file=static.source,
                    where=k,
                    hint="use a static trial in which these markers are visible",
                )
            offsets[k] = float(np.mean(v))
            raw[k] = raw[k] - offsets[k]
    return JointAngles(trial.marker_time, raw, offsets, trial.source)


def stance_legs(
    trial: Trial,
    stances: Sequence[StanceEvent],
    *,
    markers: JointMarkerMap | None = None,
) -> list[str]:
    """The leg (``"left"`` / ``"right"``) of each stance: the side whose contact markers lie
    closest to the centre of pressure (horizontal distance, median over the middle half).

    Raises
    ------
    DataError
        A contact marker is missing, or a stance has no centre of pressure near either foot.
    """
    markers = markers or JointMarkerMap()
    contact = {s: _mean_marker(trial, markers.names("contact", s), "contact", s) for s in SIDES}
    mt = trial.marker_time
    rate = trial.platforms[0].rate
    legs = []
    for ev in stances:
        _, cop = combined_grf(trial, ev.plates)
        q = (ev.end_sample - ev.start_sample) // 4
        idx = np.arange(ev.start_sample + q, ev.end_sample - q)
        t = idx / rate
        dist = {}
        for s, xyz in contact.items():
            xy = np.column_stack([np.interp(t, mt, xyz[:, i]) for i in range(2)])
            d = np.linalg.norm(xy - cop[idx, :2], axis=1)
            d = d[np.isfinite(d)]
            dist[s] = float(np.median(d)) if d.size else np.inf
        if not np.isfinite(min(dist.values())):
            raise DataError(
                f"stance {ev.index + 1} ({ev.start_s:.3f} s): no centre of pressure "
                "or contact markers to tell the leg",
                file=trial.source,
                where=f"platforms {ev.plates}",
            )
        legs.append(min(dist, key=dist.get))
    return legs
