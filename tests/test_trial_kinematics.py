"""Blade kinematics and stance extraction against analytic synthetic trials and hand computation."""

from __future__ import annotations

import numpy as np
import pytest

import trial_synth as synth
from bladelab.errors import DataError, InputFileError, SpecError
from bladelab.trial.c3d import read_c3d, write_c3d
from bladelab.trial.events import detect_stances
from bladelab.trial.kinematics import (
    MarkerMap,
    blade_kinematics,
    compression,
    extract_stance,
    load_marker_map,
)
from conftest import FUKUCHI_RUN


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    path = tmp_path_factory.mktemp("kin") / "s.c3d"
    synth.write_single_plate(path)
    return read_c3d(path)


def test_unfiltered_extraction_reproduces_the_analytic_motion(synthetic):
    st = extract_stance(synthetic, 0, marker_cutoff=None, force_cutoff=None)
    t = st.time + st.metadata["window_start_s"]
    assert st.sample_rate == pytest.approx(1000.0)
    origin = synth.clamp_origin(t)
    np.testing.assert_allclose(st.clamp_x, origin[:, 0], atol=2e-6)
    np.testing.assert_allclose(st.clamp_y, origin[:, 1], atol=2e-6)
    np.testing.assert_allclose(st.clamp_z, origin[:, 2], atol=2e-6)
    np.testing.assert_allclose(st.clamp_pitch, synth.clamp_pitch(t), atol=5e-5)
    d = np.linalg.norm(synth.TIP_OFFSET) * synth.compression_scale(t)
    np.testing.assert_allclose(st.distance, d, atol=5e-6)
    grf = synth.grf(t)
    # linear interpolation of a 1 kHz half-sine: error ≤ PEAK·(π/T)²·dt²/8 plus the corner
    np.testing.assert_allclose(st.grf_z, grf[:, 2], atol=synth.PEAK * 0.02)
    assert st.metadata["athlete"] == "TT1" and st.metadata["category"] == 5


def test_pitch_sign_convention(synthetic):
    """Positive pitch turns +z toward +x: the clamp's front marker is lower than its back."""
    kin = blade_kinematics(synthetic, cutoff=None)
    front = synthetic.marker("CLAMP_ANT")[:, 2] < synthetic.marker("CLAMP_POST")[:, 2]
    assert np.all((kin.clamp_pitch > 0) == front)


def test_filtered_extraction_is_close(synthetic):
    st = extract_stance(synthetic, 0)
    t = st.time + st.metadata["window_start_s"]
    np.testing.assert_allclose(st.clamp_x, synth.clamp_origin(t)[:, 0], atol=1e-3)
    np.testing.assert_allclose(np.rad2deg(st.clamp_pitch), np.rad2deg(synth.clamp_pitch(t)), atol=0.3)
    assert st.grf_z.max() == pytest.approx(synth.PEAK, rel=0.02)


def test_window_centred_on_peak_with_margins(synthetic):
    margin = 0.03
    st = extract_stance(synthetic, 0, margin=margin)
    m = st.metadata
    assert m["peak_s"] == pytest.approx(st.duration / 2, abs=1.5e-3)
    assert m["touchdown_s"] >= margin - 1.5e-3
    assert st.duration - m["toeoff_s"] >= margin - 1.5e-3
    half = max(m["peak_s"] - m["touchdown_s"], m["toeoff_s"] - m["peak_s"])
    assert st.duration == pytest.approx(2 * (half + margin), abs=2e-3)
    # before touch-down and after toe-off the force is ~0
    assert np.all(np.abs(st.grf_z[st.time < m["touchdown_s"] - 0.01]) < 30)


def test_compression_delta_d(synthetic):
    st = extract_stance(synthetic, 0, marker_cutoff=None)
    dd, d0 = compression(st.distance, st.time, st.metadata["touchdown_s"])
    td = synth.TD
    assert d0 == pytest.approx(np.linalg.norm(synth.TIP_OFFSET) * synth.compression_scale(np.array([td]))[0], abs=2e-4)
    assert st.metadata["d0_m"] == pytest.approx(d0, abs=2e-4)
    assert dd.max() == pytest.approx(d0 - 0.85 * np.linalg.norm(synth.TIP_OFFSET), abs=1e-3)


