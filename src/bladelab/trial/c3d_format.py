"""C3D file-format details: header, processor type, raw parameters, units, opening a file.

ezc3d does the reading; this module checks a file before handing it over and reads the few raw
values ezc3d hides or rewrites:

- the **processor type** (byte 4 of the parameter section: 84 Intel, 85 DEC, 86 MIPS/SGI). Intel
  and DEC files are read; MIPS/SGI files (big-endian, also old Macintosh software) are refused
  with an error that names the processor type, since ezc3d cannot read them;
- the **frame counts** the file announces: the header (words 4–5) and the parameter
  ``POINT:FRAMES`` as written (ezc3d silently shortens both to what it finds). A file holding
  fewer frames than ``POINT:FRAMES`` says is truncated, except a marker-only file, which is read
  with a warning (several writers leave a stale header count; ezc3d reads such files). A header
  count that disagrees with ``POINT:FRAMES`` while the data hold all of ``POINT:FRAMES`` is a
  stale header: the file is read, with a warning;
- **units**, read leniently: ``m``, ``mete`` (a 4-character truncation), ``meters``, ``metres``,
  ``mm``, ``millimeters``, ``cm``, ``centimetres`` ... Unknown units are an error naming the
  parameter.

Warnings are :class:`C3DWarning` (a ``UserWarning``), formatted like bladelab's errors (file,
where, message, hint); :func:`read_c3d` also keeps them in ``trial.metadata["warnings"]``.
"""

from __future__ import annotations

import struct
import sys
import warnings
from pathlib import Path

import numpy as np

from bladelab.errors import BladelabError, DataError, InputFileError

__all__ = [
    "PROCESSOR_TYPES",
    "C3DWarning",
    "RawC3D",
    "WarningLog",
    "inspect_c3d",
    "length_scale",
    "moment_scale",
    "open_c3d",
]

#: Processor type byte of the parameter section -> name; 84 and 85 are read, 86 is refused.
PROCESSOR_TYPES: dict[int, str] = {84: "Intel (PC)", 85: "DEC (VAX)", 86: "MIPS/SGI (big-endian)"}
_READABLE_PROCESSORS = (84, 85)
_C3D_PARAMETER_BLOCK_KEY = 0x50  # byte 2 of every C3D file

_LENGTH_ABBREVIATIONS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2}
# full names; any truncation to at least 3 (metres) or 4 (milli-, centi-) letters is accepted
_LENGTH_WORDS = (
    ("meters", 3, 1.0), ("metres", 3, 1.0), ("meter", 3, 1.0), ("metre", 3, 1.0),
    ("millimeters", 4, 1e-3), ("millimetres", 4, 1e-3),
    ("centimeters", 4, 1e-2), ("centimetres", 4, 1e-2),
)


class C3DWarning(UserWarning):
    """Something in a C3D file was odd but could be read (stale header, plate never unloading...)."""


class WarningLog(list):
    """Warnings issued while reading one file: each is emitted as a :class:`C3DWarning` and kept."""

    def warn(self, message: str, *, file=None, where: str | None = None, hint: str | None = None):
        text = BladelabError(message, file=file, where=where, hint=hint).args[0]
        self.append(text)
        warnings.warn(text, C3DWarning, stacklevel=_caller_level())


def _caller_level() -> int:
    """Stack level of the first caller outside bladelab.trial (where the reading was asked)."""
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_globals.get("__name__", "").startswith("bladelab.trial"):
        frame, level = frame.f_back, level + 1
    return level


# --------------------------------------------------------------------------------------------
# units
# --------------------------------------------------------------------------------------------


