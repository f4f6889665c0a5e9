"""A stride against measured human running: the bands and the criteria's verdicts."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bladelab.predict.collocation.human_running import (
    angle_agreement,
    human_running_criteria,
    reference_band,
)
from bladelab.predict.collocation.settings import CollocationSettings

DOFS = ("pelvis_tx", "pelvis_tz", "pelvis_tilt", "hip_flexion_l", "knee_angle_l",
        "hip_flexion_r", "knee_angle_r")


def _stride(*, speed=3.5, contact=(0.24, 0.24), peak_bw=(2.5, 2.5), period=0.70,
            knee_deg=(100.0, 95.0), tilt_deg=-8.0, flight=0.1, contacts=(1, 1), cot=4.0,
            model="able", right_after=0.5, stride_time_range=None):
    """A stand-in for a CollocationSolution with the numbers the criteria read; the right
    stance ``right_after`` of the stride after the left one."""
    weight = 75.0 * 9.81
    legs = ("left", "right") if model == "able" else ("intact", "prosthetic")
    q = np.zeros((51, len(DOFS)))  # (nodes, coordinates)
    q[:, DOFS.index("pelvis_tilt")] = math.radians(tilt_deg)
    q[20, DOFS.index("knee_angle_l")] = -math.radians(knee_deg[0])
    q[40, DOFS.index("knee_angle_r")] = -math.radians(knee_deg[1])
    phases = {"legs": {leg: {"contact_time_s": c, "contacts": n,
                             "peak_vertical_grf_N": p * weight}
                       for leg, c, n, p in zip(legs, contact, contacts, peak_bw, strict=True)},
              "flight_fraction": flight}
    t = np.arange(51) / 50
    force = np.stack([np.where((t - lag) % 1.0 < 0.3, 1000.0, 0.0) for lag in (0.0, right_after)],
                     axis=1)
    return SimpleNamespace(mean_speed_mps=speed, contact_phases=lambda: phases,
                           leg_vertical_force=lambda: force,
                           model_spec={"model": model}, leg_names=legs, body_weight_N=weight,
                           period_s=period, nlp=SimpleNamespace(q=q), dof_names=DOFS,
                           cost_of_transport_J_per_kg_m=cot,
                           settings=CollocationSettings(stride_time_range_s=stride_time_range))


def test_bands_are_the_anchors_and_interpolate_between_them():
    assert reference_band("contact time", 3.5)[:2] == pytest.approx((0.20, 0.30))
    assert reference_band("contact time", 9.0)[:2] == pytest.approx((0.10, 0.13))
    lo, hi, unit = reference_band("contact time", 6.25)
    assert (lo, hi, unit) == (pytest.approx(0.15), pytest.approx(0.215), "s")
    assert reference_band("contact time", 2.0)[:2] == reference_band("contact time", 3.5)[:2]


def test_a_human_stride_meets_every_criterion():
    crit = human_running_criteria(_stride())
    assert all(c.met for c in crit), [c.line() for c in crit if not c.met]
    assert {c.name for c in crit} >= {"contact time, left leg", "stride time",
                                      "peak swing knee flexion, right leg", "mean pelvis tilt",
                                      "gross cost of transport"}


def test_a_stride_held_on_a_band_edge_by_its_bound_meets_it_and_says_it_was_imposed():
    # IPOPT relaxes bounds by 1e-8 relative: a stride held at 0.64 s ends a hair below it
    held = human_running_criteria(_stride(period=0.64 * (1 - 1e-8),
                                          stride_time_range=(0.64, 0.78)))
    stride = next(c for c in held if c.name == "stride time")
    assert stride.met and stride.note == "imposed: 0.64–0.78 s"
    short = next(c for c in human_running_criteria(_stride(period=0.6399))
                 if c.name == "stride time")
    assert not short.met and short.note == ""


def test_the_stiff_short_gait_fails_where_it_is_not_human():
    """Seed 001's body's optimum at 3.5 m/s: 0.11 s contacts, 5.2 BW, 41° of knee flexion,
    −21° of pelvis tilt, a swinging foot striking once more."""
    crit = human_running_criteria(_stride(contact=(0.106, 0.116), peak_bw=(5.2, 5.3),
                                          period=0.50, knee_deg=(41.0, 33.0), tilt_deg=-21.0,
                                          contacts=(2, 1), cot=2.6))
    failed = {c.name for c in crit if not c.met}
    assert failed == {"contact time, left leg", "contact time, right leg",
                      "peak vertical ground force, left leg",
                      "peak vertical ground force, right leg", "stride time",
                      "peak swing knee flexion, left leg", "peak swing knee flexion, right leg",
                      "mean pelvis tilt", "ground contacts per stride, left leg",
                      "gross cost of transport"}
    line = next(c for c in crit if c.name == "contact time, left leg").line()
    assert line == "contact time, left leg: 0.106 s (people: 0.2–0.3 s): OUTSIDE"


def test_a_gallop_fails_the_step_phase_whichever_leg_leads():
    """Both stances close together then one long flight: outside 40–60 % of the stride."""
    for lag, met in ((0.5, True), (0.42, True), (0.16, False), (0.84, False)):
        crit = {c.name: c for c in human_running_criteria(_stride(right_after=lag))}
        assert crit["step phase"].value == pytest.approx(100 * lag, abs=1e-6)
        assert crit["step phase"].met is met


def test_the_gallop_sentence_counts_strides_outside_the_band_and_skips_unknown_ones():
    from bladelab.predict.collocation.human_running import gallop_sentence

    text = gallop_sentence([50.0, 16.0, 84.0, float("nan"), 41.0])
    assert text.startswith("2 of 4 strides gallop") and "16–84 %" in text
    assert gallop_sentence([45.0, 55.0, float("nan")]) == ""
    assert gallop_sentence([]) == ""


def test_prosthetic_leg_may_touch_shorter_and_no_flight_fails():
    crit = human_running_criteria(_stride(speed=4.0, model="amputee", contact=(0.22, 0.16),
                                          flight=0.0))
    by_name = {c.name: c for c in crit}
    assert by_name["contact time, prosthetic leg"].met
    assert not by_name["contact time, intact leg"].low == 0.15
    assert not by_name["flight phase"].met


def test_a_transtibial_runner_lands_softer_on_the_blade_than_on_the_intact_leg():
    name = "peak vertical ground force, prosthetic minus intact leg"
    for peaks, met in (((3.0, 2.7), True), ((2.84, 2.92), False)):
        crit = {c.name: c for c in human_running_criteria(
            _stride(speed=4.0, model="amputee", contact=(0.22, 0.19), peak_bw=peaks))}
        assert crit[name].value == pytest.approx(peaks[1] - peaks[0])
        assert crit[name].met is met
    assert crit[name].line().startswith(f"{name}: 0.08 BW (people: ≤ 0 BW")
    assert name not in {c.name for c in human_running_criteria(_stride())}


def test_fast_strides_have_no_cost_band_and_say_when_a_band_is_held():
    crit = human_running_criteria(_stride(speed=10.0, contact=(0.1, 0.1), peak_bw=(3.5, 3.5),
                                          period=0.45, knee_deg=(120, 120)))
    assert "gross cost of transport" not in {c.name for c in crit}
    assert "band held from 9 m/s" in next(c for c in crit if c.name == "stride time").line()


def test_angle_agreement_is_zero_for_the_measured_stride_and_sees_an_offset():
    """The stride rolled to its left touch-down against the same angles: RMSE 0, knee r = 1;
    the knee 20° more flexed: RMSE 20° (outside 15°), correlation still 1."""
    n = 50
    pct = np.linspace(0.0, 1.0, n + 1)
    measured = np.zeros((n + 1, len(DOFS)))
    for name, amp in (("hip_flexion_l", 30.0), ("knee_angle_l", -50.0), ("hip_flexion_r", 30.0),
                      ("knee_angle_r", -50.0)):
        phase = 0.0 if name.endswith("_l") else 0.5
        measured[:, DOFS.index(name)] = np.radians(amp * (1 - np.cos(2 * np.pi * (pct - phase))))
    shift = 10  # the left leg lands at node 10 of the solved stride
    q = np.vstack([np.roll(measured[:-1], shift, axis=0)] * 1)
    q = np.vstack([q, q[:1]])
    fz = np.zeros((n + 1, 2))
    fz[shift:shift + 12, 0] = 1000.0
    sol = _stride()
    sol.nlp.q = q
    sol.leg_vertical_force = lambda: fz
    crit = {c.name: c for c in angle_agreement(sol, measured, 20.0)}
    assert crit["knee flexion RMSE against the measured stride, left leg"].value == pytest.approx(
        0.0, abs=1e-9)
    assert crit["knee flexion correlation with the measured stride, left leg"].value == (
        pytest.approx(1.0))
    sol.nlp.q = q.copy()
    sol.nlp.q[:, DOFS.index("knee_angle_l")] -= np.radians(20.0)
    crit = {c.name: c for c in angle_agreement(sol, measured, 20.0)}
    knee = crit["knee flexion RMSE against the measured stride, left leg"]
    assert knee.value == pytest.approx(20.0) and not knee.met
    assert crit["knee flexion correlation with the measured stride, left leg"].met
    assert "ankle dorsiflexion RMSE against the measured stride, left leg" not in crit  # no ankle


def test_the_shipped_human_body_stride_is_the_demo_start_and_meets_its_criteria():
    """The demo's predict example starts from a converged amputee Cat6 stride at 4 m/s on the
    human body; its contacts, prosthetic peak, cost and posture are within people's bands."""
    from bladelab.demo import PREDICT_EXAMPLE_STRIDE
    from bladelab.predict.collocation.solution import CollocationSolution

    sol = CollocationSolution.read(PREDICT_EXAMPLE_STRIDE)
    assert sol.converged and sol.model_spec == {"model": "amputee", "blade": "Cat6",
                                                "body": "human"}
    assert sol.mean_speed_mps == pytest.approx(4.0)
    met = {c.name: c.met for c in human_running_criteria(sol)}
    for name in ("contact time, intact leg", "contact time, prosthetic leg",
                 "peak vertical ground force, prosthetic leg", "mean pelvis tilt",
                 "gross cost of transport", "ground contacts per stride, prosthetic leg"):
        assert met[name], name
    assert sol.gait_warnings() == []


