"""The confirmation run of a study's optimum, with the solve replaced by the collocation
evaluator's tests' stand-in (a real solve takes minutes; the measured one is in
benchmarks/design/transtibial-socket-cap-2026-12-05)."""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
import types
from pathlib import Path

import numpy as np
import pytest

from bladelab.design import collocation_evaluator as ce
from bladelab.design import confirmation as cf
from bladelab.design.doe import central_composite
from bladelab.design.optimum import constrained_optimum, surface_constraints
from bladelab.design.space import DesignSpace, Factor
from bladelab.design.stride_files import coded_distance, point_from_stem
from bladelab.design.surfaces import fit_surface
from bladelab.errors import SpecError
from bladelab.predict.collocation.solution import CollocationSolution
from test_design_collocation_evaluator import CENTRE, RANGES, STRIDE, _evaluator, fake  # noqa: F401

SPACE = DesignSpace(tuple(Factor(n, lo, hi, "") for n, (lo, hi) in RANGES.items()))


def _study(tmp_path, *, cap: float | None = None):
    """A study's result as the confirmation reads it: two designs' strides in the study's
    folder, a fitted Δv_x surface and its optimum (capped at ``cap`` m/s)."""
    strides = tmp_path / "s"
    strides.mkdir()
    far = {**CENTRE, "stiffness_kN_per_m": 32.0}
    for point in (CENTRE, far):
        shutil.copy(STRIDE, strides / f"{ce.point_file_stem(point)}.json")
    coded = central_composite(4).coded
    y = 0.05 * coded[:, 0] + 0.01 * np.random.default_rng(0).standard_normal(len(coded))
    surfaces = {"delta_vx_m_per_s": fit_surface(coded, y, factor_names=SPACE.names,
                                                response="delta_vx_m_per_s", unit="m/s"),
                "avg_vx_m_per_s": fit_surface(coded, np.full(len(coded), 4.0),  # prescribed
                                              factor_names=SPACE.names,
                                              response="avg_vx_m_per_s", unit="m/s")}
    cons = {} if cap is None else {"delta_vx_m_per_s": {"max": cap}}
    optimum = constrained_optimum(surfaces["delta_vx_m_per_s"], sense="max", space=SPACE,
                                  constraints=surface_constraints(surfaces, cons))
    return types.SimpleNamespace(out_dir=tmp_path, optimum=optimum, optimum_error=None,
                                 surfaces=surfaces, space=SPACE)


@pytest.fixture
def stored_own(monkeypatch):
    """A design's stored stride is its own file wherever it is (the stand-in's strides do not
    carry the problem's settings)."""
    def stored(self, point, spec, settings):
        own = self._stride_file(point)
        return ((CollocationSolution.read(own), own) if own is not None and own.is_file()
                else (None, None))

    monkeypatch.setattr(ce.CollocationEvaluator, "_stored", stored)


def test_the_optimum_is_solved_from_the_study_strides_and_kept_apart(fake, stored_own,  # noqa: F811
                                                                      tmp_path, monkeypatch):
    calls, _ = fake
    monkeypatch.setattr(ce, "stride_responses",
                        lambda sol, runner: {"delta_vx_m_per_s": 0.1, "avg_vx_m_per_s": 4.0})
    result = _study(tmp_path, cap=0.02)
    ev = _evaluator(tmp_path)
    lines = []
    rec = cf.confirm_optimum(ev, result, say=lines.append)
    # first solve from the study's nearest design, then the settling starts: the study's two
    # designs, not the confirmation's own stride
    starts = [re.search(r"(stiffness\S+?\.json)", c["source"])[1] for c in calls]
    study = sorted((coded_distance(rec["point"], point_from_stem(p.stem), RANGES), p.name)
                   for p in (tmp_path / "s").iterdir())
    assert starts[0] == study[0][1] and sorted(starts[1:]) == sorted(n for _, n in study)
    assert len(calls) == 1 + len(rec["starts"]) and len(lines) == len(rec["starts"])
    kept = tmp_path / rec["stride"]
    assert kept.is_file() and kept.parent == tmp_path / cf.CONFIRMATION_DIR / "strides"
    assert sorted(p.name for p in (tmp_path / "s").iterdir()) == sorted(
        f"{ce.point_file_stem(p)}.json" for p in (CENTRE, {**CENTRE, "stiffness_kN_per_m": 32.0}))
    # predicted beside solved (the stand-in's Δv_x is 0.1 m/s), the cap checked on the stride
    assert list(rec["responses"]) == ["delta_vx_m_per_s"]  # a prescribed response: none
    row = rec["responses"]["delta_vx_m_per_s"]
    assert row["solved"] == 0.1 and row["predicted"] == pytest.approx(0.02, abs=1e-6)
    assert row["inside"] == (row["pi"][0] <= 0.1 <= row["pi"][1])
    assert rec["constraints"]["delta_vx_m_per_s"] == {"bound": 0.02, "upper": True,
                                                      "solved": 0.1, "met": False}
    assert json.loads((tmp_path / cf.CONFIRMATION_FILE).read_text()) == json.loads(
        json.dumps(rec))
    # the same optimum again: read back, nothing solved; another optimum: solved anew
    assert cf.confirm_optimum(ev, result) == json.loads(json.dumps(rec))
    assert len(calls) == 1 + len(rec["starts"])
    other = types.SimpleNamespace(**{**vars(result), "optimum": constrained_optimum(
        result.surfaces["delta_vx_m_per_s"], sense="min", space=SPACE)})
    cf.confirm_optimum(ev, other)
    assert len(calls) > 1 + len(rec["starts"])


