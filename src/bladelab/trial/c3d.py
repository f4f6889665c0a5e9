"""C3D files: read a trial into the lab frame, write synthetic trials (both via ezc3d).

Reading
    The file is checked first (:mod:`bladelab.trial.c3d_format`: processor type, truncation,
    stale frame counts). Marker units come from ``POINT:UNITS`` (m, cm, mm, read leniently:
    'mete', 'meters', 'millimetres' ...); samples with a negative residual or NaN are gaps
    (NaN). Force platforms of types 1–4 (:mod:`bladelab.trial.platforms`): each platform's axes
    come from its ``CORNERS``; ``ORIGIN`` (plate axes): its x and y give the centre of the top
    surface relative to the sensor origin, and the surface lies ``|ORIGIN_z|`` above the sensor
    origin (files disagree on the sign of ``ORIGIN_z``; this reading puts the COP under the foot
    markers on the Fukuchi treadmill file and agrees with ezc3d's own force-platform module on all
    the real files). Each plate's zero offset is estimated over its unloaded periods and removed
    when larger than 5 N (``zero_offset=False`` keeps the file's values). Forces are the ground
    reaction force on the subject; the centre of pressure is computed on the plate surface and
    expressed in the lab frame, with the free moment about the vertical.

The lab frame
    bladelab's lab frame is x forward, y lateral, z up. Files differ (the Fukuchi treadmill files
    have y up), so the reader maps the file's axes onto the lab frame with a signed permutation:
    ``up`` defaults to the normal of the first force platform (else the file's +z), its sense
    taken from the markers when they lie clearly above one side of the plate's surface, else
    from the data (the ground reaction force on a loaded plate points up); a warning says when
    the corners say otherwise; ``forward`` to the direction of overground progression of
    the markers, or on a treadmill to the direction in which the horizontal force changes from
    braking to propulsion during contact. Both can be given explicitly ("+x", "-y", ...). The
    mapping used is stored in ``trial.metadata["axes"]``.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from bladelab._io import atomic_path
from bladelab.errors import SpecError
from bladelab.trial.c3d_format import C3DWarning, WarningLog, length_scale, open_c3d
from bladelab.trial.platforms import (
    SUPPORTED_PLATFORM_TYPES,
    FilePlate,
    plate_rotation,
    read_platforms,
)
from bladelab.trial.trial import METADATA_KEYS, ForcePlatform, Trial

__all__ = ["SUPPORTED_PLATFORM_TYPES", "C3DWarning", "plate_corners", "read_c3d", "write_c3d"]

_AXES = {"x": 0, "y": 1, "z": 2}


# --------------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------------


def read_c3d(
    path: str | Path,
    *,
    forward: str = "auto",
    up: str = "auto",
    cop_threshold: float = 20.0,
    zero_offset: bool = True,
) -> Trial:
    r"""Read a C3D file into a :class:`~bladelab.trial.trial.Trial` (lab frame, SI).

    Parameters
    ----------
    path
        The C3D file.
    forward, up
        The file axis ("+x", "-x", "+y", ...) that is the lab's forward (running) direction and
        the vertical; "auto" detects them (see the module docstring).
    cop_threshold
        Vertical force [N] under which a platform's COP and free moment are NaN.
    zero_offset
        Remove each platform's zero offset, estimated over its unloaded periods, when it is
        larger than 5 N (see :mod:`bladelab.trial.platforms`).

    Odd but readable files (a stale frame count, a plate that never unloads or is stuck, a
    vertical force whose sign contradicts the plate's corners) give :class:`C3DWarning`\ s, also
    kept in ``trial.metadata["warnings"]``.

    Raises
    ------
    InputFileError
        The file is missing, is not a C3D file, is truncated/corrupt, or comes from an
        unsupported (big-endian) processor type.
    DataError
        A platform has an unsupported type, references missing analog channels, or has
        degenerate corners; marker units are unknown.
    """
    path = Path(path)
    log = WarningLog()
    c3d, raw = open_c3d(path, log)
    params = c3d["parameters"]
    data = c3d["data"]

    # markers, in file axes [m]
    units_value = _param(params, "POINT", "UNITS", [])
    point_units = (str(units_value[0]) if len(units_value) else "").strip() or "mm"
    scale = length_scale(point_units, file=path, where="POINT:UNITS")
    labels = [str(s).strip() for s in _param(params, "POINT", "LABELS", [])]
    points = np.asarray(data["points"], dtype=float)[:3] * scale  # (3, n_points, n_frames)
    residuals = np.asarray(data["meta_points"]["residuals"], dtype=float)[0]
    if points.shape[1] != len(labels):
        labels = (labels + [f"POINT{i + 1}" for i in range(points.shape[1])])[: points.shape[1]]
    invalid = (residuals < 0) | ~np.all(np.isfinite(points), axis=0)
    points[:, invalid] = np.nan
    marker_rate = float(c3d["header"]["points"]["frame_rate"])

    # analogs (ezc3d returns them scaled by SCALE/GEN_SCALE/OFFSET)
    analog_labels = [str(s).strip() for s in _param(params, "ANALOG", "LABELS", [])]
    analog_units = [str(s).strip() for s in _param(params, "ANALOG", "UNITS", [])]
    analogs_arr = np.asarray(data["analogs"], dtype=float)
    analogs_arr = analogs_arr[0] if analogs_arr.ndim == 3 else analogs_arr.reshape(0, 0)
    n_analog = analogs_arr.shape[0]
    analog_labels = (analog_labels + [f"ANALOG{i + 1}" for i in range(n_analog)])[:n_analog]
    analog_rate = float(c3d["header"]["analogs"]["frame_rate"])

    # a file without analog data (e.g. a static trial) recorded no platform signals
    plates_file = (
        read_platforms(
            path, params, analogs_arr, analog_labels, analog_units, analog_rate,
            point_scale=scale, zero_offset=zero_offset,
            used_in_file=raw.platforms_used is not None, log=log,
        )
        if n_analog and analogs_arr.shape[1]
        else []
    )

    # file axes -> lab axes
    up_vec = _choose_up(up, plates_file, points, path, log)
    fwd_vec = _choose_forward(forward, up_vec, points, plates_file, analog_rate, path)
    lat_vec = np.cross(up_vec, fwd_vec)
    rot = np.vstack([fwd_vec, lat_vec, up_vec])  # lab = rot @ file

    markers = {
        label: (rot @ points[:, i, :]).T.copy() for i, label in enumerate(labels) if label
    }
    platforms = tuple(_to_lab(p, rot, up_vec, cop_threshold) for p in plates_file)

    metadata: dict[str, Any] = {"source": str(path), "point_units": point_units}
    metadata["axes"] = {
        "forward": _axis_name(fwd_vec), "lateral": _axis_name(lat_vec), "up": _axis_name(up_vec)
    }
    if log:
        metadata["warnings"] = list(log)
    names = _param(params, "SUBJECTS", "NAMES", [])
    if names and str(names[0]).strip():
        metadata["athlete"] = str(names[0]).strip()
    if "BLADELAB" in params:
        for key in METADATA_KEYS:
            value = _param(params, "BLADELAB", key.upper(), None)
            if value is None or len(value) == 0:
                continue
            v = value[0]
            metadata[key] = v.strip() if isinstance(v, str) else _num(v)
    return Trial(
        markers=markers,
        marker_rate=marker_rate,
        analogs={label: analogs_arr[i].copy() for i, label in enumerate(analog_labels)},
        analog_rate=analog_rate,
        platforms=platforms,
        metadata=metadata,
    )


def _param(params, group: str, name: str, default):
    try:
        return params[group][name]["value"]
    except (KeyError, TypeError):
        return default


def _num(value) -> Any:
    f = float(value)
    return int(f) if f.is_integer() else f


def _axis_vec(spec: str, what: str, path) -> np.ndarray:
    s = spec.strip().lower()
    sign = -1.0 if s.startswith("-") else 1.0
    s = s.lstrip("+-")
    if s not in _AXES:
        raise SpecError(f"{what} axis {spec!r} is not one of +x, -x, +y, -y, +z, -z", file=path)
    v = np.zeros(3)
    v[_AXES[s]] = sign
    return v


def _axis_name(v: np.ndarray) -> str:
    i = int(np.argmax(np.abs(v)))
    return ("+" if v[i] > 0 else "-") + "xyz"[i]


def _snap(v: np.ndarray) -> np.ndarray:
    i = int(np.argmax(np.abs(v)))
    out = np.zeros(3)
    out[i] = np.sign(v[i])
    return out


def _choose_up(up: str, plates: list[FilePlate], points, path, log: WarningLog) -> np.ndarray:
    """The lab's up in file axes; plates whose loaded force points down are inverted.

    Auto: the axis is the first plate's normal (else the file's +z). Its sense comes from the
    markers when they lie clearly on one side of the plate's surface (median height beyond
    ``MARKER_SIDE_M``): a subject stands above the plates. Without such markers it comes from
    the data: the ground reaction force on a loaded plate points up (a foot pushes a plate
    down); the plates with unloaded periods vote (those that never unload when none has any); a
    tie keeps the corners' sense.
    """
    if up != "auto":
        up_vec = _axis_vec(up, "up", path)
    elif plates:
        up_vec = _snap(-plates[0].rot[:, 2])  # plate z points down into the plate
        height = _marker_height(points, plates[0].corners.mean(axis=0), up_vec)
        if height is not None and abs(height) > MARKER_SIDE_M:
            if height < 0:
                _warn_up_flipped(
                    log, path, plates[0], up_vec,
                    f"the markers lie along file {_axis_name(-up_vec)} of its surface (median "
                    f"{abs(height):.2f} m): taking file {_axis_name(-up_vec)} as up, as the "
                    f"markers say")
                up_vec = -up_vec
            return _invert_downward(plates, up_vec, path, log)
        voters = [p for p in plates if p.loading.status == "unloads"] or [
            p for p in plates if p.loading.sense != 0
        ]
        against = [p for p in voters if _sense_along(p, up_vec) < 0]
        if 2 * len(against) > len(voters):
            p = against[0]
            _warn_up_flipped(
                log, path, p, up_vec,
                f"under load its ground reaction force points along file {_axis_name(-up_vec)} "
                f"(peak {abs(p.loading.peak):.0f} N): taking file {_axis_name(-up_vec)} as up, "
                f"as the data say (the ground pushes a foot up)")
            up_vec = -up_vec
    else:
        return np.array([0.0, 0.0, 1.0])
    return _invert_downward(plates, up_vec, path, log)


def _warn_up_flipped(log, path, plate, up_vec: np.ndarray, evidence: str) -> None:
    """Warn that the plate's CORNERS say one up axis and ``evidence`` the other."""
    log.warn(
        f"its CORNERS make file {_axis_name(_snap(plate.rot[:, 2]))} the plate's z axis (into the "
        f"plate, i.e. down), but {evidence}",
        file=path, where=plate.name,
        hint="check the corner order (C3D: z into the plate), or give the up axis (--up)",
    )


