"""C3D files from other vendors and eras: one file per quirk, written here to
reproduce what the public c3d.org samples show, read back through ``read_c3d``.

Files are written with ezc3d, or, where ezc3d cannot write the quirk (a stale header, another
processor's byte order, a missing parameter), with the small raw writer below.
"""

from __future__ import annotations

import struct
import warnings

import ezc3d
import numpy as np
import pytest

import trial_synth as synth
from bladelab.errors import DataError, InputFileError
from bladelab.trial import C3DWarning, detect_stances, plate_corners, read_c3d, write_c3d

# --------------------------------------------------------------------------------------------
# writers
# --------------------------------------------------------------------------------------------


def _pack_floats(values, order: str, dec: bool) -> bytes:
    if not dec:
        return struct.pack(f"{order}{len(values)}f", *values)
    out = b""
    for v in values:  # DEC (VAX F): 4 × the IEEE value, 16-bit halves swapped
        b = struct.pack("<f", 4.0 * v)
        out += b[2:4] + b[0:2]
    return out


def _raw_param(order, dec, name, gid, kind, value) -> bytes:
    if kind == "char":
        vals = [value] if isinstance(value, str) else list(value)
        width = max([len(v) for v in vals] + [1])
        dims = [width] if isinstance(value, str) else [width, len(vals)]
        data, code = b"".join(v.ljust(width).encode() for v in vals), -1
    else:
        arr = np.asarray(value)
        dims, flat = list(arr.shape), arr.ravel(order="F")
        if kind == "int":
            data, code = struct.pack(f"{order}{flat.size}h", *(int(v) for v in flat)), 2
        else:
            data, code = _pack_floats([float(v) for v in flat], order, dec), 4
    body = struct.pack("bB", code, len(dims)) + bytes(dims) + data + b"\x00"
    return (struct.pack("bb", len(name), gid) + name.encode()
            + struct.pack(f"{order}h", 2 + len(body)) + body)


