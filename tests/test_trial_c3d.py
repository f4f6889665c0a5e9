"""C3D reader and writer: real files checked against hand computations and physics."""

from __future__ import annotations

import shutil

import ezc3d
import numpy as np
import pandas as pd
import pytest

import trial_synth as synth
from bladelab.errors import BladelabError, DataError, InputFileError, SpecError
from bladelab.trial.c3d import C3DWarning, plate_corners, read_c3d, write_c3d
from bladelab.units import body_weight
from conftest import FUKUCHI_FORCES, FUKUCHI_INFO, FUKUCHI_STATIC, WALKING
from conftest import FUKUCHI_RUN as FUKUCHI


def _subject_mass(subject: int) -> float:
    info = pd.read_csv(FUKUCHI_INFO, sep="\t")
    return float(info.loc[info["Subject"] == subject, "Mass"].iloc[0])


@pytest.fixture(scope="module")
def fukuchi():
    return read_c3d(FUKUCHI)


def test_type4_calibration_matrix_by_hand(fukuchi):
    """Vertical GRF = CAL_MATRIX @ raw analogs, rotated by the plate axes derived by hand."""
    c = ezc3d.c3d(str(FUKUCHI))
    fp = c["parameters"]["FORCE_PLATFORM"]
    raw = c["data"]["analogs"][0]  # 6 channels as stored (scaled)
    cal = np.asarray(fp["CAL_MATRIX"]["value"])[:, :, 0]
    f_plate = cal @ raw  # (6, n)
    # corners (mm): c1=(3049,0,733.7) c2=(3049,0,1219.7) c3=(1249,0,1219.7) c4=(1249,0,733.7)
    # plate x = c1-c2 -> file -z ; plate y = c1-c4 -> file +x ; plate z = x × y -> file -y (down)
    # lab: forward = file +x, up = file +y, lateral = up × forward = file -z
    expected_up = -f_plate[2]
    expected_forward = f_plate[1]
    expected_lateral = f_plate[0]  # plate x is file -z = lab +y
    force = fukuchi.platforms[0].force
    np.testing.assert_allclose(force[:, 2], expected_up, atol=1e-9)
    np.testing.assert_allclose(force[:, 0], expected_forward, atol=1e-9)
    np.testing.assert_allclose(force[:, 1], expected_lateral, atol=1e-9)
    # ignoring the calibration would give a physically impossible peak
    assert np.max(np.abs(raw[2])) < 10.0 < np.max(force[:, 2])


def test_fukuchi_forces_are_physiological(fukuchi):
    bw = body_weight(_subject_mass(1))  # RBDSinfo.txt: 62 kg
    fz = fukuchi.platforms[0].force[:, 2]
    # on a treadmill the mean vertical GRF over many strides equals body weight
    assert abs(fz.mean() / bw - 1.0) < 0.05
    assert 2.3 < fz.max() / bw < 2.8


def test_fukuchi_axes_and_units(fukuchi):
    info = fukuchi.info()
    assert info["axes"] == {"forward": "+x", "lateral": "-z", "up": "+y"}
    assert info["point_units"] == "mm"
    assert fukuchi.marker_rate == 150.0 and fukuchi.platforms[0].rate == 300.0
    assert fukuchi.platforms[0].type == 4
    # the runner stands on the treadmill: heel markers near z = 0 (m, not mm), feet forward of hips
    heel = fukuchi.marker("R.Heel.Bottom")
    assert -0.05 < np.nanmin(heel[:, 2]) < 0.1
    foot = fukuchi.marker("R.MT1") - fukuchi.marker("R.Heel.Bottom")
    assert np.nanmedian(foot[:, 0]) > 0.05  # toes point forward


