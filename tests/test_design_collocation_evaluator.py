"""The collocation design evaluator's starts, files and failures, with the solve replaced by a
stand-in (a real transfemoral solve takes minutes: docs/design.md has the measured ones)."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest

from bladelab.design import collocation_evaluator as ce
from bladelab.design import settling
from bladelab.design.evaluators import make_evaluator
from bladelab.design.stride_files import point_from_stem, start_identity
from bladelab.errors import InputFileError, OptimizationError, SpecError
from bladelab.predict.collocation.solution import CollocationSolution

STRIDE = Path(__file__).parent / "data" / "transfemoral-4mps.json"
CENTRE = {"stiffness_kN_per_m": 25.0, "width_m": 0.065, "height_m": 0.44, "toe_length_m": 0.22}
RANGES = {"stiffness_kN_per_m": (18.0, 32.0), "width_m": (0.05, 0.08), "height_m": (0.40, 0.48),
          "toe_length_m": (0.19, 0.25)}


class _Outcome:
    """A solve's result as the evaluator reads it: converged or not, the gait's defects."""

    stage = "predictive"

    def __init__(self, base: CollocationSolution, converged: bool, defects: list[str],
                 status: str = "Infeasible_Problem_Detected", violation: float = 1.0):
        self._base, self.converged, self._defects = base, converged, defects
        self.nlp = base.nlp if converged else type(
            "N", (), {"status": status, "max_violation": violation, "iterations": 3000})()

    def to_guess(self, source):
        return type("G", (), {"source": source})()

    @property
    def mean_speed_mps(self):
        return self._base.mean_speed_mps

    def gait_warnings(self):
        return list(self._defects)

    def write(self, path):  # the base stride's file stands for this one
        Path(path).write_bytes(STRIDE.read_bytes())
        return Path(path)


@pytest.fixture
def fake(monkeypatch):
    """Replace the solve and the responses; record each solve's start and blade."""
    base = CollocationSolution.read(STRIDE)
    calls, script = [], []

    def predict_stride(runner, settings, guess, *, model_spec, track=None, progress=None,
                       speed_floor=None):
        calls.append({"source": guess.source, "track": track, "spec": model_spec,
                      "floor": speed_floor,
                      "speed": settings.speed_m_per_s, "dofs": runner.dof_names,
                      "mesh": settings.mesh_intervals,
                      "backward_euler": settings.blade_backward_euler,
                      "step_phase_tolerance": settings.step_phase_tolerance,
                      "prosthetic_load_max_bw": settings.prosthetic_load_max_bw,
                      "period_bounds_s": settings.period_bounds_s,
                      "stride_time_people": settings.stride_time_people,
                      "swing_knee": settings.swing_knee_min_deg,
                      "reference": (settings.reference, settings.reference_weight,
                                    settings.reference_dofs),
                      "contacts": runner.contact_params.copy()})
        return _Outcome(base, *(script.pop(0) if script else (True, [])))

    monkeypatch.setattr(ce, "predict_stride", predict_stride)
    monkeypatch.setattr(ce, "stride_responses", lambda sol, runner: {"delta_vx_m_per_s": 0.1})
    return calls, script


def _start_name(source: str) -> str:
    """The stride file a solve's guess source names."""
    return re.search(r"collocation solution (\S+\.json)", source)[1]


def _evaluator(tmp_path, **kw):
    return make_evaluator("collocation", start=str(STRIDE), solutions_dir=str(tmp_path / "s"),
                          factor_ranges=RANGES, **kw)


def test_each_design_wears_its_own_generated_blade(fake, tmp_path):
    calls, _ = fake
    ev = _evaluator(tmp_path, speed_mps=4.5)
    assert ev({**CENTRE}) == {"delta_vx_m_per_s": 0.1}
    call = calls[0]
    assert call["speed"] == 4.5 and call["backward_euler"]  # the blade's links: no ringing
    assert call["floor"] is None  # a prescribed speed has no floor
    assert call["spec"]["model"] == "transfemoral"
    blade = call["spec"]["blade_spec"]  # the generated blade travels with the stride
    assert len(blade["joints"]) == 5
    assert blade["contact"]["stiffness_N_per_m"] == pytest.approx(1e5)  # xtreme's 1e6 × 0.1
    assert blade["contact"]["damping_Ns_per_m"] == pytest.approx(1e3 * 0.1 ** 0.5)
    from bladelab.runner.layout import CP_BLADE, CP_K

    soles = call["contacts"][call["contacts"][:, CP_BLADE] == 1]
    assert len(soles) == 3 and np.allclose(soles[:, CP_K], 1e5)  # the runner wears them
    assert sum(d.startswith("blade_joint") for d in call["dofs"]) == 5  # 6 links
    assert (tmp_path / "s" / f"{ce.point_file_stem(CENTRE)}.json").is_file()


