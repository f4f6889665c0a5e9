"""The kernel against the MuJoCo reference (same blade built segment by segment with MjSpec)."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab import units
from bladelab.blade import load_blade, multilink_blade
from bladelab.sim import prepare, simulate
from bladelab.sim.synthetic import generate_stance

# (K [N·m/deg], D [N·m·s/deg]) spanning seed 000's range
PAIRS = [(13.0, 0.15), (18.0, 0.3), (22.0, 0.5)]


def nrmse(a: np.ndarray, ref: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - ref) ** 2)) / np.ptp(ref))


@pytest.fixture(scope="module", params=["xceed", "xtreme"])
def blade_and_stance(request):
    blade = load_blade(request.param).build()
    stance, _ = generate_stance(blade, speed_mps=7.0, body_mass_kg=70.0, sample_rate=1000.0)
    return blade, stance


@pytest.mark.parametrize("friction", [True, False], ids=["friction", "frictionless"])
def test_kernel_agrees_with_mujoco(blade_and_stance, friction):
    blade, stance = blade_and_stance
    if not friction:
        blade = blade.with_contact(friction_static=0.0)
    for k_deg, d_deg in PAIRS:
        K = units.stiffness_per_deg_to_per_rad(k_deg)
        D = units.damping_per_deg_to_per_rad(d_deg)
        ker = simulate(prepare(blade, stance), stiffness=K, damping=D)
        ref = simulate(prepare(blade, stance, engine="mujoco"), stiffness=K, damping=D)
        assert ref.engine == "mujoco" and ref.dt <= 2.01e-5
        assert ref.grf_z.max() > 1000.0
        tag = f"{blade.name} K={k_deg} D={d_deg} friction={friction}"
        assert nrmse(ker.grf_z, ref.grf_z) < 0.01, tag
        assert nrmse(ker.grf_total, ref.grf_total) < 0.01, tag
        assert nrmse(ker.distance, ref.distance) < 0.01, tag
        assert nrmse(ker.deflection[:, 0], ref.deflection[:, 0]) < 0.01, tag
        if friction:
            assert nrmse(ker.grf_x, ref.grf_x) < 0.01, tag
        else:
            assert np.all(ker.grf_x == 0.0) and np.all(ref.grf_x == 0.0)


def test_nonlinear_spring_agrees_with_mujoco(blade_and_stance):
    """K2·q·|q| (the nonlinear option) is applied the same way by both engines."""
    blade, stance = blade_and_stance
    K = units.stiffness_per_deg_to_per_rad(13.0)
    K2 = 3.0 * K  # the spring stiffens by 30 % per 0.1 rad of deflection
    ker = simulate(prepare(blade, stance), stiffness=K, stiffness_quadratic=K2)
    lin = simulate(prepare(blade, stance), stiffness=K)
    ref = simulate(prepare(blade, stance, engine="mujoco"), stiffness=K, stiffness_quadratic=K2)
    assert nrmse(lin.grf_z, ref.grf_z) > 0.03  # K2 matters here
    assert nrmse(ker.grf_z, ref.grf_z) < 0.01
    assert nrmse(ker.distance, ref.distance) < 0.01
    assert nrmse(ker.torque[:, 0], ref.torque[:, 0]) < 0.01


def test_hunt_crossley_contact_agrees_with_mujoco(blade_and_stance):
    blade, stance = blade_and_stance
    hc = blade.with_contact(law="hunt_crossley", stiffness=6e7, exponent=1.5, dissipation=1.0)
    ker = simulate(prepare(hc, stance))
    ref = simulate(prepare(hc, stance, engine="mujoco"))
    assert ref.grf_z.max() > 1000.0
    assert nrmse(ker.grf_z, ref.grf_z) < 0.01
    assert nrmse(ker.grf_x, ref.grf_x) < 0.01
    assert nrmse(ker.distance, ref.distance) < 0.01


def test_six_link_blade_agrees_with_mujoco():
    blade = multilink_blade("xtreme", n_links=6)
    assert len(blade.joints) == 5
    stance, _ = generate_stance(load_blade("xtreme").build(), speed_mps=6.0, body_mass_kg=70.0)
    ker = simulate(prepare(blade, stance))
    # light distal links: MuJoCo's explicit stick friction needs a smaller step than the default
    ref = simulate(prepare(blade, stance, engine="mujoco", dt=2e-6))
    assert ker.deflection.shape[1] == 5
    assert ref.grf_z.max() > 1000.0
    assert nrmse(ker.grf_z, ref.grf_z) < 0.01
    assert nrmse(ker.grf_x, ref.grf_x) < 0.01
    assert nrmse(ker.distance, ref.distance) < 0.01
    for j in range(5):
        if np.ptp(ref.deflection[:, j]) > np.deg2rad(1.0):
            assert nrmse(ker.deflection[:, j], ref.deflection[:, j]) < 0.01


def test_mujoco_energy_terms_balance():
    """The reference's own energy bookkeeping closes (independent of the kernel's)."""
    blade = load_blade("xceed").build().with_contact(friction_static=0.0, damping=0.0)
    stance, _ = generate_stance(load_blade("xceed").build(), speed_mps=6.0, body_mass_kg=65.0)
    ref = simulate(prepare(blade, stance, engine="mujoco"), damping=0.0)
    assert ref.energy["spring"].max() > 20.0
    err = ref.energy_balance_error()
    assert np.abs(err).max() < 0.01 * np.abs(ref.energy["clamp_work"]).max()