@pytest.mark.parametrize("name", [FUKUCHI, *WALKING], ids=lambda p: p.name)
def test_cop_and_free_moment_match_ezc3d_module(name):
    """ezc3d's own force-platform module is an independent implementation of COP and Tz.

    ezc3d keeps the file's zero offsets, so the comparison reads the file as it is.
    """
    trial = read_c3d(name, zero_offset=False)
    c = ezc3d.c3d(str(name), extract_forceplat_data=True)
    axes = trial.metadata["axes"]
    perm = np.zeros((3, 3))
    for row, key in enumerate(("forward", "lateral", "up")):
        a = axes[key]
        perm[row, "xyz".index(a[1])] = 1.0 if a[0] == "+" else -1.0
    up_axis = "xyz".index(axes["up"][1])
    for plate, ref in zip(trial.platforms, c["data"]["platform"], strict=True):
        loaded = plate.force[:, 2] > 100
        np.testing.assert_allclose(plate.force, ref["force"].T @ perm.T, atol=1e-6)
        cop_ref = (ref["center_of_pressure"].T / 1000.0) @ perm.T
        np.testing.assert_allclose(plate.cop[loaded], cop_ref[loaded], atol=1e-6)
        tz_ref = ref["Tz"][up_axis] / 1000.0 * (1 if axes["up"][0] == "+" else -1)
        np.testing.assert_allclose(plate.free_moment[loaded], tz_ref[loaded], atol=1e-6)


def test_fukuchi_cop_under_the_stance_foot(fukuchi):
    """Independent of any COP code: the COP lies under the forefoot markers of the loaded foot."""
    plate = fukuchi.platforms[0]
    t = plate.time
    loaded = plate.force[:, 2] > 800
    mt = {}
    for side in "LR":
        xyz = (fukuchi.marker(f"{side}.MT1") + fukuchi.marker(f"{side}.MT5")) / 2
        mt[side] = np.column_stack([np.interp(t, fukuchi.marker_time, xyz[:, i]) for i in range(3)])
    down = np.where((mt["R"][:, 2] < mt["L"][:, 2])[:, None], mt["R"], mt["L"])
    d = np.linalg.norm(down[loaded, :2] - plate.cop[loaded, :2], axis=1)
    assert np.nanmedian(d) < 0.08
    lo, hi = plate.corners.min(axis=0), plate.corners.max(axis=0)
    assert np.all((plate.cop[loaded, :2] >= lo[:2] - 1e-9) & (plate.cop[loaded, :2] <= hi[:2] + 1e-9))


def test_forces_txt_export_agrees_on_matching_quantities(fukuchi):
    """RBDS0041runT252forces.txt is another runner's 2.5 m/s trial (not RBDS001 at 3.5 m/s).

    What matches: rate and length (300 Hz, 30 s), file axes (y up: COPy = 0 = plate surface),
    sign conventions (GRF on the runner, vertical positive; Fx brakes then propels along +x),
    peak/mean vertical force ratio (mean = body weight on a treadmill) and contact times.
    """
    txt = pd.read_csv(FUKUCHI_FORCES, sep="\t")
    plate = fukuchi.platforms[0]
    assert len(txt) == plate.n_samples == 9000
    # vertical = file y in both; our plate surface is file y = 0 like the export's COPy
    assert fukuchi.metadata["axes"]["up"] == "+y"
    assert np.all(txt["COPy"] == 0.0)
    np.testing.assert_allclose(plate.corners[:, 2], 0.0)
    assert txt["Fy"].mean() > 5 * abs(txt["Fx"].mean())
    # braking then propulsion along file +x in the export, as the reader's forward axis says
    fy, fx = txt["Fy"].to_numpy(), txt["Fx"].to_numpy()
    edges = np.flatnonzero(np.diff(np.concatenate([[0], (fy > 200).astype(int), [0]])))
    scores = []
    for s, e in zip(edges[::2], edges[1::2], strict=True):
        if e - s > 20:  # a contact: braking (Fx < 0) in the first half, propulsion after
            scores.append(np.linspace(-1, 1, e - s) @ fx[s:e])
    assert len(scores) > 50 and np.mean(np.array(scores) > 0) > 0.9
    assert fukuchi.metadata["axes"]["forward"] == "+x"
    # peak / mean vertical force (= peak in body weights) in the same physiological band
    ratio_txt = np.percentile(fy, 99.9) / fy.mean()
    ratio_ours = np.percentile(plate.force[:, 2], 99.9) / plate.force[:, 2].mean()
    assert 2.0 < ratio_txt < 3.0 and 2.0 < ratio_ours < 3.0
    # free moment: export in N·mm, ours in N·m: same order of magnitude
    ty = np.percentile(np.abs(txt["Ty"]), 95) / 1000.0
    ours = np.nanpercentile(np.abs(plate.free_moment), 95)
    assert 0.2 < ours / ty < 5.0


