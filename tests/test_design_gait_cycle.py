"""Gait cycles from a measured trial (the Fukuchi 3.5 m/s treadmill run) and its CLI."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.cli import main
from bladelab.design.gait_cycle import (
    ANGLE_NAMES,
    GaitCycle,
    average_gait_cycle,
    gait_cycle_from_trial,
    gait_cycles_from_trial,
    measured_gait_cycle,
    read_gait_csv,
)
from bladelab.errors import DataError, SpecError
from bladelab.trial import detect_stances, read_c3d
from conftest import FUKUCHI_RUN as RUN
from conftest import FUKUCHI_STATIC as STATIC


@pytest.fixture(scope="module")
def trials(fukuchi_trials):
    return fukuchi_trials


@pytest.fixture(scope="module")
def cycles(trials):
    run, static = trials
    return gait_cycles_from_trial(run, leg="right", static=static)


def _stride_and_stance(run):
    """Independent of the module: force-plate stances alternate legs on the treadmill, the
    first one being the right foot's (see test_trial_joint_angles), so a right stride runs from
    stance i to stance i + 2 for even i."""
    ev = detect_stances(run)
    starts = np.array([e.start_s for e in ev])
    right = np.arange(0, len(ev) - 2, 2)
    stride = float(np.mean(starts[right + 2] - starts[right]))
    contact = float(np.mean([ev[i].contact_time_s for i in right]))
    return stride, contact, len(right)


def test_period_is_the_force_plate_stride(trials, cycles):
    run, _ = trials
    stride, _, n = _stride_and_stance(run)
    mean = average_gait_cycle(cycles)
    assert len(cycles) == n
    assert mean.period == pytest.approx(stride, abs=2 / run.platforms[0].rate)
    assert 0.6 < mean.period < 0.8  # 3.5 m/s recreational runner


def test_physiological_knee_and_hip(trials, cycles):
    run, _ = trials
    stride, contact, _ = _stride_and_stance(run)
    mean = average_gait_cycle(cycles)
    deg = {k: np.degrees(v) for k, v in mean.angles.items()}
    duty = contact / stride
    mid = int(round(0.5 * duty * mean.phase.size))
    knee = deg["knee_prosthetic"]
    assert 30 <= knee[mid] <= 55  # knee flexion at mid-stance
    swing = mean.phase > duty
    assert 80 <= knee[swing].max() <= 130  # peak swing flexion
    assert 80 <= deg["knee_sound"].max() <= 130
    assert deg["hip_prosthetic"][0] > 15  # hip flexed at touch-down
    assert deg["hip_prosthetic"].min() < 0  # extended at toe-off
    # the sound leg touches down about half a cycle later: its knee is at its stance
    # flexion then, while the prosthetic-side knee swings
    half = mean.phase.size // 2
    assert deg["knee_sound"][half + mid] == pytest.approx(knee[mid], abs=10)
    # cycle-to-cycle variation of a steady treadmill run is small
    sd = np.degrees(np.std([c.angles["knee_prosthetic"] for c in cycles], axis=0))
    assert sd.mean() < 5


def test_average_of_cycles_is_the_mean():
    ph = np.arange(20) / 20
    a = GaitCycle(0.7, ph, {n: np.sin(2 * np.pi * ph) for n in ANGLE_NAMES})
    b = GaitCycle(0.8, ph, {n: np.cos(2 * np.pi * ph) for n in ANGLE_NAMES})
    m = average_gait_cycle([a, b])
    assert m.period == pytest.approx(0.75)
    np.testing.assert_allclose(m.angles["knee_sound"],
                               0.5 * (np.sin(2 * np.pi * ph) + np.cos(2 * np.pi * ph)))


def test_bad_leg_and_no_cycle(trials):
    run, static = trials
    with pytest.raises(SpecError, match="leg"):
        gait_cycle_from_trial(run, leg="middle")
    with pytest.raises(DataError, match="no complete gait cycle"):
        gait_cycles_from_trial(run, leg="right", max_period_s=0.1)


def test_cli_writes_the_gait_csv(tmp_path, capsys):
    out = tmp_path / "cycle.csv"
    assert main(["design", "gait-cycle", str(RUN), "--static",
                 str(STATIC), "--leg", "right", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "cycles of the right leg" in text
    cyc = read_gait_csv(out)
    run = read_c3d(RUN)
    stride, _, _ = _stride_and_stance(run)
    assert cyc.period == pytest.approx(stride, abs=2 / 300)
    assert np.degrees(cyc.angles["knee_prosthetic"]).max() > 80


def test_measured_gait_cycle_is_the_mean_of_the_trials_cycles(tmp_path, cycles):
    res = measured_gait_cycle(RUN, static_file=STATIC, leg="right", out=tmp_path / "c.csv")
    assert res.zeroed_at_standing and len(res.cycles) == len(cycles)
    for k in ANGLE_NAMES:  # the same cycles, averaged sample by sample
        mean_k = np.mean([c.angles[k] for c in cycles], axis=0)
        assert np.allclose(res.mean.angles[k], mean_k, atol=1e-12)
        lo, hi, sd = res.angle_ranges_deg()[k]
        assert (lo, hi) == pytest.approx((np.degrees(mean_k).min(), np.degrees(mean_k).max()))
        spread = np.degrees(np.std([c.angles[k] for c in cycles], axis=0)).mean()
        assert sd == pytest.approx(spread)
    # the CSV holds times to 1 µs
    assert read_gait_csv(res.path).period == pytest.approx(np.mean(res.periods_s), abs=2e-6)
    with pytest.raises(SpecError, match="at least 8 samples"):
        measured_gait_cycle(RUN, n=4)


def test_cli_errors(tmp_path, capsys):
    # a standing trial has no force platforms: no stance, clear error, exit 2, no file
    out = tmp_path / "x.csv"
    assert main(["design", "gait-cycle", str(STATIC), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and "force platforms" in err and "Traceback" not in err
    assert not out.exists()
    mp = tmp_path / "map.yaml"
    mp.write_text("right:\n  thigh_distal: [R.Knee.Marker]\n")
    assert main(["design", "gait-cycle", str(RUN), "--markers", str(mp),
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "R.Knee.Marker" in err and "RBDS001runT35.c3d" in err
    assert not out.exists()
    assert main(["design", "gait-cycle", str(tmp_path / "none.c3d"), "--out", str(out)]) == 2
