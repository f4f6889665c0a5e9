"""Blade mechanics against analytic cases derived by hand (docs/mechanics.md)."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.errors import DataError
from bladelab.mechanics import blade_angle, mechanics_table, stance_mechanics
from bladelab.trial.stance import Stance

D0 = 0.45  # m, unloaded clamp–tip distance


def _stance(t, force_z, compression, *, grf_x=None, pitch=None, n_pre=0, **meta) -> Stance:
    """A stance whose blade compresses by ``compression`` [m] under ``force_z`` [N].

    ``n_pre`` unloaded samples (F = 0, d = D0) are prepended before touch-down.
    """
    dt = t[1] - t[0]
    if n_pre:
        t = np.concatenate([t[0] - dt * np.arange(n_pre, 0, -1), t])
        force_z = np.concatenate([np.zeros(n_pre), force_z])
        compression = np.concatenate([np.zeros(n_pre), compression])
    n = len(t)
    zeros = np.zeros(n)
    return Stance(
        time=t,
        clamp_x=zeros,
        clamp_y=zeros,
        clamp_z=np.full(n, D0),
        clamp_pitch=zeros if pitch is None else pitch,
        grf_x=zeros if grf_x is None else grf_x,
        grf_y=zeros,
        grf_z=force_z,
        distance=D0 - compression,
        metadata=dict(meta),
    )


def test_linear_spring_loaded_and_unloaded_on_one_path_has_no_hysteresis():
    k, x0, T = 25e3, 0.08, 0.12  # N/m, m, s
    t = np.linspace(0.0, T, 241)
    x = x0 * np.sin(np.pi * t / T)
    m = stance_mechanics(_stance(t, k * x, x, n_pre=5))
    # Hand-derived: E = ½ k x0² stored and returned.
    assert m.energy_stored == pytest.approx(0.5 * k * x0**2, rel=1e-9)
    assert m.energy_returned == pytest.approx(0.5 * k * x0**2, rel=1e-9)
    assert abs(m.energy_dissipated) < 1e-9 * m.energy_stored
    assert m.efficiency == pytest.approx(100.0, abs=1e-7)
    assert m.d0 == pytest.approx(D0)
    assert m.peak_compression == pytest.approx(x0)
    assert m.peak_force == pytest.approx(k * x0)
    kc = m.compressive_stiffness
    assert np.all(np.isnan(kc[m.compression < 5e-3]))  # guarded where Δd ≈ 0
    np.testing.assert_allclose(kc[np.isfinite(kc)], k, rtol=1e-12)
    d = m.to_dict()
    assert d["peak_Kc_kN_per_m"] == pytest.approx(k / 1e3)
    assert d["energy_stored_J"] == pytest.approx(0.5 * k * x0**2)
    assert d["efficiency_pct"] == pytest.approx(100.0, abs=1e-7)


def test_kelvin_voigt_dissipates_pi_c_omega_x0_squared_per_cycle():
    # F = k x + c ẋ with x = a (1 − cos ωt): per cycle ∮ F dx = ∫ c ẋ² dt = π c ω a².
    # Loading (0..π/ω): ½ k (2a)² + π c ω a² / 2;  unloading returns ½ k (2a)² − π c ω a² / 2.
    k, c, a = 20e3, 150.0, 0.04
    omega = 2 * np.pi / 0.2
    t = np.linspace(0.0, 2 * np.pi / omega, 4001)
    x = a * (1 - np.cos(omega * t))
    xdot = a * omega * np.sin(omega * t)
    m = stance_mechanics(_stance(t, k * x + c * xdot, x, n_pre=3), contact_threshold=1.0)
    dissipated = np.pi * c * omega * a**2
    assert m.energy_dissipated == pytest.approx(dissipated, rel=1e-4)
    assert m.energy_stored == pytest.approx(2 * k * a**2 + dissipated / 2, rel=1e-4)
    assert m.energy_returned == pytest.approx(2 * k * a**2 - dissipated / 2, rel=1e-4)
    eff = 100 * (2 * k * a**2 - dissipated / 2) / (2 * k * a**2 + dissipated / 2)
    assert m.efficiency == pytest.approx(eff, rel=1e-4)
    loading_x, loading_f = m.compression_loop.loading
    unloading_x, unloading_f = m.compression_loop.unloading
    assert loading_x[-1] == pytest.approx(2 * a) and unloading_x[0] == pytest.approx(2 * a)
    # The unloading branch lies below the loading branch at the same compression (hysteresis).
    assert np.interp(a, unloading_x[::-1], unloading_f[::-1]) < np.interp(a, loading_x, loading_f)


def test_d0_is_the_unloaded_distance_before_touch_down_or_the_first_sample():
    t = np.linspace(0, 0.1, 101)
    x = 0.05 * np.sin(np.pi * t / 0.1)
    s = _stance(t, 2e4 * x + 30.0, x)  # loaded from the first sample
    s_pre = _stance(t, 2e4 * x + 30.0, x, n_pre=10)
    assert stance_mechanics(s).d0 == pytest.approx(D0)
    assert stance_mechanics(s_pre).d0 == pytest.approx(D0)
    assert stance_mechanics(s_pre).contact_index == 10
    assert stance_mechanics(s, d0=D0 + 0.01).peak_compression == pytest.approx(0.06)


def _tip(theta, length, pitch=0.0):
    """Tip [m] of a rod of ``length`` from the clamp at blade angle θ, clamp at (0, D0)."""
    # In the clamp frame the tip is L (sin θ, −cos θ); to the lab by R_y(pitch).
    cx, cz = length * np.sin(theta), -length * np.cos(theta)
    return cx * np.cos(pitch) + cz * np.sin(pitch), D0 - cx * np.sin(pitch) + cz * np.cos(pitch)


def test_blade_angle_is_relative_to_the_clamp_and_forward_positive():
    theta = np.deg2rad(np.array([-10.0, 0.0, 25.0, 60.0]))
    pitch = np.deg2rad(np.array([-30.0, 5.0, 20.0, 40.0]))
    tx, tz = _tip(theta, 0.4, pitch)
    got = blade_angle(np.zeros(4), np.full(4, D0), pitch, tx, tz)
    np.testing.assert_allclose(got, theta, atol=1e-12)
    # Tip straight ahead of an unpitched clamp: +90°.
    assert blade_angle(0.0, 0.0, 0.0, 1.0, 0.0) == pytest.approx(np.pi / 2)


def test_torsional_spring_about_the_clamp_gives_its_stiffness_and_negative_deflection():
    # A rod of length L hinged at the clamp with a torsional spring k_t; a vertical force F at
    # the tip is in equilibrium when F·L·sin θ = k_t (θ − θ0) (moment arm L sin θ).
    k_t, L, theta0 = 1100.0, 0.35, np.deg2rad(20.0)
    t = np.linspace(0, 0.12, 121)
    theta = theta0 + np.deg2rad(25.0) * np.sin(np.pi * t / 0.12)
    force = np.where(t > 0, k_t * (theta - theta0) / (L * np.sin(theta)), 0.0)
    pitch = np.deg2rad(np.linspace(-30, 40, len(t)))  # clamp pitches; the rod turns with it
    tx, tz = _tip(theta, L, pitch)
    # Stiffness with the clamp upright (vertical force = the textbook case) ...
    s0 = _stance(t, force, np.zeros_like(t))
    tx0, tz0 = _tip(theta, L)
    m = stance_mechanics(s0, tip_x=tx0, tip_z=tz0, hinge=(0.0, 0.0), contact_threshold=1.0)
    k = m.torsional_stiffness
    ok = np.isfinite(k)
    assert ok.sum() > 90
    np.testing.assert_allclose(k[ok], k_t, rtol=1e-9)
    assert m.peak_angular_deformation == pytest.approx(-np.deg2rad(25.0), rel=1e-3)
    assert m.to_dict()["K_at_peak_Nm_per_deg"] == pytest.approx(k_t * np.pi / 180, rel=1e-9)
    # ... and the angle with the clamp pitching: the deflection is still measured relative to the clamp.
    sp = _stance(t, force, np.zeros_like(t), pitch=pitch)
    mp = stance_mechanics(sp, tip_x=tx, tip_z=tz, contact_threshold=1.0)
    np.testing.assert_allclose(mp.angular_deformation, theta0 - theta, atol=1e-12)
    assert mp.angle_loop.peak_index == int(np.argmax(theta))


def test_simulated_result_uses_the_same_path_and_table_is_tidy():
    t = np.linspace(0, 0.1, 101)
    x = 0.06 * np.sin(np.pi * t / 0.1)
    meas = stance_mechanics(_stance(t, 2e4 * x, x, n_pre=2, group="TT-A"))
    sim = stance_mechanics(_stance(t, 2.2e4 * x, x, n_pre=2, group="TT-A"))
    table = mechanics_table([meas, sim])
    assert list(table["group"]) == ["TT-A", "TT-A"]
    assert table["peak_Kc_kN_per_m"].tolist() == pytest.approx([20.0, 22.0])
    frame = meas.to_frame()
    assert {"time_s", "force_N", "compression_m", "Kc_kN_per_m"} <= set(frame.columns)


def test_bad_input_is_a_clear_error():
    t = np.linspace(0, 0.1, 11)
    with pytest.raises(DataError, match="contact threshold"):
        stance_mechanics(_stance(t, np.zeros(11), np.zeros(11)))
    x = np.linspace(0, 0.01, 11)
    s = _stance(t, 1e4 * x + 50, x)
    bad = Stance(**{**s.__dict__, "distance": np.where(t > 0.05, np.nan, s.distance)})
    with pytest.raises(DataError, match="distance"):
        stance_mechanics(bad)
    with pytest.raises(DataError, match="tip_x"):
        stance_mechanics(s, tip_x=np.zeros(3), tip_z=np.zeros(3))
    with pytest.raises(DataError, match="force component"):
        stance_mechanics(s, force="sideways")  # type: ignore[arg-type]


def test_kc_only_above_the_distance_noise_and_efficiency_plausibility():
    k, x0, T = 25e3, 0.08, 0.12  # N/m, m, s
    t = np.linspace(0.0, T, 241)
    x = x0 * np.sin(np.pi * t / T)
    quiet = stance_mechanics(_stance(t, k * x, x, n_pre=40))
    assert quiet.distance_noise == 0.0 and quiet.compression_threshold == pytest.approx(5e-3)
    # 1.5 mm of noise on the distance before touch-down: K_c from 10 × 1.5 = 15 mm on
    noisy = _stance(t, k * x, x, n_pre=400)
    rng = np.random.default_rng(0)
    d = noisy.distance.copy()
    d[:400] += rng.normal(0.0, 1.5e-3, 400)
    import dataclasses

    m = stance_mechanics(dataclasses.replace(noisy, distance=d))
    assert m.distance_noise == pytest.approx(1.5e-3, rel=0.15)
    assert m.compression_threshold == pytest.approx(10 * m.distance_noise)
    defined = np.isfinite(m.compressive_stiffness)
    assert np.all(m.compression[defined] >= m.compression_threshold)
    assert np.any((m.compression > 5e-3) & (m.compression < m.compression_threshold))
    # a simulated stance takes its measured one's threshold
    sim = stance_mechanics(_stance(t, k * x, x, n_pre=5), min_compression=m.compression_threshold,
                           noise_factor=0.0)
    assert sim.compression_threshold == m.compression_threshold
    row = m.to_dict()
    assert row["Kc_threshold_mm"] == pytest.approx(1e3 * m.compression_threshold)
    assert row["Kc_at_peak_compression_kN_per_m"] == pytest.approx(k / 1e3, rel=0.01)  # d0 noisy
    assert row["efficiency_plausible"] is True  # a lossless spring returns 100 %
    lossy = stance_mechanics(_stance(t, k * x * np.where(t < T / 2, 1.0, 0.3), x, n_pre=5))
    assert lossy.efficiency < 50 and lossy.to_dict()["efficiency_plausible"] is False
