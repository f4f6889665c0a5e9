"""Force platforms of a C3D file: channels -> force, COP and free moment in the file's axes.

Types
    1: Fx, Fy, Fz, COPx, COPy, Tz (the COP channels are relative to the plate centre, in plate
    axes; ``ORIGIN`` x, y are ignored, as ezc3d and BTK do); 2: Fx, Fy, Fz, Mx, My, Mz; 3 (Kistler):
    fx12, fx34, fy14, fy23, fz1–fz4 with the sensor offsets a, b in ``ORIGIN``; 4: like type 2
    after the 6×6 ``CAL_MATRIX`` is applied. Other types are refused.

Geometry
    Plate axes from ``CORNERS`` (x = c1 − c2, y = c1 − c4, z = x × y, into the plate). ``ORIGIN``
    x, y: the surface centre relative to the sensor origin; the surface lies ``|ORIGIN_z|`` above
    the sensor origin (files disagree on the sign of ``ORIGIN_z``).

Loading, zero offset (``analyse_loading``)
    The plate's vertical force (along −z, out of the plate) is examined before anything else:

    - *flat*: it varies by less than 50 N (or ten times its sample-to-sample noise): no foot ever
      landed on it. A flat plate that reads more than 50 N away from zero (e.g. stuck at
      −1448 N) is reported by a warning naming it.
    - *unloaded periods*: steady stretches (≥ 20 ms within a band of max(25 N, 5 % of the
      range, 3 × noise)) at the end of the range the signal keeps returning to (at least twice
      as many such samples as at the other end; if neither end is, the end nearer zero); the
      other end is the loaded side. Their level is the plate's **zero offset**. With ``zero_offset`` (the
      default) an offset larger than ``ZERO_TOLERANCE_N`` (5 N) is removed from every force and
      moment channel (their medians over the unloaded periods); smaller ones are kept, so a
      zeroed file reads exactly as its acquisition software and ezc3d give it.
    - *light load*: the candidate unloaded stretches are not steady (their robust spread exceeds
      max(3 × noise, ``ZERO_TOLERANCE_N``)): something rests on the plate there (the Peak
      Performance sample FP1 reads 13–50 N before and after its main contact, spread 15 N, noise
      0.1 N, with the same share on each of its four sensors as at the peak); nothing is removed
      and a warning names the plate.
    - *never unloads*: no such stretch, or its level lies on the loaded side of zero by more
      than half the load range (a treadmill walker, a plate loaded all along): nothing is
      removed and a warning names the plate.

    The loaded side gives the **sense** of the vertical force: a foot pushes a plate down, so
    the ground reaction force on a loaded plate points up. :func:`read_c3d` uses it to choose
    the lab's up direction and to invert a plate whose calibration gives the force on the plate
    rather than on the subject (each with a warning).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bladelab.errors import DataError
from bladelab.trial.c3d_format import WarningLog, length_scale, moment_scale

__all__ = [
    "PLATE_FLAT_N",
    "SUPPORTED_PLATFORM_TYPES",
    "ZERO_TOLERANCE_N",
    "FilePlate",
    "Loading",
    "analyse_loading",
    "plate_rotation",
    "read_platforms",
]

SUPPORTED_PLATFORM_TYPES: tuple[int, ...] = (1, 2, 3, 4)
#: A plate whose vertical force varies by less than this [N] never carried a foot.
PLATE_FLAT_N = 50.0
#: Zero offsets within ± this [N] are left alone (the plate counts as zeroed).
ZERO_TOLERANCE_N = 5.0
_MIN_STEADY_S = 0.02  # shortest unloaded stretch [s]


@dataclasses.dataclass
class Loading:
    """How a plate's vertical force (along −z_plate) behaves; see the module docstring.

    status: "flat", "unloads" or "never"; sense: +1 when load raises it, −1 when load lowers it,
    0 for a flat plate; level: the unloaded (or flat) level [N]; mask: the unloaded samples;
    peak: the loaded extreme [N]; noise: sample-to-sample noise [N].
    """

    status: str
    sense: int
    level: float
    mask: np.ndarray | None
    peak: float
    noise: float
    spread: float = 0.0  # robust spread (1.4826 · MAD) of the unloaded samples [N]

    @property
    def steady(self) -> bool:
        """Whether the unloaded samples stay within ``max(3 × noise, ZERO_TOLERANCE_N)``."""
        return self.spread <= max(3.0 * self.noise, ZERO_TOLERANCE_N)


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return edges[::2], edges[1::2]


def _steady(mask: np.ndarray, min_len: int) -> np.ndarray:
    out = np.zeros_like(mask)
    for s, e in zip(*_runs(mask), strict=True):
        if e - s >= min_len:
            out[s:e] = True
    return out


def analyse_loading(v: np.ndarray, rate: float) -> Loading:
    """Find the unloaded level, the loaded side and the unloaded samples of a vertical force."""
    v = np.asarray(v, dtype=float)
    finite = v[np.isfinite(v)]
    if finite.size < 2:
        return Loading("flat", 0, 0.0, None, 0.0, 0.0)
    d = np.diff(finite)
    noise = float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))
    lo, hi = np.percentile(finite, [0.5, 99.5])
    span = hi - lo
    if span < max(PLATE_FLAT_N, 10.0 * noise):
        level = float(np.median(finite))
        return Loading("flat", 0, level, np.isfinite(v), level, noise)
    band = max(PLATE_FLAT_N / 2.0, 0.05 * span, 3.0 * noise)
    min_len = max(3, int(round(_MIN_STEADY_S * rate)))
    with np.errstate(invalid="ignore"):
        at_lo = _steady(v <= lo + band, min_len)
        at_hi = _steady(v >= hi - band, min_len)
    n_lo, n_hi = int(at_lo.sum()), int(at_hi.sum())
    if n_lo == 0 and n_hi == 0:
        return _never(finite, noise)
    if n_lo >= 2 * n_hi or n_hi >= 2 * n_lo:
        sense = 1 if n_lo > n_hi else -1  # the signal keeps returning to its unloaded level
    else:  # no end clearly steadier (e.g. a plate loaded all along): the one nearer zero
        sense = 1 if abs(np.median(v[at_lo])) <= abs(np.median(v[at_hi])) else -1
    candidate = at_lo if sense > 0 else at_hi
    level = float(np.median(v[candidate]))
    with np.errstate(invalid="ignore"):
        mask = _steady(np.abs(v - level) <= band, min_len)
    if not mask.any():
        mask = candidate
    level = float(np.median(v[mask]))
    spread = float(1.4826 * np.median(np.abs(v[mask] - level)))
    peak = float(hi if sense > 0 else lo)
    if sense * level > 0.5 * abs(peak - level):  # its "unloaded" level is itself a load
        return _never(finite, noise, level=level)
    return Loading("unloads", sense, level, mask, peak, noise, spread)


def _never(finite: np.ndarray, noise: float, level: float | None = None) -> Loading:
    k = int(np.argmax(np.abs(finite)))
    sense = 1 if finite[k] >= 0 else -1
    low = float(np.min(finite) if sense > 0 else np.max(finite))
    return Loading("never", sense, low if level is None else level, None, float(finite[k]), noise)


@dataclasses.dataclass
class FilePlate:
    """A platform in the file's axes, before the lab mapping (SI)."""

    index: int
    type: int
    force: np.ndarray  # (n, 3) [N], file axes
    cop: np.ndarray  # (n, 3) [m], file axes
    free_moment: np.ndarray  # (n,) [N·m] about the plate z axis
    corners: np.ndarray  # (4, 3) [m]
    rot: np.ndarray  # plate axes (columns) in file axes
    channels: tuple[str, ...]
    rate: float
    loading: Loading
    zero_offset_N: float = 0.0  # vertical offset removed [N] (along −z_plate)

    @property
    def name(self) -> str:
        return f"platform {self.index}"

    def invert(self) -> None:
        """Negate the wrench (force and free moment; the COP does not change)."""
        self.force = -self.force
        self.free_moment = -self.free_moment
        self.loading = dataclasses.replace(
            self.loading, sense=-self.loading.sense, level=-self.loading.level, peak=-self.loading.peak
        )
        self.zero_offset_N = -self.zero_offset_N