#: Markers whose median height lies farther than this [m] from the first plate's surface give
#: the vertical sense (a subject stands above the plates).
MARKER_SIDE_M = 0.1


def _marker_height(points: np.ndarray, surface: np.ndarray, up_vec: np.ndarray) -> float | None:
    """Median height [m] of all marker samples above ``surface`` along ``up_vec`` (None: none)."""
    if points.size == 0:
        return None
    h = np.tensordot(up_vec, points - surface[:, None, None], axes=1).ravel()
    h = h[np.isfinite(h)]
    return float(np.median(h)) if h.size else None


def _invert_downward(plates: list[FilePlate], up_vec, path, log: WarningLog) -> np.ndarray:
    """Invert the plates whose loaded vertical force points down along ``up_vec``."""
    for p in plates:
        if p.loading.sense != 0 and _sense_along(p, up_vec) < 0:
            log.warn(
                f"loaded, its vertical force points down (peak {-abs(p.loading.peak):.0f} N along "
                f"file {_axis_name(up_vec)}, the lab's up): the file's calibration gives the force "
                "on the plate; its sign is inverted to give the ground reaction force",
                file=path, where=p.name,
                hint="check the plate's calibration (CAL_MATRIX, channel signs) or the up axis",
            )
            p.invert()
    return up_vec