def length_scale(unit: str, *, file=None, where: str = "POINT:UNITS", default: float | None = None) -> float:
    """Metres per unit of a C3D length unit (lenient: 'mete', 'meters', 'millimetres', 'MM' ...).

    An empty unit gives ``default`` (when given). An unknown one raises :class:`DataError`
    naming ``where``, unless ``default`` is given, which is then returned.
    """
    u = str(unit).strip().lower().replace(".", "").replace(" ", "")
    if not u and default is not None:
        return default
    if u in _LENGTH_ABBREVIATIONS:
        return _LENGTH_ABBREVIATIONS[u]
    for word, shortest, scale in _LENGTH_WORDS:
        if len(u) >= shortest and word.startswith(u):
            return scale
    if default is not None:
        return default
    raise DataError(
        f"unknown length unit {unit!r}", file=file, where=where,
        hint="expected m, cm or mm (also meters, metres, millimeters ...); fix it in the export",
    )


def moment_scale(unit: str, default: float) -> float:
    """N·m per unit of a moment channel ('Nmm', 'N.mm', 'N·mm', 'Nm', 'N-m' ...); else ``default``."""
    u = str(unit).strip().lower()
    for sep in (".", "·", "*", "-", " ", "_"):
        u = u.replace(sep, "")
    if not u.startswith("n") or len(u) < 2:
        return default
    return length_scale(u[1:], default=default)


# --------------------------------------------------------------------------------------------
# raw header and parameters
# --------------------------------------------------------------------------------------------


class RawC3D:
    """What the file itself says, before ezc3d: processor type, data start, frame counts."""

    def __init__(self, processor, data_start, header_frames, param_frames, analog_per_frame,
                 platforms_used):
        self.processor = processor
        self.data_start = data_start  # 1-based block of the data section
        self.header_frames = header_frames  # None when the header count is saturated
        self.param_frames = param_frames  # POINT:FRAMES as written, None when absent
        self.analog_per_frame = analog_per_frame  # header word 3
        self.platforms_used = platforms_used  # FORCE_PLATFORM:USED as written, None when absent


def inspect_c3d(path: Path) -> RawC3D:
    """Check the header and parameter section of ``path`` and read the raw values.

    Raises
    ------
    InputFileError
        Missing file, no C3D header, an unsupported processor type (named), or a file that ends
        before its data section.
    """
    if not path.is_file():
        raise InputFileError("file not found", file=path, hint="check the path")
    with open(path, "rb") as fh:
        head = fh.read(512)
        if len(head) < 512 or head[1] != _C3D_PARAMETER_BLOCK_KEY or head[0] < 1:
            raise InputFileError(
                "not a C3D file (no C3D header)", file=path,
                hint="export the trial as C3D from the motion-capture software",
            )
        fh.seek((head[0] - 1) * 512)
        pheader = fh.read(4)
        if len(pheader) < 4:
            raise InputFileError(
                f"truncated: {path.stat().st_size} bytes, the parameter section announced at byte "
                f"{(head[0] - 1) * 512} is missing", file=path,
                hint="re-export it from the motion-capture software",
            )
        n_blocks, processor = pheader[2], pheader[3]
        if processor not in _READABLE_PROCESSORS:
            name = PROCESSOR_TYPES.get(processor)
            what = (f"processor type {processor} ({name}) is not supported" if name else
                    f"unknown processor type {processor} (expected 84 Intel, 85 DEC or 86 MIPS)")
            raise InputFileError(
                what, file=path, where="parameter section, processor type byte",
                hint=("bladelab reads Intel and DEC C3D files; convert the file to Intel (PC) "
                      "format, e.g. open and save it in Mokka/BTK or the capture software"),
            )
        fh.seek((head[0] - 1) * 512)
        params = fh.read(max(n_blocks, 1) * 512)
    data_start = int.from_bytes(head[16:18], "little")
    size = path.stat().st_size
    if data_start < 2 or size < (data_start - 1) * 512:
        raise InputFileError(
            f"truncated: {size} bytes, but the header puts the data block at byte "
            f"{max(data_start - 1, 0) * 512}", file=path,
            hint="re-export it from the motion-capture software",
        )
    first = int.from_bytes(head[6:8], "little")
    last = int.from_bytes(head[8:10], "little")
    header_frames = None if last >= 65535 or last < first else last - first + 1
    frames = _raw_parameter(params, "POINT", "FRAMES", dec=processor == 85)
    param_frames = None
    if frames is not None and frames > 0:
        param_frames = int(frames)
    used = _raw_parameter(params, "FORCE_PLATFORM", "USED", dec=processor == 85)
    return RawC3D(processor, data_start, header_frames, param_frames,
                  int.from_bytes(head[4:6], "little"), None if used is None else int(used))


