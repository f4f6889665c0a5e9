"""The metabolic models (Uchida 2016 / Umberger 2003; Bhargava 2004) against hand-computed cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.runner import build_runner
from bladelab.runner.metabolics import (
    BASAL_RATE_W_PER_KG,
    MB_MODEL,
    METABOLIC_MODELS,
    bhargava_muscle_rate,
    metabolic_params,
    muscle_metabolic_rate,
    total_metabolic_rate,
)


def test_isometric_activation_maintenance_only():
    # A = u = 0.5 (u > a); h_AM = (1.28*50 + 25) * 0.5**0.6 * 1.5; no shortening heat, no work
    expected = 89.0 * 0.5**0.6 * 1.5
    assert muscle_metabolic_rate(0.5, 0.3, 1.0, 0.0, 800.0, 0.0, 1.0, 50.0) == pytest.approx(
        expected
    )


def test_shortening_with_deactivation_average():
    # u < a: A = (0.2 + 0.6)/2 = 0.4; FT 20 %: v_max,ST = 10/1.3, v_max,FT = 2.5 v_max,ST
    a_st = 100.0 / (10.0 / 1.3)  # 13.0
    a_ft = 153.0 / (2.5 * 10.0 / 1.3)  # 7.956
    h_am = (1.28 * 20 + 25) * 0.4**0.6 * 1.5
    h_s = (a_st * 2.0 * 0.8 + a_ft * 2.0 * 0.2) * 0.4**2 * 1.5
    work = 500.0 * 0.2 / 0.5  # shortening at 0.2 m/s against 500 N, per kg of a 0.5 kg muscle
    expected = (h_am + h_s + work) * 0.5
    got = muscle_metabolic_rate(0.2, 0.6, 0.9, -2.0, 500.0, -0.2, 0.5, 20.0)
    assert got == pytest.approx(expected)
    assert a_st == pytest.approx(13.0)


def test_lengthening_counts_negative_work():
    # A = 1, FT 50 %: alpha_L = 4 * 100 / (10/1.75) = 70; h_L = 70 * 1 * 1 * 1.5 = 105
    # h_AM = 89 * 1.5 = 133.5; negative work -1000*0.1/1 = -100 (Uchida: included)
    assert muscle_metabolic_rate(1.0, 1.0, 1.0, 1.0, 1000.0, 0.1, 1.0, 50.0) == pytest.approx(
        133.5 + 105.0 - 100.0
    )


def test_absorbed_work_is_never_refunded():
    # a weakly active muscle stretched hard: h = 1 W/kg floor (A = 0.01: h_AM = 89*1.5*0.01^0.6 =
    # 8.4, h_L = 70*0.01*1.5 = 1.05), work -5000*0.1/1 = -500 W/kg: the total is 0, not -490
    assert muscle_metabolic_rate(0.01, 0.01, 1.0, 1.0, 5000.0, 0.1, 1.0, 50.0) == 0.0
    # a little absorbed work only lowers the total (h + w = 238.5 - 200 > 0)
    assert muscle_metabolic_rate(1.0, 1.0, 1.0, 1.0, 2000.0, 0.1, 1.0, 50.0) == pytest.approx(
        133.5 + 105.0 - 200.0)


def test_heat_floor_of_one_watt_per_kg():
    assert muscle_metabolic_rate(0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 50.0) == pytest.approx(2.0)


def test_long_fibres_scale_by_isometric_force():
    f_iso = math.exp(math.log(0.05) * (0.2 / 0.56) ** 3)
    h_am = 89.0 * 1.5 * (0.4 + 0.6 * f_iso)
    assert muscle_metabolic_rate(1.0, 1.0, 1.2, 0.0, 0.0, 0.0, 1.0, 50.0) == pytest.approx(h_am)


def test_muscle_masses_are_the_seed_volumes():
    model = build_runner("able")
    mb = metabolic_params(model)
    i = model.muscle_names.index("glut_max_l")
    # seed 001 eq. 2.1: V = phi * V_total = 0.12 * 11095 cm^3; rho = 1059.7 kg/m^3
    assert mb[i, 0] == pytest.approx(1059.7 * 0.12 * 11095e-6, rel=1e-9)
    assert mb[i, 1] == 45.0


def test_shortening_heat_scales_with_the_inverse_maximum_shortening_velocity():
    """Umberger's shortening heat coefficients are 100/v_max,ST and 153/v_max,FT: twice the
    fibres' maximum velocity, half the heat at the same shortening speed (the maintenance heat
    stays)."""
    h_am = muscle_metabolic_rate(1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 50.0, 10.0)
    slow, fast = (muscle_metabolic_rate(1.0, 1.0, 1.0, -2.0, 0.0, -0.2, 1.0, 50.0, v)
                  for v in (10.0, 20.0))
    assert slow > h_am and fast - h_am == pytest.approx(0.5 * (slow - h_am), rel=1e-12)
    assert muscle_metabolic_rate(1.0, 1.0, 1.0, -2.0, 0.0, -0.2, 1.0, 50.0) == slow  # default


def test_total_rate_is_basal_plus_muscles():
    mp = np.array([[1000.0, 0.1, 0.2, 0.0, 0.04, 1.0, 0.6, 10.0]])
    mb = np.array([[1.0, 50.0]])
    ms = np.array([[0.5, 0.1, 0.0, 300.0]])  # isometric at optimal length
    u = np.array([0.5])
    expected = BASAL_RATE_W_PER_KG * 70.0 + 89.0 * 0.5**0.6 * 1.5
    assert total_metabolic_rate(u, ms, mp, mb, 70.0) == pytest.approx(expected)
    assert total_metabolic_rate(u[:0], ms[:0], mp[:0], mb[:0], 70.0) == pytest.approx(1.51 * 70)


def test_bhargava_isometric_heat_at_full_excitation():
    # half slow-twitch, 1 kg, optimal length, isometric: activation 40/2 + 133/2 and
    # maintenance 74/2 + 111/2 W (Bhargava et al. 2004's constants)
    got = bhargava_muscle_rate(1.0, 1.0, 1.0, 0.0, 1000.0, 0.0, 1000.0, 1.0, 50.0)
    assert got == pytest.approx(86.5 + 92.5)


def test_bhargava_shortening_heat_grows_with_force():
    # shortening at 0.1 m/s: α = 0.16·F_iso + 0.18·F_fibre, heat α·|v|, work F_ce·|v|
    base = 86.5 + 92.5
    got = bhargava_muscle_rate(1.0, 1.0, 1.0, -0.1, 800.0, 0.0, 1000.0, 1.0, 50.0)
    assert got == pytest.approx(base + (160.0 + 144.0) * 0.1 + 80.0)
    stronger = bhargava_muscle_rate(1.0, 1.0, 1.0, -0.1, 1600.0, 0.0, 2000.0, 1.0, 50.0)
    assert stronger - base == pytest.approx(2.0 * (got - base))


def test_bhargava_lengthening_is_not_credited_below_the_floors():
    # lengthening: heat −0.157·F·v (negative), no work; with little excitation the total
    # would be negative: raised to 0, then the heat floor of 1 W/kg
    got = bhargava_muscle_rate(0.5, 0.5, 1.0, 0.1, 1000.0, 0.0, 500.0, 2.0, 50.0)
    s = math.sin(math.pi / 4)
    f = 1.0 - math.cos(math.pi / 4)
    heat = 2.0 * (20.0 * s + 66.5 * f) + 2.0 * (37.0 * s + 55.5 * f) - 15.7
    assert got == pytest.approx(heat)
    assert bhargava_muscle_rate(0.01, 0.01, 1.0, 0.5, 5000.0, 0.0, 50.0, 2.0, 50.0) == \
        pytest.approx(2.0)


@pytest.mark.parametrize(("l_norm", "factor"), [(0.3, 0.5), (0.75, 0.75), (1.25, 0.5),
                                                (1.6, 0.0)])
def test_bhargava_maintenance_heat_length_dependence(l_norm, factor):
    act = 86.5
    got = bhargava_muscle_rate(1.0, 1.0, l_norm, 0.0, 0.0, 0.0, 0.0, 1.0, 50.0)
    assert got == pytest.approx(act + factor * 92.5)


def test_total_rate_dispatches_on_the_model_column():
    mp = np.array([[1000.0, 0.1, 0.2, 0.0, 0.04, 1.0, 0.6, 10.0]])
    ms = np.array([[0.5, 0.1, 0.0, 300.0]])  # isometric at optimal length
    u = np.array([1.0])
    uchida = total_metabolic_rate(u, ms, mp, np.array([[1.0, 50.0, 0.0]]), 70.0)
    bhargava = total_metabolic_rate(u, ms, mp, np.array([[1.0, 50.0, 1.0]]), 70.0)
    assert uchida == pytest.approx(BASAL_RATE_W_PER_KG * 70.0 + 89.0 * 1.5)
    assert bhargava == pytest.approx(BASAL_RATE_W_PER_KG * 70.0 + 86.5 + 92.5)


def test_metabolic_model_is_read_from_the_parameter_set():
    from bladelab.runner.params import default_runner_params

    params = default_runner_params("able", body="human").model_copy(
        update={"metabolic_model": "bhargava2004"})
    mb = metabolic_params(build_runner(params))
    assert np.all(mb[:, MB_MODEL] == METABOLIC_MODELS.index("bhargava2004"))
    assert np.all(metabolic_params(build_runner("able"))[:, MB_MODEL] == 0.0)
