"""Several starts per problem, the best kept (bladelab.predict.collocation.starts), and the
merge of sweep folders that shares its rule and columns (benchmarks/collocation/merge_starts.py).

The drivers' use of it is tested with the continuation (test_collocation_continuation.py) and
the sweep (test_collocation_sweep.py)."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bladelab.errors import SpecError
from bladelab.predict.collocation import starts as st
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.stride_guess import StrideGuess

MERGE = Path(__file__).resolve().parents[1] / "benchmarks" / "collocation" / "merge_starts.py"


def C(label, objective, converged=True, warnings=()):
    return st.Candidate(label, converged, objective, tuple(warnings))


# -- the kept start -----------------------------------------------------------------------
def test_the_lowest_converged_objective_is_kept():
    cands = [C("warm", 2.9), C("warm-mu-1e-4", 2.6), C("template", 2.1, converged=False)]
    assert st.pick(cands).label == "warm-mu-1e-4"


def test_a_start_with_gait_warnings_loses_to_a_clean_one_with_a_higher_objective():
    cands = [C("warm", 2.9), C("warm-mu-1e-4", 2.4, warnings=["a one-legged hop"]),
             C("template", 3.1)]
    assert st.pick(cands).label == "warm"


def test_when_every_converged_start_has_warnings_the_lowest_is_kept_anyway():
    cands = [C("warm", 2.9, warnings=["no flight"]), C("template", 2.5, warnings=["a hop"]),
             C("previous-but-one", 1.0, converged=False)]
    kept = st.pick(cands)
    assert kept.label == "template" and kept.warnings == ("a hop",)
    assert "every converged start has gait warnings" in st.kept_message(cands, kept)


def test_with_nothing_converged_the_first_start_is_kept_and_ties_go_to_the_earlier():
    assert st.pick([C("warm", 1.0, False), C("template", 0.5, False)]).label == "warm"
    assert st.pick([C("warm", 2.0), C("template", 2.0)]).label == "warm"
    with pytest.raises(SpecError):
        st.pick([])


def test_start_columns_give_each_objective_the_count_and_the_spread():
    cols = st.start_columns([C("warm", 3.0), C("warm-mu-1e-4", 2.5), C("template", 9.0, False)],
                            "warm-mu-1e-4")
    assert list(cols) == ["start", "starts", "objective", "objective_warm",
                          "objective_warm-mu-1e-4", "objective_template", "spread_pct"]
    assert cols["start"] == "warm-mu-1e-4" and cols["starts"] == 2
    assert cols["objective"] == 2.5 and cols["objective_warm"] == 3.0
    assert math.isnan(cols["objective_template"])  # did not converge
    assert cols["spread_pct"] == pytest.approx(20.0)  # (3.0 - 2.5) / 2.5
    one = st.start_columns([C("warm", 3.0), C("template", 1.0, False)], "warm",
                           labels=["warm", "template", "other"])
    assert one["starts"] == 1 and math.isnan(one["spread_pct"])  # no spread of one
    assert math.isnan(one["objective_other"])
    # a start that ended in a hop (gait warnings) counts as converged but not in the spread
    hop = st.start_columns([C("warm", 3.0), C("warm-mu-1e-4", 4.5, warnings=["a hop"]),
                            C("template", 2.7)], "template")
    assert hop["starts"] == 3 and hop["objective_warm-mu-1e-4"] == 4.5
    assert hop["spread_pct"] == pytest.approx(100.0 * 0.3 / 2.7)
    flagged = st.start_columns([C("warm", 3.0, warnings=["x"]), C("template", 2.7,
                                                                 warnings=["y"])], "template")
    assert flagged["spread_pct"] == pytest.approx(100.0 * 0.3 / 2.7)  # all flagged: all count


# -- the starts of a problem --------------------------------------------------------------
def _start(label="warm", mu=None):
    s = CollocationSettings(mesh_intervals=12, speed_m_per_s=4.0, warm_start_mu=mu)
    return st.Start(label, s, lambda: None, "warm start from the 3.5 m/s solution")


def test_the_starts_come_in_a_fixed_order_and_only_where_they_apply():
    warm, template, prev = _start(), _start("template"), _start("previous-but-one")
    warm_source = "collocation solution at 3.5 m/s"
    plan = st.plan_starts(5, warm, warm_source=warm_source, template=template, previous=prev,
                          restart_start=True)
    assert [s.label for s in plan] == ["warm", "warm-mu-1e-4", "template",
                                       "previous-but-one", "warm-restart"]
    assert plan[4].settings.warm_start_mu is None and plan[4].settings.same_problem(
        warm.settings)
    assert [s.label for s in st.plan_starts(4, warm, warm_source=warm_source, template=None,
                                            previous=None, restart_start=True)] == [
        "warm", "warm-mu-1e-4", "warm-restart"]
    # the restart only when asked for (the largest K): a smaller K solves what it did before
    assert [s.label for s in st.plan_starts(4, warm, warm_source=warm_source,
                                            template=None, previous=None)] == [
        "warm", "warm-mu-1e-4"]
    assert plan[1].settings.warm_start_mu == st.BARRIER_MU
    assert plan[1].settings.same_problem(warm.settings)
    assert [s.label for s in st.plan_starts(3, warm, warm_source=warm_source, template=template,
                                            previous=prev)][-1] == "template"
    # a template first guess: no barrier start (tracking stage), no second template
    assert [s.label for s in st.plan_starts(3, warm, warm_source="template at 4 m/s",
                                            template=template, previous=None)] == ["warm"]
    assert [s.label for s in st.plan_starts(1, warm, warm_source=warm_source, template=template,
                                            previous=prev)] == ["warm"]
    # settings that already use the barrier start: the alternative is IPOPT's default
    other = st.barrier_start(_start(mu=st.BARRIER_MU))
    assert other.label == "warm-mu-default" and other.settings.warm_start_mu is None
    # ... and the restart would repeat it
    assert [s.label for s in st.plan_starts(5, _start(mu=st.BARRIER_MU), warm_source=warm_source,
                                            template=None, previous=None,
                                            restart_start=True)] == [
        "warm", "warm-mu-default"]


def test_the_barrier_start_drops_the_warm_starts_multipliers():
    """Otherwise it would start from the same primal and dual values as the warm start."""
    lam = (np.ones(3), np.ones(2))
    guess = StrideGuess("collocation solution", 0.7, np.zeros((5, 2)), np.zeros((5, 2)),
                        multipliers=lam)
    warm = st.Start("warm", CollocationSettings(mesh_intervals=4, speed_m_per_s=4.0),
                    lambda: guess)
    barrier = st.barrier_start(warm)
    assert warm.guess().multipliers is lam and barrier.guess().multipliers is None
    np.testing.assert_array_equal(barrier.guess().q, guess.q)
    again = st.restart(warm)
    assert again.guess().multipliers is None and again.settings.warm_start_mu is None
    np.testing.assert_array_equal(again.guess().q, guess.q)


def test_each_start_has_its_own_files_and_the_warm_start_the_one_start_names(tmp_path):
    ok, best = tmp_path / "speed-4.5.json", tmp_path / "speed-4.5.best_iterate.json"
    assert st.start_files(ok, best, "warm") == (ok, best)
    assert st.start_files(ok, best, "template") == (
        tmp_path / "speed-4.5.template.json", tmp_path / "speed-4.5.template.best_iterate.json")


@pytest.mark.parametrize("bad", [0, 6, 2.0, True, "3"])
def test_a_number_of_starts_out_of_range_is_refused_by_name(bad):
    with pytest.raises(SpecError, match="--starts"):
        st.check_starts(bad, where="--starts")


# -- merge_starts.py shares the rule and the columns --------------------------------------
def _merge_module():
    spec = importlib.util.spec_from_file_location("merge_starts", MERGE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _path(tmp_path, name, rows, fakes, objectives, warned=()):
    """A one-model sweep folder whose solves have the given objectives."""
    import dataclasses

    from bladelab.predict.collocation.sweep import SWEEP_TABLE

    folder = tmp_path / name
    (folder / "able").mkdir(parents=True)
    sol = fakes["able"][1]
    out = []
    for (speed, converged), obj in zip(rows, objectives, strict=True):
        file = f"able/speed-{speed:g}.json"
        nlp = dataclasses.replace(sol.nlp, objective=obj, success=converged)
        dataclasses.replace(sol, nlp=nlp).write(folder / file)
        out.append({"model": "able", "blade": "", "problem": "speed",
                    "prescribed_speed_mps": speed, "converged": converged, "file": file,
                    "warnings": "a hop" if obj in warned else ""})
    pd.DataFrame(out).to_csv(folder / SWEEP_TABLE, index=False)
    return folder


def test_merge_starts_keeps_the_best_path_with_the_library_s_columns(fakes, tmp_path,
                                                                     monkeypatch):
    from bladelab.predict.collocation.solution import CollocationSolution

    warned = {2.0}
    monkeypatch.setattr(CollocationSolution, "gait_warnings",
                        lambda self: ["a hop"] if self.nlp.objective in warned else [])
    rows = [(3.5, True), (4.0, True), (4.5, True)]
    a = _path(tmp_path, "a", rows, fakes, [2.5, 2.0, 3.0], warned)
    b = _path(tmp_path, "b", [(3.5, True), (4.0, True), (4.5, False)], fakes, [2.6, 2.2, 1.0])
    merged = _merge_module().merge(tmp_path / "out", {"defaults": a, "mu": b})
    got = merged.set_index("prescribed_speed_mps")
    assert list(got.start) == ["defaults", "mu", "defaults"]  # 4 m/s: a's 2.0 is a hop
    assert list(got.starts) == [2, 2, 1]
    assert got.loc[3.5, "spread_pct"] == pytest.approx(4.0)
    assert got.loc[4.0, "objective"] == 2.2 and math.isnan(got.loc[4.5, "objective_mu"])
    assert (tmp_path / "out" / "able" / "speed-4.json").is_file()
    header = (tmp_path / "out" / "collocation-sweep.csv").read_text().splitlines()[0].split(",")
    assert header[header.index("warnings"):] == [
        "warnings", "start", "starts", "objective", "objective_defaults", "objective_mu",
        "spread_pct"]