def test_a_design_starts_from_its_nearest_solved_neighbour(fake, tmp_path):
    calls, _ = fake
    ev = _evaluator(tmp_path)
    near = {**CENTRE, "stiffness_kN_per_m": 32.0}
    far = {**CENTRE, "stiffness_kN_per_m": 18.0, "width_m": 0.08}
    ev(far)
    ev(CENTRE)
    assert STRIDE.name in calls[0]["source"]  # nothing solved yet: the start
    assert ce.point_file_stem(far) in calls[1]["source"]
    ev(near)  # the centre (distance 1 coded) is nearer than far (distance 2.24)
    assert ce.point_file_stem(CENTRE) in calls[2]["source"]
    assert all(c["track"] is False for c in calls)


def test_a_start_with_a_flawed_gait_is_followed_by_the_next(fake, tmp_path):
    calls, script = fake
    ev = _evaluator(tmp_path)
    ev(CENTRE)
    script += [(True, ["the prosthetic leg touches the ground 2 times per stride"]), (True, [])]
    ev({**CENTRE, "width_m": 0.05})
    assert ce.point_file_stem(CENTRE) in calls[1]["source"]
    assert STRIDE.name in calls[2]["source"] and calls[2]["track"] is False


def test_a_design_with_no_clean_stride_is_a_named_failure(fake, tmp_path):
    calls, script = fake
    ev = _evaluator(tmp_path)
    script += [(False, []), (True, ["no flight phase (not running)"])]
    with pytest.raises(OptimizationError) as err:
        ev(CENTRE)
    msg = str(err.value)
    assert "Infeasible_Problem_Detected" in msg and "no flight phase" in msg
    assert [c["track"] for c in calls] == [False, True]  # the start, then tracking first
    stem = ce.point_file_stem(CENTRE)
    assert not (tmp_path / "s" / f"{stem}.json").exists()  # never stored as a solution
    assert (tmp_path / "s" / f"{stem}.best_iterate.json").is_file()


def test_a_solve_stopped_by_the_iteration_limit_near_feasibility_is_continued(fake, tmp_path):
    """A start that ran out of iterations on a nearly feasible iterate is solved once more from
    that iterate (predictive only) before the next start is tried; one far from feasible is
    not."""
    calls, script = fake
    ev = _evaluator(tmp_path)
    script += [(False, [], "Maximum_Iterations_Exceeded", 1e-5), (True, [])]
    ev(CENTRE)
    assert len(calls) == 2 and "continued after 3000 iterations" in calls[1]["source"]
    assert calls[1]["track"] is False
    script += [(False, [], "Maximum_Iterations_Exceeded", 0.5), (True, [])]
    ev({**CENTRE, "width_m": 0.05})
    assert len(calls) == 4 and "continued" not in calls[3]["source"]  # the next start instead


def test_point_file_names_read_back():
    stem = ce.point_file_stem({"a_m": 0.065, "b": 25.0})
    assert stem == "a_m=0.065__b=25"
    assert point_from_stem(stem) == {"a_m": 0.065, "b": 25.0}
    assert point_from_stem("solution") is None


def test_a_missing_start_is_named(tmp_path):
    with pytest.raises(InputFileError) as err:
        make_evaluator("collocation", start=str(tmp_path / "none.json"))
    assert "none.json" in str(err.value)


def test_the_runner_of_a_multilink_stride_is_rebuilt_from_its_file():
    from bladelab.design.blade_generator import generate_blade
    from bladelab.predict.collocation.stored import check_model_spec, runner_from_spec

    gen = generate_blade(CENTRE)
    spec = check_model_spec({"model": "transfemoral", "blade": gen.model.name,
                             "blade_spec": gen.spec.model_dump(mode="json", exclude_none=True)})
    runner = runner_from_spec(json.loads(json.dumps(spec)))  # as read back from a file
    assert runner.kind == "transfemoral" and runner.blade_model is not None
    assert np.allclose([j.stiffness for j in runner.blade_model.joints],
                       [j.stiffness for j in gen.model.joints], rtol=1e-12)
    assert runner.blade_model.mass == pytest.approx(gen.model.mass, rel=1e-12)


