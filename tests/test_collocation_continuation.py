"""Speed continuation and maximum speed.

The success paths replace the solve (``continuation.predict_stride``) by
``collocation_fake.FakeSolve``, which returns the fake solution of ``collocation_fake`` at the
guess's speed, marked so that the next solve's warm start can be traced to it; failure and
resume run IPOPT for real on a tiny mesh with a few iterations."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation import continuation as cont
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stride_guess import COLLOCATION_SOURCE

N = 12  # mesh intervals: the fake solutions' (conftest.FAKE_MESH)
ABLE = {"model": "able", "blade": None}


def _settings(**kw):
    return CollocationSettings(mesh_intervals=N, speed_m_per_s=3.5, **kw)


def _first(runner):
    from bladelab.predict.collocation.guess import template_guess

    return template_guess(runner, speed=3.0, n=N)


# -- speed continuation -------------------------------------------------------------------
def test_each_speed_is_warm_started_from_the_previous_solution(fakes, fake_solve, tmp_path):
    runner = fakes["able"][0]
    events = []
    res = cont.speed_continuation(runner, [3, 3.5, 4], _settings(), _first, model_spec=ABLE,
                                  out_dir=tmp_path, progress=events.append)
    assert res.complete and res.failed is None and res.last_converged_speed == 4.0
    calls = fake_solve.calls
    assert [c["speed"] for c in calls] == [3.0, 3.5, 4.0]
    assert calls[0]["guess"].source.startswith("template at 3 m/s")
    for prev, call in zip(calls, calls[1:], strict=False):
        g, before = call["guess"], prev["solution"].nlp
        assert g.source.startswith(COLLOCATION_SOURCE)  # no tracking stage
        # the previous solution itself, at its own speed: predict_stride starts from its
        # multipliers at its point or scales it to the new speed
        assert math.isclose(g.speed, prev["speed"], rel_tol=1e-12)
        np.testing.assert_array_equal(g.q, before.q)
        assert g.period == before.period
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "speed-3.5.json", "speed-3.json", "speed-4.json"]
    assert json.loads((tmp_path / "speed-4.json").read_text())["kind"] == "collocation-solution"
    assert [e.event for e in events if e.problem == "3.5 m/s"] == ["start", "converged"]
    table = res.table()
    assert list(table["prescribed_speed_mps"]) == [3.0, 3.5, 4.0]
    assert list(table["mean_speed_mps"]) == pytest.approx([3.0, 3.5, 4.0])
    for col in ("cost_of_transport_J_per_kg_m", "stride_time_s", "contact_time_left_s",
                "contact_time_right_s", "peak_vertical_grf_left_bw",
                "peak_vertical_grf_right_bw", "iterations", "wall_s"):
        assert col in table.columns and table[col].notna().all()


def test_a_rerun_reads_solved_speeds_back_and_chains_new_ones_from_them(fakes, fake_solve,
                                                                        tmp_path):
    runner = fakes["able"][0]
    first = cont.speed_continuation(runner, [3, 3.5], _settings(), _first, model_spec=ABLE,
                                    out_dir=tmp_path)
    fake_solve.calls.clear()
    # runner None: nothing is built for speeds read back (runner_from_spec is the fake's)
    again = cont.speed_continuation(None, [3, 3.5, 4], _settings(), _first, model_spec=ABLE,
                                    out_dir=tmp_path)
    assert [c["speed"] for c in fake_solve.calls] == [4.0]
    assert [r.solved for r in again.records] == [False, False, True]
    np.testing.assert_array_equal(fake_solve.calls[0]["guess"].q[:, 1:],
                                  first.records[-1].solution.nlp.q[:, 1:])
    assert again.rows()[:2] == first.rows()
    # solver options are not part of the problem: still read back
    fake_solve.calls.clear()
    cont.speed_continuation(runner, [3, 3.5, 4], _settings(max_iter=7, tol=1e-6), _first,
                            model_spec=ABLE, out_dir=tmp_path)
    assert fake_solve.calls == []


def test_a_failed_speed_stops_the_continuation_and_a_rerun_resumes_from_its_iterate(
        fakes, fake_solve, tmp_path):
    runner = fakes["able"][0]
    fake_solve.fail = {("able", 4.0)}
    res = cont.speed_continuation(runner, [3.5, 4, 4.5], _settings(), _first, model_spec=ABLE,
                                  out_dir=tmp_path, refinements=0)
    assert not res.complete and res.failed.speed_mps == 4.0
    assert res.last_converged_speed == 3.5 and res.fastest.speed_mps == 3.5
    assert [c["speed"] for c in fake_solve.calls] == [3.5, 4.0]  # 4.5 m/s never tried
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "speed-3.5.json", "speed-4.best_iterate.json"]
    row = res.rows()[-1]
    assert row["converged"] is False and row["status"] == "Maximum_Iterations_Exceeded"
    # the rerun starts 4 m/s from its best iterate; converged, the best iterate goes
    failed = fake_solve.calls[-1]["solution"]
    fake_solve.fail, fake_solve.calls = set(), []
    res = cont.speed_continuation(runner, [3.5, 4, 4.5], _settings(), _first, model_spec=ABLE,
                                  out_dir=tmp_path)
    assert res.complete and [c["speed"] for c in fake_solve.calls] == [4.0, 4.5]
    np.testing.assert_array_equal(fake_solve.calls[0]["guess"].q, failed.nlp.q)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "speed-3.5.json", "speed-4.5.json", "speed-4.json"]


def test_a_step_that_fails_is_halved_and_the_speed_tried_again(fakes, fake_solve, tmp_path):
    runner = fakes["able"][0]
    fake_solve.max_step = 0.3  # m/s: a larger step fails
    events = []
    res = cont.speed_continuation(runner, [3.5, 4.5], _settings(), _first, model_spec=ABLE,
                                  out_dir=tmp_path, progress=events.append)
    # quarter steps at most: 4.5 fails, 4.0 fails, 3.75, 4.0, 4.5 fails, 4.25, 4.5
    assert [c["speed"] for c in fake_solve.calls] == [3.5, 4.5, 4.0, 3.75, 4.0, 4.5, 4.25, 4.5]
    assert res.complete
    solved = [r.speed_mps for r in res.records]
    assert solved[0] == 3.5 and solved[-1] == 4.5
    assert all(r.converged for r in res.records)
    steps = np.diff(solved)
    assert np.all(steps > 0) and np.all(steps <= 0.3 + 1e-9)
    assert sum(e.event == "refine" for e in events) >= 2
    assert not any(p.name.endswith("best_iterate.json") for p in tmp_path.iterdir())
    # the retried speed starts from the intermediate solution, not its stale best iterate
    retry = [c for c in fake_solve.calls if c["speed"] == 4.5][-1]
    assert "at 4.25 m/s" in retry["guess"].source


def test_refinements_are_limited_per_prescribed_speed(fakes, fake_solve, tmp_path):
    runner = fakes["able"][0]
    fake_solve.max_step = 0.2
    res = cont.speed_continuation(runner, [3.5, 4.5], _settings(), _first, model_spec=ABLE,
                                  out_dir=tmp_path, refinements=2)
    # 4.5 fails, 4.0 fails, 3.75 fails (an eighth step is not allowed): stop at 3.75
    assert [c["speed"] for c in fake_solve.calls] == [3.5, 4.5, 4.0, 3.75]
    assert not res.complete and res.failed.speed_mps == 3.75
    assert res.last_converged_speed == 3.5


def test_a_file_of_another_problem_is_refused_unless_forced(fakes, fake_solve, tmp_path):
    runner = fakes["able"][0]
    cont.speed_continuation(runner, [3.5], _settings(), _first, model_spec=ABLE,
                            out_dir=tmp_path)
    other = _settings(weights={"metabolic": 2.0, "activation": 1.0, "acceleration": 0.1})
    with pytest.raises(InputFileError, match="another problem .*'metabolic': 2.0") as err:
        cont.speed_continuation(runner, [3.5], other, _first, model_spec=ABLE,
                                out_dir=tmp_path)
    assert "--force" in err.value.hint
    fake_solve.calls.clear()
    res = cont.speed_continuation(runner, [3.5], other, _first, model_spec=ABLE,
                                  out_dir=tmp_path, force=True)
    assert len(fake_solve.calls) == 1 and res.records[0].solved
    assert CollocationSolution.read(tmp_path / "speed-3.5.json").settings.same_problem(other)


def test_max_speed_starts_from_the_fastest_solution_and_is_read_back(fakes, fake_solve,
                                                                     tmp_path):
    runner = fakes["able"][0]
    res = cont.speed_continuation(runner, [4, 3.5], _settings(), _first, model_spec=ABLE,
                                  out_dir=tmp_path)
    fastest = res.fastest
    assert fastest.speed_mps == 4.0
    ms = cont.max_speed_settings(_settings(max_iter=9))
    assert ms.max_speed and ms.weights.speed == 1.0 and ms.max_iter == 9
    rec = cont.max_speed(runner, ms, fastest.solution, model_spec=ABLE, out_dir=tmp_path)
    call = fake_solve.calls[-1]
    assert call["speed"] is None and call["guess"].source.startswith(COLLOCATION_SOURCE)
    np.testing.assert_array_equal(call["guess"].q, fastest.solution.nlp.q)
    assert rec.path.name == "max-speed.json" and rec.converged
    row = rec.row(tmp_path)
    assert row["problem"] == "max-speed" and row["prescribed_speed_mps"] is None
    assert row["mean_speed_mps"] == pytest.approx(4.8) and row["file"] == "max-speed.json"
    n = len(fake_solve.calls)
    assert not cont.max_speed(runner, ms, fastest.solution, model_spec=ABLE,
                              out_dir=tmp_path).solved
    assert len(fake_solve.calls) == n
    with pytest.raises(SpecError, match="speed_m_per_s None"):
        cont.max_speed(runner, _settings(), fastest.solution, model_spec=ABLE, out_dir=tmp_path)


@pytest.mark.parametrize(("speeds", "settings", "match"), [
    ([], _settings(), "no speed"),
    ([3.5, -1], _settings(), "> 0 m/s"),
    ([3.5, 3.50], _settings(), "given twice"),
    ([3.5], CollocationSettings(mesh_intervals=N, speed_m_per_s=None), "prescribed-speed"),
])
def test_bad_speeds_and_settings_are_refused(speeds, settings, match, tmp_path):
    with pytest.raises(SpecError, match=match):
        cont.speed_continuation(None, speeds, settings, _first, model_spec=ABLE,
                                out_dir=tmp_path)


def test_a_real_solve_that_fails_is_kept_as_best_iterate(fakes, tmp_path):
    """IPOPT for real (6 intervals, 3 iterations): the first speed fails in the tracking stage,
    nothing further is tried; the rerun goes straight to the predictive stage."""
    runner = fakes["able"][0]
    settings = CollocationSettings(mesh_intervals=6, speed_m_per_s=3.5, max_iter=3)

    def first(r):
        from bladelab.predict.collocation.guess import template_guess

        return template_guess(r, speed=3.5, n=6)

    stages = []
    res = cont.speed_continuation(runner, [3.5, 4], settings, first, model_spec=ABLE,
                                  out_dir=tmp_path,
                                  progress=lambda p: p.solve and stages.append(p.solve.stage))
    assert res.failed.speed_mps == 3.5 and res.last_converged_speed is None
    assert res.failed.solution.stage == "tracking" and set(stages) == {"tracking"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["speed-3.5.best_iterate.json"]
    stages.clear()
    res = cont.speed_continuation(runner, [3.5, 4], settings, first, model_spec=ABLE,
                                  out_dir=tmp_path,
                                  progress=lambda p: p.solve and stages.append(p.solve.stage))
    assert res.failed.solution.stage == "predictive" and set(stages) == {"predictive"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["speed-3.5.best_iterate.json"]


# -- several starts per problem (bladelab.predict.collocation.starts) ----------------------
def _objectives(monkeypatch, fake_solve, objective):
    from collocation_fake import objectives_by_start

    objectives_by_start(fake_solve, monkeypatch, objective)


def _solution_first(fakes):
    # a collocation solution at 3.5 m/s
    return lambda runner: fakes["able"][1].to_guess(f"{COLLOCATION_SOURCE}: the first guess")


def test_each_speed_is_solved_from_several_starts_and_continued_from_the_best(
        fakes, fake_solve, monkeypatch, tmp_path):
    objs = {"warm": 2.0, "template": 3.0, "previous-but-one": 1.8}
    _objectives(monkeypatch, fake_solve,
                lambda start, v: 1.5 if (start, v) == ("warm-mu-1e-4", 4.0)
                else objs.get(start, 2.5))
    events = []
    res = cont.speed_continuation(fakes["able"][0], [3.5, 4, 4.5], _settings(),
                                  _solution_first(fakes), model_spec=ABLE, out_dir=tmp_path,
                                  starts=4, progress=events.append)
    calls = fake_solve.calls
    # fixed order; the previous-but-one only from the third speed on
    assert [(c["speed"], c["start"]) for c in calls] == [
        (3.5, "warm"), (3.5, "warm-mu-1e-4"), (3.5, "template"),
        (4.0, "warm"), (4.0, "warm-mu-1e-4"), (4.0, "template"),
        (4.5, "warm"), (4.5, "warm-mu-1e-4"), (4.5, "template"), (4.5, "previous-but-one")]
    assert calls[3]["guess"].source.startswith(COLLOCATION_SOURCE + " at 3.5 m/s")
    assert calls[5]["guess"].source.startswith("template at 4 m/s")
    # kept: 3.5 warm (2.0), 4 the barrier start (1.5), 4.5 the previous-but-one (1.8)
    assert [r.row()["start"] for r in res.records] == [
        "warm", "warm-mu-1e-4", "previous-but-one"]
    kept4 = calls[4]["solution"]
    assert res.records[1].solution.nlp.objective == 1.5
    # the continuation goes on from the kept solution: 4.5's warm start is the 4 m/s barrier
    # start's solution, its previous-but-one the 3.5 m/s warm start's
    np.testing.assert_array_equal(calls[6]["guess"].q[:, 1:], kept4.nlp.q[:, 1:])
    np.testing.assert_array_equal(calls[9]["guess"].q[:, 1:], calls[0]["solution"].nlp.q[:, 1:])
    np.testing.assert_array_equal(calls[4]["guess"].q, calls[3]["guess"].q)  # same warm start
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted(
        [f"speed-{v}.json" for v in ("3.5", "4", "4.5")]
        + [f"speed-{v}.{s}.json" for v in ("3.5", "4", "4.5")
           for s in ("warm-mu-1e-4", "template")] + ["speed-4.5.previous-but-one.json"])
    rows = res.rows(tmp_path)
    assert rows[1]["file"] == "speed-4.warm-mu-1e-4.json"
    assert rows[1]["objective"] == 1.5 and rows[1]["objective_warm"] == 2.0
    assert rows[1]["starts"] == 3 and rows[1]["spread_pct"] == pytest.approx(100.0)
    assert rows[2]["objective_previous-but-one"] == 1.8 and rows[2]["starts"] == 4
    assert "objective_previous-but-one" not in rows[0]
    table = res.table()
    cols = list(table.columns)
    assert cols[cols.index("warnings"):cols.index("warnings") + 9] == [
        "warnings", "start", "starts", "objective", "objective_warm", "objective_warm-mu-1e-4",
        "objective_template", "objective_previous-but-one", "spread_pct"]
    kept = [e for e in events if e.event == "kept"]
    assert len(kept) == 3 and kept[1].path.name == "speed-4.warm-mu-1e-4.json"
    assert "spread 100.0 %" in kept[1].message
    starts = [e.message for e in events if e.event == "start" and e.problem == "4 m/s"]
    assert starts[1].startswith("start warm-mu-1e-4: warm start from the 3.5 m/s solution")


def test_a_start_with_gait_warnings_loses_to_a_clean_one(fakes, fake_solve, monkeypatch,
                                                         tmp_path):
    _objectives(monkeypatch, fake_solve, lambda start, v: 1.0 if start == "warm-mu-1e-4" else 2)
    monkeypatch.setattr(CollocationSolution, "gait_warnings",
                        lambda self: ["a one-legged hop"] if self.nlp.objective == 1.0 else [])
    res = cont.speed_continuation(fakes["able"][0], [3.5, 4], _settings(),
                                  _solution_first(fakes), model_spec=ABLE, out_dir=tmp_path,
                                  starts=2)
    assert [r.row()["start"] for r in res.records] == ["warm", "warm"]
    assert [r.row()["warnings"] for r in res.records] == ["", ""]
    # 4 m/s went on from the clean 3.5 m/s solution, not the hop
    np.testing.assert_array_equal(fake_solve.calls[2]["guess"].q[:, 1:],
                                  fake_solve.calls[0]["solution"].nlp.q[:, 1:])
    # every converged start a hop: the lowest kept, its warnings in the row
    monkeypatch.setattr(CollocationSolution, "gait_warnings", lambda self: ["a hop"])
    res = cont.speed_continuation(fakes["able"][0], [3.5], _settings(),
                                  _solution_first(fakes), model_spec=ABLE, out_dir=tmp_path,
                                  starts=2)
    row = res.records[0].row()
    assert row["start"] == "warm-mu-1e-4" and row["warnings"] == "a hop"


def test_a_rerun_does_not_solve_starts_again(fakes, fake_solve, monkeypatch, tmp_path):
    _objectives(monkeypatch, fake_solve,
                lambda start, v: None if (start, v) == ("template", 4.0) else 2.0)
    runner = fakes["able"][0]
    args = ([3.5, 4], _settings(), _solution_first(fakes))
    first = cont.speed_continuation(runner, *args, model_spec=ABLE, out_dir=tmp_path, starts=3)
    assert len(fake_solve.calls) == 6 and first.complete
    assert (tmp_path / "speed-4.template.best_iterate.json").is_file()
    before = first.rows()
    fake_solve.calls.clear()
    # a failed start of a problem that converged otherwise is read back, not solved again
    again = cont.speed_continuation(None, *args, model_spec=ABLE, out_dir=tmp_path, starts=3)
    assert fake_solve.calls == [] and again.rows() == before
    assert not any(r.solved for r in again.records)
    # a start whose file is gone is solved again, alone
    (tmp_path / "speed-4.warm-mu-1e-4.json").unlink()
    cont.speed_continuation(runner, *args, model_spec=ABLE, out_dir=tmp_path, starts=3)
    assert [(c["speed"], c["start"]) for c in fake_solve.calls] == [(4.0, "warm-mu-1e-4")]
    # one start reads the warm start's files (a one-start sweep's names) back
    fake_solve.calls.clear()
    one = cont.speed_continuation(runner, *args, model_spec=ABLE, out_dir=tmp_path)
    assert fake_solve.calls == [] and [r.path.name for r in one.records] == [
        "speed-3.5.json", "speed-4.json"]
    assert "start" not in one.rows()[0]


def test_when_no_start_converges_the_speed_fails_and_each_start_resumes_from_its_iterate(
        fakes, fake_solve, monkeypatch, tmp_path):
    fail = {4.0}
    _objectives(monkeypatch, fake_solve, lambda start, v: None if v in fail else 2.0)
    runner = fakes["able"][0]
    args = ([3.5, 4], _settings(), _solution_first(fakes))
    res = cont.speed_continuation(runner, *args, model_spec=ABLE, out_dir=tmp_path, starts=2,
                                  refinements=0)
    assert res.failed.speed_mps == 4.0 and res.failed.path.name == "speed-4.best_iterate.json"
    row = res.rows()[-1]
    assert row["converged"] is False and row["start"] == "warm" and row["starts"] == 0
    assert math.isnan(row["objective"]) and math.isnan(row["spread_pct"])
    assert {p.name for p in tmp_path.iterdir()} >= {"speed-4.best_iterate.json",
                                                    "speed-4.warm-mu-1e-4.best_iterate.json"}
    fail.clear()
    fake_solve.calls.clear()
    res = cont.speed_continuation(runner, *args, model_spec=ABLE, out_dir=tmp_path, starts=2)
    assert res.complete
    assert [(c["speed"], c["start"]) for c in fake_solve.calls] == [(4.0, "iterate")] * 2
    assert fake_solve.calls[1]["solution"].settings.warm_start_mu == 1e-4
    assert not any(p.name.endswith("best_iterate.json") for p in tmp_path.iterdir())


def test_max_speed_from_several_starts(fakes, fake_solve, monkeypatch, tmp_path):
    _objectives(monkeypatch, fake_solve,
                lambda start, v: 0.5 if (start, v) == ("template", None) else 2.0)
    runner = fakes["able"][0]
    res = cont.speed_continuation(runner, [3.5, 4], _settings(), _first, model_spec=ABLE,
                                  out_dir=tmp_path, starts=4)
    # the first speed's warm start is the template itself: no barrier start (tracking
    # stage), no second template, so one solve
    assert [c["guess"].source for c in fake_solve.calls if c["speed"] == 3.5] == [
        "template at 3 m/s"]
    fake_solve.calls.clear()
    rec = cont.max_speed(runner, cont.max_speed_settings(_settings()), res.fastest.solution,
                         model_spec=ABLE, out_dir=tmp_path, starts=4,
                         previous=res.records[0].solution)
    calls = fake_solve.calls
    assert [c["start"] for c in calls] == ["warm", "warm-mu-1e-4", "template",
                                           "previous-but-one"]
    assert calls[2]["guess"].speed == pytest.approx(4.0)  # the template at the warm start's
    np.testing.assert_array_equal(calls[3]["guess"].q, res.records[0].solution.nlp.q)
    assert rec.path.name == "max-speed.template.json" and rec.row()["start"] == "template"
    assert {p.name for p in rec.files} == {
        "max-speed.template.json", "max-speed.json", "max-speed.warm-mu-1e-4.json",
        "max-speed.previous-but-one.json"}
    with pytest.raises(SpecError, match="1 to 5 starts"):
        cont.max_speed(runner, cont.max_speed_settings(_settings()), res.fastest.solution,
                       model_spec=ABLE, out_dir=tmp_path, starts=6)
