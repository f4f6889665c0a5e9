"""The mesh-halving check of a stride (``bladelab.predict.collocation.mesh_check``): the
comparison, its file, the folder, the command line and the report."""

from __future__ import annotations

import dataclasses
import json

import pytest

from bladelab.cli import main
from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation import mesh_check
from bladelab.predict.collocation.mesh_check import (
    MESH_CHECK_DIR,
    MESH_CHECK_FILE,
    ROUND_TRIP_DIR,
    MeshCheck,
    compare_meshes,
    mesh_check_in_folder,
    read_mesh_check,
)
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.report.builder import Report
from bladelab.report.collocation import collocation_sections
from collocation_fake import SPEED, fake_solution

N = 12


@pytest.fixture(scope="module")
def strides():
    """(runner, a fake converged stride on N intervals, the same problem's on 2N whose
    objective is 2 % higher)."""
    runner, _, coarse = fake_solution("able", N)
    _, _, fine = fake_solution("able", 2 * N)
    fine = dataclasses.replace(fine, nlp=dataclasses.replace(fine.nlp, objective=1.02 * 1.25))
    return runner, coarse, fine


def test_the_check_reports_each_quantitys_change_and_whether_it_settled(strides):
    _, coarse, fine = strides
    check = compare_meshes(coarse, fine)
    assert (check.coarse_intervals, check.fine_intervals) == (N, 2 * N)
    assert check.change_pct("objective") == pytest.approx(2.0)  # 1.25 → 1.275
    t0, t1 = coarse.summary()["stride_time_s"], fine.summary()["stride_time_s"]
    assert check.change_pct("stride_time_s") == pytest.approx(100 * (t1 - t0) / t0)
    assert not check.settled and "not settled" in check.verdict()
    assert "objective +2.00 %" in check.verdict()
    labels = [row[0] for row in check.table()]
    assert "stride time [s]" in labels and "peak vertical force, left leg [BW]" in labels
    # within 1 % on both: settled
    same = compare_meshes(coarse, dataclasses.replace(
        fine, nlp=dataclasses.replace(fine.nlp, objective=1.004 * 1.25)))
    assert abs(same.change_pct("objective")) < 1.0
    assert same.settled == (abs(same.change_pct("stride_time_s")) < 1.0
                            and not same.fine_warnings)
    # a finer solve that did not converge is never settled
    failed = compare_meshes(coarse, dataclasses.replace(
        fine, nlp=dataclasses.replace(fine.nlp, success=False,
                                      status="Maximum_Iterations_Exceeded")))
    assert not failed.converged and not failed.settled
    assert "did not converge" in failed.verdict()


def test_only_the_same_problem_on_a_finer_mesh_is_compared(strides):
    _, coarse, fine = strides
    other = dataclasses.replace(fine, settings=CollocationSettings(
        mesh_intervals=2 * N, speed_m_per_s=SPEED + 0.5))
    with pytest.raises(SpecError, match="not the same problem"):
        compare_meshes(coarse, other)
    with pytest.raises(SpecError, match="12 mesh intervals, the stride 24"):
        compare_meshes(fine, coarse)


def test_the_check_round_trips_through_its_file_and_knows_its_stride(strides, tmp_path):
    _, coarse, fine = strides
    check = compare_meshes(coarse, fine)
    again = MeshCheck.from_dict(json.loads(json.dumps(check.to_dict())))
    assert again == check
    assert check.describes(coarse) and not check.describes(fine)
    with pytest.raises(InputFileError, match="not a mesh-halving check") as err:
        MeshCheck.from_dict({"kind": "something else"}, file=tmp_path / "x.json")
    assert "x.json" in str(err.value)
    bad = check.to_dict()
    del bad["fine_intervals"]
    with pytest.raises(InputFileError, match="missing or bad field"):
        MeshCheck.from_dict(bad)


def test_the_folder_keeps_the_finer_solve_and_resume_reads_it_back(strides, tmp_path,
                                                                   monkeypatch):
    """The finer solve, then the round trip (the stride's own mesh again, from the finer
    stride) in the folder; resume reads both back; another stride gets both anew."""
    runner, coarse, fine = strides
    back = dataclasses.replace(coarse, nlp=dataclasses.replace(coarse.nlp, objective=1.2))
    calls = []

    def solve(runner_, settings, guess, *, model_spec, progress=None):
        calls.append((settings.mesh_intervals, settings.max_iter, settings.warm_start_mu,
                      guess.n_intervals))
        return fine if settings.mesh_intervals == 2 * N else back

    monkeypatch.setattr(mesh_check, "predict_stride", solve)
    folder = tmp_path / MESH_CHECK_DIR
    check = mesh_check_in_folder(folder, runner, coarse, max_iter=77)
    # the stride itself (resampled by the solve), then the finer stride on the stride's mesh
    assert calls == [(2 * N, 77, 1e-4, N), (N, 77, 1e-4, 2 * N)]
    assert sorted(p.name for p in folder.iterdir()) == [MESH_CHECK_FILE, ROUND_TRIP_DIR,
                                                        "solution.json"]
    assert (folder / ROUND_TRIP_DIR / "solution.json").is_file()
    assert read_mesh_check(folder) == check
    # 1.25 (the stride) → 1.2 (the round trip) → 1.275 (the finer stride)
    basin, own = check.round_trip_pct("objective")
    assert basin == pytest.approx(-4.0) and own == pytest.approx(6.25)
    assert "a lower optimum of the stride's own mesh, which this stride is not" in (
        check.verdict())
    assert [row[2] for row in check.round_trip_table()][0] == "1.2"
    again = mesh_check_in_folder(folder, runner, coarse, resume=True)
    assert again == check and len(calls) == 2  # read back, not solved again
    # a committed study keeps the comparison without the finer strides: read back alone
    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / MESH_CHECK_FILE).write_bytes((folder / MESH_CHECK_FILE).read_bytes())
    assert mesh_check_in_folder(kept, runner, coarse, resume=True) == check
    assert len(calls) == 2 and sorted(p.name for p in kept.iterdir()) == [MESH_CHECK_FILE]
    # a check of another stride in the folder is made anew, its round trip too
    other = dataclasses.replace(coarse, nlp=dataclasses.replace(coarse.nlp, objective=1.3))
    mesh_check_in_folder(folder, runner, other, resume=True)
    assert len(calls) == 4 and read_mesh_check(folder).describes(other)
    # a finer solve that does not converge has no round trip: the old one goes
    failed = dataclasses.replace(fine, nlp=dataclasses.replace(fine.nlp, success=False))
    monkeypatch.setattr(mesh_check, "predict_stride", lambda *a, **k: failed)
    no_trip = mesh_check_in_folder(folder, runner, coarse)
    assert no_trip.returned is None and not (folder / ROUND_TRIP_DIR).exists()
    assert "round trip" not in no_trip.verdict()
    assert read_mesh_check(tmp_path / "elsewhere") is None
    with pytest.raises(SpecError, match="did not converge"):
        mesh_check.check_mesh(runner, dataclasses.replace(
            coarse, nlp=dataclasses.replace(coarse.nlp, success=False)))
    with pytest.raises(SpecError, match="whole factor"):
        mesh_check.check_mesh(runner, coarse, factor=1)


