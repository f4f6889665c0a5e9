"""C3D files: read a trial into the lab frame, write synthetic trials (both via ezc3d).

Reading
    Marker units come from ``POINT:UNITS`` (mm, cm or m); samples with a negative residual or
    NaN are gaps (NaN). Force platforms of types 1–4 are supported (type 4 applies
    ``FORCE_PLATFORM:CAL_MATRIX`` to its 6 analog channels; type 3 is the 8-channel Kistler
    layout). Each platform's axes come from its ``CORNERS``. ``ORIGIN`` (plate axes): its x and y
    give the centre of the top surface relative to the sensor origin, and the surface lies
    ``|ORIGIN_z|`` above the sensor origin (files disagree on the sign of ``ORIGIN_z``; this reading
    puts the COP under the foot markers on the Fukuchi treadmill file and agrees with ezc3d's own
    force-platform module on all the real files). Forces are the ground reaction force on the
    subject; the centre of pressure is computed on the plate surface and expressed in the lab
    frame, with the free moment about the vertical.

The lab frame
    bladelab's lab frame is x forward, y lateral, z up. Files differ (the Fukuchi treadmill files
    have y up), so the reader maps the file's axes onto the lab frame with a signed permutation:
    ``up`` defaults to the normal of the first force platform (else the file's +z), ``forward`` to
    the direction of overground progression of the markers, or on a treadmill to the direction
    in which the horizontal force changes from braking to propulsion during contact. Both can be
    given explicitly ("+x", "-y", ...). The mapping used is stored in ``trial.metadata["axes"]``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from bladelab._io import atomic_path
from bladelab.errors import DataError, InputFileError, SpecError
from bladelab.trial.trial import METADATA_KEYS, ForcePlatform, Trial

__all__ = ["SUPPORTED_PLATFORM_TYPES", "plate_corners", "read_c3d", "write_c3d"]

SUPPORTED_PLATFORM_TYPES: tuple[int, ...] = (1, 2, 3, 4)
_LENGTH_UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "meters": 1.0, "millimeters": 1e-3}
_MOMENT_UNITS = {"nmm": 1e-3, "n.mm": 1e-3, "nm": 1.0, "n.m": 1.0, "nmm ": 1e-3}
_AXES = {"x": 0, "y": 1, "z": 2}
_C3D_PARAMETER_BLOCK_KEY = 0x50  # byte 2 of every C3D file


# --------------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------------


def read_c3d(
    path: str | Path,
    *,
    forward: str = "auto",
    up: str = "auto",
    cop_threshold: float = 20.0,
) -> Trial:
    """Read a C3D file into a :class:`~bladelab.trial.trial.Trial` (lab frame, SI).

    Parameters
    ----------
    path
        The C3D file.
    forward, up
        The file axis ("+x", "-x", "+y", ...) that is the lab's forward (running) direction and
        the vertical; "auto" detects them (see the module docstring).
    cop_threshold
        Vertical force [N] under which a platform's COP and free moment are NaN.

    Raises
    ------
    InputFileError
        The file is missing, is not a C3D file, or is truncated/corrupt.
    DataError
        A platform has an unsupported type, references missing analog channels, or has
        degenerate corners; marker units are unknown.
    """
    path = Path(path)
    c3d = _open_c3d(path)
    params = c3d["parameters"]
    data = c3d["data"]

    # markers, in file axes [m]
    point_units = _param(params, "POINT", "UNITS", ["mm"])
    point_units = (point_units[0] if point_units else "mm").strip().lower() or "mm"
    if point_units not in _LENGTH_UNITS:
        raise DataError(
            f"unknown marker units {point_units!r}", file=path, where="POINT:UNITS",
            hint="expected mm, cm or m",
        )
    scale = _LENGTH_UNITS[point_units]
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
        _read_platforms(path, params, analogs_arr, analog_labels, analog_units, analog_rate)
        if n_analog and analogs_arr.shape[1]
        else []
    )

    # file axes -> lab axes
    up_vec = _choose_up(up, plates_file, path)
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


def _open_c3d(path: Path):
    import ezc3d

    if not path.is_file():
        raise InputFileError("file not found", file=path, hint="check the path")
    with open(path, "rb") as fh:
        head = fh.read(512)
    if len(head) < 512 or head[1] != _C3D_PARAMETER_BLOCK_KEY:
        raise InputFileError(
            "not a C3D file (no C3D header)", file=path,
            hint="export the trial as C3D from the motion-capture software",
        )
    # ezc3d can hang on a file cut inside its parameter section: check that the file reaches
    # the data block announced by the header (word 9) before handing it over.
    data_start = int.from_bytes(head[16:18], "little")
    param_start = head[0]
    size = path.stat().st_size
    if data_start < 2 or param_start < 1 or size < (data_start - 1) * 512:
        raise InputFileError(
            f"truncated: {size} bytes, but the header puts the data block at byte "
            f"{max(data_start - 1, 0) * 512}", file=path,
            hint="re-export it from the motion-capture software",
        )
    try:
        c3d = ezc3d.c3d(str(path))
    except Exception as err:  # ezc3d raises RuntimeError/IOError on corrupt files
        raise InputFileError(
            f"cannot be read as C3D ({err}); the file looks truncated or corrupt", file=path,
            hint="re-export it from the motion-capture software",
        ) from err
    # ezc3d reads a truncated data block without complaint (it shortens last_frame): compare
    # the frames it got with the count the raw header announces.
    got = np.asarray(c3d["data"]["points"]).shape[-1]
    announced = _announced_frames(head)
    if announced is not None and got < announced:
        raise InputFileError(
            f"truncated: the file announces {announced} frames but holds only {got}",
            file=path, hint="re-export it from the motion-capture software",
        )
    return c3d


def _announced_frames(head: bytes) -> int | None:
    """Number of frames the raw header announces (words 4–5), None when saturated.

    ezc3d silently shortens ``last_frame`` and ``POINT:FRAMES`` of a truncated file, so the
    count is taken from the header bytes themselves.
    """
    first = int.from_bytes(head[6:8], "little")
    last = int.from_bytes(head[8:10], "little")
    if last >= 65535 or last < first:
        return None
    return last - first + 1


def _param(params, group: str, name: str, default):
    try:
        return params[group][name]["value"]
    except (KeyError, TypeError):
        return default


def _num(value) -> Any:
    f = float(value)
    return int(f) if f.is_integer() else f


# A platform in the file's axes, before the lab mapping (all SI).
class _FilePlate:
    def __init__(self, index, type_, force, cop, free_moment, corners, rot, channels, rate):
        self.index, self.type, self.force, self.cop = index, type_, force, cop
        self.free_moment, self.corners, self.rot, self.channels = free_moment, corners, rot, channels
        self.rate = rate


def _read_platforms(path, params, analogs, labels, units, rate) -> list[_FilePlate]:
    if "FORCE_PLATFORM" not in params:
        return []
    used = int(np.asarray(_param(params, "FORCE_PLATFORM", "USED", [0])).ravel()[0])
    if used == 0:
        return []
    types = np.asarray(_param(params, "FORCE_PLATFORM", "TYPE", []), dtype=float).ravel()
    channel = np.asarray(_param(params, "FORCE_PLATFORM", "CHANNEL", []), dtype=float)
    corners = np.asarray(_param(params, "FORCE_PLATFORM", "CORNERS", []), dtype=float)
    origin = np.asarray(_param(params, "FORCE_PLATFORM", "ORIGIN", []), dtype=float)
    cal = np.asarray(_param(params, "FORCE_PLATFORM", "CAL_MATRIX", []), dtype=float)
    point_units = _param(params, "POINT", "UNITS", ["mm"])
    length_scale = _LENGTH_UNITS.get((point_units[0] if point_units else "mm").strip().lower(), 1e-3)
    if types.size < used or corners.size < 12 * used:
        raise DataError(
            f"FORCE_PLATFORM:USED is {used} but TYPE/CORNERS describe fewer platforms",
            file=path, where="FORCE_PLATFORM", hint="fix the platform set-up in the export",
        )
    channel = channel.reshape(channel.shape[0], -1) if channel.ndim >= 1 and channel.size else channel
    corners = corners.reshape(3, 4, -1)
    origin = origin.reshape(3, -1) if origin.size else np.zeros((3, used))
    plates = []
    for k in range(used):
        index = k + 1
        where = f"platform {index}"
        ptype = int(types[k])
        if ptype not in SUPPORTED_PLATFORM_TYPES:
            raise DataError(
                f"force platform type {ptype} is not supported (supported: 1, 2, 3, 4)",
                file=path, where=where, hint="export the platform as type 2 (Fx..Mz) from the capture software",
            )
        n_ch = 8 if ptype == 3 else 6
        if channel.ndim != 2 or channel.shape[0] < n_ch or channel.shape[1] <= k:
            raise DataError(
                f"type {ptype} needs {n_ch} channels in FORCE_PLATFORM:CHANNEL", file=path, where=where,
            )
        chans = channel[:n_ch, k].astype(int) - 1
        if np.any(chans < 0) or np.any(chans >= analogs.shape[0]):
            raise DataError(
                f"references analog channel(s) {sorted(set((chans + 1).tolist()))} but the file has "
                f"{analogs.shape[0]}", file=path, where=where,
            )
        raw = analogs[chans]  # (n_ch, n)
        ch_labels = tuple(labels[c] for c in chans)
        ch_units = [units[c].lower() if c < len(units) else "" for c in chans]
        cnr = corners[:, :, k].T * length_scale  # (4, 3) file axes [m]
        rot = _plate_rotation(cnr, path, where)
        org = origin[:, k] * length_scale if origin.shape[1] > k else np.zeros(3)
        if ptype == 4:
            if cal.size < 36 * (k + 1):
                raise DataError(
                    "type 4 platform without FORCE_PLATFORM:CAL_MATRIX", file=path, where=where,
                    hint="a type-4 platform's analog channels must be calibrated by CAL_MATRIX",
                )
            raw = cal.reshape(6, 6, -1)[:, :, k] @ raw
        force_p, cop_p, tz = _plate_kinetics(ptype, raw, ch_units, org, length_scale)
        force = (rot @ force_p).T
        with np.errstate(invalid="ignore"):
            cop = cnr.mean(axis=0) + (rot @ cop_p).T
        plates.append(_FilePlate(index, ptype, force, cop, tz, cnr, rot, ch_labels, rate))
    return plates


def _plate_kinetics(ptype, raw, ch_units, org, length_scale):
    """Force (3, n) [N], COP relative to the surface centre (3, n) [m], Tz (n,) [N·m], plate axes.

    ``org`` is FORCE_PLATFORM:ORIGIN [m]: its x, y give the surface centre relative to the sensor
    origin; the surface lies ``|org_z|`` above the sensor origin (files disagree on the sign of
    ``org_z``; the surface is never below the sensors).
    """

    def mscale(u):
        return _MOMENT_UNITS.get(u.replace(" ", ""), 1e-3 if "mm" in u else 1.0)

    n = raw.shape[1]
    h = abs(float(org[2]))
    centre_xy = np.array([org[0], org[1]])
    if ptype == 3:  # Kistler: fx12, fx34, fy14, fy23, fz1..fz4; ORIGIN = (a, b, az0)
        a, b = org[0], org[1]
        fx12, fx34, fy14, fy23, fz1, fz2, fz3, fz4 = raw
        force = np.vstack([fx12 + fx34, fy14 + fy23, fz1 + fz2 + fz3 + fz4])
        mx = b * (fz1 + fz2 - fz3 - fz4)
        my = a * (-fz1 + fz2 + fz3 - fz4)
        mz = b * (-fx12 + fx34) + a * (fy14 - fy23)
        moment = np.vstack([mx, my, mz])
        centre_xy = np.zeros(2)  # a, b locate the sensors; the moments are about the centre
    elif ptype == 1:  # Fx, Fy, Fz, Px, Py, Tz
        force = raw[:3]
        px = raw[3] * _length_scale_of(ch_units[3], length_scale)
        py = raw[4] * _length_scale_of(ch_units[4], length_scale)
        tz = raw[5] * mscale(ch_units[5])
        cop = np.vstack([px - centre_xy[0], py - centre_xy[1], np.zeros(n)])
        return force, cop, tz
    else:  # 2 and 4 (after calibration): Fx, Fy, Fz, Mx, My, Mz about the sensor origin
        force = raw[:3]
        moment = np.vstack([raw[3 + i] * mscale(ch_units[3 + i]) for i in range(3)])
    fx, fy, fz = force
    with np.errstate(divide="ignore", invalid="ignore"):
        # force F applied at p = (px, py, -h) (plate z points down): M = p × F + (0, 0, Tz)
        px = (-moment[1] - h * fx) / fz
        py = (moment[0] - h * fy) / fz
        tz = moment[2] - (px * fy - py * fx)
    cop = np.vstack([px - centre_xy[0], py - centre_xy[1], np.zeros(n)])
    return force, cop, tz


def _length_scale_of(unit: str, default: float) -> float:
    return _LENGTH_UNITS.get(unit.strip().lower(), default)


def _plate_rotation(corners: np.ndarray, path, where) -> np.ndarray:
    """Plate axes in file axes (columns x_p, y_p, z_p) from the 4 corners (C3D order)."""
    c1, c2, c3, c4 = corners
    xp = (c1 - c2) + (c4 - c3)
    yp = (c1 - c4) + (c2 - c3)
    if np.linalg.norm(xp) < 1e-9 or np.linalg.norm(yp) < 1e-9:
        raise DataError(
            "degenerate FORCE_PLATFORM:CORNERS (zero-size plate)", file=path, where=where,
            hint="the plate's corners are needed to place it in the lab",
        )
    xp = xp / np.linalg.norm(xp)
    zp = np.cross(xp, yp)
    zp = zp / np.linalg.norm(zp)
    yp = np.cross(zp, xp)
    return np.column_stack([xp, yp, zp])


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


def _choose_up(up: str, plates: list[_FilePlate], path) -> np.ndarray:
    if up != "auto":
        return _axis_vec(up, "up", path)
    if plates:
        return _snap(-plates[0].rot[:, 2])  # plate z points down into the plate
    return np.array([0.0, 0.0, 1.0])


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
        import warnings

        self._w = warnings.catch_warnings()
        self._w.__enter__()
        warnings.simplefilter("ignore", RuntimeWarning)

    def __exit__(self, *exc):
        self._w.__exit__(*exc)
        return False


def _to_lab(p: _FilePlate, rot: np.ndarray, up_vec: np.ndarray, cop_threshold: float) -> ForcePlatform:
    force = p.force @ rot.T
    cop = p.cop @ rot.T
    free = p.free_moment * float(p.rot[:, 2] @ up_vec)  # about the lab vertical
    unloaded = ~(force[:, 2] > cop_threshold)
    cop[unloaded] = np.nan
    free = np.where(unloaded, np.nan, free)
    return ForcePlatform(
        index=p.index, type=p.type, rate=p.rate, force=force, cop=cop, free_moment=free,
        corners=p.corners @ rot.T, channels=p.channels,
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
        rot = _plate_rotation(corners, path, where)
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
        c3d.add_parameter("FORCE_PLATFORM", "USED", [n_pl])
        c3d.add_parameter("FORCE_PLATFORM", "TYPE", [2] * n_pl)
        c3d.add_parameter("FORCE_PLATFORM", "ZERO", [1, 0])
        chan = np.arange(1, 6 * n_pl + 1, dtype=float).reshape(n_pl, 6).T
        c3d.add_parameter("FORCE_PLATFORM", "CHANNEL", chan)
        c3d.add_parameter("FORCE_PLATFORM", "CORNERS", np.stack(plate_corner_list, axis=2))
        c3d.add_parameter("FORCE_PLATFORM", "ORIGIN", np.stack(plate_origin_list, axis=1))
    meta = dict(metadata or {})
    if "athlete" in meta:
        c3d.add_parameter("SUBJECTS", "NAMES", [str(meta["athlete"])])
    for key in METADATA_KEYS:
        if key in meta and meta[key] is not None:
            value = meta[key]
            c3d.add_parameter(
                "BLADELAB", key.upper(),
                [float(value)] if isinstance(value, (int, float)) else [str(value)],
            )
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