def _param(params, group: str, name: str, default):
    try:
        return params[group][name]["value"]
    except (KeyError, TypeError):
        return default


def read_platforms(
    path, params, analogs, labels, units, rate, *, point_scale: float, zero_offset: bool,
    used_in_file: bool, log: WarningLog,
) -> list[FilePlate]:
    """The platforms of a file (types 1–4), file axes, SI; see the module docstring.

    ``used_in_file``: whether the file itself has ``FORCE_PLATFORM:USED`` (ezc3d fills in 0 when
    it is missing; the platforms ``TYPE`` describes are then read, with a warning).
    """
    if "FORCE_PLATFORM" not in params:
        return []
    types = np.asarray(_param(params, "FORCE_PLATFORM", "TYPE", []), dtype=float).ravel()
    used_value = np.asarray(_param(params, "FORCE_PLATFORM", "USED", []), dtype=float).ravel()
    used = int(used_value[0]) if used_value.size else 0
    if not used_in_file and types.size:
        used = types.size
        log.warn(
            f"FORCE_PLATFORM:USED is missing; reading the {used} platform(s) that "
            "FORCE_PLATFORM:TYPE describes", file=path, where="FORCE_PLATFORM:USED",
        )
    elif used == 0 and types.size:
        log.warn(
            f"FORCE_PLATFORM:USED is 0 although FORCE_PLATFORM:TYPE describes {types.size} "
            "platform(s): no platform is read", file=path, where="FORCE_PLATFORM:USED",
            hint="set FORCE_PLATFORM:USED in the export if the platforms were recorded",
        )
    if used == 0:
        return []
    channel = np.asarray(_param(params, "FORCE_PLATFORM", "CHANNEL", []), dtype=float)
    corners = np.asarray(_param(params, "FORCE_PLATFORM", "CORNERS", []), dtype=float)
    origin = np.asarray(_param(params, "FORCE_PLATFORM", "ORIGIN", []), dtype=float)
    cal = np.asarray(_param(params, "FORCE_PLATFORM", "CAL_MATRIX", []), dtype=float)
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
                file=path, where=where,
                hint="export the platform as type 2 (Fx..Mz) from the capture software",
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
        _warn_clipped(params, analogs, chans, labels, rate, path, where, log)
        ch_units = [units[c] if c < len(units) else "" for c in chans]
        cnr = corners[:, :, k].T * point_scale  # (4, 3) file axes [m]
        rot = plate_rotation(cnr, path, where)
        org = origin[:, k] * point_scale if origin.shape[1] > k else np.zeros(3)
        if ptype == 4:
            if cal.size < 36 * (k + 1):
                raise DataError(
                    "type 4 platform without FORCE_PLATFORM:CAL_MATRIX", file=path, where=where,
                    hint="a type-4 platform's analog channels must be calibrated by CAL_MATRIX",
                )
            raw = cal.reshape(6, 6, -1)[:, :, k] @ raw
        fz_plate = raw[4:8].sum(axis=0) if ptype == 3 else raw[2]
        loading = analyse_loading(-fz_plate, rate)
        raw, removed = _remove_offset(raw, ptype, loading, zero_offset, path, where, log)
        force_p, cop_p, tz = _plate_kinetics(ptype, raw, ch_units, org, point_scale)
        force = (rot @ force_p).T
        with np.errstate(invalid="ignore"):
            cop = cnr.mean(axis=0) + (rot @ cop_p).T
        plates.append(FilePlate(index, ptype, force, cop, tz, cnr, rot, ch_labels, rate, loading, removed))
    return plates


