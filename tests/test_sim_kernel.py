"""The numba planar-chain kernel: invariants, hand-derived statics, convergence, API behaviour."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

from bladelab import units
from bladelab.blade import load_blade
from bladelab.blade.model import BladeModel, CompliantJoint, ContactModel, SoleEllipse
from bladelab.errors import DataError, ModelError
from bladelab.sim import build_chain, prepare, simulate, simulate_batch
from bladelab.sim.synthetic import generate_stance
from bladelab.trial.stance import Stance

G = units.STANDARD_GRAVITY


def arc_blade(*, joints=(7,), K=1000.0, D=15.0, friction=True) -> BladeModel:
    """A 16-segment J-like arc (clamp at the origin), soles under segments 13–15."""
    pts = [(0.0, -0.05 * i) for i in range(5)]
    for k in range(1, 9):
        a = np.pi + k * np.pi / 16
        pts.append((0.18 + 0.18 * np.cos(a), -0.2 + 0.18 * np.sin(a)))
    pts += [(0.18 + 0.04 * k, -0.38) for k in range(1, 5)]
    pts = np.asarray(pts)
    length = np.hypot(*np.diff(pts, axis=0).T)
    mass = 0.6 * length / length.sum()
    com = 0.5 * (pts[1:] + pts[:-1])
    return BladeModel(
        name="arc", points=pts, segment_mass=mass, segment_com=com,
        segment_inertia=mass * length**2 / 12,
        joints=tuple(CompliantJoint(p, K, D) for p in joints),
        soles=tuple(SoleEllipse(s, (float(com[s, 0]), -0.38), 0.03, 0.008) for s in (13, 14, 15)),
        tip=tuple(pts[-1]), tip_segment=15,
        contact=ContactModel(friction_static=0.9 if friction else 0.0),
    )


def still_stance(z: float, pitch_deg: float, duration: float = 0.4, rate: float = 1000.0) -> Stance:
    t = np.arange(0.0, duration + 1e-9, 1.0 / rate)
    zero = np.zeros_like(t)
    return Stance(t, zero, zero, np.full_like(t, z), np.full_like(t, np.deg2rad(pitch_deg)),
                  zero, zero, zero, zero)


def nrmse(a: np.ndarray, ref: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - ref) ** 2)) / np.ptp(ref))


@pytest.fixture(scope="module")
def xtreme_stance():
    blade = load_blade("xtreme").build()
    stance, truth = generate_stance(blade, speed_mps=7.0, body_mass_kg=76.0, sample_rate=2000.0)
    return blade, stance, truth


def test_chain_merges_segments_preserving_mass_and_moment():
    blade = arc_blade(joints=(5, 11))
    chain = build_chain(blade)
    assert chain.n_joints == 2
    assert chain.body_mass.sum() == pytest.approx(blade.mass)
    # first moment of mass is preserved by the merge
    np.testing.assert_allclose((chain.body_mass[:, None] * chain.body_com).sum(axis=0),
                               (blade.segment_mass[:, None] * blade.segment_com).sum(axis=0))
    assert list(chain.sole_body) == [2, 2, 2]


@pytest.mark.parametrize("pitch_deg", [0.0, 25.0])
def test_static_hang_matches_geometry(pitch_deg):
    """Clamp held still in the air: K·q balances the gravity moment of the distal segments."""
    K = 5.0  # soft, so that the sag is clearly measurable
    blade = arc_blade(K=K, D=0.4)  # about critically damped
    result = simulate(prepare(blade, still_stance(1.0, pitch_deg, duration=1.0)))
    q_sim = result.deflection[-1, 0]
    hinge = blade.points[7]
    distal = slice(7, None)
    theta = np.deg2rad(pitch_deg)

    def rot(angle, xz):  # pitch about +y: (x, z) -> (c x + s z, -s x + c z)
        c, s = np.cos(angle), np.sin(angle)
        return np.stack([c * xz[..., 0] + s * xz[..., 1], -s * xz[..., 0] + c * xz[..., 1]], -1)

    def residual(q):
        # lab x of each distal segment COM relative to the hinge, rotated by pitch + q
        r = rot(theta + q, blade.segment_com[distal] - hinge)
        gravity_moment = np.sum(blade.segment_mass[distal] * G * r[:, 0])  # about +y
        return -K * q + gravity_moment

    q_ref = brentq(residual, -1.0, 1.0)
    assert abs(q_ref) > np.deg2rad(2.0)
    assert q_sim == pytest.approx(q_ref, rel=2e-3)
    # settled: the torque output equals the spring torque, the clamp did no net work lately
    assert result.torque[-1, 0] == pytest.approx(-K * q_ref, rel=2e-3)
    assert np.all(result.grf_z == 0.0)


def test_energy_balance_without_dissipation(xtreme_stance):
    """D = 0, no friction, no contact damping, rigid ground: clamp work = Δ(stored energy)."""
    blade, stance, _ = xtreme_stance
    lossless = blade.with_contact(friction_static=0.0, damping=0.0)
    result = simulate(prepare(lossless, stance, dt=2e-5), damping=0.0)
    e = result.energy
    assert np.all(e["dissipated_joint"] == 0.0) and np.all(e["dissipated_friction"] == 0.0)
    assert e["spring"].max() > 50.0  # the blade was loaded
    err = result.energy_balance_error()
    assert np.abs(err).max() < 0.01 * np.abs(e["clamp_work"]).max()


def test_energy_terms_with_dissipation_are_positive(xtreme_stance):
    blade, stance, _ = xtreme_stance
    result = simulate(prepare(blade, stance))
    e = result.energy
    for name in ("dissipated_joint", "dissipated_contact", "dissipated_friction"):
        assert np.all(np.diff(e[name]) >= -1e-9), name
    assert e["dissipated_joint"][-1] > 0.0


def test_halving_dt_changes_grf_little(xtreme_stance):
    blade, stance, _ = xtreme_stance
    a = simulate(prepare(blade, stance))  # the default step
    b = simulate(prepare(blade, stance, dt=0.5 * a.dt))
    assert nrmse(a.grf_z, b.grf_z) < 0.005
    assert nrmse(a.grf_total, b.grf_total) < 0.005
    assert nrmse(a.grf_x, b.grf_x) < 0.01
    assert nrmse(a.distance, b.distance) < 0.001


def test_loaded_blade_deflects_negative_and_compresses(xtreme_stance):
    blade, stance, truth = xtreme_stance
    result = simulate(prepare(blade, stance))
    assert result.deflection.min() < np.deg2rad(-15)
    assert blade.rest_distance - result.distance.min() > 0.04
    # the spring torque opposes the deflection
    loaded = result.grf_z > 500
    assert np.all(result.torque[loaded, 0] * result.deflection[loaded, 0] < 0)
    assert set(np.unique(result.contact_state)) <= {0, 1, 2}


def test_batch_equals_single_runs(xtreme_stance):
    blade, stance, _ = xtreme_stance
    problem = prepare(blade, stance)
    K = np.array([[800.0], [1000.0], [1250.0]])
    D = np.array([[8.0], [17.0], [28.0]])
    batch = simulate_batch(problem, K, D)
    assert batch.grf_x.shape == (3, problem.n_samples)
    assert batch.deflection.shape == (3, problem.n_samples, 1)
    assert batch.ok.all()
    for s in range(3):
        single = simulate(problem, stiffness=K[s], damping=D[s])
        np.testing.assert_array_equal(batch.grf_z[s], single.grf_z)
        np.testing.assert_array_equal(batch.distance[s], single.distance)
    # stiffer blade, less compression
    assert batch.distance[2].min() > batch.distance[0].min()


def test_parallel_batch_equals_serial_bit_for_bit(xtreme_stance):
    blade, stance, _ = xtreme_stance
    problem = prepare(blade, stance)
    rng = np.random.default_rng(3)
    K = units.stiffness_per_deg_to_per_rad(rng.uniform(13, 22, (6, 1)))
    D = units.damping_per_deg_to_per_rad(rng.uniform(0.15, 0.5, (6, 1)))
    serial = simulate_batch(problem, K, D)
    parallel = simulate_batch(problem, K, D, parallel=True)
    assert serial.ok.all() and parallel.ok.all()
    for name in ("grf_x", "grf_z", "distance", "deflection", "torque"):
        np.testing.assert_array_equal(getattr(parallel, name), getattr(serial, name), err_msg=name)


def test_the_kernel_is_compiled_once_whatever_parameters_are_passed(xtreme_stance):
    """K, D, K2 given or left out (read-only broadcast views or the chain's own arrays), scalar
    or per set: one argument type, so one compilation of the kernel (each one costs about half a
    minute on a cold cache)."""
    from bladelab.sim import kernel

    blade, stance, _ = xtreme_stance
    problem = prepare(blade, stance)
    simulate(problem)
    simulate(problem, stiffness=900.0)
    simulate(problem, stiffness=900.0, damping=10.0, stiffness_quadratic=100.0)
    simulate(problem, stiffness_quadratic=np.broadcast_to(100.0, (1,)))
    simulate_batch(problem, np.broadcast_to(900.0, (2, 1)), np.array([[8.0], [9.0]]))
    simulate_batch(problem, np.array([[800.0], [900.0]]), np.array([[8.0], [9.0]])[:, ::-1],
                   np.zeros((2, 1)))
    assert len(kernel.simulate_batch_serial.signatures) == 1, kernel.simulate_batch_serial.signatures


def test_belt_speed_equals_moving_the_clamp(xtreme_stance):
    blade, stance, _ = xtreme_stance
    belt = 3.0
    shifted = dataclasses.replace(stance, clamp_x=stance.clamp_x - belt * stance.time)
    a = simulate(prepare(blade, stance))
    b = simulate(prepare(blade, shifted, belt_speed=belt))
    np.testing.assert_allclose(b.grf_z, a.grf_z, atol=1e-6 * np.ptp(a.grf_z))
    np.testing.assert_allclose(b.distance, a.distance, atol=1e-9)


def test_result_tables_have_units_in_names(xtreme_stance):
    blade, stance, _ = xtreme_stance
    result = simulate(prepare(blade, stance))
    frame = result.to_frame()
    for col in ("time_s", "grf_x_N", "grf_z_N", "grf_total_N", "distance_m",
                "deflection_deg_j1", "torque_Nm_j1", "grf_z_N_s3", "energy_clamp_work_J"):
        assert col in frame.columns
    np.testing.assert_allclose(frame["deflection_deg_j1"], np.rad2deg(result.deflection[:, 0]))
    d = result.to_dict()
    assert d["K_Nm_per_deg"][0] == pytest.approx(units.stiffness_per_rad_to_per_deg(
        blade.joints[0].stiffness))


def test_bad_inputs_give_clear_errors(xtreme_stance):
    blade, stance, _ = xtreme_stance
    problem = prepare(blade, stance)
    with pytest.raises(ModelError, match="stiffness"):
        simulate(problem, stiffness=-1.0)
    with pytest.raises(ModelError, match="engine"):
        prepare(blade, stance, engine="opensim")
    with pytest.raises(ModelError, match="drive"):
        prepare(blade, stance, drive="spring")
    gappy = dataclasses.replace(stance, clamp_z=np.where(np.arange(len(stance.time)) == 20,
                                                         np.nan, stance.clamp_z))
    with pytest.raises(DataError, match="clamp_z"):
        prepare(blade, gappy)
    with pytest.raises(ModelError, match="track"):
        prepare(blade.with_contact(track_stiffness=0.0), stance)