def write_raw_c3d(path, *, points, rate, analogs=None, analog_rate=None, params=None,
                  byte_order="intel", header_last_frame=None):
    """A float-format C3D written byte by byte: ``points`` (frames, markers, 3) in file units,
    ``analogs`` (channels, samples); ``params`` {group: {name: (kind, value)}} added to or
    replacing the defaults (a value of None removes a parameter); ``byte_order`` "intel",
    "dec" (VAX floats) or "mips" (big-endian); ``header_last_frame`` overrides header word 5."""
    order, dec = (">", False) if byte_order == "mips" else ("<", byte_order == "dec")
    processor = {"intel": 84, "dec": 85, "mips": 86}.get(byte_order, byte_order)
    points = np.asarray(points, dtype=float)
    n_frames, n_points = points.shape[:2]
    analogs = np.zeros((0, n_frames)) if analogs is None else np.asarray(analogs, dtype=float)
    n_ch = analogs.shape[0]
    per_frame = analogs.shape[1] // n_frames if n_ch else 0
    groups = {
        "POINT": {"USED": ("int", [n_points]), "SCALE": ("float", [-1.0]),
                  "RATE": ("float", [rate]), "FRAMES": ("int", [n_frames]),
                  "DATA_START": ("int", [0]), "UNITS": ("char", "mm"),
                  "LABELS": ("char", [f"M{i + 1}" for i in range(n_points)] or [""])},
        "ANALOG": {"USED": ("int", [n_ch]), "RATE": ("float", [analog_rate or rate]),
                   "GEN_SCALE": ("float", [1.0]), "SCALE": ("float", [1.0] * max(n_ch, 1)),
                   "OFFSET": ("int", [0] * max(n_ch, 1)),
                   "LABELS": ("char", [f"CH{i + 1}" for i in range(n_ch)] or [""])},
    }
    for group, ps in (params or {}).items():
        groups.setdefault(group, {}).update(ps)

    def section(data_start):
        groups["POINT"]["DATA_START"] = ("int", [data_start])
        out = b""
        for gid, (group, ps) in enumerate(groups.items(), start=1):
            out += struct.pack("bb", len(group), -gid) + group.encode() + struct.pack(f"{order}h", 3)
            out += b"\x00"
            for name, spec in ps.items():
                if spec is not None:
                    out += _raw_param(order, dec, name, gid, *spec)
        return out

    n_blocks = (4 + len(section(0)) + 511) // 512
    data_start = 2 + n_blocks
    params_block = (bytes([1, 0x50, n_blocks, processor]) + section(data_start)).ljust(512 * n_blocks, b"\0")
    header = bytearray(512)
    header[0:2] = bytes([2, 0x50])
    last = n_frames if header_last_frame is None else header_last_frame
    struct.pack_into(f"{order}5h", header, 2, n_points, n_ch * per_frame, 1, last, 0)
    header[12:16] = _pack_floats([-1.0], order, dec)
    struct.pack_into(f"{order}2h", header, 16, data_start, per_frame)
    header[20:24] = _pack_floats([rate], order, dec)
    struct.pack_into(f"{order}h", header, 294, 12345)
    frames = b""
    for f in range(n_frames):
        row = np.concatenate([np.column_stack([points[f], np.zeros(n_points)]).ravel(),
                              analogs[:, f * per_frame:(f + 1) * per_frame].T.ravel()])
        frames += _pack_floats(row.tolist(), order, dec)
    frames = frames.ljust(-(-len(frames) // 512) * 512, b"\0")
    path.write_bytes(bytes(header) + params_block + frames)
    return path


def _int_param(c3d, group, name, value):
    """Set an ezc3d parameter as INT (``add_parameter`` writes lists of integers as floats)."""
    arr = np.asarray(value)
    c3d.add_parameter(group, name, arr.astype(float))
    c3d["parameters"][group][name]["type"] = c3d["parameters"]["POINT"]["USED"]["type"]
    c3d["parameters"][group][name]["value"] = arr.astype(int)


def _ezc3d_file(path, *, markers, rate, channels, analog_rate, units, fp, point_units="mm"):
    """markers (frames, n, 3) in file units; fp {name: (int|float, value)}."""
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [rate]
    c["parameters"]["POINT"]["LABELS"]["value"] = tuple(f"M{i + 1}" for i in range(markers.shape[1]))
    c["parameters"]["POINT"]["UNITS"]["value"] = [point_units]
    pts = np.ones((4, markers.shape[1], markers.shape[0]))
    pts[:3] = markers.transpose(2, 1, 0)
    c["data"]["points"] = pts
    c["parameters"]["ANALOG"]["RATE"]["value"] = [analog_rate]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = tuple(f"CH{i + 1}" for i in range(len(channels)))
    c["parameters"]["ANALOG"]["UNITS"]["value"] = units
    c["data"]["analogs"] = np.asarray(channels, dtype=float)[None]
    for name, (kind, value) in fp.items():
        if kind is int:
            _int_param(c, "FORCE_PLATFORM", name, value)
        else:
            c.add_parameter("FORCE_PLATFORM", name, np.asarray(value, dtype=float))
    c.write(str(path))
    return path


def _half_sine(t, t0, t1, peak):
    on = (t >= t0) & (t <= t1)
    return np.where(on, peak * np.sin(np.pi * np.clip((t - t0) / (t1 - t0), 0, 1)), 0.0)


def _lab_perm(axes):
    perm = np.zeros((3, 3))
    for row, key in enumerate(("forward", "lateral", "up")):
        a = axes[key]
        perm[row, "xyz".index(a[1])] = 1.0 if a[0] == "+" else -1.0
    return perm


# --------------------------------------------------------------------------------------------
# quirks
# --------------------------------------------------------------------------------------------


def test_motionmonitor_type4_y_up_takes_the_vertical_sense_from_the_data(tmp_path):
    """Type-4 plates in a y-up lab whose corners put the plate z axis up (the real MotionMonitor
    sample's corners do not: tests/test_trial_c3d_samples.py). The markers stand along +y and
    ezc3d's platform module shows a normal loading along +y; the vertical must be +y."""
    rate, arate, n = 100.0, 1000.0, 1300
    t = np.arange(n) / arate
    tm = np.arange(n // 10) / rate
    markers = np.stack([np.column_stack([-1.0 + 4.0 * tm, np.full_like(tm, h), np.full_like(tm, 0.2)])
                        for h in (0.1, 0.5, 1.0)], axis=1) * 1000.0  # y up, mm
    cal = np.eye(6) + 0.02 * np.arange(36).reshape(6, 6) / 36.0  # cross-talk
    channels, corners = [], []
    for xc, t0, t1 in [(0.3, 0.30, 0.55), (0.9, 0.75, 1.00)]:
        fz = _half_sine(t, t0, t1, 1500.0)  # GRF on the subject along +z_plate (= +y, up)
        fx = -0.2 * fz * np.cos(np.pi * np.clip((t - t0) / (t1 - t0), 0, 1))
        px = np.full_like(t, 0.05)
        py = np.full_like(t, -0.02)
        wrench = np.vstack([fx, 0 * t, fz, py * fz * 1e3, -px * fz * 1e3, 0 * t])  # N, N·mm
        channels.append(np.linalg.solve(cal, wrench))
        a, b = 300.0, 200.0  # half sizes [mm]; c1−c2 = +x, c1−c4 = −z  =>  z_plate = +y
        c1 = np.array([xc * 1000 + a, 0, 200 - b])
        corners.append(np.array([c1, c1 - [2 * a, 0, 0], c1 - [2 * a, 0, -2 * b], c1 + [0, 0, 2 * b]]))
    path = _ezc3d_file(
        tmp_path / "motionmonitor.c3d", markers=markers, rate=rate, channels=np.vstack(channels),
        analog_rate=arate, units=["V"] * 3 + ["Nmm"] * 3 + ["V"] * 3 + ["Nmm"] * 3,
        fp={"USED": (int, [2]), "TYPE": (int, [4, 4]), "ZERO": (int, [1, 0]),
            "CHANNEL": (int, np.arange(1, 13).reshape(2, 6).T),
            "CORNERS": (float, np.stack([c.T for c in corners], axis=2)),
            "ORIGIN": (float, np.zeros((3, 2))),
            "CAL_MATRIX": (float, np.stack([cal, cal], axis=2))},
    )
    ref = ezc3d.c3d(str(path), extract_forceplat_data=True)["data"]["platform"]
    assert ref[0]["force"][1].max() == pytest.approx(1500.0, rel=1e-3)  # normal loading, +y

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        trial = read_c3d(path)
    events = detect_stances(trial)
    assert trial.metadata["axes"]["up"] == "+y" and trial.metadata["axes"]["forward"] == "+x"
    assert np.nanmin(trial.marker("M1")[:, 2]) > 0.05  # markers above the floor
    (warning,) = [w for w in caught if issubclass(w.category, C3DWarning)]
    assert "platform 1: its CORNERS make file +y the plate's z axis" in str(warning.message)
    assert [e.plates for e in events] == [(1,), (2,)]
    for e, (t0, t1) in zip(events, [(0.30, 0.55), (0.75, 1.00)], strict=True):
        assert e.peak_fz_N == pytest.approx(1500.0, rel=0.01)
        assert abs(e.start_s - t0) < 0.005 and abs(e.end_s - t1) < 0.005
    for plate, r in zip(trial.platforms, ref, strict=True):
        np.testing.assert_allclose(plate.force, r["force"].T @ _lab_perm(trial.metadata["axes"]).T,
                                   atol=1e-6)


def _kistler_channels(t, a, b, az0):
    fz = -_half_sine(t, 0.2, 0.45, 1200.0)  # GRF on the subject, plate z down
    fx, fy = 0.1 * fz, -0.05 * fz
    ax, ay, tz = 0.08, -0.04, 0.0
    my = fx * az0 - ax * fz
    mx = ay * fz - fy * az0
    mz = tz + (ax * fy - ay * fx)
    m = np.array([[1, 1, 1, 1], [1, 1, -1, -1], [-1, 1, 1, -1], [1, -1, 1, -1]], dtype=float)
    fzs = np.linalg.solve(m, np.vstack([fz, mx / b, my / a, np.zeros_like(fz)]))
    return np.vstack([fx / 2 - mz / (2 * b), fx / 2 + mz / (2 * b), fy / 2, fy / 2, *fzs]), (ax, ay)


@pytest.mark.parametrize("units, metres", [
    ("mete", 1.0), ("meters", 1.0), ("metres", 1.0), ("m", 1.0), ("mm", 1e-3),
    ("millimeters", 1e-3), ("MM ", 1e-3), ("cm", 1e-2), ("centimetres", 1e-2),
])
def test_kistler_type3_point_units_read_leniently(tmp_path, units, metres):
    """The Kistler sample stores POINT:UNITS as 'mete' (4 characters of 'meters')."""
    t = np.arange(600) / 1000.0
    a, b, az0 = 0.12, 0.20, -0.045
    channels, (ax, ay) = _kistler_channels(t, a, b, az0)
    corners = plate_corners((1.0, 0.5, 0.0), 0.6, 0.4)
    tm = np.arange(60) / 100.0
    markers = np.stack([np.column_stack([tm, 0 * tm + 0.3, 0 * tm + 0.9])], axis=1)
    path = _ezc3d_file(
        tmp_path / "kistler.c3d", markers=markers / metres, rate=100.0, channels=channels,
        analog_rate=1000.0, units=["N"] * 8, point_units=units,
        fp={"USED": (int, [1]), "TYPE": (int, [3]), "CHANNEL": (int, np.arange(1, 9).reshape(8, 1)),
            "CORNERS": (float, (corners.T / metres)[:, :, None]),
            "ORIGIN": (float, (np.array([a, b, az0]) / metres).reshape(3, 1))},
    )
    trial = read_c3d(path, forward="+x", up="+z")
    np.testing.assert_allclose(trial.marker("M1"), markers[:, 0], atol=1e-5)
    plate = trial.platforms[0]
    loaded = plate.force[:, 2] > 100
    cop = plate.cop[loaded, :2]
    np.testing.assert_allclose(cop, np.broadcast_to([1.0 + ax, 0.5 - ay], cop.shape), atol=1e-5)
    (event,) = detect_stances(trial)
    assert event.peak_fz_N == pytest.approx(1200.0, rel=0.01)


def test_unknown_point_units_are_refused_naming_the_parameter(tmp_path):
    path = write_raw_c3d(tmp_path / "furlong.c3d", points=np.zeros((10, 1, 3)), rate=100.0,
                         params={"POINT": {"UNITS": ("char", "furlong")}})
    with pytest.raises(DataError, match="unknown length unit 'furlong'") as err:
        read_c3d(path)
    assert "POINT:UNITS" in str(err.value) and str(path) in str(err.value)
    assert "hint" in str(err.value)


@pytest.mark.parametrize("point_frames", [30, 1149])
def test_optotrak_marker_only_file_with_a_stale_frame_count_is_read(tmp_path, point_frames):
    """The Optotrak sample: 54 markers, 30 frames, no analog data, a header announcing more
    frames than the file holds. ezc3d reads its 30 frames; so must we (with a warning)."""
    rng = np.random.default_rng(3)
    points = rng.uniform(-500, 1500, size=(30, 54, 3))
    path = write_raw_c3d(
        tmp_path / "optotrak.c3d", points=points, rate=30.0, header_last_frame=1149,
        params={"POINT": {"SCALE": ("float", [-7.8661418]), "UNITS": ("char", ["mm"] * 54),
                          "FRAMES": ("int", [point_frames])}},
    )
    assert np.asarray(ezc3d.c3d(str(path))["data"]["points"]).shape == (4, 54, 30)
    with pytest.warns(C3DWarning, match="1149") as record:
        trial = read_c3d(path)
    assert "truncated" not in str(record[0].message)
    assert trial.n_frames == 30 and len(trial.markers) == 54 and trial.platforms == ()
    np.testing.assert_allclose(trial.marker("M7"), points[:, 6] / 1000.0, atol=1e-6)
    assert any("1149" in w for w in trial.metadata["warnings"])


def test_big_endian_file_is_refused_naming_the_processor_type(tmp_path):
    """SGI/MIPS (and old Macintosh) files are big-endian: processor type 86, which ezc3d does
    not read. The error must say so, never 'truncated'."""
    points = np.arange(60, dtype=float).reshape(10, 2, 3)
    path = write_raw_c3d(tmp_path / "sgi.c3d", points=points, rate=50.0, byte_order="mips")
    with pytest.raises(RuntimeError, match="MIPS"):
        ezc3d.c3d(str(path))
    with pytest.raises(InputFileError, match=r"processor type 86 \(MIPS/SGI") as err:
        read_c3d(path)
    msg = str(err.value)
    assert "truncated" not in msg and "processor type byte" in msg and str(path) in msg
    assert "hint" in msg

    bad = write_raw_c3d(tmp_path / "odd.c3d", points=points, rate=50.0, byte_order=0)
    with pytest.raises(InputFileError, match="unknown processor type 0"):
        read_c3d(bad)


def test_dec_file_is_read(tmp_path):
    """DEC (VAX) files, the other old processor type, are read (ezc3d converts their floats)."""
    points = np.arange(60, dtype=float).reshape(10, 2, 3) * 10.0
    intel = read_c3d(write_raw_c3d(tmp_path / "pc.c3d", points=points, rate=50.0))
    dec = read_c3d(write_raw_c3d(tmp_path / "dec.c3d", points=points, rate=50.0, byte_order="dec"))
    assert dec.marker_rate == intel.marker_rate == 50.0
    for label in intel.markers:
        np.testing.assert_allclose(dec.marker(label), intel.marker(label), atol=1e-9)


def _with_channel_offsets(path, offsets):
    """Add constant offsets to a file's analog channels (a plate that was not zeroed)."""
    c = ezc3d.c3d(str(path))
    analogs = np.asarray(c["data"]["analogs"]).copy()
    analogs[0] += np.asarray(offsets, dtype=float)[:, None]
    c["data"]["analogs"] = analogs
    c.write(str(path))
    return path


def test_plate_calibrated_as_force_on_the_plate_is_inverted(tmp_path):
    """Of two plates, one gives the force on the plate (all its channels negated): the corners
    keep the vertical, that plate's sign is inverted, with a warning naming it."""
    path = tmp_path / "two.c3d"
    force, _ = synth.write_two_plates_one_foot(path)
    c = ezc3d.c3d(str(path))
    analogs = np.asarray(c["data"]["analogs"]).copy()
    analogs[0, 6:12] *= -1.0  # platform 2's channels
    c["data"]["analogs"] = analogs
    c.write(str(path))
    with pytest.warns(C3DWarning, match="platform 2: loaded, its vertical force points down"):
        trial = read_c3d(path)
    assert trial.metadata["axes"]["up"] == "+z"
    np.testing.assert_allclose(trial.platforms[0].force + trial.platforms[1].force, force, atol=1e-3)
    (event,) = detect_stances(trial)
    assert event.plates == (1, 2) and event.peak_fz_N == pytest.approx(synth.PEAK, rel=0.01)


@pytest.mark.parametrize("vertical_offset", [150.0, -2500.0])
def test_plate_not_zeroed_offset_removed_from_unloaded_periods(tmp_path, vertical_offset):
    """A constant offset on every channel: +150 N keeps the plate 'loaded' all along, −2500 N
    keeps it below any threshold. Both gave 'no stance found … lower --threshold'."""
    path = tmp_path / "offset.c3d"
    _, ta = synth.write_single_plate(path)
    # plate z points down: a lab vertical offset is −offset on Fz; moments in N·mm
    _with_channel_offsets(path, [12.0, -8.0, -vertical_offset, 4000.0, -2500.0, 1500.0])
    trial = read_c3d(path)
    (event,) = detect_stances(trial)
    assert abs(event.start_s - synth.TD) < 0.004 and abs(event.end_s - synth.TO) < 0.004
    assert event.peak_fz_N == pytest.approx(synth.PEAK, rel=0.01)
    plate = trial.platforms[0]
    np.testing.assert_allclose(plate.force, synth.grf(ta), atol=0.5)
    loaded = plate.force[:, 2] > 300
    np.testing.assert_allclose(plate.cop[loaded], synth.cop(ta)[loaded], atol=2e-3)
    assert plate.zero_offset_N == pytest.approx(vertical_offset, abs=0.5)

    # switched off: the file's values, and a message that points at the zero, not the threshold
    raw = read_c3d(path, zero_offset=False)
    assert raw.platforms[0].zero_offset_N == 0.0
    with pytest.raises(DataError, match="no stance found") as err:
        detect_stances(raw)
    assert "lower --threshold" not in str(err.value) and "zero" in str(err.value)


def test_plate_that_never_unloads_is_named(tmp_path):
    """A plate loaded all along (a treadmill walker): no zero offset can be estimated."""
    t = np.arange(2000) / 1000.0
    force = np.column_stack([0 * t, 0 * t, 700.0 + 250.0 * np.sin(2 * np.pi * 1.8 * t)])
    path = tmp_path / "walker.c3d"
    write_c3d(path, markers={"A": np.tile([0.0, 0.0, 1.0], (200, 1))}, marker_rate=100.0,
              analog_rate=1000.0, platforms=[
                  {"force": force, "cop": np.tile([0.5, 0.0, 0.0], (2000, 1)),
                   "corners": plate_corners((0.5, 0.0, 0.0), 1.0, 0.6)},
                  {"force": np.zeros((2000, 3)), "corners": plate_corners((1.5, 0.0, 0.0), 1.0, 0.6)},
              ])
    with pytest.warns(C3DWarning, match="platform 1: never unloads") as record:
        trial = read_c3d(path, forward="+x")
    assert not any("platform 2" in str(w.message) for w in record)
    np.testing.assert_allclose(trial.platforms[0].force, force, atol=1e-3)  # nothing removed
    assert trial.platforms[0].zero_offset_N == 0.0


def test_stuck_plate_is_named(tmp_path):
    """One plate stuck at −1448 N beside a working one: warned about, not silently ignored."""
    ta = np.arange(1000) / 1000.0
    path = tmp_path / "stuck.c3d"
    stuck = np.column_stack([0 * ta, 0 * ta, np.full_like(ta, -1448.0)])
    write_c3d(path, markers=synth.markers(np.arange(200) / 200.0), marker_rate=200.0,
              analog_rate=1000.0, platforms=[
                  {"force": synth.grf(ta), "cop": synth.cop(ta),
                   "corners": plate_corners((0.5, 0.0, 0.0), 0.9, 0.6)},
                  {"force": stuck, "corners": plate_corners((1.4, 0.0, 0.0), 0.9, 0.6)},
              ])
    with pytest.warns(C3DWarning, match="platform 2: its vertical force stays at -1448 N"):
        trial = read_c3d(path)
    assert any("platform 2" in w for w in trial.metadata["warnings"])
    assert [e.plates for e in detect_stances(trial)] == [(1,)]


def test_type1_platforms_match_ezc3d(tmp_path):
    """Four type-1 plates (Fx, Fy, Fz, COPx, COPy, Tz; ezc3d's FP_Type1 sample has four), with
    an ORIGIN that type 1 does not use: force, COP and free moment as ezc3d's module gives them."""
    arate, n = 1000.0, 1200
    t = np.arange(n) / arate
    channels, corners = [], []
    for k in range(4):
        t0 = 0.1 + 0.25 * k
        fz = -_half_sine(t, t0, t0 + 0.2, 900.0 + 50 * k)  # plate z down
        on = fz < -1.0
        cop_x = np.where(on, 40.0 - 200.0 * (t - t0), 0.0)  # mm, relative to the plate centre
        cop_y = np.where(on, -15.0 + 5 * k, 0.0)
        channels.append(np.vstack([0.1 * fz, -0.02 * fz, fz, cop_x, cop_y, np.where(on, 2000.0, 0.0)]))
        corners.append(plate_corners((0.3 + 0.6 * k, 0.0, 0.0), 0.6, 0.4).T * 1000.0)
    tm = np.arange(n // 10) / 100.0
    markers = np.stack([np.column_stack([-200 + 2500 * tm, 0 * tm + 100, 0 * tm + 900])], axis=1)
    path = _ezc3d_file(
        tmp_path / "type1.c3d", markers=markers, rate=100.0, channels=np.vstack(channels),
        analog_rate=arate, units=["N", "N", "N", "mm", "mm", "Nmm"] * 4,
        fp={"USED": (int, [4]), "TYPE": (int, [1] * 4), "ZERO": (int, [1, 0]),
            "CHANNEL": (int, np.arange(1, 25).reshape(4, 6).T),
            "CORNERS": (float, np.stack(corners, axis=2)),
            "ORIGIN": (float, np.tile([[12.0], [-7.0], [-30.0]], (1, 4)))},
    )
    trial = read_c3d(path)
    ref = ezc3d.c3d(str(path), extract_forceplat_data=True)["data"]["platform"]
    perm = _lab_perm(trial.metadata["axes"])
    assert [p.type for p in trial.platforms] == [1, 1, 1, 1]
    for plate, r in zip(trial.platforms, ref, strict=True):
        loaded = plate.force[:, 2] > 50
        np.testing.assert_allclose(plate.force, r["force"].T @ perm.T, atol=1e-6)
        np.testing.assert_allclose(plate.cop[loaded], (r["center_of_pressure"].T / 1000.0 @ perm.T)[loaded],
                                   atol=1e-6)
        tz = r["Tz"][2] / 1000.0 * perm[2, 2]
        np.testing.assert_allclose(plate.free_moment[loaded], tz[loaded], atol=1e-6)
    assert [e.plates for e in detect_stances(trial)] == [(1,), (2,), (3,), (4,)]


def test_platforms_without_used_parameter_are_read(tmp_path):
    """A FORCE_PLATFORM group without USED (ezc3d fills in 0): the platforms TYPE describes."""
    t = np.arange(1000) / 1000.0
    fz = -_half_sine(t, 0.3, 0.6, 800.0)
    channels = np.vstack([0.1 * fz, 0 * t, fz, 0 * t + 50, 0 * t + 20, 0 * t])
    corners = plate_corners((0.3, 0.0, 0.0), 0.6, 0.4).T * 1000.0
    path = write_raw_c3d(
        tmp_path / "no_used.c3d", points=np.zeros((100, 1, 3)), rate=100.0, analogs=channels,
        analog_rate=1000.0,
        params={"ANALOG": {"UNITS": ("char", ["N", "N", "N", "mm", "mm", "Nmm"])},
                "FORCE_PLATFORM": {"TYPE": ("int", [1]), "CHANNEL": ("int", np.arange(1, 7).reshape(6, 1)),
                                   "CORNERS": ("float", corners[:, :, None]),
                                   "ORIGIN": ("float", np.zeros((3, 1)))}},
    )
    with pytest.warns(C3DWarning, match="FORCE_PLATFORM:USED is missing"):
        trial = read_c3d(path, forward="+x")
    assert [p.type for p in trial.platforms] == [1]
    (event,) = detect_stances(trial)
    assert event.peak_fz_N == pytest.approx(800.0, rel=0.01)


def test_write_c3d_stores_integer_parameters_for_ezc3d(tmp_path):
    """ezc3d's platform reader refuses FORCE_PLATFORM:USED/TYPE/CHANNEL stored as floats."""
    path = tmp_path / "ours.c3d"
    _, ta = synth.write_single_plate(path)
    c = ezc3d.c3d(str(path), extract_forceplat_data=True)
    fp = c["parameters"]["FORCE_PLATFORM"]
    int_type = c["parameters"]["POINT"]["USED"]["type"]
    assert all(fp[name]["type"] == int_type for name in ("USED", "TYPE", "CHANNEL", "ZERO"))
    assert c["parameters"]["BLADELAB"]["CATEGORY"]["type"] == int_type
    (ref,) = c["data"]["platform"]
    np.testing.assert_allclose(ref["force"].T, synth.grf(ta), atol=1e-3)  # file axes = lab axes
    loaded = synth.grf(ta)[:, 2] > 50
    np.testing.assert_allclose(ref["center_of_pressure"].T[loaded] / 1000.0, synth.cop(ta)[loaded],
                               atol=1e-5)
    trial = read_c3d(path)
    assert trial.metadata["category"] == 5 and trial.metadata["speed_pct_pb"] == 95