def _sense_along(p: FilePlate, up_vec: np.ndarray) -> float:
    """+1 when plate ``p``'s ground reaction force under load points along ``up_vec``."""
    return p.loading.sense * float(np.sign(-p.rot[:, 2] @ up_vec))


def _choose_forward(forward, up_vec, points, plates, rate, path) -> np.ndarray:
    if forward != "auto":
        v = _axis_vec(forward, "forward", path)
        if abs(v @ up_vec) > 0.5:
            raise SpecError(f"forward axis {forward!r} is the vertical axis", file=path)
        return v
    horizontal = [i for i in range(3) if abs(up_vec[i]) < 0.5]
    # 1) overground: progression of the markers' centroid over more than 1 m
    if points.size:
        with np.errstate(invalid="ignore"), _quiet():
            centroid = np.nanmean(points, axis=1)  # (3, n_frames)
        ok = np.all(np.isfinite(centroid), axis=0)
        if ok.sum() >= 2:
            c = centroid[:, ok]
            travel = c[:, -1] - c[:, 0]
            i = max(horizontal, key=lambda j: abs(travel[j]))
            if abs(travel[i]) > 1.0:
                v = np.zeros(3)
                v[i] = np.sign(travel[i])
                return v
    # 2) treadmill: horizontal force goes from braking (-) to propulsion (+) during contact
    if plates:
        total = sum(p.force for p in plates)
        vert = total @ up_vec
        loaded = vert > max(0.2 * np.nanmax(vert), 50.0) if np.isfinite(vert).any() else vert > 0
        edges = np.flatnonzero(np.diff(np.concatenate([[0], loaded.astype(int), [0]])))
        starts, ends = edges[::2], edges[1::2]
        score = np.zeros(3)
        energy = np.zeros(3)
        for s, e in zip(starts, ends, strict=True):
            if e - s < 5:
                continue
            tau = np.linspace(-1.0, 1.0, e - s)
            seg = np.nan_to_num(total[s:e])
            score += tau @ seg
            energy += np.sum(seg**2, axis=0)
        i = max(horizontal, key=lambda j: energy[j])
        if energy[i] > 0 and score[i] != 0:
            v = np.zeros(3)
            v[i] = np.sign(score[i])
            return v
    v = np.zeros(3)
    v[horizontal[0]] = 1.0
    return v


