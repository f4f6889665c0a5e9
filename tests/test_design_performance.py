"""Seed 002 performance functions against hand-derived point-mass mechanics."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bladelab.design.performance import (
    STANDARD_GRAVITY as G,
)
from bladelab.design.performance import (
    average_horizontal_velocity,
    bouncing_ball,
    cycle_performance,
    horizontal_velocity_change,
    impulse,
    performance_by_stance,
    stance_performance,
    stance_windows,
)
from bladelab.errors import DataError

M = 60.0
TC = 0.12


def _forces(t):
    """A sprint-like stance: vertical half sine, braking-then-propulsive horizontal force."""
    fz = 2200.0 * np.sin(np.pi * t / TC)
    fx = -250.0 * np.sin(2 * np.pi * t / TC) + 60.0 * np.sin(np.pi * t / TC)
    return fx, fz


def _stance_then_flight(vx0: float):
    """Integrate a point mass through the stance, then fly ballistically back to take-off height.

    The touch-down vertical velocity is chosen so that take-off is its mirror image (the
    bouncing-ball assumption of seed 002).
    """
    j_net = 2200.0 * 2 * TC / np.pi - M * G * TC  # ∫(Fz - mg) dt of the half sine, by hand
    vz0 = -j_net / (2 * M)

    def rhs(t, s):
        fx, fz = _forces(t)
        return [s[2], s[3], fx / M, fz / M - G]

    sol = solve_ivp(rhs, (0.0, TC), [0.0, 1.0, vx0, vz0], rtol=1e-11, atol=1e-12)
    x1, z1, vx1, vz1 = sol.y[:, -1]
    assert vz1 == pytest.approx(-vz0, rel=1e-6)  # mirror image, as constructed
    t_flight = 2.0 * vz1 / G  # back to take-off height
    distance = vx1 * t_flight
    return t_flight, distance


def test_evaluation_equals_projectile_distance_minus_initial_velocity_term():
    vx0 = 8.0
    t_flight, distance = _stance_then_flight(vx0)
    t = np.linspace(0.0, TC, 1201)
    fx, fz = _forces(t)
    p = stance_performance(t, fx, fz, M)
    assert p.basis == "net"
    assert p.aerial_time == pytest.approx(t_flight, rel=1e-4)
    assert p.evaluation == pytest.approx(distance - vx0 * t_flight, rel=1e-4)
    # E = I_x·I_z,net/(m²g) and Δv_x = I_x/m by hand from the half-sine integrals
    i_x = 60.0 * 2 * TC / np.pi
    assert p.impulse_x == pytest.approx(i_x, rel=1e-5)
    assert p.delta_vx == pytest.approx(i_x / M, rel=1e-5)
    # the gross reading gives the step time: aerial time + contact time
    gross = stance_performance(t, fx, fz, M, net_of_body_weight=False)
    assert gross.aerial_time == pytest.approx(t_flight + TC, rel=1e-4)
    assert gross.impulse_z == pytest.approx(2200.0 * 2 * TC / np.pi, rel=1e-5)


def test_evaluation_zero_without_horizontal_impulse():
    t = np.linspace(0.0, TC, 601)
    fz = 2200.0 * np.sin(np.pi * t / TC)
    assert stance_performance(t, np.zeros_like(t), fz, M).evaluation == 0.0
    fx = -250.0 * np.sin(2 * np.pi * t / TC)  # braking and propulsion cancel
    p = stance_performance(t, fx, fz, M)
    assert abs(p.impulse_x) < 1e-9
    assert abs(p.evaluation) < 1e-12
    assert bouncing_ball(0.0, 300.0, M) == (300.0 / (M * G), 0.0, 0.0)


def _hopper(n_periods: float = 2.2, fs: float = 2000.0):
    """A point mass bouncing on a linear spring leg (no damping), moving forward at 5 m/s."""
    k, L0, vx = 20e3, 1.0, 5.0

    def rhs(t, s):
        fz = k * (L0 - s[1]) if s[1] < L0 else 0.0
        return [s[2], s[3], 0.0, fz / M - G]

    t = np.arange(0.0, 1.6, 1.0 / fs)
    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0, 1.08, vx, 0.0], t_eval=t, rtol=1e-10, atol=1e-12,
                    max_step=2e-4)
    x, z = sol.y[0], sol.y[1]
    fz = np.where(z < L0, k * (L0 - z), 0.0)
    return t, x, z, fz, L0


def test_vertical_impulse_over_a_period_equals_weight_times_period():
    t, x, z, fz, L0 = _hopper()
    on = z < L0
    td = np.flatnonzero(np.diff(on.astype(int)) == 1) + 1  # touch-down samples
    assert len(td) >= 3
    a, b = td[0], td[2] + 1  # two steps: one stance per "leg", a full gait cycle
    tt, fzz, fx = t[a:b], fz[a:b], np.zeros(b - a)
    legs = np.zeros(b - a, dtype=int)
    legs[td[1] - a:] = 1
    stance = on[a:b].copy()
    stance[-1] = False  # the next cycle's touch-down sample
    masks = {"prosthetic": stance & (legs == 0), "sound": stance & (legs == 1)}
    T = tt[-1] - tt[0]
    cyc = cycle_performance(tt, fx, fzz, M, stance_masks=masks, com_x=x[a:b])
    assert cyc.period == pytest.approx(T)
    assert cyc.impulse_z == pytest.approx(M * G * T, rel=0.02)
    assert abs(cyc.impulse_z_net) < 0.02 * M * G * T
    assert cyc.mean_vx == pytest.approx(5.0, rel=1e-6)
    assert cyc.delta_vx == 0.0
    # per stance, the net-impulse aerial time is the simulated flight time
    table = performance_by_stance(tt, fx, fzz, M, stance_masks=masks)
    assert sorted(table["leg"]) == ["prosthetic", "sound"]
    for _, row in table.iterrows():
        t_on = row["t_end"] - row["t_start"]
        flight = T / 2 - t_on
        assert row["aerial_time"] == pytest.approx(flight, rel=0.02)
    r = cyc.responses()
    assert {"delta_vx_m_per_s", "evaluation_prosthetic_m", "evaluation_sound_m"} <= set(r)


def test_velocity_functions_by_hand():
    t = np.linspace(0.0, 0.5, 501)
    fx = np.full_like(t, 120.0)  # constant force: v = v0 + (F/m) t
    assert horizontal_velocity_change(t, fx, M) == pytest.approx(120.0 * 0.5 / M)
    mean = average_horizontal_velocity(t, fx, M, v_x0=7.0)
    assert mean == pytest.approx(7.0 + 0.5 * 120.0 / M * 0.5, rel=1e-12)
    assert horizontal_velocity_change(t, fx, M, window=(0.1, 0.3)) == pytest.approx(
        120.0 * 0.2 / M)
    mask = (t > 0.1) & (t < 0.2) | (t > 0.3) & (t < 0.4)
    assert len(stance_windows(mask)) == 2
    assert impulse(t, fx, mask=mask) == pytest.approx(120.0 * (0.098 + 0.098), rel=1e-9)


def test_bad_inputs():
    t = np.linspace(0.0, 0.1, 11)
    f = np.ones(11)
    with pytest.raises(DataError, match="strictly increasing"):
        stance_performance(t[::-1], f, f, M)
    with pytest.raises(DataError, match="grf_z"):
        stance_performance(t, f, f[:5], M)
    with pytest.raises(DataError, match="mass"):
        stance_performance(t, f, f, -1.0)
    bad = f.copy()
    bad[3] = np.nan
    with pytest.raises(DataError, match="non-finite"):
        stance_performance(t, bad, f, M)
    two = np.array([1, 1, 0, 0, 1, 1, 0, 0, 0, 0, 0], dtype=bool)
    with pytest.raises(DataError, match="2 windows"):
        stance_performance(t, f, f, M, mask=two)