def test_a_design_solved_before_is_read_back_not_solved_again(fake, tmp_path, monkeypatch):
    import copy
    import dataclasses
    import math

    calls, _ = fake
    ev = _evaluator(tmp_path)
    spec = {"model": "transfemoral", "blade": ev.blade_spec(CENTRE)["name"],
            "blade_spec": ev.blade_spec(CENTRE)}
    base = CollocationSolution.read(STRIDE)  # its intact leg lands twice: flagged
    (tmp_path / "s").mkdir()
    stored = tmp_path / "s" / f"{ce.point_file_stem(CENTRE)}.json"
    dataclasses.replace(base, model_spec=spec, settings=ev.settings()).write(stored)
    ev(CENTRE)
    assert len(calls) == 1  # a flagged stride is solved again
    previous = tmp_path / "s" / f"{ce.point_file_stem(CENTRE)}.previous.json"
    assert previous.is_file()  # and kept beside the new one, not overwritten
    assert ev._neighbours({**CENTRE, "width_m": 0.05}) == [stored]  # not a neighbour
    dataclasses.replace(base, model_spec=spec, settings=ev.settings()).write(stored)
    monkeypatch.setattr(CollocationSolution, "gait_warnings", lambda self: [])
    assert ev(CENTRE) == {"delta_vx_m_per_s": 0.1} and len(calls) == 1  # a clean one: read
    # its blade generated again elsewhere, a stiffness one ulp off: the same problem, read
    ulp = copy.deepcopy(spec)
    joint = ulp["blade_spec"]["joints"][0]
    joint["K_Nm_per_deg"] = math.nextafter(joint["K_Nm_per_deg"], math.inf)
    dataclasses.replace(base, model_spec=ulp, settings=ev.settings()).write(stored)
    assert ev(CENTRE) == {"delta_vx_m_per_s": 0.1} and len(calls) == 1
    dataclasses.replace(ev, speed_mps=4.5)(CENTRE)  # another problem: solved
    assert len(calls) == 2
    start = tmp_path / "start.json"  # a start that solves this very design: read
    dataclasses.replace(base, model_spec=spec, settings=ev.settings()).write(start)
    stored.unlink()
    assert dataclasses.replace(ev, start=str(start))(CENTRE)
    assert len(calls) == 2
    assert stored.is_file()  # and stored with the study's strides, a neighbour of the others
    # a stride of another problem in its place is replaced by the start, and kept aside
    other = dataclasses.replace(ev, speed_mps=4.5)
    dataclasses.replace(base, model_spec=spec, settings=other.settings()).write(stored)
    previous.unlink()
    assert dataclasses.replace(ev, start=str(start))(CENTRE) and len(calls) == 2
    assert CollocationSolution.read(stored).settings.same_problem(ev.settings())
    assert CollocationSolution.read(previous).settings.speed_m_per_s == 4.5


def test_settling_keeps_the_lowest_objective_from_the_neighbours(fake, tmp_path, monkeypatch):
    import types

    calls, _ = fake
    ev = _evaluator(tmp_path)
    far = {**CENTRE, "stiffness_kN_per_m": 18.0, "width_m": 0.08}
    near = {**CENTRE, "stiffness_kN_per_m": 32.0}
    for p in (CENTRE, near, far):
        ev(p)
    objectives = iter([0.95, 0.90])  # from near (distance 1), then from far (2.24)

    def stored(self, point, spec, settings):
        return types.SimpleNamespace(nlp=types.SimpleNamespace(objective=1.0)), None

    def solve(runner, settings, guess, *, model_spec, track=None, progress=None,
              speed_floor=None):
        calls.append({"source": guess.source})
        out = _Outcome(CollocationSolution.read(STRIDE), True, [])
        out.nlp = types.SimpleNamespace(objective=next(objectives), status="Solve_Succeeded")
        return out

    monkeypatch.setattr(ce.CollocationEvaluator, "_stored", stored)
    monkeypatch.setattr(ce, "predict_stride", solve)
    rows = settling.settle_strides(ev, [CENTRE], neighbours=2, progress=False)
    tries = rows[0].pop("tries")
    assert rows == [{"point": CENTRE, "before": 1.0, "after": 0.90,
                     "from": f"{ce.point_file_stem(far)}.json",
                     "responses_before": {"delta_vx_m_per_s": 0.1}, "unchanged": []}]
    # every start's stride is recorded, kept or not: the spread between local optima
    assert [t["from"] for t in tries] == [f"{ce.point_file_stem(p)}.json" for p in (near, far)]
    assert [t["objective"] for t in tries] == [0.95, 0.90]
    assert all(t["converged"] and t["responses"] == {"delta_vx_m_per_s": 0.1} for t in tries)
    assert ce.point_file_stem(near) in calls[-2]["source"]  # nearest first
    assert ce.point_file_stem(far) in calls[-1]["source"]


