"""Blade kinematics from markers, and the stance window handed to simulation.

Markers (names configurable with a :class:`MarkerMap`, or a YAML file of the same keys):

==================  =================  ==========================================================
role                default name       meaning
==================  =================  ==========================================================
clamp_anterior      ``CLAMP_ANT``      front of the clamp (pylon adapter), on the clamp's x axis
clamp_posterior     ``CLAMP_POST``     back of the clamp, on the clamp's x axis
tip                 ``BLADE_TIP``      distal end of the blade (segment 16 in seed 000)
==================  =================  ==========================================================

The clamp origin is the midpoint of the two clamp markers. The clamp pitch is the rotation
about +y of the clamp's x axis (from ``CLAMP_POST`` to ``CLAMP_ANT``), right-hand rule:
``pitch = atan2(-dz, dx)``; 0 when the two markers are level, positive when the front is lower
(+z turned toward +x). The characteristic distance d(t) is the 3-D distance between the clamp
origin and the tip marker; Δd = d0 − d(t), with d0 the distance at touch-down (seed 000 §2.1,
§2.4).

The stance window (seed 000 §2.1: "the GRF window centred on the GRF peak") runs from
``t_peak − h`` to ``t_peak + h`` with ``h = max(t_peak − t_touchdown, t_toeoff − t_peak) + margin``
(default margin 20 ms), clipped to the recording, so it includes at least ``margin`` before
touch-down and after toe-off. Signals are filtered (markers 20 Hz, forces 75 Hz, 4th-order
zero-lag Butterworth, as in seed 002) and resampled to one rate (default 1000 Hz) by cubic
interpolation (markers) and linear interpolation (forces).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, ValidationError

from bladelab._io import read_yaml
from bladelab.errors import DataError, SpecError
from bladelab.trial.events import StanceEvent, combined_grf, detect_stances
from bladelab.trial.filters import fill_gaps, lowpass
from bladelab.trial.stance import Stance
from bladelab.trial.trial import METADATA_KEYS, Trial

__all__ = [
    "BladeKinematics",
    "MarkerMap",
    "blade_kinematics",
    "compression",
    "extract_stance",
    "load_marker_map",
    "stance_window",
]


class MarkerMap(BaseModel):
    """Which trial markers play the clamp and tip roles (see the module docstring)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    clamp_anterior: str = "CLAMP_ANT"
    clamp_posterior: str = "CLAMP_POST"
    tip: str = "BLADE_TIP"


def load_marker_map(path: str | Path) -> MarkerMap:
    """Read a YAML marker map (keys ``clamp_anterior``, ``clamp_posterior``, ``tip``).

    Raises
    ------
    InputFileError
        Missing file or invalid YAML.
    SpecError
        Unknown keys or non-string values.
    """
    path = Path(path)
    data = read_marker_yaml(path, "a marker map is a mapping role: marker name")
    return validated_marker_map(
        MarkerMap,
        data,
        path,
        "keys: clamp_anterior, clamp_posterior, tip (marker names as strings)",
    )


def read_marker_yaml(path: Path, shape_hint: str) -> dict:
    """The mapping in a YAML marker-map file (errors name the file; ``shape_hint`` says what
    the mapping should look like)."""
    data = read_yaml(path, what="marker map", hint="check the --markers path") or {}
    if not isinstance(data, dict):
        raise SpecError(shape_hint, file=path)
    return data


def validated_marker_map(model: type, data: dict, path: Path, hint: str):
    """``model(**data)`` (a pydantic marker map), its first validation error as a SpecError
    naming the file and the field."""
    try:
        return model(**data)
    except ValidationError as err:
        first = err.errors()[0]
        raise SpecError(
            first["msg"], file=path, where=".".join(str(x) for x in first["loc"]), hint=hint
        ) from err


@dataclasses.dataclass(frozen=True, eq=False)
class BladeKinematics:
    """Clamp pose, tip and characteristic distance on the marker time base.

    Attributes
    ----------
    time
        [s], shape (n,).
    clamp_origin
        Midpoint of the clamp markers [m], shape (n, 3).
    clamp_pitch
        [rad], shape (n,).
    tip
        Tip marker [m], shape (n, 3).
    distance
        d(t) = |tip − clamp origin| [m], shape (n,).
    """

    time: np.ndarray
    clamp_origin: np.ndarray
    clamp_pitch: np.ndarray
    tip: np.ndarray
    distance: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        """Arrays as lists (SI)."""
        return {f.name: getattr(self, f.name).tolist() for f in dataclasses.fields(self)}


