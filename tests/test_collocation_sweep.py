"""The collocation category sweep, ``bladelab sweep --method collocation``.

Solves are replaced by ``collocation_fake.FakeSolve`` (the continuation's ``predict_stride``):
the fake solution at the guess's speed, marked so that each warm start can be traced."""

from __future__ import annotations

import csv
import dataclasses
import json

import numpy as np
import pytest

from bladelab.cli import main
from collocation_fake import fake_solution

N = 12  # mesh intervals: the fake solutions' (conftest.FAKE_MESH)


def _sweep(out, *extra):
    """The sweep on seed 001's body from the template (the fake solutions')."""
    return main(["sweep", "--method", "collocation", "--out", str(out), "--mesh", str(N),
                 "--max-iter", "1", "--body", "seed001", "--guess", "template", *extra])


def test_able_alone_with_empty_categories(fake_solve, tmp_path):
    """``--able --categories ''`` sweeps the able model alone; without --able an empty list is
    refused naming the option."""
    out = tmp_path / "sweep"
    assert _sweep(out, "--able", "--categories", "", "--speeds", "3.5") == 0
    assert sorted(p.name for p in out.iterdir()) == ["able", "collocation-sweep.csv"]
    assert {c["label"] for c in fake_solve.calls} == {"able"}
    assert _sweep(tmp_path / "none", "--categories", "", "--speeds", "3.5") == 2
    assert not (tmp_path / "none").exists()


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
    # seed 001's per-stride quantities of each solution (analyses.stride_analyses)
    for col in ("leg_stiffness_left_kN_per_m", "positive_power_knee_intact_W_per_kg",
                "negative_power_rsp_prosthetic_W_per_kg", "leg_energy_stored_right_J",
                "blade_energy_returned_J", "blade_recoil_pct"):
        assert col in cols
    assert rows[0]["blade_energy_stored_J"] == "" and float(rows[3]["blade_energy_stored_J"]) > 0
    assert float(rows[0]["positive_power_total_W_per_kg"]) > 0
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


def test_a_mesh_check_of_every_converged_solve_joins_the_table_and_the_report(
        fake_solve, monkeypatch, tmp_path, capsys):
    """--mesh-check: each converged solve solved again on twice the intervals (the fake
    solve stands in for it too), its columns in the table, read back on --resume, the report's
    sentence and table; checks of solves no longer in the sweep go with --force."""
    from bladelab.predict.collocation import mesh_check
    from bladelab.report.builder import Report
    from bladelab.report.collocation_sweep import collocation_sweep_sections

    fine = fake_solution("amputee", 2 * N)[2]  # a consistent stride on twice the intervals
    checked = []

    def solve_fine(runner, settings, guess, *, model_spec, progress=None):
        checked.append(settings.mesh_intervals)
        back = settings.mesh_intervals == N  # the round trip: 2 % below the finer stride
        nlp = dataclasses.replace(fine.nlp, objective=fine.nlp.objective * (0.98 if back else 1))
        return dataclasses.replace(fine, settings=settings, model_spec=model_spec, nlp=nlp)

    monkeypatch.setattr(mesh_check, "predict_stride", solve_fine)
    out = tmp_path / "sweep"
    args = ("--categories", "Cat6", "--speeds", "3.5,4", "--mesh-check")
    assert _sweep(out, *args) == 0
    err = capsys.readouterr().err
    assert "amputee Cat6, 4 m/s: mesh check: Mesh-halving check (12 → 24 intervals)" in err
    assert checked == [2 * N, N] * 3 and len(fake_solve.calls) == 3  # finer, round trip
    assert sorted(p.name for p in (out / "amputee-Cat6" / "mesh-check").iterdir()) == [
        "max-speed", "speed-3.5", "speed-4"]
    rows = _csv(out / "collocation-sweep.csv")
    for row in rows:
        assert row["mesh_check_intervals"] == str(2 * N)
        assert row["mesh_check_settled"] in ("True", "False")
        assert float(row["mesh_check_objective_change_pct"]) == pytest.approx(0.0)
        # the round trip 2 % below the stride (whose objective the finer one equals)
        assert float(row["mesh_check_round_trip_objective_pct"]) == pytest.approx(-2.0)
        assert float(row["mesh_check_own_objective_pct"]) == pytest.approx(100 * (1 / 0.98 - 1))
    fake_solve.calls.clear()
    assert _sweep(out, *args, "--resume") == 0
    capsys.readouterr()
    assert fake_solve.calls == [] and len(checked) == 6  # the checks are read back too
    rep = Report("t")
    collocation_sweep_sections(rep, out)
    section = rep.sections[0]
    assert "Mesh-halving check: " in " ".join(section.text)
    (per_solve,) = [t for t in section.tables if t.title.startswith("Mesh-halving check")]
    assert len(per_solve.frame) == 3
    # the category summary says per category whether its two solves settled
    from bladelab.report.collocation_sweep import read_sweep_table, sweep_summary

    table = read_sweep_table(out)
    table["flagged"] = False  # (the fake strides carry gait warnings)
    assert table.mesh_check_settled.astype(str).eq("True").all()
    table["mesh_check_settled"] = table.mesh_check_settled.astype(object)
    table.loc[table.problem == "max-speed", "mesh_check_settled"] = False
    assert sweep_summary(table).settled.tolist() == ["4 m/s: yes; maximum speed: no"]
    table.loc[table.prescribed_speed_mps == 4.0, "mesh_check_settled"] = None
    assert sweep_summary(table).settled.tolist() == ["4 m/s: not checked; maximum speed: no"]
    assert "settled" not in sweep_summary(table.drop(columns="mesh_check_settled"))
    assert _sweep(out, "--categories", "Cat6", "--speeds", "3.5", "--mesh-check",
                  "--force") == 0
    capsys.readouterr()
    assert sorted(p.name for p in (out / "amputee-Cat6" / "mesh-check").iterdir()) == [
        "max-speed", "speed-3.5"]


