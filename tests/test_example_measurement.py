"""Realistic measurement degradation: noise statistics, the zero-noise path, seeding, C3D output.

The clean stance here is analytic (half-sine GRF, smooth clamp path and pitch), so expected values
come from its formulas, not from the code under test.
"""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.errors import DataError
from bladelab.example.measurement import (
    CLAMP_CLUSTER,
    TIP_MARKER,
    clamp_cluster_positions,
    degrade_stance,
    extend_flight,
    measure_stance,
)
from bladelab.trial import Stance, detect_stances, read_c3d

PEAK = 2000.0
T0, TC = 0.10, 0.15  # touch-down [s], contact time [s]


def _clean(rate: float = 2000.0) -> tuple[Stance, np.ndarray]:
    t = np.arange(0.0, 0.35 + 1e-12, 1.0 / rate)
    phase = np.clip((t - T0) / TC, 0.0, 1.0)
    load = np.where((t > T0) & (t < T0 + TC), np.sin(np.pi * phase), 0.0)
    smooth = load**2  # C1-smooth kinematics (sin²), half-sine force
    pitch = np.deg2rad(-25.0 + 60.0 * (3 * phase**2 - 2 * phase**3))
    x = 4.0 * t
    z = 0.45 - 0.05 * smooth
    d = 0.42 - 0.06 * smooth
    # tip: forward and down of the clamp, at distance d exactly
    v = np.column_stack([0.2 * np.cos(pitch), np.zeros_like(t), -np.full_like(t, 0.37)])
    v *= (d / np.linalg.norm(v, axis=1))[:, None]
    tip = np.column_stack([x, np.zeros_like(t), z]) + v
    st = Stance(time=t, clamp_x=x, clamp_y=np.zeros_like(t), clamp_z=z, clamp_pitch=pitch,
                grf_x=300.0 * np.sin(2 * np.pi * phase) * (load > 0), grf_y=np.zeros_like(t),
                grf_z=PEAK * load, distance=d)
    return st, tip


def test_cluster_layout_and_pitch_convention():
    # pitch +30°: a point on the clamp's +x axis goes down (−z), +z turns toward +x
    p = np.deg2rad(30.0)
    pos = clamp_cluster_positions(np.array([1.0]), np.array([0.0]), np.array([0.5]), np.array([p]))
    a = CLAMP_CLUSTER["CLAMP_ANT"][0]
    assert pos["CLAMP_ANT"][0] == pytest.approx([1.0 + a * np.cos(p), 0.0, 0.5 - a * np.sin(p)])
    h = CLAMP_CLUSTER["CLAMP_SUP"][2]
    assert pos["CLAMP_SUP"][0] == pytest.approx([1.0 + h * np.sin(p), 0.0, 0.5 + h * np.cos(p)])
    # the pipeline's pitch formula atan2(-dz, dx) of POST->ANT gives back the pitch
    dv = pos["CLAMP_ANT"][0] - pos["CLAMP_POST"][0]
    assert np.arctan2(-dv[2], dv[0]) == pytest.approx(p)


def test_noise_has_the_requested_standard_deviation():
    st, tip = _clean()
    long, tip_l = extend_flight(st, tip=tip, before_s=0.2, after_s=0.2)
    kw = dict(tip=tip_l, marker_rate_hz=250.0, analog_rate_hz=1000.0)
    clean = measure_stance(long, marker_noise_m=0.0, force_noise_frac=0.0, force_floor_n=0.0,
                           seed=7, **kw)
    noisy = measure_stance(long, marker_noise_m=1e-3, force_noise_frac=0.01, force_floor_n=1.0,
                           seed=7, **kw)
    assert noisy.time_offset_s == clean.time_offset_s  # same seed: same sampling phase
    diff = np.concatenate([(noisy.markers[k] - clean.markers[k]).ravel() for k in clean.markers])
    assert diff.size > 2000
    assert np.std(diff) == pytest.approx(1e-3, rel=0.05)
    assert abs(np.mean(diff)) < 1e-4
    f_clean = clean.platforms[0]["force"]
    f_noise = noisy.platforms[0]["force"] - f_clean
    loaded = f_clean[:, 2] > 20.0
    assert loaded.sum() > 100
    assert np.std(f_noise[loaded]) == pytest.approx(0.01 * PEAK, rel=0.1)
    assert np.std(f_noise[~loaded]) == pytest.approx(1.0, rel=0.1)
    # plate 2 is never loaded (boundary past the stance): only the floor noise
    assert np.std(noisy.platforms[1]["force"]) == pytest.approx(1.0, rel=0.1)