def blade_kinematics(
    trial: Trial,
    *,
    markers: MarkerMap | None = None,
    cutoff: float | None = 20.0,
    order: int = 4,
    max_gap: float = 0.1,
    span: tuple[float, float] | None = None,
) -> BladeKinematics:
    """Clamp origin, clamp pitch, tip and d(t) from the markers.

    Parameters
    ----------
    trial
        The trial.
    markers
        Marker roles (default names when None).
    cutoff, order
        Marker low-pass [Hz] (None: unfiltered).
    max_gap
        Longest marker gap [s] that is filled.
    span
        Only this time span [s] is used (gaps elsewhere do not matter); None: the whole trial.

    Raises
    ------
    DataError
        A marker is missing (the message lists the existing ones), has a gap longer than
        ``max_gap``, or is missing at the edges of ``span``.
    """
    markers = markers or MarkerMap()
    rate = trial.marker_rate
    n = trial.n_frames
    a, b = 0, n
    if span is not None:
        a = max(int(np.floor(span[0] * rate)), 0)
        b = min(int(np.ceil(span[1] * rate)) + 1, n)
    xyz = {}
    for role in ("clamp_anterior", "clamp_posterior", "tip"):
        label = getattr(markers, role)
        raw = trial.marker(label)[a:b]
        where = f"marker {label} ({role})"
        filled, _ = fill_gaps(
            raw, rate=rate, max_gap=max_gap, where=where, file=trial.source, first_frame=a
        )
        if np.any(~np.isfinite(filled)):
            bad = np.flatnonzero(~np.all(np.isfinite(filled), axis=1))
            raise DataError(
                f"missing at frames {a + bad[0]}–{a + bad[-1]} (t = {(a + bad[0]) / rate:.3f}–"
                f"{(a + bad[-1]) / rate:.3f} s), at the edge of the span where it cannot be filled",
                file=trial.source,
                where=where,
                hint="choose another stance or repair the trajectory",
            )
        if cutoff is not None:
            # filter the filled signal (its gaps are short and already interpolated)
            filled = lowpass(filled, rate, cutoff, order=order, where=where, file=trial.source)
        xyz[role] = filled
    ant, post, tip = xyz["clamp_anterior"], xyz["clamp_posterior"], xyz["tip"]
    origin = 0.5 * (ant + post)
    d = ant - post
    pitch = np.arctan2(-d[:, 2], d[:, 0])
    distance = np.linalg.norm(tip - origin, axis=1)
    return BladeKinematics(
        time=np.arange(a, b) / rate,
        clamp_origin=origin,
        clamp_pitch=pitch,
        tip=tip,
        distance=distance,
    )


def compression(
    distance: np.ndarray, time: np.ndarray, touchdown_s: float
) -> tuple[np.ndarray, float]:
    """Δd(t) = d0 − d(t) [m] with d0 = d at touch-down (linear interpolation); returns (Δd, d0)."""
    d0 = float(np.interp(touchdown_s, time, distance))
    return d0 - np.asarray(distance, dtype=float), d0


def stance_window(
    event: StanceEvent, *, margin: float = 0.02, duration: float | None = None
) -> tuple[float, float]:
    """Window [s] centred on the GRF peak, covering touch-down and toe-off plus ``margin``.

    ``duration`` (the recording length [s]) clips the window when given.
    """
    half = max(event.peak_time_s - event.start_s, event.end_s - event.peak_time_s) + margin
    t0, t1 = event.peak_time_s - half, event.peak_time_s + half
    if duration is not None:
        t0, t1 = max(t0, 0.0), min(t1, duration)
    return t0, t1


