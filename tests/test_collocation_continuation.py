"""Speed continuation, maximum speed and ``bladelab sweep --method collocation`` (issue 15).

The success paths replace the solve (``continuation.predict_stride``) by :class:`FakeSolve`,
which returns the fake solution of ``collocation_fake`` at the guess's speed, marked so that
the next solve's warm start can be traced to it; failure and resume run IPOPT for real on a
tiny mesh with a few iterations."""

from __future__ import annotations

import csv
import dataclasses
import json
import math

import numpy as np
import pytest

from bladelab.cli import main
from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation import continuation as cont
from bladelab.predict.collocation.solution import CollocationSolution, check_model_spec
from bladelab.predict.collocation.solve import COLLOCATION_SOURCE, CollocationSettings
from collocation_fake import fake_solution

N = 12
ABLE = {"model": "able", "blade": None}
CAT6 = {"model": "amputee", "blade": "Cat6"}
MARK = 3  # the coordinate column each fake solve shifts (not pelvis_tx, column 0)


@pytest.fixture(scope="module")
def fakes():
    """Per model kind: (runner, a converged-looking solution on N intervals at 3.5 m/s)."""
    out = {}
    for kind in ("able", "amputee"):
        runner, _, sol = fake_solution(kind, N)
        out[kind] = (runner, sol)
    return out


class FakeSolve:
    """Stands in for ``predict_stride``: the fake solution with the guess's coordinates at the
    prescribed speed (the maximum speed: 1.2 × the guess's), coordinate ``MARK`` shifted by
    1 mrad so that a solve's output differs from its input; fails for (model label, speed)
    in ``fail`` (None: the maximum speed)."""

    def __init__(self, fakes, fail=()):
        self.fakes, self.fail, self.calls = fakes, set(fail), []

    def __call__(self, runner, settings, guess, *, model_spec, progress=None):
        spec = check_model_spec(model_spec)
        base = self.fakes[spec["model"]][1]
        v = settings.speed_m_per_s
        g = guess.resample(settings.mesh_intervals)
        g = g.with_speed(v if v is not None else 1.2 * g.speed)
        q = g.q.copy()
        q[:, MARK] += 1e-3
        label = cont.model_label(spec)
        ok = (label, v) not in self.fail
        nlp = dataclasses.replace(
            base.nlp, q=q, qd=g.qd, period=g.period, success=ok,
            status="Solve_Succeeded" if ok else "Maximum_Iterations_Exceeded")
        sol = dataclasses.replace(base, nlp=nlp, settings=settings, model_spec=spec,
                                  guess_source=guess.source, stage="predictive")
        self.calls.append({"label": label, "speed": v, "guess": guess, "solution": sol})
        return sol


@pytest.fixture
def fake_solve(fakes, monkeypatch):
    """Install a FakeSolve (returned; set ``.fail`` to make solves fail); runners come from
    ``fakes`` instead of being built."""
    from bladelab.predict.collocation import solution

    fake = FakeSolve(fakes)
    monkeypatch.setattr(cont, "predict_stride", fake)
    monkeypatch.setattr(solution, "runner_from_spec",
                        lambda spec: fakes[check_model_spec(spec)["model"]][0])
    return fake


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
        assert math.isclose(g.speed, call["speed"], rel_tol=1e-12)
        np.testing.assert_array_equal(g.q[:, 1:], before.q[:, 1:])  # the previous solution
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
                                  out_dir=tmp_path)
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


# -- bladelab sweep --method collocation ----------------------------------------------------
def _sweep(out, *extra):
    return main(["sweep", "--method", "collocation", "--out", str(out), "--mesh", str(N),
                 "--max-iter", "1", *extra])