def test_settling_also_starts_from_the_studys_cheapest_stride(fake, tmp_path, monkeypatch):
    """With ``cheapest`` a design is also solved from the lowest-objective stride of another
    design of this problem (after its nearest neighbours), once, whether or not it is far;
    without it (the default of a pass recorded before) only the neighbours."""
    calls, _ = fake
    base = CollocationSolution.read(STRIDE).settings  # every stored stride is this file
    ev = _evaluator(tmp_path, swing_clearance_m=base.swing_clearance_m,
                    blade_backward_euler=base.blade_backward_euler)
    assert base.same_problem(ev.settings())
    near = {**CENTRE, "stiffness_kN_per_m": 32.0}
    mid = {**CENTRE, "width_m": 0.08, "height_m": 0.48}
    cheap = {**CENTRE, "stiffness_kN_per_m": 18.0, "width_m": 0.05, "toe_length_m": 0.25}
    for p in (CENTRE, near, mid, cheap):
        ev(p)
    for p, objective in ((mid, 0.5), (cheap, 0.2)):  # the far corner's stride is cheapest
        path = ev._stride_file(p)
        data = json.loads(path.read_text())
        data["objective"] = objective
        path.write_text(json.dumps(data))
    stored = CollocationSolution.read(STRIDE)
    monkeypatch.setattr(ce.CollocationEvaluator, "_stored",
                        lambda self, point, spec, settings: (stored, None))
    del calls[:]
    row = settling.settle_strides(ev, [CENTRE], neighbours=1, cheapest=True, progress=False)[0]
    assert [t["from"] for t in row["tries"]] == [f"{ce.point_file_stem(p)}.json"
                                                 for p in (near, cheap)]
    assert len(calls) == 2
    # the cheapest among the neighbours already: not tried twice
    row = ev.settle(CENTRE, neighbours=3, cheapest=True)
    assert [t["from"] for t in row["tries"]].count(f"{ce.point_file_stem(cheap)}.json") == 1
    assert len(row["tries"]) == 3
    row = settling.settle_strides(ev, [CENTRE], neighbours=1, progress=False)[0]
    assert [t["from"] for t in row["tries"]] == [f"{ce.point_file_stem(near)}.json"]
    other = _evaluator(tmp_path)  # another problem: none of the stored strides is its
    assert other._cheapest_other(CENTRE, other.settings(), []) is None


def test_settling_does_not_solve_again_from_an_unchanged_start(fake, tmp_path, monkeypatch):
    """A start whose stride is the one this design was last solved from (same identity: its
    objective and whether it carries multipliers) is not solved again, and is listed as
    unchanged; a changed start is solved, and each try records its start's identity."""
    calls, _ = fake
    ev = _evaluator(tmp_path)
    near = {**CENTRE, "stiffness_kN_per_m": 32.0}
    for p in (CENTRE, near):
        ev(p)
    stored = CollocationSolution.read(STRIDE)
    monkeypatch.setattr(ce.CollocationEvaluator, "_stored",
                        lambda self, point, spec, settings: (stored, None))
    name = f"{ce.point_file_stem(near)}.json"
    del calls[:]
    row = ev.settle(CENTRE, neighbours=1)
    identity = row["tries"][0]["start"]
    assert identity == start_identity(CollocationSolution.read(ev._stride_file(near)))
    assert len(calls) == 1 and row["unchanged"] == []
    row = settling.settle_strides(ev, [CENTRE], neighbours=1, known=[{name: identity}],
                                  progress=False)[0]
    assert len(calls) == 1 and row["tries"] == [] and row["unchanged"] == [name]
    assert row["after"] == row["before"] and row["from"] is None
    lines = []  # a line per start, skipped or solved
    ev.settle(CENTRE, neighbours=1, known={name: identity}, say=lines.append)
    row = ev.settle(CENTRE, neighbours=1, known={name: "1.0 primal"},  # it changed since
                    say=lines.append)
    assert len(calls) == 2 and [t["from"] for t in row["tries"]] == [name]
    assert len(lines) == 2 and all(f"start 1 of 1 ({name})" in line for line in lines)
    assert "skipped" in lines[0] and "objective" in lines[1] and lines[1].endswith(" s")
    # the design's stored stride says what it was solved from: a first pass knows that start
    from bladelab.design.settling import _known_starts

    own = ev._stride_file(CENTRE)
    data = json.loads(own.read_text())
    data["guess_source"] = f"collocation solution {name}, start {identity}"
    own.write_text(json.dumps(data))
    assert ev.solved_from(CENTRE) == {name: identity}
    assert _known_starts([], [CENTRE, near], ev) == [{name: identity}, {}]
    data["guess_source"] = f"collocation solution {name}, continued after 3000 iterations"
    own.write_text(json.dumps(data))
    assert ev.solved_from(CENTRE) == {}  # not one solve from that start as it was
    # the same primal values with IPOPT's multipliers start elsewhere: another start
    duals = dataclasses.replace(stored.nlp, multipliers=(np.zeros(3), np.zeros(2)))
    with_duals = start_identity(dataclasses.replace(stored, nlp=duals))
    assert with_duals.endswith(" primal-dual") and start_identity(stored).endswith(" primal")


def test_settling_records_a_failed_start_without_responses(fake, tmp_path, monkeypatch):
    """A start that does not converge is recorded with IPOPT's status and no objective or
    responses, and the stored stride stays."""
    calls, script = fake
    ev = _evaluator(tmp_path)
    near = {**CENTRE, "stiffness_kN_per_m": 32.0}
    for p in (CENTRE, near):
        ev(p)
    before = ev._stride_file(CENTRE).read_bytes()
    stored = CollocationSolution.read(STRIDE)  # the design's stride, as _stored reads it
    monkeypatch.setattr(ce.CollocationEvaluator, "_stored",
                        lambda self, point, spec, settings: (stored, None))
    script.append((False, [], "Maximum_Iterations_Exceeded"))
    row = ev.settle(CENTRE, neighbours=1)
    assert row["from"] is None and row["after"] == row["before"]
    start = start_identity(CollocationSolution.read(ev._stride_file(near)))
    assert row["tries"] == [{"from": f"{ce.point_file_stem(near)}.json", "start": start,
                             "converged": False, "status": "Maximum_Iterations_Exceeded",
                             "objective": None, "warnings": [], "responses": None}]
    assert ev._stride_file(CENTRE).read_bytes() == before