def _vax_float(b: bytes) -> float:
    """A DEC (VAX F) 4-byte float as a Python float."""
    return struct.unpack("<f", b[2:4] + b[0:2])[0] / 4.0


def _raw_parameter(block: bytes, group: str, name: str, *, dec: bool = False) -> float | None:
    """First value of a numeric parameter as written in the parameter section (little-endian).

    Returns None when the parameter is absent or the section cannot be walked.
    """
    pos, gid_of = 4, {}
    records = []
    try:
        while pos + 4 <= len(block):
            nchar = abs(struct.unpack_from("b", block, pos)[0])
            gid = struct.unpack_from("b", block, pos + 1)[0]
            if nchar == 0:
                break
            label = block[pos + 2: pos + 2 + nchar].decode("ascii", "replace").upper()
            off_at = pos + 2 + nchar
            offset = struct.unpack_from("<h", block, off_at)[0]
            if gid < 0:
                gid_of[-gid] = label
            else:
                records.append((gid, label, off_at + 2))
            if offset <= 0:
                break
            pos = off_at + offset
        for gid, label, at in records:
            if gid_of.get(gid) != group or label != name:
                continue
            ptype = struct.unpack_from("b", block, at)[0]
            ndims = block[at + 1]
            data = at + 2 + ndims
            if ptype == 2:
                value = struct.unpack_from("<h", block, data)[0]
                return float(value + 65536 if value < 0 else value)  # frame counts are unsigned
            if ptype == 4:
                raw = block[data: data + 4]
                return _vax_float(raw) if dec else struct.unpack("<f", raw)[0]
            if ptype == 1:
                return float(block[data])
            return None
    except (struct.error, IndexError):
        return None
    return None


# --------------------------------------------------------------------------------------------
# opening
# --------------------------------------------------------------------------------------------


def open_c3d(path: Path, log: WarningLog):
    """Check ``path``, read it with ezc3d, and compare the frames read with those announced.

    Returns ``(c3d, raw)``: ezc3d's object and the :class:`RawC3D` values.

    Raises
    ------
    InputFileError
        See :func:`inspect_c3d`; a file ezc3d cannot read; a file with analog data that holds
        fewer frames than it announces (truncated).
    """
    import ezc3d

    raw = inspect_c3d(path)
    try:
        c3d = ezc3d.c3d(str(path))
    except Exception as err:  # ezc3d raises RuntimeError/IOError on corrupt files
        raise InputFileError(
            f"cannot be read as C3D ({err}); the file looks truncated or corrupt", file=path,
            hint="re-export it from the motion-capture software",
        ) from err
    got = np.asarray(c3d["data"]["points"]).shape[-1]
    analogs = np.asarray(c3d["data"]["analogs"])
    marker_only = raw.analog_per_frame == 0 or analogs.ndim != 3 or analogs.shape[1] == 0
    announced = raw.param_frames if raw.param_frames is not None else raw.header_frames
    source = "POINT:FRAMES" if raw.param_frames is not None else "the header"
    if announced is not None and got < announced:
        if not marker_only:
            raise InputFileError(
                f"truncated: the file announces {announced} frames ({source}) but holds only {got}",
                file=path, hint="re-export it from the motion-capture software",
            )
        log.warn(
            f"announces {announced} frames ({source}) but holds {got}: reading the {got} frames "
            "it holds (a marker-only file)", file=path,
            where="POINT:FRAMES" if raw.param_frames is not None else "header",
            hint="check that the recording is complete",
        )
    elif raw.header_frames is not None and raw.header_frames != got:
        log.warn(
            f"announces {raw.header_frames} frames, but POINT:FRAMES and the data hold {got}: "
            f"the header's count is stale; reading {got}", file=path, where="header",
        )
    return c3d, raw
