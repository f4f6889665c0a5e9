"""Cost: nRMSE definition, weights, contact window, guards."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.errors import DataError, OptimizationError
from bladelab.identify.cost import StanceCost, contact_window, nrmse
from conftest import FUKUCHI_FORCES


def _signals(n=101):
    t = np.linspace(0, 0.12, n)
    grf_z = 2000 * np.sin(np.pi * t / 0.12) ** 2
    grf_x = 300 * np.sin(2 * np.pi * t / 0.12)
    dist = 0.5 - 0.05 * np.sin(np.pi * t / 0.12)
    return grf_z, grf_x, dist


def test_nrmse_hand_values():
    ref = np.array([0.0, 1.0, 2.0, 3.0, 4.0])  # range 4
    sim = ref + np.array([1.0, -1.0, 1.0, -1.0, 1.0])  # RMSE 1
    assert nrmse(sim, ref) == pytest.approx(0.25)
    both = nrmse(np.vstack([sim, ref]), ref)
    assert np.allclose(both, [0.25, 0.0])


def test_constant_reference_is_a_clear_error():
    with pytest.raises(DataError, match="distance column is constant"):
        nrmse(np.ones(5), np.full(5, 0.5), channel="distance")
    grf_z, grf_x, _ = _signals()
    with pytest.raises(DataError, match="distance column is constant"):
        StanceCost.from_arrays(grf_z=grf_z, grf_x=grf_x, distance=np.full(grf_z.size, 0.48))


def test_no_contact_is_a_clear_error():
    _, grf_x, dist = _signals()
    with pytest.raises(DataError, match="no contact"):
        StanceCost.from_arrays(grf_z=np.full(dist.size, 3.0), grf_x=grf_x, distance=dist)
    with pytest.raises(DataError, match="no contact"):
        contact_window(np.zeros(10))


def test_weights_and_components_by_hand():
    grf_z, grf_x, dist = _signals()
    cost = StanceCost.from_arrays(grf_z=grf_z, grf_x=grf_x, distance=dist, contact_threshold=0.0)
    m = cost.mask
    # simulated: constant offsets whose RMSE over the window are known exactly
    span_z = np.ptp(grf_z[m])
    span_d = np.ptp(dist[m])
    terms = cost.evaluate(grf_z=grf_z + 0.1 * span_z, grf_x=grf_x, distance=dist + 0.04 * span_d)
    assert terms.nrmse_grf[0] == pytest.approx(0.1)
    assert terms.nrmse_distance[0] == pytest.approx(0.04)
    assert terms.cost[0] == pytest.approx(0.5 * 0.1 + 0.5 * 0.04)
    cost2 = StanceCost.from_arrays(grf_z=grf_z, grf_x=grf_x, distance=dist, weights=(0.8, 0.2),
                                   grf_components=("z", "x"), contact_threshold=0.0)
    span_x = np.ptp(grf_x[m])
    t2 = cost2.evaluate(grf_z=grf_z + 0.1 * span_z, grf_x=grf_x + 0.3 * span_x,
                        distance=dist + 0.04 * span_d)
    assert t2.nrmse_grf[0] == pytest.approx(0.2)  # mean of 0.1 and 0.3
    assert t2.cost[0] == pytest.approx(0.8 * 0.2 + 0.2 * 0.04)
    r = cost2.residuals(grf_z=grf_z + 0.1 * span_z, grf_x=grf_x + 0.3 * span_x,
                        distance=dist + 0.04 * span_d)
    assert np.sum(r**2) == pytest.approx(0.4 * 0.1**2 + 0.4 * 0.3**2 + 0.2 * 0.04**2)


def test_window_excludes_flight_samples():
    grf_z, grf_x, dist = _signals()
    grf_z = np.concatenate([np.zeros(20), grf_z, np.zeros(20)])
    dist = np.concatenate([np.full(20, 0.5), dist, np.full(20, 0.5)])
    cost = StanceCost.from_arrays(grf_z=grf_z, distance=dist, grf_x=None)
    sim_z = grf_z.copy()
    sim_z[:20] = 500.0  # error in flight only: not counted
    assert cost.evaluate(grf_z=sim_z, distance=dist).cost[0] == pytest.approx(0.0)


def test_batches_and_bad_rows():
    grf_z, grf_x, dist = _signals()
    cost = StanceCost.from_arrays(grf_z=grf_z, grf_x=grf_x, distance=dist)
    sims = np.vstack([grf_z, grf_z * 1.1, np.full_like(grf_z, np.nan)])
    terms = cost.evaluate(grf_z=sims, distance=np.vstack([dist] * 3))
    assert terms.cost.shape == (3,) and terms.cost[0] == 0 and terms.cost[1] > 0
    assert np.isinf(terms.cost[2])
    with pytest.raises(DataError, match="samples"):
        cost.evaluate(grf_z=grf_z[:-1], distance=dist[:-1])


def test_bad_options():
    grf_z, grf_x, dist = _signals()
    with pytest.raises(OptimizationError, match="weights"):
        StanceCost.from_arrays(grf_z=grf_z, distance=dist, weights=(0.0, 0.0))
    with pytest.raises(OptimizationError, match="grf_components"):
        StanceCost.from_arrays(grf_z=grf_z, distance=dist, grf_components=("y",))
    # no distance (no tip marker): allowed with weight 0
    nan = np.full(grf_z.size, np.nan)
    StanceCost.from_arrays(grf_z=grf_z, distance=nan, weights=(1.0, 0.0))
    with pytest.raises(DataError, match="non-finite"):
        StanceCost.from_arrays(grf_z=grf_z, distance=nan)


def test_real_running_forces():
    """Real treadmill forces (Fukuchi 2017, 300 Hz, vertical = Fy): contacts and flight."""
    table = np.loadtxt(FUKUCHI_FORCES, skiprows=1)
    fz = table[:600, 2]  # two seconds
    mask = contact_window(fz, threshold=60.0)  # treadmill: flight reads 10-40 N
    edges = np.flatnonzero(np.diff(mask.astype(int)))
    runs = [(a + 1, b + 1) for a, b in zip(edges[:-1], edges[1:], strict=True) if mask[a + 1]]
    contacts = [(a, b) for a, b in runs if b - a > 15]  # drop single-sample noise crossings
    durations = [(b - a) / 300.0 for a, b in contacts]
    assert len(durations) >= 3 and all(0.2 < d < 0.35 for d in durations)  # running at 2.5 m/s
    gap = slice(contacts[0][1] + 1, contacts[1][0] - 1)
    quiet = fz[gap][fz[gap] < 60.0]  # flight between two contacts, noise spikes removed
    with pytest.raises(DataError, match="no contact"):
        contact_window(quiet, threshold=60.0)
    # one real stance as the reference: itself scores 0, a 10 % force gain 0.5 * 10 % * peak/range
    one = slice(contacts[0][0] - 3, contacts[0][1] + 3)
    ref = fz[one]
    dist = 0.5 - 2e-5 * np.clip(ref, 0, None)  # a distance that compresses with load
    cost = StanceCost.from_arrays(grf_z=ref, distance=dist, contact_threshold=60.0)
    m = cost.mask
    expected = 0.5 * 0.1 * np.sqrt(np.mean(ref[m] ** 2)) / np.ptp(ref[m])
    assert cost.evaluate(grf_z=ref, distance=dist).cost[0] == 0.0
    assert cost.evaluate(grf_z=1.1 * ref, distance=dist).cost[0] == pytest.approx(expected)