def test_a_reference_weight_keeps_the_athletes_joints_near_the_start(fake, tmp_path):
    """reference_weight: every design's stride follows the start stride's trunk, intact-leg and
    residual-hip angles (not the prosthetic knee or the blade); a stride solved freely is not
    this problem's, and is solved again."""
    import dataclasses

    calls, _ = fake
    ev = _evaluator(tmp_path, reference_weight=10)
    ev(CENTRE)
    path, weight, dofs = calls[-1]["reference"]
    assert Path(path) == STRIDE and weight == 10.0 and dofs == ce.REFERENCE_DOFS
    assert "knee_angle_r" not in dofs and not any(d.startswith("blade") for d in dofs)
    assert set(dofs) <= set(calls[-1]["dofs"])
    free = dataclasses.replace(ev, reference_weight=0.0)
    assert calls[-1]["reference"][1] == 10.0 and not free.settings().same_problem(ev.settings())
    free(CENTRE)
    assert len(calls) == 2 and calls[-1]["reference"] == (None, 0.0, None)
    with pytest.raises(SpecError) as err:
        _evaluator(tmp_path, reference_weight=-1.0)
    assert err.value.where == "reference_weight"
    # every design starts from the reference (the study's start), its neighbours after it
    ev({**CENTRE, "width_m": 0.05})
    assert STRIDE.name in calls[-1]["source"] and calls[-1]["track"] is False
    _, script = fake
    script += [(False, [])] * 2 + [(True, [])]
    ev({**CENTRE, "width_m": 0.08})
    assert [_start_name(c["source"]) for c in calls[-3:]] == [
        STRIDE.name, f"{ce.point_file_stem(CENTRE)}.json",
        f"{ce.point_file_stem({**CENTRE, 'width_m': 0.05})}.json"]


def test_a_design_tries_its_nearest_solved_neighbours_in_turn(fake, tmp_path):
    calls, script = fake
    ev = _evaluator(tmp_path)
    solved = [CENTRE] + [{**CENTRE, "width_m": w} for w in (0.05, 0.08)] + [
        {**CENTRE, "stiffness_kN_per_m": 18.0}, {**CENTRE, "height_m": 0.40}]
    for p in solved:
        ev(p)
    del calls[:]
    target = {**CENTRE, "width_m": 0.05, "height_m": 0.40}
    script += [(False, [])] * (ce.START_NEIGHBOURS + 1) + [(True, [])]
    ev(target)
    sources = [c["source"] for c in calls]
    assert len(sources) == ce.START_NEIGHBOURS + 2  # the neighbours, the start, tracking
    # nearest first: the two at distance 1, then the centre (1.41), never the far ones
    assert {_start_name(s) for s in sources[:2]} == {
        f"{ce.point_file_stem(solved[1])}.json", f"{ce.point_file_stem(solved[4])}.json"}
    assert ce.point_file_stem(CENTRE) in sources[2]
    assert STRIDE.name in sources[3] and STRIDE.name in sources[4] and calls[4]["track"]


def test_the_human_body_with_peoples_angles(fake, tmp_path):
    """On the human body the evaluator's model spec says so and people's joint angles are in
    the objective at the body's weight; seed 001's body (the default) runs without them; a
    technique reference replaces people's angles, and asking for both is refused; the human
    body has no built-in start, so it needs one."""
    from bladelab.predict.collocation.settings import PEOPLE_REFERENCE
    from bladelab.predict.defaults import PEOPLE_WEIGHT_PER_RAD2

    calls, _ = fake
    human = make_evaluator("collocation", start=str(STRIDE), solutions_dir=str(tmp_path / "h"),
                           body="human")
    human(CENTRE)
    assert calls[-1]["spec"]["body"] == "human"
    assert "mtp_angle_l" in calls[-1]["dofs"]  # the human body's toe
    assert calls[-1]["reference"][:2] == (PEOPLE_REFERENCE, PEOPLE_WEIGHT_PER_RAD2)
    assert human.to_dict()["people_weight"] == PEOPLE_WEIGHT_PER_RAD2
    assert ce.CollocationEvaluator().body == ce.DEFAULT_BODY == "seed001"
    assert ce.CollocationEvaluator().start_file == ce.DEFAULT_START
    assert ce.DEFAULT_START.is_file()
    _evaluator(tmp_path)(CENTRE)
    assert "body" not in calls[-1]["spec"] and calls[-1]["reference"][1] == 0.0
    kept = _evaluator(tmp_path, body="human", reference_weight=5.0)
    assert kept.settings().reference == str(STRIDE) and kept.people_weight_per_rad2 == 0.0
    with pytest.raises(SpecError, match="one weight") as err:
        _evaluator(tmp_path, body="human", reference_weight=5.0, people_weight=10.0)
    assert err.value.where == "people_weight"
    with pytest.raises(SpecError, match="unknown body") as err:
        _evaluator(tmp_path, body="robot")
    assert err.value.where == "body"
    with pytest.raises(SpecError, match="no built-in start stride") as err:
        make_evaluator("collocation", body="human")
    assert err.value.where == "body"


