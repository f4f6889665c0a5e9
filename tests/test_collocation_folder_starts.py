"""One stride from several starts into a folder: each start's files, the kept one copied to the
folder's solution, the record of the starts, resume and the folder rules (the solve is a fake)."""

from __future__ import annotations

import dataclasses
import json

import pytest

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation import folder_starts as fs
from bladelab.predict.collocation.stride_guess import StrideGuess
from collocation_fake import fake_solution


@pytest.fixture(scope="module")
def solved():
    return fake_solution("able", 12)[2]


def _with(sol, objective: float, converged: bool = True):
    nlp = dataclasses.replace(sol.nlp, objective=objective, success=converged,
                              status="Solve_Succeeded" if converged
                              else "Maximum_Iterations_Exceeded")
    return dataclasses.replace(sol, nlp=nlp)


@pytest.fixture
def fake(monkeypatch, solved):
    """predict_stride replaced: each start's outcome by its barrier start and guess."""
    calls = []
    outcome = {}

    def predict_stride(runner, settings, guess, *, model_spec, progress=None):
        label = ("template" if guess.source.startswith("template")
                 else "warm-mu-1e-4" if settings.warm_start_mu == 1e-4
                 # the restart: the guess again with the warm start's settings
                 else "warm-restart" if ("warm", None) in calls else "warm")
        calls.append((label, settings.warm_start_mu))
        return outcome.get(label, _with(solved, 2.0))

    monkeypatch.setattr(fs, "predict_stride", predict_stride)
    return calls, outcome


def _run(out, solved, **kw):
    template = dataclasses.replace(solved.to_guess(), source="template (test)")
    return fs.predict_stride_from_starts(
        out, None, solved.settings, solved.to_guess, lambda: template,
        model_spec=solved.model_spec, **{"starts": 3, **kw})


def test_the_lowest_objective_of_the_starts_is_the_folders_solution(fake, solved, tmp_path):
    calls, outcome = fake
    outcome.update({"warm": _with(solved, 2.0), "warm-mu-1e-4": _with(solved, 1.5),
                    "template": _with(solved, 1.0, converged=False)})
    said = []
    res = _run(tmp_path, solved, say=said.append)
    # the guess, its barrier start, the template: in that order
    assert calls == [("warm", None), ("warm-mu-1e-4", 1e-4), ("template", None)]
    assert res.solution.nlp.objective == 1.5 and res.path == tmp_path / "solution.json"
    assert sorted(p.name for p in (tmp_path / "starts").iterdir()) == [
        "solution.json", "solution.template.best_iterate.json", "solution.warm-mu-1e-4.json",
        "starts.json"]
    record = json.loads((tmp_path / "starts" / "starts.json").read_text())
    assert record["start"] == "warm-mu-1e-4" and record["starts"] == 2
    assert record["objective_warm"] == 2.0 and record["spread_pct"] == pytest.approx(100 / 3)
    assert any("kept warm-mu-1e-4 of 3 starts" in line for line in said)
    # a folder that holds starts is refused; resumed, nothing is solved again
    with pytest.raises(InputFileError, match="holds a collocation solve"):
        _run(tmp_path, solved)
    calls.clear()
    again = _run(tmp_path, solved, resume=True)
    assert calls == []  # the converged starts and the best iterate read back
    assert again.solution.nlp.objective == 1.5 and not again.solved
    # --force solves every start again
    outcome["template"] = _with(solved, 1.2)
    forced = _run(tmp_path, solved, force=True)
    assert [c[0] for c in calls] == ["warm", "warm-mu-1e-4", "template"]
    assert forced.solution.nlp.objective == 1.2
    assert not (tmp_path / "starts" / "solution.template.best_iterate.json").exists()

def test_a_fourth_start_is_the_restart_from_the_guess_s_primal_values(fake, solved, tmp_path):
    calls, outcome = fake
    outcome["warm-restart"] = _with(solved, 0.9)
    res = _run(tmp_path, solved, starts=4)
    assert calls == [("warm", None), ("warm-mu-1e-4", 1e-4), ("template", None),
                     ("warm-restart", None)]
    assert res.solution.nlp.objective == 0.9
    assert (tmp_path / "starts" / "solution.warm-restart.json").exists()
    with pytest.raises(SpecError, match="1 to 4 starts"):
        fs.check_stride_starts(5)


def test_with_no_converged_start_the_folder_keeps_a_best_iterate(fake, solved, tmp_path):
    calls, outcome = fake
    for label in ("warm", "warm-mu-1e-4", "template"):
        outcome[label] = _with(solved, 3.0, converged=False)
    res = _run(tmp_path, solved, starts=2)
    assert [c[0] for c in calls] == ["warm", "warm-mu-1e-4"]
    assert res.path == tmp_path / "best_iterate.json" and not res.solution.converged
    assert not (tmp_path / "solution.json").exists()


def test_a_guess_that_is_no_collocation_solution_has_no_barrier_start(fake, solved, tmp_path):
    calls, _ = fake
    trial = StrideGuess(**{**{f.name: getattr(solved.to_guess(), f.name)
                              for f in dataclasses.fields(StrideGuess)},
                           "source": "trial (test)", "multipliers": None})
    template = dataclasses.replace(trial, source="template (test)")
    fs.predict_stride_from_starts(tmp_path, None, solved.settings, lambda: trial,
                                  lambda: template, starts=3, model_spec=solved.model_spec)
    assert [c[0] for c in calls] == ["warm", "template"]
