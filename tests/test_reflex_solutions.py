"""The reflex route's starts (``data/runner/reflex-starts``): each re-simulated from its
parameter file for 10 s runs (no fall) at 3.5 ± 0.1 m/s, with alternating steps, a flight phase
in every stride and the power balance within 2 %, and so do two copies with the parameters moved
by 1e-9; none survives copies moved by 1e-3, which is why they are starts and not accepted
solutions (docs/predictive.md, "Reflex starts")."""

from __future__ import annotations

from pathlib import Path

import pytest

import bladelab
from bladelab.errors import SpecError
from bladelab.predict.reflex.optimize import runner_and_layout
from bladelab.predict.reflex.verify import verify_solution

STARTS = Path(bladelab.__file__).parent / "data" / "runner" / "reflex-starts"
#: The seed-001 gaits the reflex route starts from (the no-strikes variant is not run here).
GAITS = [STARTS / "able-3.5.json", STARTS / "amputee-Cat6-3.5.json"]


def test_verification_rejects_a_falling_controller(tmp_path):
    from bladelab.predict.reflex.controller import write_parameters

    _, layout = runner_and_layout("able", None)
    path = write_parameters(tmp_path / "x0.json", layout, layout.x0, speed_m_per_s=3.5)
    out = verify_solution(path, duration=2.0)
    assert out["fell"] and not out["ok"]


def test_verification_uses_the_files_own_objective_settings(tmp_path):
    # a file optimised with other weights, another time step and robust sampling: the check
    # re-simulates it with those weights and that time step, once (no robust sampling)
    from bladelab.predict.reflex.controller import write_parameters
    from bladelab.predict.reflex.objective import ObjectiveSettings, simulate_controlled

    runner, layout = runner_and_layout("able", None)
    stored = {"w_cot": 2.0, "w_lean": 1.0, "dt": 0.0004, "robust_samples": 4, "gone": 1}
    path = write_parameters(
        tmp_path / "x0.json", layout, layout.x0, speed_m_per_s=3.5, settings=stored
    )
    out = verify_solution(path, duration=0.6)
    own = ObjectiveSettings(speed=3.5, duration=0.6, w_cot=2.0, w_lean=1.0, dt=0.0004)
    default = ObjectiveSettings(speed=3.5, duration=0.6)
    want = simulate_controlled(runner, layout.x0, layout=layout, settings=own)[0].cost
    other = simulate_controlled(runner, layout.x0, layout=layout, settings=default)[0].cost
    assert out["cost"] == pytest.approx(want, rel=1e-12)
    assert abs(want - other) > 1e-6 * abs(want)  # the settings do change the cost
    # a file optimised with pushed copies (which need >= 7 s) and a half-step copy
    # re-simulates for any duration, once, at its own step
    pushed = {"duration": 15.0, "robust_samples": 3, "robust_push": 0.02,
              "robust_speed_change": 0.01, "robust_half_step": True}
    path = write_parameters(tmp_path / "p.json", layout, layout.x0, speed_m_per_s=3.5,
                            settings=pushed)
    assert verify_solution(path, duration=0.6)["cost"] == pytest.approx(other, rel=1e-12)


@pytest.mark.parametrize("path", GAITS, ids=[p.stem for p in GAITS])
def test_start_runs(path):
    # two copies moved by 1e-9 (relative) stand in for another CPU's or library's rounding
    out = verify_solution(path, jittered_copies=2)
    for run in (out, *out["jittered"]):
        assert not run["fell"]
        assert run["duration_s"] == pytest.approx(10.0)
        assert run["mean_speed_m_per_s"] == pytest.approx(3.5, abs=0.1)
        assert run["strides"] >= 2 and run["strides_with_flight"] == run["strides"]
        assert run["same_leg_steps"] == 0  # running, not galloping
        assert run["power_balance_residual_pct"] <= 2.0
    assert out["ok"]


@pytest.mark.parametrize("path", GAITS, ids=[p.stem for p in GAITS])
def test_start_is_not_an_accepted_solution(path):
    # the README's claim: copies moved by 1e-3 fall (4 of 4 able, 3 of 4 amputee at 6-9.5 s)
    out = verify_solution(path, jittered_copies=4, jitter=1e-3)
    fell = [run["fell"] for run in out["jittered"]]
    assert out["nominal_ok"] and sum(fell) >= 3 and not out["ok"]


def test_the_nominal_verdict_is_kept_apart_from_the_added_runs():
    # the amputee reflex start runs nominally but falls from a 5 % faster start (at ~1.3 s)
    path = STARTS / "amputee-Cat6-3.5.json"
    out = verify_solution(path, initial_speed_change=0.05)
    assert out["nominal_ok"] and not out["fell"]
    assert any(c["fell"] for c in out["initial_speed"]) and not out["ok"]


