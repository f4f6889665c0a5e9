"""One prosthetic stance, ready for simulation: the object the characterise workflow consumes.

A :class:`Stance` holds, on one uniform time base, the clamp pose (x, y, z [m], pitch [rad]),
the ground reaction force (x, y, z [N]) and the characteristic distance d(t) between clamp
origin and blade tip [m]. It is written and read as the documented *stance CSV*
(``docs/stance-csv.md``): columns ``time`` [s], ``clamp_x``, ``clamp_y``, ``clamp_z`` [m],
``clamp_pitch`` [deg], ``grf_x``, ``grf_y``, ``grf_z`` [N], ``distance`` [m], and metadata as
``# key: value`` header lines.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from bladelab import units
from bladelab._io import atomic_open
from bladelab.errors import DataError, InputFileError

STANCE_COLUMNS: tuple[str, ...] = (
    "time",
    "clamp_x",
    "clamp_y",
    "clamp_z",
    "clamp_pitch",
    "grf_x",
    "grf_y",
    "grf_z",
    "distance",
)
STANCE_UNITS: dict[str, str] = {
    "time": "s",
    "clamp_x": "m",
    "clamp_y": "m",
    "clamp_z": "m",
    "clamp_pitch": "deg",
    "grf_x": "N",
    "grf_y": "N",
    "grf_z": "N",
    "distance": "m",
}


@dataclasses.dataclass(frozen=True, eq=False)
class Stance:
    """A stance window on a uniform time base (SI units inside).

    Attributes
    ----------
    time
        Sample times [s], uniform, shape (n,).
    clamp_x, clamp_y, clamp_z
        Clamp origin in the lab frame [m] (x forward, z up).
    clamp_pitch
        Clamp pitch about +y [rad].
    grf_x, grf_y, grf_z
        Ground reaction force on the blade [N].
    distance
        Characteristic distance clamp origin – blade tip [m]; NaN where unknown.
    metadata
        Free-form ``key -> value`` (athlete, side, blade, category, speed_pct_pb, source, ...).
    """

    time: np.ndarray
    clamp_x: np.ndarray
    clamp_y: np.ndarray
    clamp_z: np.ndarray
    clamp_pitch: np.ndarray
    grf_x: np.ndarray
    grf_y: np.ndarray
    grf_z: np.ndarray
    distance: np.ndarray
    metadata: dict[str, Any] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        n = len(self.time)
        for name in STANCE_COLUMNS:
            arr = np.asarray(getattr(self, name), dtype=float)
            if arr.shape != (n,):
                raise DataError(
                    f"has shape {arr.shape}, expected ({n},) like 'time'", where=f"stance.{name}"
                )
            object.__setattr__(self, name, arr)

    @property
    def sample_rate(self) -> float:
        """Sampling rate [Hz]."""
        return 1.0 / float(np.median(np.diff(self.time)))

    @property
    def duration(self) -> float:
        """Duration of the window [s]."""
        return float(self.time[-1] - self.time[0])

    def column(self, name: str) -> np.ndarray:
        """A column in stance-CSV units (``clamp_pitch`` in deg, the rest SI)."""
        values = getattr(self, name)
        return units.rad2deg(values) if name == "clamp_pitch" else values


def write_stance_csv(stance: Stance, path: str | Path) -> Path:
    """Write ``stance`` as a stance CSV (atomically) and return the path."""
    path = Path(path)
    table = np.column_stack([stance.column(name) for name in STANCE_COLUMNS])
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("# bladelab stance CSV v1\n")
        fh.write("# units: " + ", ".join(f"{c} [{STANCE_UNITS[c]}]" for c in STANCE_COLUMNS) + "\n")
        for key, value in stance.metadata.items():
            fh.write(f"# {key}: {value}\n")
        fh.write(",".join(STANCE_COLUMNS) + "\n")
        np.savetxt(fh, table, delimiter=",", fmt="%.9g")
    return path


def read_stance_csv(path: str | Path) -> Stance:
    """Read a stance CSV written by bladelab or by the user's own processing software.

    Raises
    ------
    InputFileError
        The file is missing or not a CSV.
    DataError
        A column is missing, a value is not finite, time is not uniform and increasing, or the
        values look like they are in the wrong units (mm instead of m, kN instead of N, ms
        instead of s, rad instead of deg).
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError("file not found", file=path, hint="check the path")
    metadata: dict[str, Any] = {}
    header: list[str] | None = None
    rows: list[list[float]] = []
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError as err:
        raise InputFileError("not a text CSV file", file=path) from err
    for lineno, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            key, sep, value = stripped[1:].partition(":")
            if sep and header is None and key.strip() not in ("units",):
                metadata[key.strip()] = _parse_meta(value.strip())
            continue
        if header is None:
            header = [h.strip() for h in stripped.split(",")]
            continue
        try:
            rows.append([float(v) if v.strip() != "" else np.nan for v in stripped.split(",")])
        except ValueError as err:
            raise DataError(f"non-numeric value ({err})", file=path, where=f"line {lineno}") from err
    if header is None:
        raise DataError("no header line", file=path, hint=f"first line must be {','.join(STANCE_COLUMNS)}")
    missing = [c for c in STANCE_COLUMNS if c not in header]
    if missing:
        raise DataError(
            f"missing column(s) {', '.join(missing)}; found {', '.join(header)}",
            file=path,
            hint="a stance CSV needs " + ", ".join(f"{c} [{STANCE_UNITS[c]}]" for c in STANCE_COLUMNS),
        )
    if not rows:
        raise DataError("no data rows", file=path)
    widths = {len(r) for r in rows}
    if widths != {len(header)}:
        raise DataError(f"rows have {sorted(widths)} fields, header has {len(header)}", file=path)
    table = np.asarray(rows, dtype=float)
    columns = {name: table[:, header.index(name)] for name in STANCE_COLUMNS}
    _validate_columns(columns, path)
    columns["clamp_pitch"] = units.deg2rad(columns["clamp_pitch"])
    metadata.setdefault("source", str(path))
    return Stance(**columns, metadata=metadata)


