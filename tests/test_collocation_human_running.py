"""A stride against measured human running: the bands and the criteria's verdicts."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bladelab.predict.collocation.human_running import (
    human_running_criteria,
    reference_band,
)

DOFS = ("pelvis_tx", "pelvis_tz", "pelvis_tilt", "hip_flexion_l", "knee_angle_l",
        "hip_flexion_r", "knee_angle_r")


def _stride(*, speed=3.5, contact=(0.24, 0.24), peak_bw=(2.5, 2.5), period=0.70,
            knee_deg=(100.0, 95.0), tilt_deg=-8.0, flight=0.1, contacts=(1, 1), cot=4.0,
            model="able"):
    """A stand-in for a CollocationSolution with the numbers the criteria read."""
    weight = 75.0 * 9.81
    legs = ("left", "right") if model == "able" else ("intact", "prosthetic")
    q = np.zeros((len(DOFS), 51))
    q[DOFS.index("pelvis_tilt")] = math.radians(tilt_deg)
    q[DOFS.index("knee_angle_l"), 20] = -math.radians(knee_deg[0])
    q[DOFS.index("knee_angle_r"), 40] = -math.radians(knee_deg[1])
    phases = {"legs": {leg: {"contact_time_s": c, "contacts": n,
                             "peak_vertical_grf_N": p * weight}
                       for leg, c, n, p in zip(legs, contact, contacts, peak_bw, strict=True)},
              "flight_fraction": flight}
    return SimpleNamespace(mean_speed_mps=speed, contact_phases=lambda: phases,
                           model_spec={"model": model}, leg_names=legs, body_weight_N=weight,
                           period_s=period, nlp=SimpleNamespace(q=q), dof_names=DOFS,
                           cost_of_transport_J_per_kg_m=cot)


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


def test_prosthetic_leg_may_touch_shorter_and_no_flight_fails():
    crit = human_running_criteria(_stride(speed=4.0, model="amputee", contact=(0.22, 0.16),
                                          flight=0.0))
    by_name = {c.name: c for c in crit}
    assert by_name["contact time, prosthetic leg"].met
    assert not by_name["contact time, intact leg"].low == 0.15
    assert not by_name["flight phase"].met


def test_fast_strides_have_no_cost_band_and_say_when_a_band_is_held():
    crit = human_running_criteria(_stride(speed=10.0, contact=(0.1, 0.1), peak_bw=(3.5, 3.5),
                                          period=0.45, knee_deg=(120, 120)))
    assert "gross cost of transport" not in {c.name for c in crit}
    assert "band held from 9 m/s" in next(c for c in crit if c.name == "stride time").line()