def test_the_acceptance_judges_a_gait_at_the_speed_it_reaches():
    from bladelab.predict.reflex.acceptance import acceptance_runs

    path = STARTS / "amputee-Cat6-3.5.json"
    out = acceptance_runs(path, 2.0, pushes=False, speed="reached")
    nominal = verify_solution(path, duration=2.0)
    assert out["judged_at_m_per_s"] == round(nominal["mean_speed_m_per_s"], 2)
    assert out["mean_speed_m_per_s"] == nominal["mean_speed_m_per_s"]
    assert out["judged_at_reached_speed"] and out["nominal_ok"]
    # one nominal simulation serves the reached speed and the verdict: its cost is the
    # objective at the file's own prescribed speed, as a plain re-simulation's
    assert out["cost"] == nominal["cost"]
    assert out["simulations"] == 1 + 4 + 2  # the nominal, copies, starts
    prescribed = acceptance_runs(path, 2.0, pushes=False)
    assert prescribed["judged_at_m_per_s"] == 3.5 and not prescribed["judged_at_reached_speed"]
    # the copies are judged at the reached speed: the same runs as a call at that speed
    at = acceptance_runs(path, 2.0, pushes=False, speed=out["judged_at_m_per_s"])
    assert [c["cost"] for c in at["jittered"]] == [c["cost"] for c in out["jittered"]]
    assert [c["ok"] for c in at["jittered"]] == [c["ok"] for c in out["jittered"]]
    with pytest.raises(SpecError, match="reached"):
        verify_solution(path, speed="fastest")


def _stride_times(force, bw=700.0, dt=0.001):
    """Strides (start, end) [s] of :func:`_strides` on a (n, 2) vertical GRF record [N]."""
    import numpy as np

    from bladelab.predict.reflex.verify import _strides
    from bladelab.runner.analyses import step_touchdowns

    t = np.arange(len(force)) * dt
    steps = step_touchdowns(t, force, bw)
    return sorted((round(t[a], 3), round(t[b], 3)) for a, b in _strides(t, steps))


def _running(n=4):
    """Left stances at 0.1, 0.7, 1.3 ... s and right ones at 0.4, 1.0 ... (0.2 s long, 1500 N)."""
    import numpy as np

    t = np.arange(0.0, 0.3 + 0.6 * n, 0.001)
    f = np.zeros((len(t), 2))
    for i in range(n):
        for leg, t0 in ((0, 0.1 + 0.6 * i), (1, 0.4 + 0.6 * i)):
            f[(t >= t0 - 1e-9) & (t < t0 + 0.2 - 1e-9), leg] = 1500.0
    return t, f


def test_strides_run_from_step_to_step_of_each_leg():
    t, f = _running(3)
    # left 0.1 -> 0.7 -> 1.3, right 0.4 -> 1.0 -> 1.6 (the force is seen one sample later)
    assert _stride_times(f) == [(0.101, 0.701), (0.401, 1.001), (0.701, 1.301), (1.001, 1.601)]
    # a 20 ms bounce inside a stance, a 50 N scuff and the swinging right foot striking the
    # ground 30 ms after the left touch-down (a swing contact) start no stride
    f[(t >= 0.15 - 1e-9) & (t < 0.17 - 1e-9), 0] = 0.0
    f[(t >= 0.55 - 1e-9) & (t < 0.6 - 1e-9), 0] = 50.0
    f[(t >= 0.73 - 1e-9) & (t < 0.77 - 1e-9), 1] = 400.0
    assert _stride_times(f) == [(0.101, 0.701), (0.401, 1.001), (0.701, 1.301), (1.001, 1.601)]
    # a 300 N touch of the swinging left foot 0.15 s into the right stance is a step (SCONE's
    # rule: more than 0.1 s after the last): it splits the left stride
    f[(t >= 0.55 - 1e-9) & (t < 0.6 - 1e-9), 0] = 300.0
    assert (0.551, 0.701) in _stride_times(f)


def test_same_leg_steps_count_hops_and_gallops():
    import numpy as np

    from bladelab.predict.reflex.verify import _same_leg_steps
    from bladelab.runner.analyses import step_touchdowns

    t = np.arange(0.0, 3.0, 0.001)

    def forces(pattern):
        f = np.zeros((len(t), 2))
        for i, side in enumerate(pattern):  # a 0.12 s stance every 0.3 s
            f[(t >= 0.1 + 0.3 * i - 1e-9) & (t < 0.22 + 0.3 * i - 1e-9), side] = 1500.0
        return f

    assert _same_leg_steps(step_touchdowns(t, forces([0, 1] * 4), 700.0)) == 0
    # left, right, right, left, right, right, ...: every third step repeats (2 of 8 here)
    assert _same_leg_steps(step_touchdowns(t, forces([0, 1, 1, 0, 1, 1, 0, 1]), 700.0)) == 2
