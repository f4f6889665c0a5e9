"""People's swing knee: the smooth peak-flexion constraint and its settings."""

from __future__ import annotations

import json
import math

import casadi as ca
import numpy as np
import pytest

from bladelab.errors import SpecError
from bladelab.predict import defaults
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.swing_knee import (
    SHARPNESS,
    biological_knees,
    peak_flexion_rows,
    people_swing_knee_deg,
)
from bladelab.predict.collocation.transcription import StrideNLP
from toy_stride import bouncing_guess, toy_dynamics


def test_the_default_is_people_s_peak_from_the_packaged_curves():
    # the literal in defaults (which imports nothing) is the two runners' mean peak
    assert defaults.SWING_KNEE_MIN_DEG == pytest.approx(people_swing_knee_deg(), abs=0.05)
    assert 100 < people_swing_knee_deg() < 120


def test_the_smooth_peak_lies_between_the_largest_node_and_ln_n_above_it():
    rng = np.random.default_rng(7)
    n, minimum = 50, 1.9
    X = ca.MX.sym("X", 2, n)
    rows = ca.Function("rows", [X], [peak_flexion_rows(X, np.array([1.0, 2.0]), ("a", "knee"),
                                                       {"knee": minimum})])
    for _ in range(20):
        x = rng.uniform(-1.3, 0.0, size=(2, n))
        peak = -2.0 * x[1].min()  # flexion = -q, q = x * scale
        value = float(rows(x))
        assert peak - minimum <= value <= peak - minimum + math.log(n) / SHARPNESS + 1e-12
    # a sharp peak: the smooth maximum is the peak itself to well within a degree
    x = np.zeros((2, n))
    x[1, 17] = -1.0
    assert float(rows(x)) == pytest.approx(2.0 - minimum, abs=1e-6)
    with pytest.raises(ValueError, match="knee"):
        peak_flexion_rows(X, np.ones(2), ("a", "knee"), {"knee": -0.1})


def test_only_a_person_s_knees_are_held():
    names = ("pelvis_tx", "knee_angle_l", "knee_angle_r")
    assert biological_knees(names, "able") == ("knee_angle_l", "knee_angle_r")
    assert biological_knees(names, "amputee") == ("knee_angle_l", "knee_angle_r")
    assert biological_knees(names, "transfemoral") == ("knee_angle_l",)


def test_the_nlp_keeps_the_held_coordinate_flexed_and_leaves_it_free_otherwise():
    # the toy's tilt is free and constant over a stride (no moment on it, no cost): free, it
    # stays at the guess's 0; held, every node flexes at least to the minimum less
    # ln(n)/SHARPNESS (all nodes equal: the smooth peak exceeds each by exactly that)
    n, minimum = 20, 0.3
    guess = bouncing_guess(n, 2.0)
    free = StrideNLP(toy_dynamics(), n=n, speed=2.0, compiled=False)
    sol = free.solve(free.initial_vector(guess), hessian="exact", tol=1e-8)
    assert sol.success and np.abs(sol.q[:, 2]).max() < 1e-6
    held = StrideNLP(toy_dynamics(), n=n, speed=2.0, compiled=False,
                     knee_flexion_min={"pelvis_tilt": minimum})
    assert held.n_cons == free.n_cons + 1
    _, _, lbg, ubg = held.bounds()
    i = held._g_names.index("peak flexion pelvis_tilt")
    assert (lbg[i], ubg[i]) == (0.0, np.inf)
    sol = held.solve(held.initial_vector(guess), hessian="exact", tol=1e-8)
    assert sol.success, sol.status
    flexion = -sol.q[:, 2]
    assert minimum - math.log(n) / SHARPNESS - 1e-6 <= flexion.min()
    with pytest.raises(SpecError, match="knee_angle_l"):
        StrideNLP(toy_dynamics(), n=n, speed=2.0, compiled=False,
                  knee_flexion_min={"knee_angle_l": minimum})


def test_settings_hold_the_swing_knee_by_body_and_refuse_bad_values():
    human = CollocationSettings(**people_settings("human"))
    assert human.swing_knee_min_deg == defaults.SWING_KNEE_MIN_DEG
    assert CollocationSettings(**people_settings("seed001")).swing_knee_min_deg is None
    assert CollocationSettings(**people_settings("human", kind="amputee")
                               ).swing_knee_min_deg == defaults.SWING_KNEE_MIN_DEG
    # the transfemoral runner's intact knee is free unless asked for
    assert CollocationSettings(**people_settings("human", kind="transfemoral")
                               ).swing_knee_min_deg is None
    assert CollocationSettings(**people_settings("human", swing_knee_deg=100,
                                                 kind="transfemoral")
                               ).swing_knee_min_deg == 100.0
    assert CollocationSettings(**people_settings("human", swing_knee_deg=0)
                               ).swing_knee_min_deg is None
    assert CollocationSettings(**people_settings("seed001", swing_knee_deg=95)
                               ).swing_knee_min_deg == 95.0
    assert not human.same_problem(CollocationSettings(**people_settings("human",
                                                                        swing_knee_deg=0)))
    assert CollocationSettings.from_dict(json.loads(json.dumps(human.to_dict()))) == human
    for bad in (-5, 0, 150, math.nan, True, "108"):
        with pytest.raises(SpecError) as err:
            CollocationSettings(swing_knee_min_deg=bad)
        assert err.value.where == "swing_knee_min_deg"