@pytest.mark.parametrize("name", WALKING, ids=lambda p: p.name)
def test_walking_plates_zero_offset(name):
    """The OpenSim walking plates read −14 to −20 N unloaded: removed as a constant offset."""
    raw = read_c3d(name, zero_offset=False)
    zeroed = read_c3d(name)
    for p0, p1 in zip(raw.platforms, zeroed.platforms, strict=True):
        fz = p0.force[:, 2]
        by_hand = np.median(fz)  # the plates are unloaded most of the time
        assert -25.0 < by_hand < -10.0
        assert p1.zero_offset_N == pytest.approx(by_hand, abs=1.0)
        diff = p1.force - p0.force
        np.testing.assert_allclose(diff, np.broadcast_to(diff[0], diff.shape), atol=1e-9)  # constant
        assert diff[0, 2] == pytest.approx(-p1.zero_offset_N, abs=1e-3)
        assert abs(np.median(p1.force[:, 2])) < 1.0
    assert "warnings" not in zeroed.metadata


def test_fukuchi_zeroed_plate_is_left_alone(fukuchi):
    """A zeroed plate (unloaded level within 5 N) reads exactly as the file gives it."""
    raw = read_c3d(FUKUCHI, zero_offset=False)
    assert fukuchi.platforms[0].zero_offset_N == 0.0
    np.testing.assert_array_equal(fukuchi.platforms[0].force, raw.platforms[0].force)


def test_walking_two_type2_platforms():
    for name in WALKING:
        trial = read_c3d(name)
        assert [p.type for p in trial.platforms] == [2, 2]
        assert trial.metadata["axes"]["up"] == "+z"
        # gaps are NaN, never zeros
        n_nan = sum(int(np.isnan(m[:, 0]).sum()) for m in trial.markers.values())
        assert n_nan > 0
        for p in trial.platforms:
            assert 600 < p.force[:, 2].max() < 1000  # walking: ~1.1–1.5 body weights


def test_write_read_round_trip(tmp_path):
    path = tmp_path / "synthetic.c3d"
    tm, ta = synth.write_single_plate(path)
    trial = read_c3d(path)
    assert trial.metadata["axes"] == {"forward": "+x", "lateral": "+y", "up": "+z"}
    for label, xyz in synth.markers(tm).items():
        np.testing.assert_allclose(trial.marker(label), xyz, atol=1e-6)  # float32 in mm
    plate = trial.platforms[0]
    assert plate.type == 2 and plate.rate == synth.ANALOG_RATE
    np.testing.assert_allclose(plate.force, synth.grf(ta), atol=1e-3)
    loaded = plate.force[:, 2] > 50
    np.testing.assert_allclose(plate.cop[loaded], synth.cop(ta)[loaded], atol=1e-5)
    np.testing.assert_allclose(plate.free_moment[loaded], 3.0, atol=1e-3)
    assert trial.metadata["athlete"] == "TT1"
    assert trial.metadata["category"] == 5 and trial.metadata["speed_pct_pb"] == 95
    assert trial.metadata["side"] == "right" and trial.metadata["blade"] == "xtreme"


def test_write_read_round_trip_in_metres_with_gaps(tmp_path):
    path = tmp_path / "m.c3d"
    t = np.arange(50) / 100.0
    xyz = np.column_stack([t, 0 * t + 0.2, 0 * t + 1.0])
    xyz[10:13] = np.nan
    write_c3d(path, markers={"A": xyz}, marker_rate=100.0, point_units="m")
    trial = read_c3d(path)
    assert trial.metadata["point_units"] == "m"
    assert np.isnan(trial.marker("A")[10:13]).all()
    np.testing.assert_allclose(trial.marker("A")[20], xyz[20], atol=1e-6)
    assert trial.platforms == ()


