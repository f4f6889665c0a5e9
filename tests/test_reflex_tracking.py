"""Tracking a collocation stride with the reflex controller (the reflex optimisation's warm start)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from bladelab.cli import main
from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.reflex import read_parameters, runner_and_layout, simulate_controlled
from bladelab.predict.reflex.objective import ObjectiveSettings
from bladelab.predict.reflex.tracking import (
    NO_STRIDE,
    PHASES,
    TOUCHDOWN_BW,
    GaitReference,
    tracked_dofs,
    tracking_error,
)

ROOT = Path(__file__).resolve().parents[1]
CAT6_4 = ROOT / "benchmarks/collocation/study-2026-11-25/amputee/amputee-Cat6/speed-4.json"
ABLE_4 = ROOT / "benchmarks/collocation/study-2026-11-25/able/able/speed-4.json"
BEST_ITERATE = (ROOT / "benchmarks/collocation/study-2026-11-25-cat6-starts/amputee-Cat6/"
                "speed-5.template.best_iterate.json")
SHIPPED = ROOT / "src/bladelab/data/runner/reflex-starts/amputee-Cat6-3.5.json"


@pytest.fixture(scope="module")
def reference():
    return GaitReference.read(CAT6_4)


def test_reference_starts_at_leg0_touchdown(reference):
    sol = CollocationSolution.read(CAT6_4)
    assert reference.dof_names == tracked_dofs(sol.dof_names)
    assert "pelvis_tx" not in reference.dof_names and "socket_angle_r" not in reference.dof_names
    assert reference.angles.shape == (PHASES, len(reference.dof_names))
    assert reference.period_s == pytest.approx(sol.period_s)
    # leg 0's vertical force, resampled at the reference's phases: the first phase point is
    # just after the touch-down (loaded), and the stride's last stretch before it is unloaded
    t, fz = np.asarray(sol.nlp.time), sol.leg_vertical_force()[:, 0]
    threshold = TOUCHDOWN_BW * sol.body_weight_N
    start = next(t[i] + (threshold - fz[i]) / (fz[i + 1] - fz[i]) * (t[i + 1] - t[i])
                 for i in range(len(t) - 1) if fz[i] <= threshold < fz[i + 1])
    phases = (np.arange(PHASES) + 0.5) / PHASES
    f_at = np.interp((start + phases * sol.period_s) % sol.period_s, t, fz)
    assert f_at[0] > threshold and f_at[-1] <= threshold
    # the angles are the solution's, shifted to that start
    j = sol.dof_names.index("knee_angle_l")
    k = reference.dof_names.index("knee_angle_l")
    q_at = np.interp((start + phases * sol.period_s) % sol.period_s, t, sol.nlp.q[:, j])
    np.testing.assert_allclose(reference.angles[:, k], q_at, atol=1e-12)


def _replay(reference, periods, shift=0.0, samples_per_stride=200):
    """Samples and touch-downs of a simulation that runs the reference's angles (+ ``shift``
    [rad]) with the given stride times [s], leg 0 landing at t = 0 and after each stride."""
    starts = np.concatenate([[0.0], np.cumsum(periods)])
    times, rows = [], []
    for t0, period in zip(starts[:-1], periods, strict=True):
        phase = np.arange(samples_per_stride) / samples_per_stride
        # the reference's angles are at mid-phase points: wrap-interpolate between them
        mid = (np.arange(PHASES) + 0.5) / PHASES
        q = np.column_stack([np.interp(phase, mid, reference.angles[:, j], period=1.0)
                             for j in range(len(reference.dof_names))])
        times.append(t0 + phase * period)
        rows.append(q + shift)
    time = np.concatenate(times)
    qpos = np.vstack(rows)
    touchdowns = np.array([[t, 0.0, leg, 0.0] for t in starts for leg in (0, 1)])
    touchdowns[1::2, 0] += 0.5 * np.append(periods, periods[-1])  # leg 1 half a stride later
    return time, qpos, touchdowns[touchdowns[:, 0] <= time[-1]]


def test_tracking_error_by_hand(reference):
    n_dof = len(reference.dof_names)
    index = np.arange(n_dof)
    period = reference.period_s
    n = 8
    duration = n * period
    expected = math.floor((duration - 0.0) / period) - 1  # the strides the reference runs
    # itself: zero up to the interpolation of its own mid-phase points
    time, qpos, td = _replay(reference, [period] * n)
    j, strides = tracking_error(time, qpos, td, reference, index, 0.0, duration)
    assert strides == n - 1 == expected  # the last stride's end is past the samples
    assert j < 1e-4
    # every angle 0.1 rad off: (0.1)² more, exactly (the interpolation error is the same)
    j_shift, _ = tracking_error(*_replay(reference, [period] * n, shift=0.1), reference, index,
                                0.0, duration)
    assert j_shift - j == pytest.approx(0.01, rel=0.02)
    # strides 10 % longer: + ln(1.1)² each
    slow = 1.1 * period
    j_slow, s_slow = tracking_error(*_replay(reference, [slow] * n), reference, index, 0.0,
                                    n * slow)
    assert s_slow == n - 1
    assert j_slow == pytest.approx(j + math.log(1.1) ** 2, abs=2e-4)
    # the run ends after 3 strides of the 7 expected: the 4 missing ones count NO_STRIDE each
    time, qpos, td = _replay(reference, [period] * 4)
    j_fell, s_fell = tracking_error(time, qpos, td, reference, index, 0.0, duration)
    assert s_fell == 3
    assert j_fell == pytest.approx((3 * j + 4 * NO_STRIDE) / expected, abs=1e-4)
    # strides that start before `skip` are not tracked
    _, s_skip = tracking_error(*_replay(reference, [period] * n), reference, index,
                               2.5 * period, duration)
    assert s_skip == n - 4
    # no stride at all
    assert tracking_error(time, qpos, np.zeros((0, 4)), reference, index, 0.0, duration) == (
        NO_STRIDE, 0)


def test_reference_refuses_a_best_iterate_and_another_runner(reference):
    with pytest.raises(InputFileError, match="did not converge"):
        GaitReference.read(BEST_ITERATE)
    with pytest.raises(InputFileError, match="same runner"):
        reference.check_model("amputee", "Cat4", "--track")
    with pytest.raises(InputFileError, match="same runner"):
        reference.check_model("able", None, "--track")
    reference.check_model("amputee", "Cat6", "--track")


def test_settings_refuse_a_weight_without_a_stride():
    with pytest.raises(SpecError, match="needs a stride"):
        ObjectiveSettings(w_track=10.0)
    with pytest.raises(SpecError, match=">= 0"):
        ObjectiveSettings(track=str(CAT6_4), w_track=-1.0)
    assert ObjectiveSettings.from_dict(ObjectiveSettings(track="x.json", w_track=5.0).to_dict()
                                       ).w_track == 5.0


def test_tracking_term_adds_to_the_cost_and_leaves_the_gait_alone():
    model, layout = runner_and_layout("amputee", "Cat6")
    x = read_parameters(SHIPPED, layout)
    base = ObjectiveSettings(speed=3.5, duration=2.5, dt=1e-3, integrator="implicit",
                             track_skip=0.5)
    plain, _ = simulate_controlled(model, x, layout=layout, settings=base)
    measured, _ = simulate_controlled(model, x, layout=layout,
                                      settings=replace(base, track=str(CAT6_4)))
    weighted, _ = simulate_controlled(model, x, layout=layout,
                                      settings=replace(base, track=str(CAT6_4), w_track=1e3))
    assert plain.j_track == 0.0 and plain.track_strides == 0
    assert measured.distance == plain.distance and measured.cost == plain.cost
    assert 0.0 < measured.j_track <= NO_STRIDE
    assert weighted.cost == pytest.approx(plain.cost + 1e3 * measured.j_track)


def test_cli_track_errors(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["predict", "--method", "reflex",
                 "--model", "amputee", "--blade", "Cat4", "--track", str(CAT6_4),
                 "--out", str(out), "--generations", "1"])
    err = capsys.readouterr().err
    assert code == 2 and "--track" in err and "same runner" in err and not out.exists()
    code = main(["predict", "--method", "reflex",
                 "--model", "able", "--track", str(ABLE_4), "--track-weight", "0",
                 "--out", str(out)])
    assert code == 2 and "--track-weight" in capsys.readouterr().err
    code = main(["predict", "--method", "collocation", "--track", str(CAT6_4),
                 "--out", str(out)])
    assert code == 2 and "only with --method reflex" in capsys.readouterr().err
    code = main(["predict", "--method", "reflex",
                 "--model", "able", "--integrator", "rk4", "--out", str(out)])
    assert code == 2 and "--integrator" in capsys.readouterr().err


def test_a_tracked_run_and_its_report(tmp_path, capsys):
    import json

    import pandas as pd

    run = tmp_path / "run"
    assert main(["predict", "--method", "reflex",
                 "--model", "amputee", "--blade", "Cat6", "--speed", "4",
                 "--init", str(SHIPPED), "--track", str(CAT6_4), "--integrator", "implicit",
                 "--dt", "1e-3", "--duration", "2", "--generations", "2", "--popsize", "4",
                 "--sigma", "0.05", "--out", str(run)]) == 0
    best = json.loads((run / "best.json").read_text())
    assert best["settings"]["track"] == str(CAT6_4) and best["settings"]["w_track"] == 1000.0
    assert best["settings"]["integrator"] == "implicit"
    j = best["evaluation"]["j_track"]
    assert 0.0 < j <= NO_STRIDE
    capsys.readouterr()
    assert main(["report", str(run), "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)["solutions"]
    assert shown[-1] == f"tracked collocation stride ({CAT6_4.name})" and len(shown) == 2
    tables = {p.stem: pd.read_csv(p) for p in (run / "report" / "tables").glob("*.csv")}
    summary = tables[next(k for k in tables if "run-summary" in k)].iloc[0]
    assert summary["J_track (rad²)"] == pytest.approx(j, rel=1e-9)
    assert bool(summary["stored cost reproduced (yes/no)"])


def test_simulation_refuses_a_stride_of_another_runner():
    model, layout = runner_and_layout("able", None)
    settings = ObjectiveSettings(duration=0.5, track=str(CAT6_4), w_track=1.0)
    with pytest.raises(InputFileError, match="same runner"):
        simulate_controlled(model, layout.vector({}), layout=layout, settings=settings)


def test_a_missing_stride_names_the_setting(tmp_path):
    model, layout = runner_and_layout("amputee", "Cat6")
    settings = ObjectiveSettings(duration=0.5, track=str(tmp_path / "gone.json"), w_track=1.0)
    with pytest.raises(InputFileError, match="settings.track"):
        simulate_controlled(model, layout.vector({}), layout=layout, settings=settings)


def test_a_simulation_starts_from_a_strides_touchdown_state(tmp_path):
    """``start_stride``: the simulation's first state is the stride's at leg 0's touch-down
    (leg 0's vertical force crosses 0.1 BW there, interpolated by hand between the two nodes
    around it), the pelvis at x = 0 and its forward speed shifted by the asked speed minus the
    stride's mean; a stride of a runner with other coordinates, a missing file and a best
    iterate are refused by name, and the CLI checks the file before any run."""
    from bladelab.predict.reflex.objective import stride_initial_state

    sol = CollocationSolution.read(CAT6_4)
    t, q, qd = (np.asarray(a) for a in (sol.nlp.time, sol.nlp.q, sol.nlp.qd))
    f0 = sol.leg_vertical_force()[:, 0] / sol.body_weight_N
    k = next(i for i in range(len(t) - 1) if f0[i] <= 0.1 < f0[i + 1])
    w = (0.1 - f0[k]) / (f0[k + 1] - f0[k])
    model, layout = runner_and_layout("amputee", "Cat6")
    settings = ObjectiveSettings(duration=0.05, start_stride=str(CAT6_4), speed=4.2)
    _, res = simulate_controlled(model, layout.x0, layout=layout, settings=settings,
                                 record_every=1)
    for j, name in enumerate(sol.dof_names):
        want_q = q[k, j] + w * (q[k + 1, j] - q[k, j])
        want_v = qd[k, j] + w * (qd[k + 1, j] - qd[k, j])
        if name == "pelvis_tx":
            want_q, want_v = 0.0, want_v + 4.2 - sol.mean_speed_mps
        assert res.qpos[0, model.dof(name)] == pytest.approx(want_q, abs=1e-9), name
        assert res.qvel[0, model.dof(name)] == pytest.approx(want_v, rel=1e-9, abs=1e-9), name
    human, _ = runner_and_layout("able", None, "human")
    with pytest.raises(InputFileError, match="lacks mtp_angle_l, mtp_angle_r") as err:
        stride_initial_state(human, str(ABLE_4), 3.5)
    assert err.value.where == "settings.start_stride"
    with pytest.raises(InputFileError, match="not there"):
        stride_initial_state(model, str(tmp_path / "gone.json"), 4.0, where="start_stride")
    with pytest.raises(InputFileError, match="did not converge"):
        stride_initial_state(model, str(BEST_ITERATE), 4.0)
    assert main(["predict", "--method", "reflex", "--model", "able", "--body", "human",
                 "--start-stride", str(ABLE_4), "--out", str(tmp_path / "run")]) == 2
    assert not (tmp_path / "run").exists()