@pytest.mark.parametrize("field, value, bad", [("step_phase_tolerance", 0.1, 0.7),
                                               ("prosthetic_load_max_bw", 3.0, -1.0)])
def test_a_stride_constraint_reaches_every_designs_solve(fake, tmp_path, field, value, bad):
    """The alternating-steps constraint and the socket-load limit are settings of every
    design's solve and of the evaluator's identity (a study made without one is not resumed
    with it: a study's file from before the setting ran without it); none by default; a bad
    value is refused by name."""
    calls, _ = fake
    _evaluator(tmp_path)(CENTRE)
    assert calls[-1][field] is None
    ev = _evaluator(tmp_path / "constrained", **{field: value})
    ev(CENTRE)
    assert calls[-1][field] == value
    assert ev.to_dict()[field] == value
    assert ce.CollocationEvaluator.LEGACY_SETTINGS[field] is None
    with pytest.raises(SpecError) as err:
        _evaluator(tmp_path, **{field: bad})
    assert err.value.where == field


def test_the_stride_time_is_held_in_every_designs_solve(fake, tmp_path):
    """People's stride time (or a given range) bounds every design's period; free by default;
    it is part of the evaluator's identity (a free study is not resumed with it) and a range
    outside the NLP's own period bounds is refused by name."""
    from bladelab.predict.collocation.running_bands import reference_band
    from bladelab.predict.collocation.transcription import PERIOD_BOUNDS_S

    calls, _ = fake
    _evaluator(tmp_path)(CENTRE)
    assert calls[-1]["period_bounds_s"] == PERIOD_BOUNDS_S
    assert not calls[-1]["stride_time_people"]
    people = _evaluator(tmp_path / "people", speed_mps=4.0, stride_time_people=True)
    people(CENTRE)
    lo, hi = calls[-1]["period_bounds_s"]
    band = reference_band("stride time", 4.0)
    assert lo == pytest.approx(band[0], abs=1e-5) and hi == pytest.approx(band[1], abs=1e-5)
    assert PERIOD_BOUNDS_S[0] < lo < hi < PERIOD_BOUNDS_S[1]
    assert people.to_dict()["stride_time_people"] is True
    assert ce.CollocationEvaluator.LEGACY_SETTINGS["stride_time_people"] is False
    ranged = _evaluator(tmp_path / "range", stride_time_range_s=(0.62, 0.70))
    ranged(CENTRE)
    assert calls[-1]["period_bounds_s"] == (0.62, 0.70)
    with pytest.raises(SpecError) as err:
        _evaluator(tmp_path, stride_time_range_s=(0.62, 9.0))
    assert err.value.where == "stride_time_range_s"


def test_the_transtibial_runner_is_predicts_amputee_wearing_the_design(fake, tmp_path):
    """amputation "transtibial": each design's blade on predict's amputee runner, on the human
    body by default from its built-in centre stride, with predict's swing knee and people's
    angles of the residual knee too; the prosthetic knee's settings are refused (its knee is
    the athlete's own) and an unknown amputation is named."""
    from bladelab.predict.defaults import PEOPLE_WEIGHT_PER_RAD2, SWING_KNEE_MIN_DEG

    calls, _ = fake
    ev = make_evaluator("collocation", amputation="transtibial",
                        solutions_dir=str(tmp_path / "tt"), factor_ranges=RANGES)
    assert ev.body == "human" and ev.model == "amputee"
    assert ev.start_file == ce.DEFAULT_STARTS[("transtibial", "human")]
    assert ev.start_file.is_file()
    ev({**CENTRE, "width_m": 0.05})
    spec = calls[-1]["spec"]
    assert spec["model"] == "amputee" and spec["body"] == "human"
    assert spec["blade_spec"]["name"] == spec["blade"]
    assert "knee_angle_r" in calls[-1]["dofs"] and "knee_angle_l" in calls[-1]["dofs"]
    assert calls[-1]["swing_knee"] == SWING_KNEE_MIN_DEG
    assert calls[-1]["reference"][1] == PEOPLE_WEIGHT_PER_RAD2
    assert ev.to_dict()["amputation"] == "transtibial"
    kept = make_evaluator("collocation", amputation="transtibial", reference_weight=5.0)
    assert "knee_angle_r" in kept.settings().reference_dofs
    # the transfemoral runner keeps its settings: no swing knee beside the passive knee
    _evaluator(tmp_path)(CENTRE)
    assert calls[-1]["swing_knee"] is None and calls[-1]["spec"]["model"] == "transfemoral"
    for name, value in (("knee_moment_min_Nm", 0.0), ("knee_flexion_max_loaded_deg", 10.0)):
        with pytest.raises(SpecError, match="residual") as err:
            make_evaluator("collocation", amputation="transtibial", **{name: value})
        assert err.value.where == name
    with pytest.raises(SpecError, match="unknown amputation") as err:
        make_evaluator("collocation", amputation="knee-disarticulation")
    assert err.value.where == "amputation"
    with pytest.raises(SpecError, match="no built-in start stride of the transtibial") as err:
        make_evaluator("collocation", amputation="transtibial", body="seed001")
    assert err.value.where == "body"