def test_write_is_atomic_and_validates(tmp_path):
    path = tmp_path / "bad.c3d"
    t = np.zeros((10, 3))
    with pytest.raises(SpecError, match="integer multiple"):
        write_c3d(path, markers={"A": t}, marker_rate=100.0, analog_rate=150.0,
                  platforms=[{"force": np.zeros((15, 3)), "corners": plate_corners((0, 0, 0), 1, 1)}])
    upward = plate_corners((0, 0, 0), 1, 1)[[1, 0, 3, 2]]  # mirrored order: plate z up
    with pytest.raises(SpecError, match="point down"):
        write_c3d(path, markers={"A": t}, marker_rate=100.0,
                  platforms=[{"force": np.zeros((10, 3)), "corners": upward}])
    assert list(tmp_path.iterdir()) == []


def test_not_a_c3d(tmp_path):
    bad = tmp_path / "notes.c3d"
    bad.write_text("this is not a C3D file\n" * 50)
    with pytest.raises(InputFileError, match="not a C3D") as err:
        read_c3d(bad)
    assert str(bad) in str(err.value)
    with pytest.raises(InputFileError, match="not found"):
        read_c3d(tmp_path / "missing.c3d")


@pytest.mark.parametrize("fraction", [0.02, 0.5, 0.99])
def test_truncated_c3d(tmp_path, fraction):
    data = WALKING[0].read_bytes()
    bad = tmp_path / "truncated.c3d"
    bad.write_bytes(data[: int(len(data) * fraction)])
    with pytest.raises(InputFileError, match="truncated") as err:
        read_c3d(bad)
    assert str(bad) in str(err.value)


def test_truncated_inside_parameters(tmp_path):
    data = WALKING[0].read_bytes()
    bad = tmp_path / "truncated.c3d"
    bad.write_bytes(data[:700])
    with pytest.raises(InputFileError):
        read_c3d(bad)


def _patched_copy(tmp_path, group, name, value):
    c = ezc3d.c3d(str(WALKING[0]))
    c["parameters"][group][name]["value"] = value
    out = tmp_path / "patched.c3d"
    c.write(str(out))
    return out


def test_unsupported_platform_type(tmp_path):
    path = _patched_copy(tmp_path, "FORCE_PLATFORM", "TYPE", np.array([2, 5]))
    with pytest.raises(DataError, match="type 5 is not supported") as err:
        read_c3d(path)
    assert "platform 2" in str(err.value) and str(path) in str(err.value)


def test_missing_platform_channel(tmp_path):
    chan = np.arange(1, 13).reshape(2, 6).T.copy()
    chan[0, 1] = 40
    path = _patched_copy(tmp_path, "FORCE_PLATFORM", "CHANNEL", chan)
    with pytest.raises(DataError, match="analog channel"):
        read_c3d(path)


def test_static_trial_without_analogs_has_no_platforms(tmp_path):
    trial = read_c3d(FUKUCHI_STATIC)
    assert trial.platforms == ()


def test_axis_options(tmp_path):
    path = tmp_path / "copy.c3d"
    shutil.copy(WALKING[0], path)
    trial = read_c3d(path, forward="-y", up="+z")
    assert trial.metadata["axes"] == {"forward": "-y", "lateral": "+x", "up": "+z"}
    with pytest.raises(BladelabError, match="vertical"):
        read_c3d(path, forward="+z", up="+z")
    with pytest.raises(SpecError):
        read_c3d(path, up="+w")


