"""Transfemoral runner: prosthetic knee law, gait cycles, motion adaptation, simulated cycle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.design import central_composite, default_design_space, generate_blade
from bladelab.design.gait_cycle import (
    ANGLE_NAMES,
    GaitCycle,
    default_gait_cycle,
    gait_cycle_from_runner,
    read_gait_csv,
)
from bladelab.design.motion_model import fit_motion_model
from bladelab.design.responses import RUNNER_RESPONSE_UNITS
from bladelab.design.transfemoral import RunnerEvaluator, simulate_transfemoral
from bladelab.errors import DataError, InputFileError, SpecError
from bladelab.runner.prosthetic_knee import ProstheticKnee

G = 9.80665


# -- prosthetic knee ---------------------------------------------------------------------------
def test_knee_torque_hand_values():
    k = ProstheticKnee(flexion_damping=2.0, extension_damping=0.5, assist_stiffness=10.0,
                       assist_rest_angle=0.0, stop_angle=0.0, stop_stiffness=1000.0,
                       stop_damping=20.0)
    # flexing at 0.3 rad, 2 rad/s: −2·2 − 10·0.3 = −7
    assert k.torque(0.3, 2.0) == pytest.approx(-7.0)
    # extending at 0.3 rad, −2 rad/s: −0.5·(−2) − 10·0.3 = −2
    assert k.torque(0.3, -2.0) == pytest.approx(-2.0)
    # hyperextended by 0.01 rad, still extending at −1 rad/s:
    # −0.5·(−1) − 10·(−0.01) − 1000·(−0.01) − 20·(−1) = 0.5 + 0.1 + 10 + 20
    assert k.torque(-0.01, -1.0) == pytest.approx(30.6)


def test_knee_refuses_negative_damping():
    with pytest.raises(SpecError, match="flexion_damping"):
        ProstheticKnee(flexion_damping=-1.0)


# -- gait cycles ---------------------------------------------------------------------------------
def test_default_cycle_is_periodic_and_mirrored():
    c = default_gait_cycle()
    a0, aT = c.at(0.0), c.at(c.period)
    for n in ANGLE_NAMES:
        assert a0[n] == pytest.approx(aT[n])
    half = c.at(0.5 * c.period)
    # the sound hip half a period later equals the prosthetic hip at touch-down (mirror)
    assert half["hip_sound"] == pytest.approx(a0["hip_prosthetic"], abs=1e-9)


def test_gait_csv_roundtrip(tmp_path):
    c = default_gait_cycle()
    path = tmp_path / "gait.csv"
    c.to_frame().to_csv(path, index=False)
    back = read_gait_csv(path)
    assert back.period == pytest.approx(c.period)
    t = np.linspace(0, c.period, 17)
    for n in ANGLE_NAMES:
        np.testing.assert_allclose(back.at(t)[n], c.at(t)[n], atol=1e-9)


def test_gait_csv_errors(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("time_s,hip_sound_deg\n0,1\n0.1,2\n")
    with pytest.raises(InputFileError, match="missing columns"):
        read_gait_csv(path)
    with pytest.raises(DataError, match="missing joint angles"):
        GaitCycle(0.5, np.arange(5) / 5, {"hip_sound": np.zeros(5)})


def test_motion_model_recovers_quadratic_motion():
    """Cycles whose period and angles are exact quadratics of the design: the fitted motion
    model predicts a new design exactly (seed 002's motion adaptation)."""
    space = default_design_space()
    coded = central_composite(space).coded
    base = default_gait_cycle().resampled(51)

    def cycle_at(c):
        k, w, h, t = c
        period = 0.52 + 0.02 * k - 0.01 * t * t + 0.005 * k * w
        ang = {n: a + math.radians(5) * k + math.radians(3) * t * h - math.radians(2) * w * w
               for n, a in base.angles.items()}
        return GaitCycle(period, base.phase, ang)

    model = fit_motion_model(coded, [cycle_at(c) for c in coded], factor_names=space.names,
                             n_nodes=51)
    new = np.array([0.3, -0.7, 0.5, 0.9])
    pred, truth = model.predict(new), cycle_at(new)
    assert pred.period == pytest.approx(truth.period, abs=1e-12)
    for n in ANGLE_NAMES:
        np.testing.assert_allclose(pred.angles[n], truth.angles[n], atol=1e-10)
    with pytest.raises(SpecError, match="cannot estimate"):
        fit_motion_model(coded[:9], [cycle_at(c) for c in coded[:9]], factor_names=space.names)


class _FakeRunnerResult:
    """Duck-typed RunnerResult: right-leg contact at 0.1-0.2 s and 0.6-0.7 s and 1.1-1.2 s."""

    def __init__(self):
        import pandas as pd

        self.t = np.arange(0, 1.3, 0.001)
        w = 2 * np.pi / 0.5
        self.st = pd.DataFrame({
            "time": self.t, "pelvis_tilt": -0.2 + 0 * self.t,
            "hip_flexion_l": 0.5 * np.sin(w * self.t), "knee_angle_l": -0.8 - 0.5 * np.cos(w * self.t),
            "ankle_angle_l": 0.1 * np.sin(w * self.t), "hip_flexion_r": 0.5 * np.cos(w * self.t),
            "knee_angle_r": -0.3 + 0 * self.t,
        })
        k = np.arange(self.t.size) % 500
        on = (k >= 100) & (k < 200)
        self.g = pd.concat([pd.DataFrame({"time": self.t, "leg": "intact", "Fz": 0.0 * self.t}),
                            pd.DataFrame({"time": self.t, "leg": "prosthetic",
                                          "Fz": np.where(on, 1500.0, 0.0)})])

    def states(self):
        return self.st

    def leg_grf(self):
        return self.g


def test_gait_cycle_from_runner_result():
    c = gait_cycle_from_runner(_FakeRunnerResult())
    assert c.period == pytest.approx(0.5)
    # the last complete cycle starts at t = 0.6 s: hip_r = 0.5 cos(w t), flexion-positive knee
    t0 = 0.6
    a = c.at(np.array([0.0, 0.125]))
    w = 2 * np.pi / 0.5
    np.testing.assert_allclose(a["hip_prosthetic"], 0.5 * np.cos(w * (t0 + np.array([0, 0.125]))),
                               atol=1e-6)
    assert a["knee_prosthetic"][0] == pytest.approx(0.3)
    assert a["trunk_pitch"][0] == pytest.approx(0.2)
    with pytest.raises(DataError, match="cycle 5"):
        gait_cycle_from_runner(_FakeRunnerResult(), cycle=5)


# -- simulated cycle -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def cycle_result():
    blade = generate_blade(default_design_space().point([0, 0, 0, -1])).model
    return blade, simulate_transfemoral(blade, dt=2e-5)


def test_cycle_momentum_balance(cycle_result):
    """Impulse of all ground forces over the cycle = mass × change of COM velocity (with
    gravity for z): the recorded forces are the ones that moved the body."""
    _, r = cycle_result
    fx = r.grf_prosthetic[:, 0] + r.grf_sound[:, 0]
    fz = r.grf_prosthetic[:, 1] + r.grf_sound[:, 1]
    h = r.time[1] - r.time[0]
    ix, iz = fx[1:].sum() * h, fz[1:].sum() * h  # each sample is the mean over its interval
    dv = r.com_velocity[-1] - r.com_velocity[0]
    scale = iz
    assert abs(ix - r.mass * dv[0]) < 0.01 * scale
    assert abs(iz - r.mass * G * r.period - r.mass * dv[1]) < 0.01 * scale


def test_cycle_landing_and_knee(cycle_result):
    blade, r = cycle_result
    st = r.prosthetic_stance
    assert st[:6].any()  # the blade lands within the first 5 ms
    assert r.grf_prosthetic[:, 1].min() >= 0.0
    assert r.knee_angle.min() > math.radians(-3)  # the hyperextension stop holds
    # the segments are scaled so that the whole model (prosthesis included) has the body mass
    assert r.mass == pytest.approx(76.0, abs=1e-4)
    # knee moment is the GRF moment about the knee: zero off the blade
    assert np.all(r.knee_moment[~st] == 0.0)


def test_cycle_responses(cycle_result):
    _, r = cycle_result
    res = r.responses()
    assert list(res) == list(RUNNER_RESPONSE_UNITS)
    assert all(math.isfinite(v) for v in res.values())
    assert 0.05 < res["contact_time_prosthetic_s"] < 0.3
    assert res["swing_clearance_m"] < 0.5


def test_runner_evaluator_and_errors(tmp_path):
    with pytest.raises(SpecError):
        simulate_transfemoral(generate_blade({"stiffness_kN_per_m": 25.0}).model, speed_mps=0.0)
    path = tmp_path / "gait.csv"
    default_gait_cycle().to_frame().to_csv(path, index=False)
    ev = RunnerEvaluator(gait=str(path), dt=4e-5)
    res = ev(default_design_space().point([0, 0, 0, 0]))
    assert set(res) == set(RUNNER_RESPONSE_UNITS)


def test_seed002_shorter_toe_lowers_knee_margin_on_the_runner():
    """Seed 002, fig. 9: a shorter toe gives a smaller knee extension moment (here its minimum
    over the prosthetic stance) on the transfemoral runner (measured: −316 vs −168 N·m)."""
    ev = RunnerEvaluator()
    space = default_design_space()
    short = ev(space.point([0, 0, 0, -1]))
    long_ = ev(space.point([0, 0, 0, 1]))
    assert short["knee_moment_min_Nm"] < long_["knee_moment_min_Nm"] - 50.0
