"""Public c3d.org samples with force platforms, read by ``read_c3d`` against values derived by hand.

The expected numbers come from the raw stored analog values and the files' own parameters
(derivations in ``tests/data/c3d-org/README.md``), never from bladelab's output. Each vertical
force must be within 3 % of the hand value (absolute: 3 % of the file's peak near zero).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from bladelab.errors import DataError
from bladelab.trial import C3DWarning, detect_stances, read_c3d

DATA = Path(__file__).parent / "data" / "c3d-org"
REL = 0.03


def _read(name: str):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        trial = read_c3d(DATA / name)
    return trial, [str(w.message) for w in caught if issubclass(w.category, C3DWarning)]


def _fz(trial) -> np.ndarray:
    (plate,) = trial.platforms
    return plate.force[:, 2]


# --------------------------------------------------------------------------------------------
# MotionMonitor: type 4, y up, calibration gives the force on the plate, clipped landing
# --------------------------------------------------------------------------------------------


def test_motionmonitor_standing_weight_and_unloaded_zero():
    trial, messages = _read("sample24/MotionMonitorC3D.c3d")
    fz = _fz(trial)
    assert trial.metadata["axes"]["up"] == "+y"  # the markers stand above the plate along +y
    assert np.nanmedian(trial.marker("M1")[:, 2]) > 0.05
    standing = 737.8  # N, mean of samples 3920–5879 by hand (1866 N/V × 0.3954 V)
    assert fz[4000] == pytest.approx(736.1, rel=REL)
    assert fz[3920:].mean() == pytest.approx(standing, rel=REL)
    assert abs(fz[:2744].mean() - (-0.7)) < REL * standing  # unloaded 0–2.80 s
    assert abs(fz[0] - (-13.6)) < REL * standing
    assert fz[3000] == pytest.approx(1864.6, rel=REL)  # A3 at full scale (2047 counts)
    assert trial.platforms[0].zero_offset_N == 0.0
    assert any("platform 1: loaded, its vertical force points down" in m for m in messages)


def test_motionmonitor_clipped_landing_is_named():
    _, messages = _read("sample24/MotionMonitorC3D.c3d")
    (clip,) = [m for m in messages if "full scale" in m]
    assert "platform 1: analog channel 3 ('A3')" in clip
    assert "2047 counts of a 12-bit converter, ANALOG:BITS" in clip
    assert "lower bounds" in clip and "hint" in clip


def test_motionmonitor_has_no_complete_stance_and_says_why():
    trial, _ = _read("sample24/MotionMonitorC3D.c3d")
    with pytest.raises(DataError, match="no complete stance: every contact touches the start "
                                        "or end of the recording") as err:
        detect_stances(trial)
    assert "include_partial=True" in str(err.value)
    assert "MotionMonitorC3D.c3d" in str(err.value)
    (event,) = detect_stances(trial, include_partial=True)
    assert not event.complete and event.end_s == pytest.approx(6.0, abs=0.01)


# --------------------------------------------------------------------------------------------
# Peak Performance: type 3 in newtons, 'mete' units, a light load around the main contact
# --------------------------------------------------------------------------------------------


def test_peak_fp1_light_load_is_not_taken_for_an_offset():
    trial, messages = _read("sample15/FP1.C3D")
    fz = _fz(trial)
    peak = 284.46  # N, fz1 + fz2 + fz3 + fz4 at sample 860 (1.433 s)
    assert trial.metadata["axes"]["up"] == "+z"
    assert fz[860] == pytest.approx(peak, rel=REL)
    assert fz.max() == pytest.approx(peak, rel=REL)
    assert abs(fz[0] - 0.11) < REL * peak
    assert abs(fz[480] - 13.55) < REL * peak
    assert fz[100] == pytest.approx(50.41, rel=REL)
    assert trial.platforms[0].zero_offset_N == 0.0
    (light,) = [m for m in messages if "light load" in m]
    assert "platform 1:" in light and "no zero offset is removed" in light


def test_peak_fp2_zeroed_plate():
    trial, messages = _read("sample15/FP2.C3D")
    fz = _fz(trial)
    peak = 302.93  # N at sample 3806 (6.343 s)
    assert trial.metadata["axes"]["up"] == "+z"
    assert fz[3806] == pytest.approx(peak, rel=REL)
    assert fz.max() == pytest.approx(peak, rel=REL)
    assert abs(fz[0] - (-0.27)) < REL * peak and abs(fz[480] - (-0.72)) < REL * peak
    assert not any("light load" in m for m in messages)


# --------------------------------------------------------------------------------------------
# sample10: one recording described as type 2 and as type 4 (DEC, integer storage)
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name, extreme", [("TYPE-2.C3D", 397.88), ("TYPE-4.C3D", 390.52)])
def test_type2_and_type4_descriptions(name, extreme):
    trial, _ = _read(f"sample10/{name}")
    fz = _fz(trial)
    assert trial.metadata["axes"]["up"] == "+z"
    assert fz[1644] == pytest.approx(extreme, rel=REL)  # 1.370 s, stored FZ1 3122
    assert fz.max() == pytest.approx(extreme, rel=REL)
    assert abs(fz[0]) < REL * extreme
    (event,) = detect_stances(trial)
    assert event.complete