class _quiet:
    def __enter__(self):
        self._w = warnings.catch_warnings()
        self._w.__enter__()
        warnings.simplefilter("ignore", RuntimeWarning)

    def __exit__(self, *exc):
        self._w.__exit__(*exc)
        return False


def _to_lab(p: FilePlate, rot: np.ndarray, up_vec: np.ndarray, cop_threshold: float) -> ForcePlatform:
    force = p.force @ rot.T
    cop = p.cop @ rot.T
    free = p.free_moment * float(p.rot[:, 2] @ up_vec)  # about the lab vertical
    unloaded = ~(force[:, 2] > cop_threshold)
    cop[unloaded] = np.nan
    free = np.where(unloaded, np.nan, free)
    return ForcePlatform(
        index=p.index, type=p.type, rate=p.rate, force=force, cop=cop, free_moment=free,
        corners=p.corners @ rot.T, channels=p.channels,
        zero_offset_N=round(p.zero_offset_N * float(np.sign(-p.rot[:, 2] @ up_vec) or 1.0), 3),
    )


# --------------------------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------------------------


def plate_corners(center: Sequence[float], length: float, width: float) -> np.ndarray:
    """Corners [m] of a level plate in a z-up frame, in the C3D order (plate z pointing down).

    Parameters
    ----------
    center
        Centre of the top surface (x, y, z) [m].
    length, width
        Extent along x and along y [m].
    """
    cx, cy, cz = (float(v) for v in center)
    a, b = length / 2.0, width / 2.0
    # x_p = c1 - c2 = +x, y_p = c1 - c4 = -y  =>  z_p = x_p × y_p = -z (down)
    return np.array(
        [[cx + a, cy - b, cz], [cx - a, cy - b, cz], [cx - a, cy + b, cz], [cx + a, cy + b, cz]]
    )


