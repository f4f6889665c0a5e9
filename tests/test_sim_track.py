"""Compliant track layer in series with the sole contact (kernel and MuJoCo reference)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.optimize import brentq

from bladelab.blade import load_blade
from bladelab.blade.spec import read_blade_spec
from bladelab.errors import ModelError
from bladelab.sim import prepare, simulate
from test_sim_kernel import arc_blade, still_stance

TRACK_K = 5.0e5  # N/m
TRACK_D = 300.0  # N·s/m


def nrmse(a: np.ndarray, ref: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - ref) ** 2)) / np.ptp(ref))


@pytest.fixture(scope="module")
def xtreme_stance():
    from bladelab.sim.synthetic import generate_stance

    blade = load_blade("xtreme").build()
    stance, _ = generate_stance(blade, speed_mps=7.0, body_mass_kg=70.0, sample_rate=2000.0)
    return blade, stance


@pytest.mark.parametrize("law", ["spring_damper", "hunt_crossley"])
def test_kernel_agrees_with_mujoco_on_a_compliant_track(xtreme_stance, law):
    blade, stance = xtreme_stance
    tb = blade.with_contact(track_stiffness=TRACK_K, track_damping=TRACK_D)
    if law == "hunt_crossley":
        tb = tb.with_contact(law="hunt_crossley", stiffness=6e7, exponent=1.5, dissipation=1.0)
    ker = simulate(prepare(tb, stance))
    ref = simulate(prepare(tb, stance, engine="mujoco"))
    rigid = simulate(prepare(blade if law == "spring_damper" else
                             blade.with_contact(law="hunt_crossley", stiffness=6e7,
                                                exponent=1.5, dissipation=1.0), stance))
    assert ref.grf_z.max() > 1000.0
    assert nrmse(rigid.grf_z, ref.grf_z) > 0.05  # the track matters here
    for name in ("grf_z", "grf_x", "distance"):
        assert nrmse(getattr(ker, name), getattr(ref, name)) < 0.01, name
    # both engines put a similar energy into the track damper
    assert ker.energy["dissipated_track"][-1] > 0.1
    assert ker.energy["dissipated_track"][-1] == pytest.approx(
        ref.energy["dissipated_track"][-1], rel=0.05)


def test_very_stiff_track_is_rigid_ground(xtreme_stance):
    blade, stance = xtreme_stance
    rigid = simulate(prepare(blade, stance))
    stiff = simulate(prepare(blade.with_contact(track_stiffness=1e11, track_damping=0.0), stance))
    assert nrmse(stiff.grf_z, rigid.grf_z) < 1e-3
    assert nrmse(stiff.grf_x, rigid.grf_x) < 2e-3
    assert nrmse(stiff.distance, rigid.distance) < 1e-4
    assert np.all(rigid.energy["dissipated_track"] == 0.0)


@pytest.mark.parametrize("law", ["spring_damper", "hunt_crossley"])
def test_static_load_compresses_contact_and_track_in_series(law):
    """A rigid blade pressed into the ground by the clamp: δ = δ_c + u with F_c(δ_c) = k_t·u."""
    depth = 2e-3  # geometric penetration of every sole's lowest point [m]
    blade = arc_blade(K=1e9, D=1e3, friction=False)  # practically rigid
    if law == "spring_damper":
        blade = blade.with_contact(stiffness=1e6, damping=1e3, transition_width=0.0,
                                   track_stiffness=TRACK_K, track_damping=TRACK_D)
        k_c = 1e6
        # linear laws in series: δ = F/k_c + F/k_t
        force = depth / (1.0 / k_c + 1.0 / TRACK_K)
    else:
        k, n = 6e7, 1.5
        blade = blade.with_contact(law="hunt_crossley", stiffness=k, exponent=n, dissipation=1.0,
                                   track_stiffness=TRACK_K, track_damping=TRACK_D)
        force = brentq(lambda f: (f / k) ** (1.0 / n) + f / TRACK_K - depth, 1e-9, 1e5)
    # soles at z = -0.38 with semi-axis 0.008: the lowest point is 0.388 below the clamp
    result = simulate(prepare(blade, still_stance(0.388 - depth, 0.0, duration=0.3)))
    per_sole = result.grf_elements[-1, :, 1]
    np.testing.assert_allclose(per_sole, force, rtol=1e-3)
    assert np.all(result.grf_x == 0.0)
    # the track's elastic energy is part of contact_elastic: ½F²/k_t per sole on top of the law's
    e_law = (0.5 * force**2 / k_c if law == "spring_damper"
             else k * (force / k) ** ((n + 1) / n) / (n + 1))
    assert result.energy["contact_elastic"][-1] == pytest.approx(
        3 * (e_law + 0.5 * force**2 / TRACK_K), rel=2e-3)


def test_energy_balance_with_an_undamped_track(xtreme_stance):
    """D = 0, no friction, no contact or track damping: clamp work = Δ(stored energy)."""
    blade, stance = xtreme_stance
    lossless = blade.with_contact(friction_static=0.0, damping=0.0, track_stiffness=TRACK_K,
                                  track_damping=0.0)
    result = simulate(prepare(lossless, stance, dt=2e-5), damping=0.0)
    e = result.energy
    assert e["spring"].max() > 50.0
    assert np.all(e["dissipated_track"] == 0.0)
    assert np.abs(e["dissipated_contact"]).max() < 1e-9  # round-off only
    err = result.energy_balance_error()
    assert np.abs(err).max() < 0.01 * np.abs(e["clamp_work"]).max()


def test_track_damping_is_booked_as_dissipation(xtreme_stance):
    """Only the track damps: its dissipation closes the energy balance."""
    blade, stance = xtreme_stance
    damped = blade.with_contact(friction_static=0.0, damping=0.0, track_stiffness=TRACK_K,
                                track_damping=TRACK_D)
    result = simulate(prepare(damped, stance, dt=2e-5), damping=0.0)
    e = result.energy
    assert np.all(np.diff(e["dissipated_track"]) >= -1e-12)
    work = np.abs(e["clamp_work"]).max()
    assert e["dissipated_track"][-1] > 0.01 * work
    err = result.energy_balance_error()
    assert np.abs(err).max() < 0.01 * work
    # without the track term the books would not close as well
    assert np.abs(err).max() < 0.25 * e["dissipated_track"][-1]


def test_blade_spec_with_a_track_simulates(tmp_path, xtreme_stance):
    _, stance = xtreme_stance
    path = Path(str(resources.files("bladelab") / "data" / "blades" / "xtreme.yaml"))
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    data.setdefault("contact", {})["track"] = {"stiffness_N_per_m": TRACK_K,
                                               "damping_Ns_per_m": TRACK_D}
    f = tmp_path / "track.yaml"
    f.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True), encoding="utf-8")
    blade = read_blade_spec(f).build()
    assert blade.contact.track_stiffness == TRACK_K
    rigid = simulate(prepare(load_blade("xtreme").build(), stance))
    soft = simulate(prepare(blade, stance))
    # a softer ground: lower, later peak force
    assert soft.grf_z.max() < rigid.grf_z.max()
    assert np.argmax(soft.grf_z) >= np.argmax(rigid.grf_z)


def test_bad_track_parameters_are_refused(xtreme_stance):
    blade, stance = xtreme_stance
    with pytest.raises(ModelError, match="track"):
        prepare(blade.with_contact(track_stiffness=-1.0), stance)
    with pytest.raises(ModelError, match="track"):
        prepare(blade.with_contact(track_stiffness=1e5, track_damping=-3.0), stance)


def test_track_with_utilised_friction_and_six_links_agrees_with_mujoco(xtreme_stance):
    from bladelab.blade import multilink_blade

    blade, stance = xtreme_stance
    tb = blade.with_contact(track_stiffness=TRACK_K, track_damping=TRACK_D)
    ker = simulate(prepare(tb, stance, drive="utilised-friction"))
    ref = simulate(prepare(tb, stance, drive="utilised-friction", engine="mujoco"))
    for name in ("grf_z", "grf_x", "distance"):
        assert nrmse(getattr(ker, name), getattr(ref, name)) < 0.01, name
    six = multilink_blade("xtreme", n_links=6).with_contact(track_stiffness=TRACK_K,
                                                             track_damping=TRACK_D)
    ker = simulate(prepare(six, stance))
    ref = simulate(prepare(six, stance, engine="mujoco", dt=2e-6))
    for name in ("grf_z", "grf_x", "distance"):
        assert nrmse(getattr(ker, name), getattr(ref, name)) < 0.01, name