#: A platform channel at its converter's full scale for at least this many samples is clipped.
CLIPPED_MIN_SAMPLES = 3


def _warn_clipped(params, analogs, chans, labels, rate, path, where, log: WarningLog) -> None:
    """Warn when a platform channel sits at its converter's full scale (``ANALOG:BITS``).

    The stored count is ``value / (SCALE · GEN_SCALE) + OFFSET``; a signed ``b``-bit converter
    spans −2^(b−1) … 2^(b−1) − 1 counts, an unsigned one 0 … 2^b − 1. Files without
    ``ANALOG:BITS`` are not checked.
    """
    bits = np.asarray(_param(params, "ANALOG", "BITS", []), dtype=float).ravel()
    if not bits.size or not 2 <= bits[0] <= 32:
        return
    b = int(bits[0])
    fmt = _param(params, "ANALOG", "FORMAT", [])
    unsigned = bool(len(fmt)) and str(fmt[0]).strip().upper().startswith("UNSIGNED")
    lo, hi = (0.0, 2.0**b - 1) if unsigned else (-(2.0 ** (b - 1)), 2.0 ** (b - 1) - 1)
    scale = np.asarray(_param(params, "ANALOG", "SCALE", []), dtype=float).ravel()
    offset = np.asarray(_param(params, "ANALOG", "OFFSET", []), dtype=float).ravel()
    gen = np.asarray(_param(params, "ANALOG", "GEN_SCALE", [1.0]), dtype=float).ravel()
    gen_scale = float(gen[0]) if gen.size else 1.0
    for c in chans:
        sc = (scale[c] if c < scale.size else 1.0) * gen_scale
        if sc == 0:
            continue
        counts = analogs[c] / sc + (offset[c] if c < offset.size else 0.0)
        with np.errstate(invalid="ignore"):
            at = np.flatnonzero((counts >= hi - 0.5) | (counts <= lo + 0.5))
        if at.size < CLIPPED_MIN_SAMPLES:
            continue
        full = hi if counts[at[0]] >= hi - 0.5 else lo
        log.warn(
            f"analog channel {c + 1} ({labels[c]!r}) sits at the converter's full scale "
            f"({full:.0f} counts of a {b}-bit converter, ANALOG:BITS) for {at.size} samples "
            f"({at[0] / rate:.3f}–{at[-1] / rate:.3f} s): the signal is clipped there and the "
            "platform's forces are lower bounds",
            file=path, where=where,
            hint="record with a lower amplifier gain or a wider converter range",
        )