def test_the_shipped_able_stride_meets_every_criterion_with_people_s_swing_knee_imposed():
    """The able runner's shipped 3.5 m/s stride (the default guess, found from it again in no
    iteration) is within people's running on every criterion, and the swing knee's criterion
    says that its depth was imposed."""
    from bladelab.predict import defaults
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.runner.params import RUNNER_DATA_DIR

    sol = CollocationSolution.read(RUNNER_DATA_DIR / "collocation" / "able-3.5-human.json")
    assert sol.converged and sol.settings.swing_knee_min_deg == defaults.SWING_KNEE_MIN_DEG
    crit = human_running_criteria(sol)
    assert [c.line() for c in crit if not c.met] == []
    knees = [c for c in crit if c.name.startswith("peak swing knee flexion")]
    assert len(knees) == 2
    for knee in knees:
        assert "imposed: at least 108.5 deg" in knee.note
        assert knee.value > defaults.SWING_KNEE_MIN_DEG - 1.0  # the smooth peak's margin


def test_the_cost_band_ends_at_5_m_per_s_whatever_the_round_off():
    """A stride prescribed at 5 m/s whose mean speed is 5 m/s to round-off keeps the cost of
    transport's criterion; a faster one has none."""
    def names(speed):
        return {c.name for c in human_running_criteria(_stride(speed=speed))}

    assert "gross cost of transport" in names(5.0 + 1e-12)
    assert "gross cost of transport" in names(5.0 - 1e-12)
    assert "gross cost of transport" not in names(5.5)


def test_a_transfemoral_runner_s_prosthetic_knee_is_not_judged_as_a_person_s():
    def knees(model):
        return {c.name for c in human_running_criteria(_stride(model=model))
                if c.name.startswith("peak swing knee")}

    assert knees("amputee") == {"peak swing knee flexion, intact leg",
                                "peak swing knee flexion, prosthetic leg"}
    assert knees("transfemoral") == {"peak swing knee flexion, intact leg"}