def test_the_maximum_speed_problem_per_design_from_another_studys_strides(fake, tmp_path):
    """max_speed: every design's solve poses the maximum-speed problem (no speed) and reports
    its stride's mean speed; start_strides: a design starts from its own stride there first,
    a design without one from its neighbours; a prescribed speed beside it and a missing
    folder are named."""
    from bladelab.design.settings import EvaluatorSettings

    calls, _ = fake
    other = tmp_path / "other"
    other.mkdir()
    own = other / f"{ce.point_file_stem(CENTRE)}.json"
    own.write_bytes(STRIDE.read_bytes())
    ev = _evaluator(tmp_path, max_speed=True, start_strides=str(other))
    assert ev.speed_mps is None and "max_speed_m_per_s" in ev.response_names
    out = ev(CENTRE)
    base = CollocationSolution.read(STRIDE)
    assert out["max_speed_m_per_s"] == pytest.approx(base.mean_speed_mps)
    assert "avg_vx_m_per_s" not in out and "avg_vx_m_per_s" not in ev.response_names  # once
    assert calls[0]["speed"] is None and _start_name(calls[0]["source"]) == own.name
    assert calls[0]["source"].count(own.name) == 1
    # the floor is this blade's own stride's speed, not a start's (a neighbour's would pin it)
    assert calls[0]["floor"] == pytest.approx(base.mean_speed_mps)
    assert f"floor {base.mean_speed_mps!r} m/s" in calls[0]["source"]
    ev({**CENTRE, "width_m": 0.05})  # no stride of it in the other study: its neighbour
    assert _start_name(calls[1]["source"]) == own.name  # the centre's, now this study's own
    assert calls[1]["floor"] is None  # no stride of this blade anywhere: the start's speed
    assert "max_speed_m_per_s" not in _evaluator(tmp_path).response_names
    import types

    def stored(self, point, spec, settings):
        return types.SimpleNamespace(nlp=types.SimpleNamespace(objective=-4.0),
                                     mean_speed_mps=5.0), None

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(ce.CollocationEvaluator, "_stored", stored)
        row = ev.settle(CENTRE, neighbours=1)  # the neighbour, then its own stride there
    neighbour = f"{ce.point_file_stem({**CENTRE, 'width_m': 0.05})}.json"
    assert [t["from"] for t in row["tries"]] == [neighbour, own.name]
    assert _start_name(calls[-1]["source"]) == own.name and calls[-1]["speed"] is None
    assert all(c["floor"] == pytest.approx(base.mean_speed_mps) for c in calls[2:])
    assert row["responses_before"]["max_speed_m_per_s"] == 5.0
    with pytest.raises(SpecError, match="exclude each other") as err:
        EvaluatorSettings(kind="collocation", speed_mps=4.0, max_speed=True)
    assert err.value.where == "max_speed"
    with pytest.raises(InputFileError, match="start strides"):
        _evaluator(tmp_path, max_speed=True, start_strides=str(tmp_path / "none"))
    banded = _evaluator(tmp_path, max_speed=True, stride_time_people=True).settings()
    assert banded.speed_m_per_s is None and banded.period_band is not None


