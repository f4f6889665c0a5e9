"""Gap-aware zero-lag Butterworth: gain and phase against the analytic response."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.errors import DataError
from bladelab.trial.filters import fill_gaps, lowpass

RATE = 1000.0


def _sine(f, n=4000):
    t = np.arange(n) / RATE
    return t, np.sin(2 * np.pi * f * t)


@pytest.mark.parametrize("f", [5.0, 20.0, 40.0])
def test_gain_is_squared_butterworth_response(f):
    """filtfilt of an order-n Butterworth has gain 1 / (1 + (f/fc)^(2n)) (no phase)."""
    fc, order = 20.0, 4
    _, x = _sine(f)
    y = lowpass(x, RATE, fc, order=order)
    mid = slice(1000, 3000)
    gain = np.std(y[mid]) / np.std(x[mid])
    assert gain == pytest.approx(1.0 / (1.0 + (f / fc) ** (2 * order)), rel=2e-3, abs=3e-4)


def test_zero_lag():
    _, x = _sine(7.0)
    y = lowpass(x, RATE, 20.0)
    lags = np.arange(-20, 21)
    xc = [np.dot(x[1000:3000], y[1000 + k : 3000 + k]) for k in lags]
    assert lags[int(np.argmax(xc))] == 0


def test_gaps_are_filled_filtered_and_restored():
    t, x = _sine(3.0)
    xy = np.column_stack([x, 2 * x])
    gapped = xy.copy()
    gapped[1500:1520] = np.nan  # 20 ms
    gapped[:10] = np.nan  # leading gap stays
    y = lowpass(gapped, RATE, 20.0, max_gap=0.05)
    assert np.isnan(y[1500:1520]).all() and np.isnan(y[:10]).all()
    ref = lowpass(xy, RATE, 20.0)
    np.testing.assert_allclose(y[1000:1490], ref[1000:1490], atol=2e-3)
    np.testing.assert_allclose(y[1530:3000], ref[1530:3000], atol=2e-3)


def test_fill_gaps_interpolates_smoothly():
    t, x = _sine(2.0)
    g = x.copy()
    g[100:130] = np.nan
    filled, mask = fill_gaps(g, rate=RATE, max_gap=0.05)
    assert mask[100:130].all() and not mask[:100].any()
    np.testing.assert_allclose(filled[100:130], x[100:130], atol=2e-3)


def test_gap_longer_than_fill_limit_is_an_error():
    _, x = _sine(2.0)
    x[2000:2200] = np.nan  # 0.2 s
    with pytest.raises(DataError, match="fill limit") as err:
        lowpass(x, RATE, 20.0, max_gap=0.1, where="marker CLAMP_ANT", file="trial.c3d")
    msg = str(err.value)
    assert "trial.c3d" in msg and "CLAMP_ANT" in msg and "frames 2000–2199" in msg


def test_cutoff_above_nyquist_is_an_error():
    with pytest.raises(DataError, match="Nyquist"):
        lowpass(np.zeros(100), 100.0, 75.0)
