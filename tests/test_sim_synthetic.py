"""Synthetic stances: a runner whose leg carries the blade, and the kernel replaying them."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.blade import load_blade
from bladelab.errors import ModelError
from bladelab.sim import prepare, simulate
from bladelab.sim.synthetic import generate_stance


def nrmse(a: np.ndarray, ref: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - ref) ** 2)) / np.ptp(ref))


@pytest.fixture(scope="module", params=[("xceed", 65.0), ("xtreme", 76.0)], ids=["C", "J"])
def generated(request):
    name, mass = request.param
    blade = load_blade(name).build()
    stance, truth = generate_stance(blade, speed_mps=7.0, body_mass_kg=mass, sample_rate=4000.0)
    return blade, stance, truth


def test_stance_looks_like_running(generated):
    """Contact time, force, compression, pitch and rolling in the ranges of DESIGN.md."""
    blade, stance, truth = generated
    assert 0.08 < truth["contact_time_s"] < 0.15
    assert 1500.0 < truth["peak_grf_z_N"] < 3500.0
    assert -35.0 < truth["min_deflection_deg"] < -15.0
    assert 0.05 < truth["max_compression_m"] < 0.13
    # the blade pitches forward by tens of degrees while it rolls over its sole
    assert truth["pitch_touchdown_deg"] < -10.0 and truth["pitch_toeoff_deg"] > 15.0
    # the clamp moves at about half the running speed; the sole barely slips
    assert 0.3 < truth["clamp_mean_speed_mps"] / 7.0 < 0.65
    assert truth["max_sole_slip_m"] < 0.005
    # the stance is on a uniform time base and starts and ends unloaded
    assert np.ptp(np.diff(stance.time)) < 1e-9
    assert stance.grf_z[0] == 0.0 and stance.grf_z[-1] == 0.0
    # the recorded distance is |tip - clamp| and starts at the undeformed value
    assert stance.distance[0] == pytest.approx(blade.rest_distance, abs=2e-4)


def test_kernel_replays_the_generated_stance(generated):
    """The prescribed-clamp kernel with the true K, D reproduces the free simulation."""
    blade, stance, truth = generated
    result = simulate(prepare(blade, stance), stiffness=truth["K_Nm_per_rad"],
                      damping=truth["D_Nms_per_rad"])
    assert nrmse(result.grf_z, stance.grf_z) < 0.01
    assert nrmse(result.grf_x, stance.grf_x) < 0.01
    assert nrmse(result.distance, stance.distance) < 0.001
    assert nrmse(result.deflection[:, 0], truth["deflection"][:, 0]) < 0.005


def test_wrong_stiffness_does_not_replay(generated):
    blade, stance, truth = generated
    result = simulate(prepare(blade, stance), stiffness=1.3 * np.asarray(truth["K_Nm_per_rad"]),
                      damping=truth["D_Nms_per_rad"])
    # a 30 % stiffer blade is clearly distinguishable (the replay with the truth is < 1 %)
    assert nrmse(result.grf_z, stance.grf_z) > 0.03
    assert nrmse(result.distance, stance.distance) > 0.002


def test_noise_is_seeded_and_scaled():
    blade = load_blade("xtreme").build()
    kw = dict(speed_mps=6.0, marker_noise_m=1e-3, pitch_noise_deg=0.3, force_noise_frac=0.01)
    a, truth = generate_stance(blade, seed=1, **kw)
    b, _ = generate_stance(blade, seed=1, **kw)
    c, _ = generate_stance(blade, seed=2, **kw)
    np.testing.assert_array_equal(a.clamp_x, b.clamp_x)
    assert not np.array_equal(a.clamp_x, c.clamp_x)
    noise = a.grf_z - truth["grf_z"]
    assert 0.5 * 0.01 * truth["peak_grf_z_N"] < noise.std() < 2.0 * 0.01 * truth["peak_grf_z_N"]


def test_generator_rejects_bad_input():
    blade = load_blade("xtreme").build()
    with pytest.raises(ModelError):
        generate_stance(blade, speed_mps=-1.0)
    with pytest.raises(ModelError, match="engine"):
        generate_stance(blade, engine="kernel")