def test_only_a_predicted_stride_study_with_an_optimum_is_confirmed(tmp_path):
    result = _study(tmp_path)
    with pytest.raises(SpecError, match="predicted strides"):
        cf.confirm_optimum(object(), result)
    with pytest.raises(SpecError, match="no optimum"):
        cf.confirm_optimum(_evaluator(tmp_path),
                           types.SimpleNamespace(**{**vars(result), "optimum": None}))


def test_the_report_sets_the_solved_optimum_beside_the_prediction(tmp_path):
    from bladelab.report.design import _confirmation_section

    assert _confirmation_section(tmp_path, None, {}) is None
    (tmp_path / cf.CONFIRMATION_FILE).write_text(json.dumps({
        "point": {"stiffness_kN_per_m": 23.6}, "starts": [{}, {}, {}], "wall_s": 290.0,
        "stride": "confirmation/strides/x.json",
        "responses": {"cost_of_transport_J_per_kg_m": {
            "predicted": 3.836, "pi": [3.719, 3.953], "solved": 3.918, "inside": True},
            "knee_moment_min_Nm": {"predicted": -112.0, "pi": [-207.0, -17.0],
                                   "solved": -191.0, "inside": True}},
        "constraints": {"socket_moment_max_Nm": {"bound": 150.0, "upper": True,
                                                 "solved": 125.4, "met": True}}}))
    section = _confirmation_section(tmp_path, None, {"cost_of_transport_J_per_kg_m": "J/(kg·m)"})
    assert "2 of 2 responses lie inside" in section["text"] and "violates" not in section["text"]
    table = section["tables"][0][1]
    assert list(table["solved"]) == [3.918, -191.0] and table["unit"][0] == "J/(kg·m)"
    assert section["tables"][1][1]["relation"][0] == "≤"


def test_the_command_line_refuses_confirm_without_a_predicted_stride_study(tmp_path, capsys):
    from bladelab.cli import main

    assert main(["design", "--out", str(tmp_path / "x"), "--confirm"]) == 2
    assert "--confirm" in capsys.readouterr().err
    assert not Path(tmp_path / "x").exists()


def test_an_optimum_at_a_design_starts_from_that_designs_stride(fake, stored_own, tmp_path):  # noqa: F811
    """The optimum on a design of the study: its own stride is the first start (a replicate
    from the neighbours alone can end in a dearer optimum)."""
    calls, _ = fake
    result = _study(tmp_path)
    point = {k: float(v) for k, v in result.optimum.point.items()}
    shutil.copy(STRIDE, tmp_path / "s" / f"{ce.point_file_stem(point)}.json")
    ev = _evaluator(tmp_path)
    cf.confirm_optimum(ev, result)
    assert f"{ce.point_file_stem(point)}.json" in calls[0]["source"]
    # once, even where the optimum's coordinates are an ulp off the file name's
    nudged = {k: v * (1 + 1e-15) for k, v in point.items()}
    fields = {f.name: getattr(ev, f.name) for f in dataclasses.fields(ev)}
    starts = cf._FromStudy(**fields, study_strides=str(tmp_path / "s"))._neighbours(nudged)
    assert [p.name for p in starts].count(f"{ce.point_file_stem(point)}.json") == 1
