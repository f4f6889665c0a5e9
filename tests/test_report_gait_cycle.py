"""Gait-cycle averages (report.gait_cycle): exact on synthetic periodic signals, strides and
stances from real steps only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.report.gait_cycle import GaitCycles, cycle_average, stance_windows, stride_windows
from bladelab.runner import build_runner
from test_runner_analyses import STANCES, _synthetic


def _shape(phase: np.ndarray) -> np.ndarray:
    """A periodic gait-like signal of the cycle phase (0–1)."""
    return 30.0 * np.sin(2 * math.pi * phase) + 10.0 * np.cos(6 * math.pi * phase) ** 2 - 5.0


def _record(durations, amplitudes, dt=5e-4):
    """Strides of the given durations [s], each the shape × its amplitude; samples every dt."""
    edges = np.concatenate([[0.0], np.cumsum(durations)])
    t = np.arange(0.0, edges[-1] + dt / 2, dt)
    k = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, len(durations) - 1)
    phase = (t - edges[k]) / np.asarray(durations)[k]
    y = np.asarray(amplitudes)[k] * _shape(phase)
    return t, y, np.stack([edges[:-1], edges[1:]], axis=1)


def test_the_gait_cycle_average_of_a_periodic_signal_is_exact():
    # strides of 0.5, 0.6 and 0.55 s sampled every 0.5 ms: every 1 % of each stride is a sample
    t, y, windows = _record([0.5, 0.6, 0.55], [1.0, 1.0, 1.0])
    avg = cycle_average(t, y, windows)
    assert avg.n == 3 and len(avg.pct) == 101
    np.testing.assert_allclose(avg.mean, _shape(avg.pct / 100), atol=1e-9)
    np.testing.assert_allclose(avg.sd, 0.0, atol=1e-9)
    # strides of other amplitudes: the mean and SD of the amplitudes times the shape
    amps = [0.8, 1.0, 1.3]
    t, y, windows = _record([0.5, 0.6, 0.55], amps)
    avg = cycle_average(t, y, windows)
    inner = slice(0, 100)  # 100 % of a stride is the first sample of the next (its amplitude)
    shape = _shape(avg.pct / 100)[inner]
    np.testing.assert_allclose(avg.mean[inner], np.mean(amps) * shape, atol=1e-9)
    np.testing.assert_allclose(avg.sd[inner], np.std(amps, ddof=1) * np.abs(shape), atol=1e-9)
    # windows outside the record are skipped; one cycle has no SD; none gives NaN
    one = cycle_average(t, y, [[0.0, 0.5], [1.5, 2.5]])
    assert one.n == 1 and np.isnan(one.sd).all()
    none = cycle_average(t, y, np.zeros((0, 2)))
    assert none.n == 0 and np.isnan(none.mean).all()


def test_strides_and_stances_of_a_synthetic_run_leave_strikes_out():
    model = build_runner("amputee")
    strikes = [(0, 0.42, 0.46), (0, 1.02, 1.06)]
    res = _synthetic(model, stances=[*STANCES, *strikes], peak=2000.0)
    np.testing.assert_allclose(stride_windows(res, "intact"), [[0.101, 0.701], [0.701, 1.301]],
                               atol=2e-3)
    st = stance_windows(res, "intact")
    np.testing.assert_allclose(st, [[0.101, 0.3], [0.701, 0.9], [1.301, 1.5]], atol=2e-3)
    cyc = GaitCycles(res)
    # the half-sine stance force, over % of the stance, in body weights
    fz = cyc.grf("intact", "Fz")
    expected = 2000.0 / model.body_weight * np.sin(math.pi * fz.pct / 100)
    np.testing.assert_allclose(fz.mean, expected, atol=0.05)  # stance found 1 ms late (20 N)
    assert fz.n == 3
    assert cyc.toe_off_pct("intact") == pytest.approx(100 * 0.2 / 0.6, abs=0.5)
    # joints fixed at 0 in the synthetic run: flat angles, no SD
    hip = cyc.angle("hip_flexion_l")
    np.testing.assert_allclose(hip.mean, 0.0)
    assert hip.n == 2


def test_a_panel_without_cycles_says_so_instead_of_staying_empty():
    """A leg with no complete stride (e.g. its contacts are not steps) gives empty curves; the
    figure then writes why into the panel rather than showing empty axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bladelab.report.gait_cycle import CycleAverage
    from bladelab.report.predictive_figures import NO_CYCLE_TEXT, _band, _finish

    fig, (full, empty) = plt.subplots(1, 2)
    pct = np.linspace(0.0, 100.0, 11)
    _band(full, CycleAverage(pct, np.sin(pct), np.full(11, np.nan), 1), "C0")
    _band(empty, CycleAverage(pct, np.full(11, np.nan), np.full(11, np.nan), 0), "C0")
    _finish(fig, 1)
    said = {ax: [t.get_text() for t in ax.texts] for ax in (full, empty)}
    assert said[empty] == [NO_CYCLE_TEXT] and said[full] == []
    plt.close(fig)
