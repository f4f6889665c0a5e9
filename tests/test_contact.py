import math

import pytest

from bladelab import contact


def test_spring_damper_no_force_out_of_contact_and_no_adhesion():
    assert contact.smooth_spring_damper_force(-0.001, -1.0, 1e6, 1e3, 1e-4) == 0.0
    # Fast withdrawal: damping would pull; force is clipped at zero.
    assert contact.smooth_spring_damper_force(0.001, -10.0, 1e5, 1e3, 0.0) == 0.0


def test_spring_damper_linear_beyond_transition():
    f = contact.smooth_spring_damper_force(0.002, 0.1, 1e6, 1e3, 1e-4)
    assert math.isclose(f, 1e6 * 0.002 + 1e3 * 0.1)
    # Inside the transition width the force is reduced by the cubic step (x = 0.5 -> 0.5).
    f_half = contact.smooth_spring_damper_force(0.5e-4, 0.0, 1e6, 0.0, 1e-4)
    assert math.isclose(f_half, 0.5 * 1e6 * 0.5e-4)


def test_hertz_sphere_matches_closed_form():
    radius, modulus, depth = 0.03, 2.7e6, 0.005
    k = contact.hertz_sphere_stiffness(radius, modulus)
    f = contact.hunt_crossley_force(depth, 0.0, k, 1.5, 1.0)
    assert math.isclose(f, 4 / 3 * math.sqrt(radius) * modulus * depth**1.5)
    # Dissipation scales by (1 + 1.5 c v).
    f_moving = contact.hunt_crossley_force(depth, 0.2, k, 1.5, 1.0)
    assert math.isclose(f_moving, f * 1.3)


@pytest.mark.parametrize("v", [-0.2, -0.04, -0.01, 0.0, 0.01, 0.03, 0.06, 0.2])
def test_stick_slip_odd_bounded_and_continuous(v):
    mu_s, mu_k, vc = 0.9, 0.7, 0.05
    mu = contact.stick_slip_friction_coefficient(v, mu_s, mu_k, vc)
    assert mu == pytest.approx(-contact.stick_slip_friction_coefficient(-v, mu_s, mu_k, vc))
    assert abs(mu) <= mu_s + 1e-12
    eps = 1e-9
    left = contact.stick_slip_friction_coefficient(v - eps, mu_s, mu_k, vc)
    right = contact.stick_slip_friction_coefficient(v + eps, mu_s, mu_k, vc)
    assert abs(left - right) < 1e-6


def test_stick_slip_regimes():
    assert contact.stick_slip_friction_coefficient(0.025, 0.9, 0.7, 0.05) == pytest.approx(0.45)
    assert contact.stick_slip_friction_coefficient(0.05, 0.9, 0.7, 0.05) == pytest.approx(0.9)
    assert contact.stick_slip_friction_coefficient(1.0, 0.9, 0.7, 0.05) == pytest.approx(0.7)


def test_stribeck_saturates_at_dynamic_coefficient():
    assert contact.stribeck_friction_coefficient(10.0, 0.9, 0.9, 0.1) == pytest.approx(0.9, rel=1e-3)
    assert contact.stribeck_friction_coefficient(0.0, 0.9, 0.9, 0.1) == 0.0
