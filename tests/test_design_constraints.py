"""Knee-buckling moment sign and blade clearance, by hand."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.design.constraints import blade_clearance, knee_buckling, knee_extension_moment
from bladelab.errors import DataError


def test_grf_line_through_knee_gives_zero():
    knee = np.array([0.10, 0.50])
    cop = np.array([0.30, 0.0])
    for s in (500.0, 1500.0):
        f = s * (knee - cop) / np.linalg.norm(knee - cop)
        m = knee_extension_moment(cop[0], cop[1], knee[0], knee[1], f[0], f[1])
        assert m[0] == pytest.approx(0.0, abs=1e-9)


def test_grf_in_front_of_knee_extends_behind_flexes():
    # vertical GRF 1000 N, 0.1 m in front of the knee: extension moment +100 N·m
    assert knee_extension_moment(0.1, 0.0, 0.0, 0.5, 0.0, 1000.0)[0] == pytest.approx(100.0)
    assert knee_extension_moment(-0.1, 0.0, 0.0, 0.5, 0.0, 1000.0)[0] == pytest.approx(-100.0)
    # COP under the knee, braking force: the GRF line leans back and passes 0.1 m behind the
    # knee at knee height; moment = -|F|·d_perp
    fx, fz = -200.0, 1000.0
    m = knee_extension_moment(0.0, 0.0, 0.0, 0.5, fx, fz)[0]
    d_perp = abs(0.5 * fx) / np.hypot(fx, fz)
    assert m == pytest.approx(-np.hypot(fx, fz) * d_perp)
    # and it is minus the y-component of r × F
    r = np.array([0.0, 0.0, -0.5])
    assert m == pytest.approx(-np.cross(r, [fx, 0.0, fz])[1])


def test_knee_buckling_minimum_over_stance_only():
    t = np.linspace(0.0, 1.0, 101)
    moment = np.sin(2 * np.pi * t) * 50.0  # negative in the second half
    stance = t < 0.45
    r = knee_buckling(t, moment, stance_mask=stance, margin=-5.0)
    assert r.min_moment == pytest.approx(0.0, abs=1e-12) and r.time_of_min == 0.0
    assert r.satisfied and r.slack == pytest.approx(5.0)
    r2 = knee_buckling(t, moment, stance_mask=~stance, margin=0.0)
    assert not r2.satisfied and r2.min_moment == pytest.approx(-50.0)
    assert r2.time_of_min == pytest.approx(0.75)
    with pytest.raises(DataError, match="no prosthetic stance"):
        knee_buckling(t, moment, stance_mask=np.zeros_like(t, dtype=bool))


def test_blade_clearance_minimum_over_swing():
    t = np.linspace(0.0, 1.0, 201)
    # two blade points swinging on arcs; the toe dips to 0.03 m at t = 0.6 (a parabola)
    toe_z = 0.03 + 2.0 * (t - 0.6) ** 2
    heel_z = toe_z + 0.1
    x = 5.0 * t
    pts = np.stack([np.stack([x, heel_z], -1), np.stack([x + 0.1, toe_z], -1)], axis=1)
    swing = (t > 0.3) & (t < 0.9)
    r = blade_clearance(t, pts, swing_mask=swing, threshold=0.02)
    assert r.min_clearance == pytest.approx(0.03, abs=1e-12)
    assert r.time_of_min == pytest.approx(0.6) and r.point_index == 1
    assert r.satisfied and r.slack == pytest.approx(0.01)
    # a ground step of 2 cm and the sole radius eat the clearance
    r2 = blade_clearance(t, pts, swing_mask=swing, ground=lambda gx: np.where(gx > 2.0, 0.02, 0.0),
                         radius=0.005, threshold=0.01)
    assert r2.min_clearance == pytest.approx(0.005, abs=1e-12) and not r2.satisfied
    # only swing counts: outside it the toe is lower
    r3 = blade_clearance(t, pts, swing_mask=t > 0.95)
    assert r3.min_clearance > 0.03
    with pytest.raises(DataError, match="shape"):
        blade_clearance(t, pts[:10], swing_mask=swing)