def test_marker_map_yaml(tmp_path, synthetic):
    good = tmp_path / "map.yaml"
    good.write_text("clamp_anterior: CLAMP_POST\nclamp_posterior: CLAMP_ANT\ntip: BLADE_TIP\n")
    mm = load_marker_map(good)
    kin = blade_kinematics(synthetic, markers=mm, cutoff=None)
    ref = blade_kinematics(synthetic, cutoff=None)
    # swapping front and back turns the axis by 180°
    np.testing.assert_allclose(np.cos(kin.clamp_pitch), -np.cos(ref.clamp_pitch), atol=1e-9)
    bad = tmp_path / "bad.yaml"
    bad.write_text("clamp_front: A\n")
    with pytest.raises(SpecError, match="clamp_front") as err:
        load_marker_map(bad)
    assert str(bad) in str(err.value)
    with pytest.raises(InputFileError):
        load_marker_map(tmp_path / "none.yaml")


def test_missing_marker_lists_existing(synthetic):
    with pytest.raises(DataError, match="no marker named 'HEEL'") as err:
        extract_stance(synthetic, 0, markers=MarkerMap(tip="HEEL"))
    assert "CLAMP_ANT, CLAMP_POST, BLADE_TIP, REF" in str(err.value)


def test_no_such_stance(synthetic):
    # messages number stances from 1 (as `bladelab trial stances`); the Python index is 0-based
    with pytest.raises(DataError, match=r"no stance 4: the trial has 1 stance \(stance 1\)") as err:
        extract_stance(synthetic, 3)
    assert "stance N is index N − 1" in str(err.value)
    assert extract_stance(synthetic, 0).metadata["stance"] == 1


def _gapped(tmp_path, start, stop):
    path = tmp_path / "gap.c3d"
    synth.write_single_plate(path)
    trial = read_c3d(path)
    mk = dict(trial.markers)
    tip = mk["BLADE_TIP"].copy()
    tip[start:stop] = np.nan
    mk["BLADE_TIP"] = tip
    out = tmp_path / "gap2.c3d"
    p = trial.platforms[0]
    write_c3d(out, markers=mk, marker_rate=trial.marker_rate, analog_rate=p.rate,
              platforms=[{"force": p.force, "cop": p.cop, "corners": p.corners}])
    return read_c3d(out)


def test_marker_gap_longer_than_fill_limit(tmp_path):
    trial = _gapped(tmp_path, 66, 96)  # 0.15 s at 200 Hz, inside the stance window
    with pytest.raises(DataError, match="fill limit") as err:
        extract_stance(trial, 0)
    assert "BLADE_TIP" in str(err.value) and "frames 66–95" in str(err.value)
    # a short gap is filled; the result stays close to the truth
    trial = _gapped(tmp_path, 70, 74)
    st = extract_stance(trial, 0, marker_cutoff=None)
    t = st.time + st.metadata["window_start_s"]
    d = np.linalg.norm(synth.TIP_OFFSET) * synth.compression_scale(t)
    np.testing.assert_allclose(st.distance, d, atol=1e-3)


def test_gap_outside_the_window_does_not_matter(tmp_path):
    trial = _gapped(tmp_path, 150, 190)  # 0.75–0.95 s, long after toe-off
    st = extract_stance(trial, 0)
    assert np.all(np.isfinite(st.distance))


def test_real_file_mechanics_with_mapped_foot_markers():
    """Mechanics only: the runner's right foot markers stand in for the clamp and tip roles."""
    trial = read_c3d(FUKUCHI_RUN)
    mm = MarkerMap(clamp_anterior="R.MT1", clamp_posterior="R.Heel.Bottom", tip="R.Shank.Top.Lateral")
    events = detect_stances(trial)
    st = extract_stance(trial, 0, markers=mm, marker_cutoff=None, force_cutoff=None, stances=events)
    t = st.time + st.metadata["window_start_s"]
    tm = trial.marker_time
    ant, post = trial.marker("R.MT1"), trial.marker("R.Heel.Bottom")
    tip = trial.marker("R.Shank.Top.Lateral")

    def at(xyz):
        return np.column_stack([np.interp(t, tm, xyz[:, i]) for i in range(3)])

    d = at(ant) - at(post)
    pitch = np.arctan2(-d[:, 2], d[:, 0])
    np.testing.assert_allclose(st.clamp_pitch, pitch, atol=np.deg2rad(1.0))
    origin = (at(ant) + at(post)) / 2
    np.testing.assert_allclose(st.clamp_x, origin[:, 0], atol=2e-3)
    np.testing.assert_allclose(st.distance, np.linalg.norm(at(tip) - origin, axis=1), atol=2e-3)
    # GRF: the calibrated vertical force, linearly interpolated
    p = trial.platforms[0]
    np.testing.assert_allclose(st.grf_z, np.interp(t, p.time, p.force[:, 2]), atol=0.1)  # t rounded to 1 µs
    assert st.grf_z.max() > 1000.0