def extract_stance(
    trial: Trial,
    index: int,
    *,
    markers: MarkerMap | None = None,
    rate: float = 1000.0,
    margin: float = 0.02,
    threshold: float = 20.0,
    marker_cutoff: float | None = 20.0,
    force_cutoff: float | None = 75.0,
    order: int = 4,
    max_gap: float = 0.1,
    stances: list[StanceEvent] | None = None,
) -> Stance:
    """Cut stance ``index`` out of a trial as a :class:`~bladelab.trial.stance.Stance`.

    Parameters
    ----------
    trial
        The trial (markers and force platforms).
    index
        Position in :func:`~bladelab.trial.events.detect_stances`'s list, from 0 (stance N of
        ``bladelab trial stances`` is index N − 1; error messages give the stance number N).
    markers
        Marker roles (default names when None).
    rate
        Output sampling rate [Hz].
    margin
        Window margin before touch-down and after toe-off [s] (see :func:`stance_window`).
    threshold
        Stance detection threshold [N] (ignored when ``stances`` is given).
    marker_cutoff, force_cutoff, order
        Low-pass cut-offs [Hz] (None: unfiltered; the force filter is skipped when the cut-off
        is not below Nyquist).
    max_gap
        Longest marker gap [s] that is filled.
    stances
        Pre-computed stances (else detected here).

    Returns
    -------
    Stance
        Uniform time base starting at 0 at the window start; metadata holds source, stance (its
        number, from 1), plates, window_start_s (trial time of t = 0), touchdown_s, toeoff_s,
        peak_s (relative to the window), d0_m, marker names, filter settings and the trial
        metadata.

    Raises
    ------
    DataError
        No such stance, missing markers, long gaps, NaN forces.
    """
    if rate <= 0:
        raise DataError(f"rate must be positive, got {rate}", where="rate")
    markers = markers or MarkerMap()
    events = stances if stances is not None else detect_stances(trial, threshold=threshold)
    if not 0 <= index < len(events):
        # messages number stances from 1, as `bladelab trial stances`, --stance and study.yaml do
        n = len(events)
        raise DataError(
            f"no stance {index + 1}: the trial has {n} stance"
            + (" (stance 1)" if n == 1 else f"s, numbered 1–{n}"),
            file=trial.source,
            where="stance",
            hint="list them with `bladelab trial stances`; in Python, extract_stance's index "
                 "counts from 0 (stance N is index N − 1)",
        )
    ev = events[index]
    t0, t1 = stance_window(ev, margin=margin, duration=min(trial.duration, _force_duration(trial)))
    pad = 0.1 + (2.0 / marker_cutoff if marker_cutoff else 0.0)
    kin = blade_kinematics(
        trial,
        markers=markers,
        cutoff=marker_cutoff,
        order=order,
        max_gap=max_gap,
        span=(max(t0 - pad, 0.0), t1 + pad),
    )
    n_out = int(np.floor((t1 - t0) * rate + 1e-9)) + 1
    t = t0 + np.arange(n_out) / rate
    t = t[t <= min(kin.time[-1], _force_duration(trial)) + 1e-12]
    if t.size < 3:
        raise DataError(
            "the stance window holds fewer than 3 samples",
            file=trial.source,
            where=f"stance {index + 1}",
        )

    from scipy import interpolate  # here, not at the top: `bladelab trial info` stays quick

    def spline(values: np.ndarray) -> np.ndarray:
        return interpolate.CubicSpline(kin.time, values, axis=0)(t)

    origin = spline(kin.clamp_origin)
    pitch = spline(np.unwrap(kin.clamp_pitch))
    distance = spline(kin.distance)

    force, _ = combined_grf(trial, ev.plates)
    frate = trial.platforms[0].rate
    if force_cutoff is not None and force_cutoff < frate / 2.0:
        force = lowpass(force, frate, force_cutoff, order=order, where="GRF", file=trial.source)
    ft = np.arange(force.shape[0]) / frate
    grf = np.column_stack([np.interp(t, ft, force[:, i]) for i in range(3)])

    _, d0 = compression(kin.distance, kin.time, ev.start_s)
    meta: dict[str, Any] = {k: trial.metadata[k] for k in METADATA_KEYS if k in trial.metadata}
    meta.update(
        {
            "source": trial.source or "",
            "stance": index + 1,  # numbered from 1, as `bladelab trial stances` lists it
            "plates": " ".join(str(p) for p in ev.plates),
            "window_start_s": round(float(t[0]), 6),
            "touchdown_s": round(ev.start_s - float(t[0]), 6),
            "toeoff_s": round(ev.end_s - float(t[0]), 6),
            "peak_s": round(ev.peak_time_s - float(t[0]), 6),
            "d0_m": round(d0, 6),
            "marker_clamp_anterior": markers.clamp_anterior,
            "marker_clamp_posterior": markers.clamp_posterior,
            "marker_tip": markers.tip,
            "marker_cutoff_Hz": marker_cutoff if marker_cutoff is not None else "none",
            "force_cutoff_Hz": force_cutoff if force_cutoff is not None else "none",
            "filter_order": order,
            "rate_Hz": rate,
        }
    )
    return Stance(
        time=t - t[0],
        clamp_x=origin[:, 0],
        clamp_y=origin[:, 1],
        clamp_z=origin[:, 2],
        clamp_pitch=pitch,
        grf_x=grf[:, 0],
        grf_y=grf[:, 1],
        grf_z=grf[:, 2],
        distance=distance,
        metadata=meta,
    )


def _force_duration(trial: Trial) -> float:
    """Length [s] of the force recording (last analog sample time)."""
    p = trial.platforms[0]
    return (p.n_samples - 1) / p.rate