def _write_raw_platform(path, ptype, channels, units, corners_m, origin):
    """A C3D with one platform of the given type and hand-made analog channels (ezc3d only)."""
    n = channels.shape[1]
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [100.0]
    c["parameters"]["POINT"]["LABELS"]["value"] = ("A",)
    c["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    pts = np.zeros((4, 1, n // 10))
    pts[3] = 1.0
    c["data"]["points"] = pts
    c["parameters"]["ANALOG"]["RATE"]["value"] = [1000.0]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = tuple(f"CH{i + 1}" for i in range(len(channels)))
    c["parameters"]["ANALOG"]["UNITS"]["value"] = units
    c["data"]["analogs"] = channels[None]
    c.add_parameter("FORCE_PLATFORM", "USED", [1])
    c.add_parameter("FORCE_PLATFORM", "TYPE", [ptype])
    c.add_parameter("FORCE_PLATFORM", "CHANNEL",
                    np.arange(1, len(channels) + 1, dtype=float).reshape(-1, 1))
    c.add_parameter("FORCE_PLATFORM", "CORNERS", (np.asarray(corners_m).T * 1000.0)[:, :, None])
    c.add_parameter("FORCE_PLATFORM", "ORIGIN", np.asarray(origin, dtype=float).reshape(3, 1))
    c.write(str(path))


def _known_load(n=500):
    t = np.arange(n) / 1000.0
    # GRF on the subject in plate axes (z down into the plate): a load pushes the subject up, Fz < 0
    fz = -(800.0 + 400.0 * np.sin(2 * np.pi * 2 * t))
    fx, fy = 0.1 * fz, -0.05 * fz
    ax, ay = 0.10 * np.cos(2 * np.pi * t), -0.05 + 0.02 * t  # COP rel. plate centre, plate axes [m]
    tz = 2.0 * np.sin(2 * np.pi * 3 * t)  # free moment about plate z [N·m]
    return fx, fy, fz, ax, ay, tz


def test_type3_kistler_against_the_manufacturer_formula(tmp_path):
    """Channels built from Kistler's formulas: ax = (Fx·az0 − My)/Fz, ay = (Fy·az0 + Mx)/Fz."""
    fx, fy, fz, ax, ay, tz = _known_load()
    a, b, az0 = 0.12, 0.20, -0.045  # sensor offsets [m]; az0 < 0 as Kistler specifies
    my = fx * az0 - ax * fz
    mx = ay * fz - fy * az0
    mz = tz + (ax * fy - ay * fx)
    # fz1..fz4 from sum, Mx = b(fz1+fz2−fz3−fz4), My = a(−fz1+fz2+fz3−fz4), and fz1−fz2+fz3−fz4 = 0
    A = np.array([[1, 1, 1, 1], [1, 1, -1, -1], [-1, 1, 1, -1], [1, -1, 1, -1]], dtype=float)
    fzs = np.linalg.solve(A, np.vstack([fz, mx / b, my / a, np.zeros_like(fz)]))
    fx12, fx34 = fx / 2 - mz / (2 * b), fx / 2 + mz / (2 * b)
    fy14, fy23 = fy / 2, fy / 2
    channels = np.vstack([fx12, fx34, fy14, fy23, *fzs])
    corners = plate_corners((1.0, 0.5, 0.0), 0.6, 0.4)  # plate x = lab +x, plate y = lab −y
    path = tmp_path / "kistler.c3d"
    _write_raw_platform(path, 3, channels, ["N"] * 8, corners, [a * 1000, b * 1000, az0 * 1000])
    with pytest.warns(C3DWarning, match="platform 1: never unloads"):  # loaded all along
        plate = read_c3d(path, forward="+x", up="+z").platforms[0]
    assert plate.type == 3
    np.testing.assert_allclose(plate.force, np.column_stack([fx, -fy, -fz]), atol=1e-3)
    np.testing.assert_allclose(plate.cop[:, 0], 1.0 + ax, atol=1e-5)
    np.testing.assert_allclose(plate.cop[:, 1], 0.5 - ay, atol=1e-5)
    np.testing.assert_allclose(plate.free_moment, -tz, atol=1e-3)  # about lab +z = −z_plate


def test_type1_cop_channels(tmp_path):
    fx, fy, fz, ax, ay, tz = _known_load()
    channels = np.vstack([fx, fy, fz, ax * 1000, ay * 1000, tz * 1000])
    corners = plate_corners((1.0, 0.5, 0.0), 0.6, 0.4)
    path = tmp_path / "type1.c3d"
    _write_raw_platform(path, 1, channels, ["N", "N", "N", "mm", "mm", "Nmm"], corners, [0, 0, 0])
    with pytest.warns(C3DWarning, match="platform 1: never unloads"):
        plate = read_c3d(path, forward="+x", up="+z").platforms[0]
    np.testing.assert_allclose(plate.force, np.column_stack([fx, -fy, -fz]), atol=1e-3)
    np.testing.assert_allclose(plate.cop[:, :2], np.column_stack([1.0 + ax, 0.5 - ay]), atol=1e-6)
    np.testing.assert_allclose(plate.free_moment, -tz, atol=1e-4)
