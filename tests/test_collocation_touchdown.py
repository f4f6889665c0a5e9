"""How a foot lands (``collocation.touchdown``), on the shipped strides of the human body: the
amputee wearing Cat6 at 4 m/s (both feet land moving forward and slide) and the transtibial
runner wearing the design box's centre blade (its blade lands sticking)."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.design.collocation_evaluator import DEFAULT_STARTS
from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.nodes import evaluate_nodes
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.predict.collocation.touchdown import STICK_SPEED_MPS, touchdown_slides
from bladelab.runner.layout import CP_LEG, CP_MU
from bladelab.runner.params import RUNNER_DATA_DIR


def _stride(path):
    sol = CollocationSolution.read(path)
    runner = runner_from_spec(sol.model_spec)
    cm = build_collocation_model(runner)
    nodes = evaluate_nodes(cm, sol.nlp.q, sol.nlp.qd, sol.nlp.tendon_force,
                           sol.nlp.tendon_force_rate)
    return sol, runner, cm, nodes


@pytest.fixture(scope="module")
def cat6():
    return _stride(RUNNER_DATA_DIR / "collocation" / "amputee-Cat6-4-human.json")


def test_each_leg_lands_once_sliding_forward_and_braking_at_the_friction_limit(cat6):
    sol, runner, cm, nodes = cat6
    slides, work = touchdown_slides(sol, runner, cm)
    assert [s.leg for s in slides] == ["intact", "prosthetic"]  # one touch-down per leg
    h_ms = 1e3 * sol.period_s / sol.settings.mesh_intervals
    for s in slides:
        leg = sol.leg_names.index(s.leg)
        rows = np.flatnonzero(runner.contact_params[:, CP_LEG] == leg)
        fx, fz = nodes["forces"][s.node, rows, 0], nodes["forces"][s.node, rows, 1]
        # it lands moving forward, faster than a sticking contact, and slides whole intervals
        assert s.speed_mps > 5 * STICK_SPEED_MPS
        assert s.slide_ms == pytest.approx(h_ms * round(s.slide_ms / h_ms))
        assert h_ms <= s.slide_ms <= 3 * h_ms + 1e-9
        # no further than at its landing speed, no shorter than half an interval at it
        assert 0.5 * s.speed_mps * h_ms <= s.slide_mm <= s.speed_mps * s.slide_ms
        # the friction law at the landing node: every loaded contact that slides forward
        # brakes at its limit, μ times its normal force
        mu = runner.contact_params[rows, CP_MU]
        v = nodes["point_velocities"][s.node, rows, 0]
        sliding = (fz > 1.0) & (v > 0.5)
        assert sliding.any()
        np.testing.assert_allclose(fx[sliding], -mu[sliding] * fz[sliding], rtol=1e-6)
        assert s.braking_bw <= fx.sum() / sol.body_weight_N + 1e-12 < 0.0
    # friction only takes energy: −F·v = μ·Fn·v·tanh(v/v_t) ≥ 0 at every node
    assert all(w > 0.0 for w in work.values())


def test_a_blade_that_lands_sticking_has_no_slide():
    sol, runner, cm, nodes = _stride(DEFAULT_STARTS[("transtibial", "human")])
    slides, work = touchdown_slides(sol, runner, cm)
    blade = next(s for s in slides if s.leg == "prosthetic")
    assert abs(blade.speed_mps) < STICK_SPEED_MPS
    assert blade.slide_ms == blade.slide_mm == blade.braking_bw == 0.0
    intact = next(s for s in slides if s.leg == "intact")
    assert intact.slide_ms > 0.0 and intact.braking_bw < 0.0
    assert work["prosthetic"] < work["intact"]