def _remove_offset(raw, ptype, loading: Loading, zero_offset, path, where, log: WarningLog):
    """Subtract the unloaded medians of the force/moment channels; warnings for odd plates."""
    if loading.status == "never":
        log.warn(
            f"never unloads: no steady unloaded period (its lowest steady vertical force is "
            f"{abs(loading.level):.0f} N against a peak of {abs(loading.peak):.0f} N), so no zero "
            "offset can be estimated; its forces are used as the file gives them",
            file=path, where=where,
            hint="if the plate was not zeroed, zero it in the capture software and re-export",
        )
        return raw, 0.0
    if loading.status == "flat" and abs(loading.level) > PLATE_FLAT_N:
        log.warn(
            f"its vertical force stays at {loading.level:.0f} N throughout (it varies by less "
            f"than {PLATE_FLAT_N:g} N): stuck, saturated, "
            "disconnected or loaded all along; no stance can be found on it",
            file=path, where=where, hint="check the plate and its amplifier, or leave it out",
        )
        return raw, 0.0
    if abs(loading.level) <= ZERO_TOLERANCE_N or loading.mask is None or not loading.mask.any():
        return raw, 0.0
    if not zero_offset:
        return raw, 0.0
    if not loading.steady:
        log.warn(
            f"its lowest stretches ({abs(loading.level):.0f} N) wander by {loading.spread:.0f} N "
            f"(robust spread) against a sample noise of {loading.noise:.1f} N: a light load, not "
            "an unloaded plate, so no zero offset is removed; its forces are used as the file "
            "gives them", file=path, where=where,
            hint="if the plate was not zeroed, zero it in the capture software and re-export",
        )
        return raw, 0.0
    zeroable = [0, 1, 2, 5] if ptype == 1 else list(range(raw.shape[0]))
    raw = raw.copy()
    for i in zeroable:
        values = raw[i][loading.mask]
        values = values[np.isfinite(values)]
        if values.size:
            raw[i] = raw[i] - np.median(values)
    return raw, loading.level


def _plate_kinetics(ptype, raw, ch_units, org, point_scale):
    """Force (3, n) [N], COP relative to the surface centre (3, n) [m], Tz (n,) [N·m], plate axes.

    ``org`` is FORCE_PLATFORM:ORIGIN [m]: its x, y give the surface centre relative to the sensor
    origin; the surface lies ``|org_z|`` above the sensor origin (files disagree on the sign of
    ``org_z``; the surface is never below the sensors).
    """

    def mscale(u):
        return moment_scale(u, 1e-3 if "mm" in u.lower() else 1.0)

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
    elif ptype == 1:  # Fx, Fy, Fz, Px, Py, Tz; P relative to the plate centre (ORIGIN unused)
        force = raw[:3]
        px = raw[3] * length_scale(ch_units[3], default=point_scale)
        py = raw[4] * length_scale(ch_units[4], default=point_scale)
        tz = raw[5] * mscale(ch_units[5])
        return force, np.vstack([px, py, np.zeros(n)]), tz
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


def plate_rotation(corners: np.ndarray, path, where) -> np.ndarray:
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