def _csv(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_sweep_solves_each_model_and_writes_the_table(fake_solve, tmp_path, capsys):
    out = tmp_path / "sweep"
    args = ("--able", "--categories", "Cat6,cat7", "--speeds", "3.5,4")
    assert _sweep(out, *args, "--json") == 0
    cap = capsys.readouterr()
    result = json.loads(cap.out)
    assert result["failures"] == {}
    assert "amputee Cat7, 4 m/s: converged" in cap.err
    assert sorted(p.name for p in out.iterdir()) == [
        "able", "amputee-Cat6", "amputee-Cat7", "collocation-sweep.csv"]
    assert sorted(p.name for p in (out / "amputee-Cat7").iterdir()) == [
        "max-speed.json", "speed-3.5.json", "speed-4.json"]
    # each model's chain: first speed from the template, then warm starts; the maximum speed
    # from the 4 m/s solution
    by_model = {}
    for c in fake_solve.calls:
        by_model.setdefault(c["label"], []).append(c)
    assert list(by_model) == ["able", "amputee Cat6", "amputee Cat7"]
    for calls in by_model.values():
        assert [c["speed"] for c in calls] == [3.5, 4.0, None]
        assert calls[0]["guess"].source.startswith("template at 3.5 m/s")
        np.testing.assert_array_equal(calls[2]["guess"].q, calls[1]["solution"].nlp.q)
    rows = _csv(out / "collocation-sweep.csv")
    assert [(r["model"], r["problem"], r["prescribed_speed_mps"]) for r in rows] == [
        (m, p, s) for m in ("able", "amputee Cat6", "amputee Cat7")
        for p, s in (("speed", "3.5"), ("speed", "4.0"), ("max-speed", ""))]
    cols = list(rows[0])
    assert cols[:6] == ["model", "blade", "problem", "prescribed_speed_mps", "converged",
                        "status"]
    for col in ("mean_speed_mps", "cost_of_transport_J_per_kg_m", "stride_time_s",
                "contact_time_intact_s", "contact_time_prosthetic_s", "contact_time_left_s",
                "peak_vertical_grf_intact_bw", "peak_vertical_grf_right_bw", "iterations",
                "wall_s", "mesh_intervals", "file"):
        assert col in cols
    assert rows[0]["contact_time_intact_s"] == "" and rows[3]["contact_time_left_s"] == ""
    assert rows[5]["file"] == "amputee-Cat6/max-speed.json"
    assert float(rows[5]["mean_speed_mps"]) == pytest.approx(4.8)
    assert result["rows"][5]["mean_speed_mps"] == pytest.approx(4.8)
    # a used folder is refused; --resume solves nothing and writes the same table
    before = (out / "collocation-sweep.csv").read_text()
    assert _sweep(out, *args) == 2
    assert "holds a collocation sweep" in capsys.readouterr().err
    fake_solve.calls.clear()
    assert _sweep(out, *args, "--resume") == 0
    capsys.readouterr()
    assert fake_solve.calls == []
    assert (out / "collocation-sweep.csv").read_text() == before
    # --force starts over: fewer speeds, and the files this run did not write are gone
    assert _sweep(out, "--categories", "Cat6", "--speeds", "3.5", "--force") == 0
    capsys.readouterr()
    assert [c["speed"] for c in fake_solve.calls] == [3.5, None]
    assert sorted(p.name for p in (out / "amputee-Cat6").iterdir()) == [
        "max-speed.json", "speed-3.5.json"]
    assert len(_csv(out / "collocation-sweep.csv")) == 2


def test_sweep_exits_2_naming_the_failed_models_after_finishing_the_others(
        fake_solve, tmp_path, capsys):
    out = tmp_path / "sweep"
    fake_solve.fail = {("amputee Cat6", 4.0), ("amputee Cat7", None)}
    assert _sweep(out, "--categories", "Cat6,Cat7,Cat4", "--speeds", "3.5,4,4.5") == 2
    cap = capsys.readouterr()
    assert "error: 2 of 3 model(s) failed" in cap.err
    assert ("error: amputee Cat6: 4 m/s not converged (IPOPT status "
            "Maximum_Iterations_Exceeded in the predictive stage; best iterate "
            "amputee-Cat6/speed-4.best_iterate.json); last converged: 3.5 m/s") in cap.err
    assert "error: amputee Cat7: maximum speed not converged" in cap.err
    assert "Traceback" not in cap.err
    rows = _csv(out / "collocation-sweep.csv")
    got = [(r["model"], r["problem"], r["prescribed_speed_mps"], r["converged"]) for r in rows]
    assert got == [
        ("amputee Cat6", "speed", "3.5", "True"), ("amputee Cat6", "speed", "4.0", "False"),
        ("amputee Cat6", "max-speed", "", "True"),  # from the 3.5 m/s solution
        ("amputee Cat7", "speed", "3.5", "True"), ("amputee Cat7", "speed", "4.0", "True"),
        ("amputee Cat7", "speed", "4.5", "True"), ("amputee Cat7", "max-speed", "", "False"),
        ("amputee Cat4", "speed", "3.5", "True"), ("amputee Cat4", "speed", "4.0", "True"),
        ("amputee Cat4", "speed", "4.5", "True"), ("amputee Cat4", "max-speed", "", "True"),
    ]
    assert (out / "amputee-Cat7" / "max-speed.best_iterate.json").is_file()


def test_sweep_with_two_jobs_reads_back_in_worker_processes(fake_solve, tmp_path, capfd):
    """--jobs 2 runs the models in a local process pool (the fake solve is not there: every
    solve is read back)."""
    out = tmp_path / "sweep"
    args = ("--able", "--categories", "Cat6", "--speeds", "3.5")
    assert _sweep(out, *args) == 0
    before = (out / "collocation-sweep.csv").read_text()
    solved = {p: p.stat().st_mtime_ns for p in out.rglob("*.json")}
    capfd.readouterr()
    assert _sweep(out, *args, "--resume", "--jobs", "2") == 0
    # read back, not solved again: no solution file rewritten (the workers' progress lines go
    # to the stderr they were started with, which a persistent pool of an earlier test owns)
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*.json")} == solved
    assert (out / "collocation-sweep.csv").read_text() == before


@pytest.mark.parametrize(("args", "where"), [
    (("--method", "collocation", "--init", "x.json"), "--init"),
    (("--method", "collocation", "--categories", "Cat9"), "--categories"),
    (("--method", "collocation", "--categories", ""), "--categories"),
    (("--method", "collocation", "--speeds", "3.5,-1"), "--speeds"),
    (("--method", "collocation", "--mesh", "3"), "--mesh"),
    (("--method", "collocation", "--guess", "no-such-file.json"), "--guess"),
    (("--method", "collocation", "--resume", "--force"), "--resume/--force"),
    (("--method", "collocation", "--resume"), "no collocation sweep to resume"),
    (("--able",), "--able"),
    (("--method", "shooting"), "--method"),
])
def test_bad_sweep_options_are_refused_naming_the_option(args, where, tmp_path, capsys):
    assert main(["sweep", "--out", str(tmp_path / "sweep"), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and where in err
    assert not (tmp_path / "sweep" / "collocation-sweep.csv").exists()
