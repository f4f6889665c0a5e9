"""Stance detection: real files against stances computed by hand from the raw analog channels."""

from __future__ import annotations

import ezc3d
import numpy as np
import pandas as pd
import pytest

import trial_synth as synth
from bladelab.errors import DataError
from bladelab.trial.c3d import plate_corners, read_c3d, write_c3d
from bladelab.trial.events import classify_stances, detect_stances
from bladelab.units import body_weight
from conftest import FUKUCHI_INFO, WALKING
from conftest import FUKUCHI_RUN as FUKUCHI


def _runs(mask):
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    return list(zip(edges[::2], edges[1::2], strict=True))


def _hand_stances(fz, rate, threshold=20.0, min_duration=0.05):
    """Plain thresholding of the raw vertical force, complete contacts only."""
    return [(s, e) for s, e in _runs(fz > threshold)
            if (e - s) / rate >= min_duration and s > 0 and e < len(fz)]


@pytest.fixture(scope="module")
def fukuchi():
    return read_c3d(FUKUCHI)


def test_fukuchi_stances_match_hand_thresholding(fukuchi):
    c = ezc3d.c3d(str(FUKUCHI))
    cal = np.asarray(c["parameters"]["FORCE_PLATFORM"]["CAL_MATRIX"]["value"])[2, 2, 0]
    fz = -cal * c["data"]["analogs"][0][2]  # F1Z, plate z points down: vertical = −Fz
    rate = c["header"]["analogs"]["frame_rate"]
    hand = _hand_stances(fz, rate)
    events = detect_stances(fukuchi)
    assert len(events) == len(hand) > 80
    for ev, (s, e) in zip(events, hand, strict=True):
        assert abs(ev.start_sample - s) <= 2 and abs(ev.end_sample - e) <= 2
        assert ev.peak_fz_N == pytest.approx(fz[s:e].max(), rel=0.03)
        t = np.arange(s, e) / rate
        assert ev.impulse_z_Ns == pytest.approx(np.trapezoid(fz[s:e], t), rel=0.03)


def test_fukuchi_stances_are_physiological(fukuchi):
    info = pd.read_csv(FUKUCHI_INFO, sep="\t")
    bw = body_weight(float(info.loc[info["Subject"] == 1, "Mass"].iloc[0]))
    events = detect_stances(fukuchi)
    peaks = np.array([e.peak_fz_N for e in events]) / bw
    contact = np.array([e.contact_time_s for e in events])
    assert np.all((peaks > 2.2) & (peaks < 2.8))
    assert np.all((contact > 0.18) & (contact < 0.28))
    # vertical impulse of a stance ≈ body weight × stride period / 2 (steady running)
    starts = np.array([e.start_s for e in events])
    step = np.median(np.diff(starts))
    assert np.median([e.impulse_z_Ns for e in events]) == pytest.approx(bw * step, rel=0.08)


@pytest.mark.parametrize("path", WALKING, ids=lambda p: p.name)
def test_walking_both_platforms_found(path):
    c = ezc3d.c3d(str(path))
    analogs = c["data"]["analogs"][0]
    rate = c["header"]["analogs"]["frame_rate"]
    events = detect_stances(read_c3d(path))
    assert sorted(e.plates for e in events) == [(1,), (2,)]
    for ev in events:
        fz = -analogs[2 if ev.plates == (1,) else 8]  # Fz1 / Fz2, plate z down
        fz = fz - np.median(fz)  # zeroed by hand: the plates read −14 to −20 N unloaded
        (s, e), = _hand_stances(fz, rate)
        assert abs(ev.start_sample - s) <= 4 and abs(ev.end_sample - e) <= 4
        assert 0.45 < ev.contact_time_s < 0.75  # walking


def test_synthetic_stance_analytic(tmp_path):
    path = tmp_path / "s.c3d"
    synth.write_single_plate(path)
    (ev,) = detect_stances(read_c3d(path))
    T = synth.TO - synth.TD
    assert ev.start_s == pytest.approx(synth.TD, abs=2e-3)
    assert ev.end_s == pytest.approx(synth.TO, abs=2e-3)
    assert ev.peak_time_s == pytest.approx((synth.TD + synth.TO) / 2, abs=1e-3)
    assert ev.peak_fz_N == pytest.approx(synth.PEAK, rel=5e-3)
    assert ev.impulse_z_Ns == pytest.approx(2 * synth.PEAK * T / np.pi, rel=5e-3)
    assert ev.impulse_x_Ns == pytest.approx(0.0, abs=0.5)
    assert ev.impulse_y_Ns == pytest.approx(0.02 * 2 * synth.PEAK * T / np.pi, rel=1e-2)
    d = ev.to_dict()
    assert {"index", "plates", "start_s", "end_s", "contact_time_s", "peak_fz_N",
            "impulse_z_Ns"} <= set(d)


def test_foot_crossing_two_plates_is_one_stance(tmp_path):
    path = tmp_path / "two.c3d"
    synth.write_two_plates_one_foot(path)
    events = detect_stances(read_c3d(path))
    assert len(events) == 1
    assert events[0].plates == (1, 2)
    assert events[0].peak_fz_N == pytest.approx(synth.PEAK, rel=5e-3)
    assert events[0].contact_time_s == pytest.approx(synth.TO - synth.TD, abs=3e-3)


def test_prosthetic_side_by_tip_over_cop(tmp_path, fukuchi):
    path = tmp_path / "s.c3d"
    synth.write_single_plate(path)
    trial = read_c3d(path)
    (ev,) = classify_stances(trial, detect_stances(trial), tip="BLADE_TIP")
    assert ev.prosthetic and ev.tip_cop_distance_m < 0.1
    (ev,) = classify_stances(trial, detect_stances(trial), tip="REF")
    assert not ev.prosthetic
    # real runner: the right forefoot is over the COP on every other stance
    events = classify_stances(fukuchi, detect_stances(fukuchi)[:10], tip="R.MT1")
    flags = [e.prosthetic for e in events]
    assert flags == [flags[0], not flags[0]] * 5
    # the right foot is the lower one during the stances flagged as right
    heel_r, heel_l = fukuchi.marker("R.Heel.Bottom"), fukuchi.marker("L.Heel.Bottom")
    for e in events:
        k = int(round(e.peak_time_s * fukuchi.marker_rate))
        assert (heel_r[k, 2] < heel_l[k, 2]) == e.prosthetic


def test_no_stance_found(tmp_path):
    path = tmp_path / "s.c3d"
    synth.write_single_plate(path)
    with pytest.raises(DataError, match="no stance found") as err:
        detect_stances(read_c3d(path), threshold=5000.0)
    assert str(path) in str(err.value) and "2000" in str(err.value)


def test_no_force_platforms(tmp_path):
    path = tmp_path / "m.c3d"
    write_c3d(path, markers={"A": np.zeros((20, 3))}, marker_rate=100.0)
    with pytest.raises(DataError, match="no force platforms") as err:
        detect_stances(read_c3d(path))
    assert str(path) in str(err.value)


def test_nan_forces(tmp_path):
    path = tmp_path / "nan.c3d"
    t = np.arange(1000) / 1000.0
    force = synth.grf(t)
    force[400:405, 2] = np.nan
    write_c3d(path, markers={"A": np.zeros((200, 3))}, marker_rate=200.0, analog_rate=1000.0,
              platforms=[{"force": force, "corners": plate_corners((0.5, 0, 0), 0.9, 0.6)}])
    with pytest.raises(DataError, match="NaN") as err:
        detect_stances(read_c3d(path))
    msg = str(err.value)
    assert "platform 1" in msg and "frame 400" in msg and str(path) in msg
