"""Blade evaluator: physics of the simulated stance, constraint proxies, seed-002 trends."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.design import default_design_space, generate_blade
from bladelab.design.evaluators import BladeEvaluator, make_evaluator, swing_clearance
from bladelab.design.responses import BLADE_RESPONSE_UNITS
from bladelab.errors import SpecError

G = 9.80665


@pytest.fixture(scope="module")
def space():
    return default_design_space()


@pytest.fixture(scope="module")
def centre(space):
    ev = BladeEvaluator()
    return ev, ev(space.point([0, 0, 0, 0]))


def _brute_force_lowest(model, pitch_deg: float) -> float:
    """Lowest z of the rotated blade: points, tip and densely sampled ellipse perimeters."""
    th = math.radians(pitch_deg)
    c, s = math.cos(th), math.sin(th)
    zs = [-s * x + c * z for x, z in [*np.asarray(model.points), model.tip]]
    u = np.linspace(0, 2 * np.pi, 20001)
    for e in model.soles:
        ca, sa = math.cos(e.angle), math.sin(e.angle)
        # perimeter in the clamp frame (ellipse turned by its angle, same rotation convention)
        px = e.semi_axis_x * np.cos(u)
        pz = e.semi_axis_z * np.sin(u)
        x = e.center[0] + ca * px + sa * pz
        z = e.center[1] - sa * px + ca * pz
        zs.append(float(np.min(-s * x + c * z)))
    return float(min(zs))


@pytest.mark.parametrize("pitch", [0.0, 35.0, 60.0])
def test_swing_clearance_matches_brute_force(space, pitch):
    model = generate_blade(space.point([0, 0, 0, 1])).model
    got = swing_clearance(model, clamp_height_m=0.5, pitch_deg=pitch)
    assert got == pytest.approx(0.5 + _brute_force_lowest(model, pitch), abs=1e-6)


def test_responses_complete_and_consistent(centre):
    ev, r = centre
    assert list(r) == list(BLADE_RESPONSE_UNITS)
    assert all(math.isfinite(v) for v in r.values())
    m = ev.body_mass_kg
    assert r["impulse_x_Ns"] == pytest.approx(m * r["delta_vx_m_per_s"])
    assert r["impulse_z_net_Ns"] == pytest.approx(r["impulse_z_Ns"] - m * G * r["contact_time_s"],
                                                  rel=0.02)
    assert r["evaluation_E_m"] == pytest.approx(
        r["impulse_x_Ns"] * r["impulse_z_net_Ns"] / (m * m * G), rel=1e-9)


def test_stance_is_physically_plausible(centre):
    """Design-notes ranges for sprinting on a blade: contact 0.08-0.2 s, peak GRF 2-5 BW,
    compression 40-130 mm; a passive runner cannot gain speed over a stance."""
    ev, r = centre
    bw = ev.body_mass_kg * G
    assert 0.07 < r["contact_time_s"] < 0.2
    assert 2.0 < r["peak_grf_z_N"] / bw < 5.0
    assert 0.04 < r["compression_m"] < 0.13
    assert r["delta_vx_m_per_s"] < 0.0
    assert ev.speed_mps - 1.0 < r["avg_vx_m_per_s"] < ev.speed_mps


def test_vertical_impulse_agrees_with_contact_force(space):
    """The momentum-based vertical impulse equals the integrated contact force (independent
    channel of the simulation) within 4 % (the blade's own 0.65 kg and the abrupt touch-down
    edge at 2 kHz make the difference; measured 2.8 %)."""
    from bladelab.sim.synthetic import generate_stance

    ev = BladeEvaluator()
    blade = ev.blade(space.point([0, 0, 0, 0])).model
    stance, truth = generate_stance(blade, speed_mps=ev.speed_mps, body_mass_kg=ev.body_mass_kg,
                                    dt=ev.dt, sample_rate=ev.sample_rate)
    r = ev._responses(blade, stance, truth)
    i_contact = float(np.trapezoid(truth["grf_z"], stance.time))
    assert r["impulse_z_Ns"] == pytest.approx(i_contact, rel=0.04)


def test_seed002_toe_length_trends(space):
    """Seed 002: a shorter toe lowers the knee extension margin; a longer toe lowers the swing
    clearance (the other trends do not hold for this passive runner: docs/design.md)."""
    ev = BladeEvaluator()
    short = ev(space.point([0, 0, 0, -1]))
    long_ = ev(space.point([0, 0, 0, 1]))
    assert short["knee_moment_min_Nm"] < long_["knee_moment_min_Nm"]
    assert long_["swing_clearance_m"] < short["swing_clearance_m"]


def test_bad_settings_are_refused():
    with pytest.raises(SpecError, match="speed_mps"):
        BladeEvaluator(speed_mps=-1.0)
    with pytest.raises(SpecError, match="knee_above_clamp_m"):
        BladeEvaluator(knee_above_clamp_m=1.0)
    with pytest.raises(SpecError, match="unknown evaluator"):
        make_evaluator("finite-elements")
    assert isinstance(make_evaluator("blade", speed_mps=6.0), BladeEvaluator)