def test_every_designs_stride_is_of_the_athlete(fake, tmp_path):
    """athlete: each design's stride is solved on the runner scaled to the athlete (its model
    specification says so, and the study's evaluator.json); a bad field is named before any
    solve, and a study of another athlete is not resumed."""
    from bladelab.design.space import default_design_space
    from bladelab.design.study import run_design

    calls, _ = fake
    athlete = {"muscle_strength": 1.5, "max_shortening_velocity": 15,
               "prosthesis_extra_length_m": 0.045}
    ev = make_evaluator("collocation", amputation="transtibial", athlete=athlete,
                        solutions_dir=str(tmp_path / "s"), factor_ranges=RANGES)
    ev(CENTRE)
    assert calls[-1]["spec"]["athlete"] == {k: float(v) for k, v in athlete.items()}
    assert ev.to_dict()["athlete"] == calls[-1]["spec"]["athlete"]
    assert len(calls) == 1  # the built-in centre stride is another athlete's: solved
    plain = make_evaluator("collocation", amputation="transtibial",
                           solutions_dir=str(tmp_path / "p"), factor_ranges=RANGES)
    plain(CENTRE)
    assert len(calls) == 1 and plain.athlete is None  # the default athlete's: read back
    plain({**CENTRE, "width_m": 0.05})
    assert "athlete" not in calls[-1]["spec"]
    for bad, where in (({"muscle_strength": 0}, "athlete.muscle_strength"),
                       ({"max_shortening_velocity": 99}, "athlete.max_shortening_velocity"),
                       ({"shoe_size": 44}, "athlete")):
        with pytest.raises(SpecError) as err:
            make_evaluator("collocation", amputation="transtibial", athlete=bad)
        assert err.value.where == where
    # a folder of this athlete's runs is not resumed for another athlete (refused before a run)
    study = tmp_path / "study"
    (study / "runs").mkdir(parents=True)
    (study / "runs" / "run_0001.json").write_text("{}")
    (study / "evaluator.json").write_text(json.dumps(ev.to_dict()))
    solves = len(calls)
    with pytest.raises(SpecError, match=r"another evaluator \(athlete: \{'muscle_strength'"):
        run_design(default_design_space(), evaluator=plain, out_dir=study, progress=False)
    assert len(calls) == solves


def test_continuation_speeds_step_to_the_studys_speed():
    from bladelab.design.start_continuation import continuation_speeds

    assert continuation_speeds(4.0, 6.0) == pytest.approx([4.0, 4.5, 5.0, 5.5, 6.0])
    down = continuation_speeds(6.0, 4.9)  # three equal steps, none above 0.5 m/s
    assert down == pytest.approx([6.0, 6.0 - 1.1 / 3, 6.0 - 2.2 / 3, 4.9])
    assert continuation_speeds(4.0, 4.5) == [] and continuation_speeds(4.0, 3.6) == []
    with pytest.raises(ValueError):
        continuation_speeds(4.0, 6.0, step_mps=0.0)


def test_a_study_far_from_its_starts_speed_continues_the_start_first(fake, tmp_path):
    """prepare: the first design solved from the start (4 m/s, 50 intervals) at 4, 4.5 ... 6
    m/s on the start's mesh, each step from the last, then on the study's 100 intervals; the
    steps kept, the last as the design's stride, which the next design starts from."""
    calls, _ = fake
    ev = _evaluator(tmp_path, speed_mps=6.0, mesh_intervals=100)
    ev.prepare(CENTRE, progress=False)
    assert [(round(c["speed"], 9), c["mesh"]) for c in calls] == [
        (4.0, 50), (4.5, 50), (5.0, 50), (5.5, 50), (6.0, 50), (6.0, 100)]
    assert all(c["track"] is False for c in calls)
    stem = ce.point_file_stem(CENTRE)
    steps = tmp_path / "s" / "continuation"
    assert _start_name(calls[0]["source"]) == STRIDE.name
    assert _start_name(calls[1]["source"]) == f"{stem}-4.000mps-mesh50.json"
    assert _start_name(calls[5]["source"]) == f"{stem}-6.000mps-mesh50.json"
    assert (steps / f"{stem}-6.000mps-mesh100.json").is_file()
    assert (tmp_path / "s" / f"{stem}.json").is_file()  # the design's own stride
    ev({**CENTRE, "width_m": 0.05})
    assert _start_name(calls[-1]["source"]) == f"{stem}.json"  # the continued centre


def test_a_failed_continuation_step_leaves_the_start_as_it_is(fake, tmp_path):
    calls, script = fake
    ev = _evaluator(tmp_path, speed_mps=5.5)
    script += [(True, []), (True, ["the prosthetic leg never carries the body"])]
    ev.prepare(CENTRE, progress=False)
    assert [c["speed"] for c in calls] == pytest.approx([4.0, 4.5])  # stopped at the hop
    stem = ce.point_file_stem(CENTRE)
    assert (tmp_path / "s" / "continuation" / f"{stem}-4.500mps-mesh50.best_iterate.json"
            ).is_file()
    assert not (tmp_path / "s" / f"{stem}.json").exists()
    ev(CENTRE)
    assert _start_name(calls[-1]["source"]) == STRIDE.name  # the start as it is


def test_no_continuation_near_the_starts_speed_or_for_the_maximum_speed(fake, tmp_path):
    calls, _ = fake
    _evaluator(tmp_path, speed_mps=4.4).prepare(CENTRE, progress=False)
    _evaluator(tmp_path / "m", max_speed=True).prepare(CENTRE, progress=False)
    make_evaluator("collocation", start=str(STRIDE), speed_mps=6.0).prepare(CENTRE)
    own = tmp_path / "own"
    own.mkdir()
    (own / f"{ce.point_file_stem(CENTRE)}.json").write_bytes(STRIDE.read_bytes())
    _evaluator(tmp_path / "o", speed_mps=6.0, start_strides=str(own)).prepare(CENTRE)
    # within one step; no speed to continue to; no folder to keep it in; its own start stride
    assert calls == []
