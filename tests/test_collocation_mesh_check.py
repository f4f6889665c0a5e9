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
    runner, coarse, fine = strides
    calls = []

    def solve(runner_, settings, guess, *, model_spec, progress=None):
        calls.append((settings.mesh_intervals, settings.max_iter, settings.warm_start_mu,
                  guess.n_intervals))
        return fine

    monkeypatch.setattr(mesh_check, "predict_stride", solve)
    folder = tmp_path / MESH_CHECK_DIR
    check = mesh_check_in_folder(folder, runner, coarse, max_iter=77)
    assert calls == [(2 * N, 77, 1e-4, N)]  # the stride itself, resampled by the solve
    assert sorted(p.name for p in folder.iterdir()) == [MESH_CHECK_FILE, "solution.json"]
    assert read_mesh_check(folder) == check
    again = mesh_check_in_folder(folder, runner, coarse, resume=True)
    assert again == check and len(calls) == 1  # read back, not solved again
    # a check of another stride in the folder is made anew
    other = dataclasses.replace(coarse, nlp=dataclasses.replace(coarse.nlp, objective=1.3))
    mesh_check_in_folder(folder, runner, other, resume=True)
    assert len(calls) == 2 and read_mesh_check(folder).describes(other)
    assert read_mesh_check(tmp_path / "elsewhere") is None
    with pytest.raises(SpecError, match="did not converge"):
        mesh_check.check_mesh(runner, dataclasses.replace(
            coarse, nlp=dataclasses.replace(coarse.nlp, success=False)))
    with pytest.raises(SpecError, match="whole factor"):
        mesh_check.check_mesh(runner, coarse, factor=1)


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