def test_same_seed_same_output_and_different_seed_differs():
    st, tip = _clean()
    a = degrade_stance(st, tip=tip, seed=3)
    b = degrade_stance(st, tip=tip, seed=3)
    c = degrade_stance(st, tip=tip, seed=4)
    for name in ("clamp_x", "clamp_pitch", "grf_z", "distance"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert not np.array_equal(a.grf_z[: min(len(a.time), len(c.time))],
                              c.grf_z[: min(len(a.time), len(c.time))])
    assert a.metadata == b.metadata


def _compare(deg: Stance, st: Stance) -> dict[str, float]:
    tc = deg.time + deg.metadata["clean_time_offset_s"]
    inside = (tc >= st.time[0]) & (tc <= st.time[-1])
    out = {}
    for name in ("clamp_x", "clamp_z", "clamp_pitch", "grf_z", "grf_x", "distance"):
        ref = np.interp(tc[inside], st.time, getattr(st, name))
        out[name] = float(np.max(np.abs(getattr(deg, name)[inside] - ref)))
    return out


def test_zero_noise_unfiltered_path_recovers_the_clean_stance():
    st, tip = _clean()
    deg = degrade_stance(st, tip=tip, marker_rate_hz=250.0, marker_noise_m=0.0,
                         force_noise_frac=0.0, cutoff_hz=None, seed=1)
    err = _compare(deg, st)
    assert err["clamp_x"] < 0.2e-3 and err["clamp_z"] < 0.2e-3
    assert err["distance"] < 0.2e-3
    assert np.rad2deg(err["clamp_pitch"]) < 0.1
    assert err["grf_z"] < 0.01 * PEAK and err["grf_x"] < 0.01 * PEAK
    # the window covers the whole contact (touch-down and toe-off inside, with margins)
    md = deg.metadata
    assert md["touchdown_s"] > 0.0 and md["toeoff_s"] < deg.time[-1]
    assert md["toeoff_s"] - md["touchdown_s"] == pytest.approx(TC, abs=3e-3)


def test_zero_noise_with_100hz_and_20hz_filter_stays_close():
    # the filter's own distortion only: a few millimetres, under a degree
    st, tip = _clean()
    deg = degrade_stance(st, tip=tip, marker_rate_hz=100.0, marker_noise_m=0.0,
                         force_noise_frac=0.0, cutoff_hz=20.0, seed=1)
    err = _compare(deg, st)
    assert err["clamp_z"] < 5e-3 and err["distance"] < 5e-3
    assert np.rad2deg(err["clamp_pitch"]) < 2.0
    assert err["grf_z"] < 0.01 * PEAK


def test_recording_written_as_c3d_reads_back_with_cop_and_split_force(tmp_path):
    st, tip = _clean()
    long, tip_l = extend_flight(st, tip=tip, before_s=0.2, after_s=0.2)
    loaded = st.grf_z > 20
    boundary = float(tip[loaded][0, 0]) - 0.05  # the COP crosses the plate edge mid-stance
    rec = measure_stance(long, tip=tip_l, plate_boundary_x=boundary, marker_noise_m=0.0,
                         force_noise_frac=0.0, force_floor_n=0.0, seed=2)
    path = rec.write_c3d(tmp_path / "t.c3d", metadata={"athlete": "X", "speed_pct_pb": 60.0})
    trial = read_c3d(path)
    assert set(trial.markers) == {*CLAMP_CLUSTER, TIP_MARKER}
    assert trial.marker_rate == 100.0 and trial.platforms[0].rate == 1000.0
    total = trial.platforms[0].force + trial.platforms[1].force
    np.testing.assert_allclose(total, rec.platforms[0]["force"] + rec.platforms[1]["force"],
                               atol=1e-2)
    for k in range(2):  # moments in the file are consistent with the modelled COP
        f = trial.platforms[k].force[:, 2] > 50
        assert f.sum() > 20
        np.testing.assert_allclose(trial.platforms[k].cop[f, :2], rec.platforms[k]["cop"][f, :2],
                                   atol=1e-3)
    events = detect_stances(trial)
    assert len(events) == 1 and events[0].plates == (1, 2)
    assert trial.metadata["athlete"] == "X"


def test_bad_rates_are_clear_errors():
    st, tip = _clean()
    with pytest.raises(DataError, match="integer multiple"):
        measure_stance(st, tip=tip, marker_rate_hz=300.0, analog_rate_hz=1000.0)
    with pytest.raises(DataError, match=">= 0"):
        measure_stance(st, tip=tip, marker_noise_m=-1.0)
