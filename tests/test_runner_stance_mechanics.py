"""Per-stance mechanics (leg stiffness, leg and blade energy) on synthetic results with
hand-derived answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bladelab.runner import build_runner, leg_energy, leg_stiffness
from bladelab.runner.analyses import stances
from bladelab.runner.stance_mechanics import blade_energy
from test_runner_analyses import STANCES, _synthetic


@pytest.fixture(scope="module")
def amputee():
    return build_runner("amputee")


def test_leg_stiffness_hand_derived(amputee):
    """K_leg = F_peak / (Δy + L0(1 − cos θ)), θ = asin(v·t_c / 2L0) (seed 001 eq. 2.19–2.21)."""
    res = _synthetic(amputee, stances=STANCES, drop=0.04, peak=2000.0)
    ks = leg_stiffness(res, threshold_n=1.0)
    assert len(ks) == 5
    row = ks[ks.leg == "intact"].iloc[0]
    # joints fixed: the COM dips with the pelvis (minus the first 1 ms of the dip, before the
    # first sample above threshold)
    assert row.delta_y == pytest.approx(0.04, abs=1e-3)
    assert row.F_peak == pytest.approx(2000.0, rel=1e-3)
    l0 = row.L0
    assert 0.85 < l0 < 1.0  # hip height of a 1.80 m athlete
    prosth = ks[ks.leg == "prosthetic"].iloc[0].L0
    assert prosth - l0 == pytest.approx(0.03, abs=1e-6)  # 3 cm longer prosthetic leg
    tc = row.contact_time
    theta = math.asin(3.0 * tc / (2 * l0))
    assert row.K_leg == pytest.approx(2000.0 / (0.04 + l0 * (1 - math.cos(theta))), rel=0.02)


def test_leg_energy_of_a_loop(amputee):
    """COM dips 4 cm and rises back under a half-sine force: stored = generated = ∫F dy."""
    res = _synthetic(amputee, stances=STANCES, drop=0.04, peak=2000.0)
    en = leg_energy(res, threshold_n=1.0)
    row = en.iloc[0]
    # F = P·sin(s), y = −D·sin(s): ∫ over descent of F·dy = P·D·∫0^{π/2} sin·cos ds = P·D/2
    assert row.E_stored == pytest.approx(2000.0 * 0.04 / 2, rel=0.01)
    assert row.E_generated == pytest.approx(2000.0 * 0.04 / 2, rel=0.01)
    assert row.recoil_pct == pytest.approx(100.0, abs=1.0)


def test_strikes_never_count_as_stances(amputee):
    # the swinging intact foot strikes the ground (40 ms, 1 kN) just after each prosthetic
    # touch-down: leg stiffness and leg energy see the same stances as without the strikes
    strikes = [(0, 0.42, 0.46), (0, 1.02, 1.06)]
    clean = _synthetic(amputee, stances=STANCES, drop=0.04)
    struck = _synthetic(amputee, stances=[*STANCES, *strikes], drop=0.04)
    struck.qpos[:] = clean.qpos  # the same motion: only the forces differ
    st = stances(struck)
    assert list(st.leg) == ["intact", "prosthetic", "intact", "prosthetic", "intact"]
    np.testing.assert_allclose(st.touchdown_s, [0.1, 0.4, 0.7, 1.0, 1.3], atol=2e-3)
    assert (st.contact_time_s > 0.19).all()
    for analysis in (leg_energy, leg_stiffness):
        a, b = analysis(clean), analysis(struck)
        assert len(a) == len(b) == 5
        np.testing.assert_allclose(a.select_dtypes("number"), b.select_dtypes("number"))
    # every stance is complete: a contact cut by the start or end of the record is left out
    cut = _synthetic(amputee, stances=[(0, -0.1, 0.05), *STANCES, (1, 1.95, 2.2)])
    assert len(stances(cut)) == 5


def _blade_loop(amputee, *, dissipation):
    """One prosthetic stance whose blade sphere compresses as a half-sine (peak 50 mm, 0.2 s)
    under the Hunt–Crossley force k·δ^1.5·(1 + 1.5·c·δ̇)."""
    res = _synthetic(amputee, stances=[(0, 0.1, 0.3), (1, 0.4, 0.6), (0, 0.7, 0.9)])
    b = int(np.flatnonzero(amputee.contact_params[:, 7] == 1)[0])
    k = amputee.contact_params[b, 3]
    t = res.time
    on = (t > 0.4) & (t < 0.6)
    depth = np.where(on, 0.05 * np.sin(math.pi * (t - 0.4) / 0.2), 0.0)
    rate = np.gradient(depth, t)
    force = np.where(on, k * depth**1.5 * np.clip(1 + 1.5 * dissipation * rate, 0, None), 0.0)
    res.contacts[:, b, 1] = force
    res.contacts[:, b, 6] = depth
    return res, depth, force


def test_blade_energy_of_elastic_and_dissipative_loops(amputee):
    elastic, depth, force = _blade_loop(amputee, dissipation=0.0)
    row = blade_energy(elastic).iloc[0]
    stored = np.trapezoid(np.where(np.gradient(depth) > 0, force, 0.0), depth)
    assert row.E_stored_J == pytest.approx(stored, rel=1e-3)
    assert row.recoil_pct == pytest.approx(100.0, abs=0.05)
    lossy, depth, force = _blade_loop(amputee, dissipation=0.2)
    row = blade_energy(lossy).iloc[0]
    # stored − returned = ∮F·dδ = ∫ 1.5·c·k·δ^1.5·δ̇² dt, the Hunt–Crossley dissipation
    cp = amputee.contact_params[int(np.flatnonzero(amputee.contact_params[:, 7] == 1)[0])]
    rate = np.gradient(depth, lossy.time)
    lost = np.trapezoid(1.5 * 0.2 * cp[3] * depth**1.5 * rate**2, lossy.time)
    assert row.hysteresis_J == pytest.approx(lost, rel=0.02)
    assert 60.0 < row.recoil_pct < 99.0
    # the seed's bookkeeping (compression from the force by eq. 2.3) cannot see the loss
    assert blade_energy(lossy, compression="hertz").recoil_pct.iloc[0] == pytest.approx(
        100.0, abs=0.05)
    assert blade_energy(_synthetic(build_runner("able"), stances=STANCES)).empty


def test_blade_energy_counts_each_stance_once_under_a_smooth_contact_law(amputee):
    """A smooth law (the collocation model's) pushes with a small force above the ground too:
    each stance's window is where the blade penetrates, not where its force is above 0."""
    res = _synthetic(amputee, stances=STANCES)
    b = int(np.flatnonzero(amputee.contact_params[:, 7] == 1)[0])
    k = amputee.contact_params[b, 3]
    t = res.time
    depth = np.zeros_like(t)
    for t0, t1 in ((0.4, 0.6), (1.0, 1.2)):
        on = (t > t0) & (t < t1)
        depth[on] = 0.05 * np.sin(math.pi * (t[on] - t0) / (t1 - t0))
    res.contacts[:, b, 1] = k * depth**1.5 + 0.1  # 0.1 N above the ground
    res.contacts[:, b, 6] = depth
    e = blade_energy(res)
    one = k * 0.05**2.5 / 2.5  # ∫k·δ^1.5 dδ up to the peak [J]
    assert len(e) == 2
    np.testing.assert_allclose(e.E_stored_J, one, rtol=1e-3)
    np.testing.assert_allclose(e.E_returned_J, one, rtol=1e-3)