def write_c3d(
    path: str | Path,
    *,
    markers: Mapping[str, np.ndarray],
    marker_rate: float,
    platforms: Sequence[Mapping[str, Any]] = (),
    analog_rate: float | None = None,
    metadata: Mapping[str, Any] | None = None,
    point_units: str = "mm",
) -> Path:
    """Write a trial as C3D (atomically); force platforms as type 2 (Fx..Mz) analog channels.

    The file's axes are the lab frame (x forward, y lateral, z up).

    Parameters
    ----------
    path
        Output file.
    markers
        ``label -> (n, 3)`` positions [m], lab frame; NaN samples are written as gaps
        (residual −1).
    marker_rate
        Marker rate [Hz].
    platforms
        One mapping per plate with ``force`` (m, 3) [N] (ground reaction force on the subject,
        lab frame), ``corners`` (4, 3) [m] in C3D order with the plate z axis pointing down (see
        :func:`plate_corners`), optional ``origin`` (3,) [m] (written as ``FORCE_PLATFORM:ORIGIN``,
        read as :func:`read_c3d` does; default (0, 0, 0)), and either ``moment`` (m, 3) [N·m] about the sensor origin in
        plate axes, or ``cop`` (m, 3) [m] in the lab frame plus optional ``free_moment`` (m,) [N·m]
        about the vertical. ``m = n × analog_rate / marker_rate``.
    analog_rate
        Analog rate [Hz], an integer multiple of ``marker_rate`` (default: ``marker_rate``).
    metadata
        athlete, side, blade, category, speed_pct_pb (stored in a ``BLADELAB`` parameter group;
        the athlete also in ``SUBJECTS:NAMES``).
    point_units
        "mm" (default) or "m": units of the marker data in the file.

    Raises
    ------
    SpecError
        Inconsistent shapes or rates, or plate corners whose z axis points up.
    """
    import ezc3d

    path = Path(path)
    if point_units not in ("mm", "m"):
        raise SpecError(f"point_units {point_units!r} must be 'mm' or 'm'", file=path)
    if not markers:
        raise SpecError("write_c3d needs at least one marker", file=path)
    labels = list(markers)
    arrays = [np.asarray(markers[k], dtype=float) for k in labels]
    n = arrays[0].shape[0]
    for k, a in zip(labels, arrays, strict=True):
        if a.shape != (n, 3):
            raise SpecError(f"marker has shape {a.shape}, expected ({n}, 3)", file=path, where=f"marker {k}")
    analog_rate = float(marker_rate if analog_rate is None else analog_rate)
    ratio = analog_rate / marker_rate
    if ratio < 1 or abs(ratio - round(ratio)) > 1e-9:
        raise SpecError(
            f"analog rate {analog_rate} Hz is not an integer multiple of the marker rate {marker_rate} Hz",
            file=path,
        )
    ratio = int(round(ratio))
    m = n * ratio
    scale = 1000.0 if point_units == "mm" else 1.0

    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [float(marker_rate)]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = tuple(labels)
    c3d["parameters"]["POINT"]["UNITS"]["value"] = [point_units]
    pts = np.zeros((4, len(labels), n))
    pts[:3] = np.stack(arrays, axis=1).transpose(2, 1, 0) * scale
    pts[3] = 1.0
    c3d["data"]["points"] = pts

    analog_rows: list[np.ndarray] = []
    analog_labels: list[str] = []
    analog_units: list[str] = []
    plate_corner_list, plate_origin_list = [], []
    for k, plate in enumerate(platforms):
        where = f"platform {k + 1}"
        force = np.asarray(plate["force"], dtype=float)
        if force.shape != (m, 3):
            raise SpecError(f"force has shape {force.shape}, expected ({m}, 3)", file=path, where=where)
        corners = np.asarray(plate["corners"], dtype=float).reshape(4, 3)
        rot = plate_rotation(corners, path, where)
        if rot[2, 2] > -0.99:
            raise SpecError(
                "corners give a plate z axis that does not point down", file=path, where=where,
                hint="order the corners as plate_corners() does",
            )
        origin = np.asarray(plate.get("origin", np.zeros(3)), dtype=float).reshape(3)
        force_p = force @ rot  # lab -> plate axes
        if plate.get("moment") is not None:
            moment_p = np.asarray(plate["moment"], dtype=float).reshape(m, 3)
        else:
            cop = np.asarray(plate.get("cop", np.full((m, 3), np.nan)), dtype=float).reshape(m, 3)
            free = np.asarray(plate.get("free_moment", np.zeros(m)), dtype=float).reshape(m)
            # COP relative to the sensor origin, plate axes (see _plate_kinetics)
            rel = np.nan_to_num(cop - corners.mean(axis=0)) @ rot
            rel[~np.all(np.isfinite(cop), axis=1)] = 0.0
            rel[:, 2] = 0.0
            rel += np.array([origin[0], origin[1], -abs(origin[2])])
            tz_p = np.nan_to_num(free) * rot[2, 2]  # about plate z (down)
            moment_p = np.cross(rel, force_p)
            moment_p[:, 2] += tz_p
        analog_rows += [force_p[:, i] for i in range(3)] + [moment_p[:, i] * 1000.0 for i in range(3)]
        analog_labels += [f"F{k + 1}{a}" for a in "XYZ"] + [f"M{k + 1}{a}" for a in "XYZ"]
        analog_units += ["N"] * 3 + ["Nmm"] * 3
        plate_corner_list.append(corners.T * scale)
        plate_origin_list.append(origin * scale)

    if analog_rows:
        c3d["parameters"]["ANALOG"]["RATE"]["value"] = [analog_rate]
        c3d["parameters"]["ANALOG"]["LABELS"]["value"] = tuple(analog_labels)
        c3d["parameters"]["ANALOG"]["UNITS"]["value"] = analog_units
        c3d["data"]["analogs"] = np.vstack(analog_rows)[None, :, :]
        n_pl = len(plate_corner_list)
        _set_param(c3d, "FORCE_PLATFORM", "USED", [n_pl], integer=True)
        _set_param(c3d, "FORCE_PLATFORM", "TYPE", [2] * n_pl, integer=True)
        _set_param(c3d, "FORCE_PLATFORM", "ZERO", [1, 0], integer=True)
        chan = np.arange(1, 6 * n_pl + 1).reshape(n_pl, 6).T
        _set_param(c3d, "FORCE_PLATFORM", "CHANNEL", chan, integer=True)
        _set_param(c3d, "FORCE_PLATFORM", "CORNERS", np.stack(plate_corner_list, axis=2))
        _set_param(c3d, "FORCE_PLATFORM", "ORIGIN", np.stack(plate_origin_list, axis=1))
    meta = dict(metadata or {})
    if "athlete" in meta:
        c3d.add_parameter("SUBJECTS", "NAMES", [str(meta["athlete"])])
    for key in METADATA_KEYS:
        if key in meta and meta[key] is not None:
            value = meta[key]
            if isinstance(value, str):
                c3d.add_parameter("BLADELAB", key.upper(), [value])
            else:
                integer = float(value).is_integer() and abs(float(value)) < 32768
                _set_param(c3d, "BLADELAB", key.upper(), [value], integer=integer)
    with atomic_path(path) as tmp:
        # ezc3d appends ".c3d" to a name without it: write there, then move onto the temp name
        written = tmp if tmp.suffix.lower() == ".c3d" else tmp.with_name(tmp.name + ".c3d")
        try:
            c3d.write(str(written))
            if written != tmp:
                os.replace(written, tmp)
        finally:
            if written != tmp and written.exists():
                written.unlink()
    return path


def _set_param(c3d, group: str, name: str, value, *, integer: bool = False) -> None:
    """Set a numeric parameter, stored as INT when ``integer`` (ezc3d's platform reader needs
    FORCE_PLATFORM:USED, TYPE, CHANNEL as integers; ``add_parameter`` alone writes floats)."""
    arr = np.asarray(value, dtype=float)
    c3d.add_parameter(group, name, arr)
    if integer:
        param = c3d["parameters"][group][name]
        param["type"] = c3d["parameters"]["POINT"]["USED"]["type"]  # ezc3d's INT
        param["value"] = np.rint(arr).astype(int)