def _parse_meta(value: str) -> Any:
    for cast in (int, float):
        try:
            return cast(value)
        except ValueError:
            pass
    return value


# What a clamp and a blade can do, in metres: the clamp origin stays within 2 m of the ground
# (the lab's z = 0), moves at most 20 m/s on average over the window (sprinters peak near
# 12 m/s), and the clamp–tip distance of a running blade is under 2 m.
MAX_CLAMP_HEIGHT_M = 2.0
MAX_CLAMP_SPEED_M_PER_S = 20.0
MAX_DISTANCE_M = 2.0
# Length units a position column may be in by mistake: (factor to metres, name).
_LENGTH_UNITS = ((1e-2, "centimetres", 100), (1e-3, "millimetres", 1000))


def _check_position_units(columns: dict[str, np.ndarray], path: Path) -> None:
    """Refuse clamp positions or distances that are implausible in metres, naming the unit they
    most likely are in (centimetres or millimetres)."""
    duration = float(columns["time"][-1] - columns["time"][0])
    height = float(np.max(np.abs(columns["clamp_z"])))
    travel = max(float(np.ptp(columns[c])) for c in ("clamp_x", "clamp_y", "clamp_z"))
    speed = travel / duration

    def clamp_ok(scale: float) -> bool:
        return height * scale <= MAX_CLAMP_HEIGHT_M and speed * scale <= MAX_CLAMP_SPEED_M_PER_S

    if not clamp_ok(1.0):
        unit = next(((name, div) for scale, name, div in _LENGTH_UNITS if clamp_ok(scale)), None)
        evidence = (f"clamp_z up to {height:.4g} (a clamp {height:.4g} m above the ground), moving "
                    f"{travel:.4g} in {duration:.3g} s ({speed:.4g} m/s)")
        raise DataError(
            f"clamp positions look like {unit[0]}, not metres: {evidence}" if unit else
            f"clamp positions are implausible in metres: {evidence}",
            file=path, where="columns clamp_x, clamp_y, clamp_z",
            hint=(f"give the clamp positions in metres (divide by {unit[1]})" if unit else
                  "give the clamp positions in metres, lab frame, z up from the ground"),
        )
    finite = columns["distance"][np.isfinite(columns["distance"])]
    longest = float(np.max(np.abs(finite))) if finite.size else 0.0
    if longest > MAX_DISTANCE_M:
        unit = next(((name, div) for scale, name, div in _LENGTH_UNITS
                     if longest * scale <= MAX_DISTANCE_M), None)
        raise DataError(
            f"distance looks like {unit[0]}, not metres: values up to {longest:.4g}" if unit else
            f"distance is implausible in metres: values up to {longest:.4g}",
            file=path, where="column distance",
            hint=f"give the clamp–tip distance in metres{f' (divide by {unit[1]})' if unit else ''}",
        )


def _validate_columns(columns: dict[str, np.ndarray], path: Path) -> None:
    time = columns["time"]
    if len(time) < 3:
        raise DataError(f"only {len(time)} samples; a stance needs at least 3", file=path)
    for name in STANCE_COLUMNS:
        if name == "distance":
            continue  # distance may be unknown (NaN) when there is no tip marker
        bad = np.flatnonzero(~np.isfinite(columns[name]))
        if bad.size:
            raise DataError(
                f"{bad.size} missing or non-finite value(s), first at row {bad[0] + 1} "
                f"(t = {time[bad[0]] if np.isfinite(time[bad[0]]) else 'NaN'})",
                file=path,
                where=f"column {name}",
                hint="fill or interpolate gaps before exporting the stance",
            )
    dt = np.diff(time)
    if np.any(dt <= 0):
        raise DataError("time is not strictly increasing", file=path, where="column time")
    if np.ptp(dt) > 1e-3 * np.median(dt) + 1e-12:
        raise DataError(
            "time is not uniformly sampled", file=path, where="column time",
            hint="resample the stance to one rate (e.g. 1000 Hz)",
        )
    if time[-1] - time[0] > 5.0:
        raise DataError(
            f"window lasts {time[-1] - time[0]:.3g} s: time looks like ms, not s",
            file=path, where="column time", hint="time must be in seconds",
        )
    _check_position_units(columns, path)
    for name in ("clamp_x", "clamp_y", "clamp_z", "distance"):
        finite = columns[name][np.isfinite(columns[name])]
        if finite.size and np.max(np.abs(finite)) > 100.0:
            raise DataError(
                f"values up to {np.max(np.abs(finite)):.4g}: looks like mm, not m",
                file=path, where=f"column {name}", hint="positions must be in metres",
            )
    peak = float(np.max(np.abs(columns["grf_z"])))
    if peak < 50.0:
        raise DataError(
            f"peak vertical force {peak:.4g}: looks like kN or body weights, not N",
            file=path, where="column grf_z", hint="forces must be in newtons",
        )
    pitch = columns["clamp_pitch"]
    if np.ptp(pitch) > 0 and np.max(np.abs(pitch)) <= np.pi / 2 and np.ptp(pitch) < 2.0 and peak > 200:
        # A loaded blade stance pitches the clamp by tens of degrees; under 2 "deg" of range
        # with all values within ±π/2 means the column is almost surely in radians.
        raise DataError(
            f"pitch range {np.ptp(pitch):.3g} over a loaded stance: looks like rad, not deg",
            file=path, where="column clamp_pitch", hint="clamp_pitch must be in degrees",
        )