def test_sweep_exits_2_naming_the_failed_models_after_finishing_the_others(
        fake_solve, tmp_path, capsys):
    out = tmp_path / "sweep"
    fake_solve.fail = {("amputee Cat6", 4.0), ("amputee Cat7", None)}
    assert _sweep(out, "--categories", "Cat6,Cat7,Cat4", "--speeds", "3.5,4,4.5") == 2
    cap = capsys.readouterr()
    assert "error: 2 of 3 model(s) failed" in cap.err
    assert ("error: amputee Cat6: 4 m/s not converged (IPOPT status "
            "Maximum_Iterations_Exceeded in the predictive stage; best iterate "
            "amputee-Cat6/speed-4.best_iterate.json); last converged: 3.875 m/s") in cap.err
    assert "error: amputee Cat7: maximum speed not converged" in cap.err
    assert "Traceback" not in cap.err
    rows = _csv(out / "collocation-sweep.csv")
    got = [(r["model"], r["problem"], r["prescribed_speed_mps"], r["converged"]) for r in rows]
    assert got == [
        # 4 m/s is tried again after 3.75 and 3.875 m/s (quarter steps and below: no more)
        ("amputee Cat6", "speed", "3.5", "True"), ("amputee Cat6", "speed", "3.75", "True"),
        ("amputee Cat6", "speed", "3.875", "True"), ("amputee Cat6", "speed", "4.0", "False"),
        ("amputee Cat6", "max-speed", "", "True"),  # from the 3.875 m/s solution
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


#: The columns of a one-start sweep's table before the solution's stride analyses (the table
#: before --starts existed).
ONE_START_HEAD = [
    "model", "blade", "problem", "prescribed_speed_mps", "converged", "status",
    "mean_speed_mps", "cost_of_transport_J_per_kg_m", "stride_time_s", "contact_time_s",
    "contact_time_intact_s", "contact_time_prosthetic_s", "contact_time_left_s",
    "contact_time_right_s", "peak_vertical_grf_intact_bw", "peak_vertical_grf_prosthetic_bw",
    "peak_vertical_grf_left_bw", "peak_vertical_grf_right_bw", "flight_fraction", "step_phase",
    "dynamics_residual_pct", "iterations", "wall_s", "mesh_intervals", "file", "warnings"]


def _header(out):
    return (out / "collocation-sweep.csv").read_text().splitlines()[0].split(",")


def test_one_start_writes_the_table_and_files_of_a_sweep_before_starts(fake_solve, tmp_path,
                                                                        capsys):
    args = ("--able", "--categories", "Cat6", "--speeds", "3.5,4")
    assert _sweep(tmp_path / "a", *args, "--starts", "1") == 0
    assert _sweep(tmp_path / "b", *args) == 0
    capsys.readouterr()
    header = _header(tmp_path / "a")
    assert header == _header(tmp_path / "b")
    assert header[:len(ONE_START_HEAD)] == ONE_START_HEAD
    assert header[len(ONE_START_HEAD)] == "leg_stiffness_left_kN_per_m"  # the analyses follow
    assert not [c for c in header if c in ("start", "starts", "objective", "spread_pct")
                or c.startswith("objective_")]
    assert sorted(p.name for p in (tmp_path / "a" / "able").iterdir()) == [
        "max-speed.json", "speed-3.5.json", "speed-4.json"]
    assert len(fake_solve.calls) == 2 * 2 * 3  # two runs, two models, three problems


def test_several_starts_keep_the_best_per_problem_and_every_file(fake_solve, monkeypatch,
                                                                 tmp_path, capsys):
    from collocation_fake import objectives_by_start

    # the barrier start wins at 4 m/s, the template at the maximum speed
    best = {("warm-mu-1e-4", 4.0): 1.0, ("template", None): 0.5}
    objectives_by_start(fake_solve, monkeypatch, lambda s, v: best.get((s, v), 2.0))
    out = tmp_path / "sweep"
    args = ("--categories", "Cat6", "--speeds", "3.5,4", "--starts", "3")
    assert _sweep(out, *args, "--json") == 0
    result = json.loads(capsys.readouterr().out)
    assert result["failures"] == {}
    # 3.5 m/s: the template first guess is the only start; then warm, barrier, template
    assert [(c["speed"], c["start"]) for c in fake_solve.calls] == [
        (3.5, "template"), (4.0, "warm"), (4.0, "warm-mu-1e-4"), (4.0, "template"),
        (None, "warm"), (None, "warm-mu-1e-4"), (None, "template")]
    # the maximum speed starts from the kept 4 m/s solution (the barrier start's)
    np.testing.assert_array_equal(fake_solve.calls[4]["guess"].q,
                                  fake_solve.calls[2]["solution"].nlp.q)
    files = sorted(p.name for p in (out / "amputee-Cat6").iterdir())
    assert files == sorted([
        "speed-3.5.json", "speed-4.json", "speed-4.warm-mu-1e-4.json", "speed-4.template.json",
        "max-speed.json", "max-speed.warm-mu-1e-4.json", "max-speed.template.json"])
    rows = _csv(out / "collocation-sweep.csv")
    assert [(r["start"], r["starts"]) for r in rows] == [
        ("warm", "1"), ("warm-mu-1e-4", "3"), ("template", "3")]
    assert rows[1]["file"] == "amputee-Cat6/speed-4.warm-mu-1e-4.json"
    assert float(rows[1]["spread_pct"]) == pytest.approx(100.0) and rows[0]["spread_pct"] == ""
    assert float(rows[2]["objective_warm"]) == 2.0 and float(rows[2]["objective"]) == 0.5
    assert result["rows"][1]["start"] == "warm-mu-1e-4"
    # --resume solves no start again and writes the same table
    before = (out / "collocation-sweep.csv").read_text()
    fake_solve.calls.clear()
    assert _sweep(out, *args, "--resume") == 0
    assert "start  starts  spread_pct" in capsys.readouterr().out
    assert fake_solve.calls == [] and (out / "collocation-sweep.csv").read_text() == before
    # --force keeps every start's file of this run, and removes those it did not write
    assert _sweep(out, *args, "--force") == 0
    assert sorted(p.name for p in (out / "amputee-Cat6").iterdir()) == files
    assert _sweep(out, "--categories", "Cat6", "--speeds", "3.5,4", "--force") == 0
    assert sorted(p.name for p in (out / "amputee-Cat6").iterdir()) == [
        "max-speed.json", "speed-3.5.json", "speed-4.json"]


def test_settling_starts_each_category_from_its_neighbours_strides(fake_solve, monkeypatch,
                                                                   tmp_path, capsys):
    """--settle: after every model, each amputee problem solved again from the kept strides of
    the two categories nearest it by stiffness (not by the order given; Cat4 at the end from
    Cat5 and Cat6), the able runner's prescribed speed from its own maximum-speed stride (its
    maximum speed has none: its continuation came from that speed), the lowest kept with every
    start's objective in the table; --resume solves nothing again."""
    from collocation_fake import objectives_by_start

    # Cat5's 3.5 m/s stride is the best start of Cat4's problem; Cat6's maximum speed does
    # not converge from Cat5's stride
    objective = {("from-Cat5", 3.5): 0.5, ("from-Cat5", None): None}
    objectives_by_start(fake_solve, monkeypatch, lambda s, v: objective.get((s, v), 2.0))
    out = tmp_path / "sweep"
    args = ("--able", "--categories", "Cat4,Cat6,Cat5", "--speeds", "3.5", "--starts", "1",
            "--settle")
    assert _sweep(out, *args) == 0
    err = capsys.readouterr().err
    assert "start from-Cat5: from Cat5's stride amputee-Cat5/speed-3.5.json" in err
    settling = [(c["label"], c["speed"], c["start"]) for c in fake_solve.calls[8:]]
    assert [c["start"] for c in fake_solve.calls[:8]] == ["template", "warm"] * 4
    assert sorted(settling, key=str) == sorted([
        ("able", 3.5, "from-max-speed"),
        ("amputee Cat4", 3.5, "from-Cat5"), ("amputee Cat4", 3.5, "from-Cat6"),
        ("amputee Cat4", None, "from-Cat5"), ("amputee Cat4", None, "from-Cat6"),
        ("amputee Cat5", 3.5, "from-Cat4"), ("amputee Cat5", 3.5, "from-Cat6"),
        ("amputee Cat5", None, "from-Cat4"), ("amputee Cat5", None, "from-Cat6"),
        ("amputee Cat6", 3.5, "from-Cat5"), ("amputee Cat6", 3.5, "from-Cat4"),
        ("amputee Cat6", None, "from-Cat5"), ("amputee Cat6", None, "from-Cat4")], key=str)
    # each settling start from the neighbour's own stride (its primal and dual values)
    cat4 = next(c for c in fake_solve.calls[8:] if c["label"] == "amputee Cat4"
                and c["speed"] == 3.5)
    cat5 = next(c for c in fake_solve.calls[:8] if c["label"] == "amputee Cat5"
                and c["speed"] == 3.5)
    np.testing.assert_array_equal(cat4["guess"].q[:, 3], cat5["solution"].nlp.q[:, 3])
    # a neighbour's maximum-speed stride is held at this model's own floor (the speed of its
    # own fastest stride), not at the neighbour's speed; the warm start keeps the solver's rule
    top = [c for c in fake_solve.calls if c["label"] == "amputee Cat4" and c["speed"] is None]
    assert {c["start"]: c["speed_floor"] for c in top} == {
        "warm": None, "from-Cat5": 3.5, "from-Cat6": 3.5}
    assert {c["guess"].speed for c in top if c["start"] != "warm"} != {3.5}
    assert sorted(p.name for p in (out / "amputee-Cat5").iterdir()) == [
        "max-speed.from-Cat4.json", "max-speed.from-Cat6.json", "max-speed.json",
        "speed-3.5.from-Cat4.json", "speed-3.5.from-Cat6.json", "speed-3.5.json"]
    assert (out / "amputee-Cat6" / "max-speed.from-Cat5.best_iterate.json").exists()
    rows = {(r["model"], r["problem"]): r for r in _csv(out / "collocation-sweep.csv")}
    r = rows["able", "speed"]  # a tie keeps the first start
    assert (r["start"], r["starts"], r["objective_from-max-speed"]) == ("warm", "2", "2.0")
    r = rows["amputee Cat4", "speed"]
    assert (r["start"], r["starts"], r["file"]) == ("from-Cat5", "3",
                                                   "amputee-Cat4/speed-3.5.from-Cat5.json")
    assert float(r["objective"]) == 0.5 and float(r["objective_warm"]) == 2.0
    assert float(r["spread_pct"]) == pytest.approx(300.0)
    r = rows["amputee Cat6", "max-speed"]
    assert (r["start"], r["starts"], r["objective_from-Cat5"]) == ("warm", "2", "")
    assert [m for m, _ in rows][:3] == ["able", "able", "amputee Cat4"]  # the order asked
    before = (out / "collocation-sweep.csv").read_text()
    fake_solve.calls.clear()
    assert _sweep(out, *args, "--resume") == 0
    assert fake_solve.calls == [] and (out / "collocation-sweep.csv").read_text() == before


def test_settling_with_a_mesh_check_checks_only_the_kept_strides(fake_solve, monkeypatch,
                                                                  tmp_path, capsys):
    """--settle --mesh-check: a settled model is checked once, after the settling pass, on
    the stride it keeps (here Cat5's start for Cat4 at 3.5 m/s); the able runner, settled
    from its own maximum-speed stride, the same way."""
    from bladelab.predict.collocation import mesh_check
    from collocation_fake import objectives_by_start

    objectives_by_start(fake_solve, monkeypatch,
                        lambda s, v: {("from-Cat5", 3.5): 0.5}.get((s, v), 2.0))
    fine = fake_solution("amputee", 2 * N)[2]
    checked = []

    def solve_fine(runner, settings, guess, *, model_spec, progress=None):
        checked.append((model_spec["model"], model_spec.get("blade"), settings.mesh_intervals))
        return dataclasses.replace(fine, settings=settings, model_spec=model_spec)

    monkeypatch.setattr(mesh_check, "predict_stride", solve_fine)
    out = tmp_path / "sweep"
    assert _sweep(out, "--able", "--categories", "Cat4,Cat5", "--speeds", "3.5", "--starts",
                  "1", "--settle", "--mesh-check") == 0
    capsys.readouterr()
    # two problems per model, each checked once (the finer solve and its round trip)
    for model, blade in (("able", None), ("amputee", "Cat4"), ("amputee", "Cat5")):
        fine_solves = [c for c in checked if c[:2] == (model, blade) and c[2] == 2 * N]
        assert len(fine_solves) == 2, (model, blade)
    assert sorted(p.name for p in (out / "amputee-Cat4" / "mesh-check").iterdir()) == [
        "max-speed", "speed-3.5.from-Cat5"]
    rows = {(r["model"], r["problem"]): r for r in _csv(out / "collocation-sweep.csv")}
    assert rows["amputee Cat4", "speed"]["mesh_check_intervals"] == str(2 * N)


def test_own_neighbours_skip_the_continuations_origin_and_fill_with_the_stored_stride():
    from bladelab.predict.collocation.sweep import own_neighbours

    def row(problem, speed, converged=True):
        return {"problem": problem, "prescribed_speed_mps": speed, "converged": converged,
                "file": f"m/{problem}-{speed}.json"}

    rows = [row("speed", 5.0), row("speed", 4.0), row("max-speed", 5.1)]
    s4, s5, top = "m/speed-4.0.json", "m/speed-5.0.json", "m/max-speed-5.1.json"
    assert own_neighbours(rows, "stored.json") == {
        "4": [("from-speed-5", s5), ("from-max-speed", top)],
        "5": [("from-max-speed", top), ("from-stored", "stored.json")],
        "max-speed": [("from-speed-4", s4), ("from-stored", "stored.json")]}
    # without a shipped stride, fewer starts; a problem that did not converge is nobody's
    rows[0]["converged"] = False
    assert own_neighbours(rows) == {"4": [("from-max-speed", top)]}
    assert own_neighbours([]) == {}


@pytest.mark.parametrize(("blades", "expected"), [
    (["Cat4", "Cat5", "Cat6", "Cat7"], {0: [1, 2], 1: [2, 0], 2: [3, 1], 3: [2, 1]}),
    (["Cat7", "Cat4"], {0: [1], 1: [0]}),
])
def test_category_neighbours_are_the_two_nearest_by_stiffness(blades, expected):
    from bladelab.predict.collocation.sweep import category_neighbours

    models = [{"model": "able", "blade": None}] + [
        {"model": "amputee", "blade": b} for b in blades]
    got = category_neighbours(models)
    assert got == {i + 1: [j + 1 for j in js] for i, js in expected.items()}


@pytest.mark.parametrize(("args", "where"), [
    (("--method", "collocation", "--init", "x.json"), "--init"),
    (("--method", "collocation", "--categories", "Cat9"), "--categories"),
    (("--method", "collocation", "--categories", ""), "--categories"),
    (("--method", "collocation", "--speeds", "3.5,-1"), "--speeds"),
    (("--method", "collocation", "--mesh", "3"), "--mesh"),
    (("--method", "collocation", "--guess", "no-such-file.json"), "--guess"),
    (("--method", "collocation", "--resume", "--force"), "--resume/--force"),
    (("--method", "collocation", "--resume"), "no collocation sweep to resume"),
    (("--method", "collocation", "--starts", "0"), "--starts"),
    (("--method", "collocation", "--starts", "6"), "--starts"),
    (("--able",), "--able"),
    (("--starts", "2"), "--starts"),
    (("--body", "toes"), "--body"),
    (("--method", "collocation", "--able", "--body", "robot"), "--body"),
    (("--method", "collocation", "--able", "--body-mass", "-1"), "--body-mass"),
    # athlete fields that only the parameter set can check: refused before anything is solved
    (("--method", "collocation", "--able", "--categories", "", "--max-shortening-velocity",
      "40"), "--max-shortening-velocity"),
    (("--method", "collocation", "--categories", "Cat6", "--residual-limb", "0.5"),
     "--residual-limb"),
    (("--height", "1.7"), "--height"),  # reflex grid
    (("--method", "collocation", "--categories", "Cat6", "--stride-time", "0.6,0.7"),
     "--stride-time"),  # one range cannot fit every speed
    (("--stride-time", "people"), "--stride-time"),  # reflex grid
    (("--settle",), "--settle"),  # reflex grid
    (("--method", "shooting"), "--method"),
])
def test_bad_sweep_options_are_refused_naming_the_option(args, where, tmp_path, capsys):
    assert main(["sweep", "--out", str(tmp_path / "sweep"), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and where in err
    assert not (tmp_path / "sweep" / "collocation-sweep.csv").exists()


def test_the_residual_limb_is_the_amputees_alone_in_a_sweep():
    """A sweep of the able runner and an amputee with a residual limb and a longer prosthesis:
    the amputee carries both, the able runner the rest of the athlete."""
    from bladelab.predict.collocation.sweep import sweep_models

    amputee_only = {"residual_limb_length_m": 0.15, "prosthesis_extra_length_m": 0.05}
    able, amputee = sweep_models(["Cat6"], able=True, body="human",
                                 athlete={"body_mass_kg": 70.0} | amputee_only)
    assert able["athlete"] == {"body_mass_kg": 70.0}
    assert amputee["athlete"] == {"body_mass_kg": 70.0} | amputee_only


def test_a_sweep_of_the_toe_body_has_folders_and_labels_of_its_own():
    """The body is part of a problem's identity: its own folder beside seed 001's."""
    from bladelab.predict.collocation.continuation import model_folder
    from bladelab.predict.collocation.stored import model_label
    from bladelab.predict.collocation.sweep import sweep_models

    seed = sweep_models(["cat6"], able=True)
    toes = sweep_models(["cat6"], able=True, body="toes")
    assert [model_folder(m) for m in seed] == ["able", "amputee-Cat6"]
    assert [model_folder(m) for m in toes] == ["able-toes", "amputee-Cat6-toes"]
    assert [model_label(m) for m in toes] == ["able (toes body)", "amputee Cat6 (toes body)"]


def test_a_model_failing_at_its_first_speed_is_told_to_try_another_guess(
        fake_solve, tmp_path, capsys):
    fake_solve.fail = {("amputee Cat6", 3.5)}
    assert _sweep(tmp_path / "sweep", "--categories", "Cat6", "--speeds", "3.5,4") == 2
    err = capsys.readouterr().err
    assert "last converged: none (the first speed starts from --guess: try another one" in err
    assert "maximum speed not attempted" in err
