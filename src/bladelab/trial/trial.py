"""The :class:`Trial` data model: one motion-capture trial in the bladelab lab frame.

Everything is SI and in the lab frame (x forward, y lateral, z up): marker trajectories [m],
force platforms as ground reaction force on the subject [N], centre of pressure [m] and free
moment about the vertical [N·m]. Marker gaps (occluded or invalid samples) are NaN.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from bladelab.errors import DataError

#: Metadata keys a trial may carry (all optional): who ran, with which blade, how fast.
METADATA_KEYS: tuple[str, ...] = ("athlete", "side", "blade", "category", "speed_pct_pb")


@dataclasses.dataclass(frozen=True, eq=False)
class ForcePlatform:
    """One force platform, already in the lab frame.

    Attributes
    ----------
    index
        1-based platform number as in the file.
    type
        C3D platform type (1, 2, 3 or 4).
    rate
        Sampling rate [Hz] (the analog rate).
    force
        Ground reaction force on the subject [N], lab frame, shape (n, 3).
    cop
        Centre of pressure [m], lab frame, shape (n, 3); NaN where the plate is unloaded
        (vertical force under ``cop_threshold`` of the reader).
    free_moment
        Free moment about the vertical through the COP [N·m], shape (n,); NaN where unloaded.
    corners
        Plate corners [m], lab frame, shape (4, 3), in the file's order.
    channels
        Analog channel labels used by this platform.
    zero_offset_N
        Vertical zero offset [N] the reader removed (0 when the plate was zeroed or the removal
        was off); see :mod:`bladelab.trial.platforms`.
    """

    index: int
    type: int
    rate: float
    force: np.ndarray
    cop: np.ndarray
    free_moment: np.ndarray
    corners: np.ndarray
    channels: tuple[str, ...] = ()
    zero_offset_N: float = 0.0

    def __post_init__(self) -> None:
        force = np.asarray(self.force, dtype=float)
        n = force.shape[0]
        if force.ndim != 2 or force.shape[1] != 3:
            raise DataError(f"force has shape {force.shape}, expected (n, 3)", where=self.name)
        cop = np.asarray(self.cop, dtype=float)
        if cop.shape != (n, 3):
            raise DataError(f"cop has shape {cop.shape}, expected ({n}, 3)", where=self.name)
        free = np.asarray(self.free_moment, dtype=float)
        if free.shape != (n,):
            raise DataError(f"free_moment has shape {free.shape}, expected ({n},)", where=self.name)
        object.__setattr__(self, "force", force)
        object.__setattr__(self, "cop", cop)
        object.__setattr__(self, "free_moment", free)
        object.__setattr__(self, "corners", np.asarray(self.corners, dtype=float).reshape(4, 3))
        object.__setattr__(self, "channels", tuple(self.channels))

    @property
    def name(self) -> str:
        """``platform N`` (for messages)."""
        return f"platform {self.index}"

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.force.shape[0])

    @property
    def time(self) -> np.ndarray:
        """Sample times [s] from the first analog frame."""
        return np.arange(self.n_samples) / self.rate

    def to_dict(self) -> dict[str, Any]:
        """Summary (no samples): index, type, rate_Hz, channels, corners_m, zero_offset_N."""
        return {
            "index": self.index,
            "type": self.type,
            "rate_Hz": self.rate,
            "n_samples": self.n_samples,
            "channels": list(self.channels),
            "corners_m": self.corners.round(4).tolist(),
            "zero_offset_N": self.zero_offset_N,
        }


@dataclasses.dataclass(frozen=True, eq=False)
class Trial:
    """A motion-capture trial: markers, analog channels and force platforms, lab frame, SI.

    Attributes
    ----------
    markers
        ``label -> (n_frames, 3)`` positions [m]; NaN marks a gap (occluded/invalid sample).
    marker_rate
        Marker sampling rate [Hz].
    analogs
        ``label -> (n_analog,)`` analog channels as stored in the file (scaled, file units).
    analog_rate
        Analog sampling rate [Hz].
    platforms
        Force platforms in the lab frame.
    metadata
        athlete, side, blade, category, speed_pct_pb (when known) and ``source``, ``point_units``,
        ``axes`` (how file axes were mapped to the lab frame).
    """

    markers: dict[str, np.ndarray]
    marker_rate: float
    analogs: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    analog_rate: float = 0.0
    platforms: tuple[ForcePlatform, ...] = ()
    metadata: dict[str, Any] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        markers = {}
        n = None
        for label, xyz in self.markers.items():
            arr = np.asarray(xyz, dtype=float)
            if arr.ndim != 2 or arr.shape[1] != 3:
                raise DataError(f"has shape {arr.shape}, expected (n, 3)", where=f"marker {label}")
            if n is not None and arr.shape[0] != n:
                raise DataError(f"has {arr.shape[0]} frames, others {n}", where=f"marker {label}")
            n = arr.shape[0]
            markers[label] = arr
        object.__setattr__(self, "markers", markers)
        object.__setattr__(self, "platforms", tuple(self.platforms))

    @property
    def source(self) -> str | None:
        """The file the trial was read from, if any."""
        return self.metadata.get("source")

    @property
    def n_frames(self) -> int:
        """Number of marker frames (0 without markers)."""
        return next((len(v) for v in self.markers.values()), 0)

    @property
    def marker_time(self) -> np.ndarray:
        """Marker frame times [s]."""
        return np.arange(self.n_frames) / self.marker_rate

    @property
    def duration(self) -> float:
        """Trial duration [s] (markers, or the first platform without markers)."""
        if self.n_frames:
            return self.n_frames / self.marker_rate
        if self.platforms:
            return self.platforms[0].n_samples / self.platforms[0].rate
        return 0.0

    def marker(self, label: str) -> np.ndarray:
        """Trajectory of ``label`` [m], shape (n, 3).

        Raises
        ------
        DataError
            The marker does not exist; the message lists the ones that do.
        """
        try:
            return self.markers[label]
        except KeyError:
            raise DataError(
                f"no marker named {label!r}; the trial has: {', '.join(self.markers) or '(none)'}",
                file=self.source,
                where=f"marker {label}",
                hint="map the role to an existing marker with --markers MAP.yaml",
            ) from None

    def info(self) -> dict[str, Any]:
        """Summary for ``bladelab trial info`` (JSON-serialisable)."""
        return {
            "source": self.source,
            "duration_s": round(self.duration, 6),
            "marker_rate_Hz": self.marker_rate,
            "n_frames": self.n_frames,
            "point_units": self.metadata.get("point_units"),
            "axes": self.metadata.get("axes"),
            "markers": list(self.markers),
            "analog_rate_Hz": self.analog_rate,
            "analogs": list(self.analogs),
            "platforms": [p.to_dict() for p in self.platforms],
            "metadata": {k: self.metadata[k] for k in METADATA_KEYS if k in self.metadata},
            "warnings": list(self.metadata.get("warnings", [])),
        }