def test_a_round_trip_to_the_same_optimum_says_so_and_keeps_its_file(strides):
    _, coarse, fine = strides
    check = mesh_check.with_round_trip(compare_meshes(coarse, fine), coarse)
    assert check.round_trip_pct("objective") == (pytest.approx(0.0), pytest.approx(2.0))
    assert "the stride's own optimum again" in check.verdict()
    assert MeshCheck.from_dict(json.loads(json.dumps(check.to_dict()))) == check
    # a round trip that lands higher has left the stride's basin: no split is claimed
    higher = mesh_check.with_round_trip(compare_meshes(coarse, fine), dataclasses.replace(
        coarse, nlp=dataclasses.replace(coarse.nlp, objective=1.3)))
    assert "a higher optimum" in higher.verdict() and "own part" not in higher.verdict()


def _predict(out, *extra):
    return main(["predict", "--method", "collocation", "--model", "able", "--body", "seed001",
                 "--out", str(out), "--speed", str(SPEED), "--mesh", str(N), *extra])


def test_the_command_solves_the_finer_mesh_and_says_so(strides, tmp_path, capsys):
    """A real (short) solve on 24 intervals from a stored 12-interval stride: it does not
    converge in 3 iterations, and the command says the stride is not shown settled."""
    _, coarse, _ = strides
    out = tmp_path / "run"
    coarse.write(out / "solution.json")
    assert _predict(out, "--resume", "--mesh-check", "--max-iter", "3", "--json") == 0
    cap = capsys.readouterr()
    summary = json.loads(cap.out)
    assert summary["mesh_check"]["fine_intervals"] == 2 * N
    assert summary["mesh_check"]["converged"] is False
    assert "mesh check: predictive stage: started" in cap.err
    assert "the finer solve did not converge" in cap.err
    assert (out / MESH_CHECK_DIR / "best_iterate.json").is_file()
    # the report names it in its first section (the collocation solution's own sections)
    report = Report("t")
    collocation_sections(report, out)
    first = report.sections[0]
    assert first.title == "Against measured human running"
    assert "the finer solve did not converge" in " ".join(first.text)
    (table,) = [t for t in first.tables if t.title.startswith("Mesh-halving check")]
    assert "24 mesh intervals against this stride's 12" in table.title
    assert list(table.frame.columns) == ["quantity", "12 intervals", "24 intervals", "change"]
    # a check with its round trip: the verdict and the round trip's own table
    _, _, fine = strides
    trip = mesh_check.with_round_trip(compare_meshes(coarse, fine), dataclasses.replace(
        coarse, nlp=dataclasses.replace(coarse.nlp, objective=1.2)))
    (out / MESH_CHECK_DIR / MESH_CHECK_FILE).write_text(json.dumps(trip.to_dict()))
    report = Report("t")
    collocation_sections(report, out)
    first = report.sections[0]
    assert "a lower optimum of the stride's own mesh" in " ".join(first.text)
    (table,) = [t for t in first.tables if t.title.startswith("Round trip")]
    assert table.frame["round trip against this stride"].iloc[0] == "−4.00 %"


def test_a_new_stride_in_the_folder_drops_the_old_check(strides, tmp_path, capsys):
    runner, coarse, fine = strides
    out = tmp_path / "run"
    coarse.write(out / "solution.json")
    (out / MESH_CHECK_DIR).mkdir()
    (out / MESH_CHECK_DIR / MESH_CHECK_FILE).write_text(
        json.dumps(compare_meshes(coarse, fine).to_dict()), encoding="utf-8")
    assert _predict(out, "--force", "--max-iter", "2") == 2  # a new (unconverged) solve
    capsys.readouterr()
    assert not (out / MESH_CHECK_DIR).exists()


def test_the_reflex_method_refuses_the_option(tmp_path, capsys):
    assert main(["predict", "--method", "reflex", "--out", str(tmp_path / "r"),
                 "--mesh-check"]) == 2
    assert "--mesh-check" in capsys.readouterr().err
