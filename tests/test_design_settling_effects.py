"""Each factor's effect through a design study's settling passes
(bladelab.design.settling_effects) and the report's section on it."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pandas as pd
import pytest

from bladelab.design.doe import central_composite
from bladelab.design.settling_effects import (
    effects_by_stage,
    effects_summary,
    last_stage_moves,
    settling_stages,
)
from bladelab.design.space import default_design_space
from bladelab.report.design_strides import settling_effects_section


def _design(run, before, after, frm, y_before):
    return {"run": run, "before": before, "after": after, "from": frm,
            "responses_before": None if y_before is None else {"y": y_before}}


def _record(y_before_run2=5.0):
    return [
        {"pass": 1, "complete": True, "designs": [
            _design(1, 10.0, 10.0, None, 1.0),
            _design(2, 10.0, 9.0, "n.json", y_before_run2),  # lowered by 10 %
            _design(3, 8.0, 8.0, None, 7.0)]},
        {"pass": 2, "complete": False, "designs": [
            _design(3, 8.0, 7.8, "m.json", 7.0)]},  # lowered by 2.5 %, then stopped
    ]


def test_stages_walk_back_from_today_through_each_pass():
    today = pd.DataFrame({"run": [1, 2, 3], "y": [1.0, 2.0, 3.0]})
    stages = settling_stages(today, _record(), ["y"])
    assert [s.label for s in stages] == ["runs", "pass 1", "pass 2 (stopped after 1 designs)"]
    assert stages[0].values["y"].tolist() == [1.0, 5.0, 7.0]
    assert stages[1].values["y"].tolist() == [1.0, 2.0, 7.0]
    assert stages[2].values["y"].tolist() == [1.0, 2.0, 3.0]
    assert [s.changed for s in stages] == [0, 1, 1]
    assert np.isnan(stages[0].largest_drop)
    assert stages[1].largest_drop == pytest.approx(0.1)
    assert stages[2].largest_drop == pytest.approx(0.025)
    # the objective is a response too: the record's "before" is its earlier value
    today["stride_objective"] = [10.0, 9.0, 7.8]
    objective = settling_stages(today, _record(), ["stride_objective"])
    assert objective[0].values["stride_objective"].tolist() == [10.0, 10.0, 8.0]


def test_a_stage_before_an_unrecorded_change_is_not_rebuilt():
    today = pd.DataFrame({"run": [1, 2, 3], "y": [1.0, 2.0, 3.0]})
    stages = settling_stages(today, _record(y_before_run2=None), ["y"])
    assert [s.label for s in stages] == ["pass 1", "pass 2 (stopped after 1 designs)"]
    # a run left out of the table (e.g. a flagged stride) is skipped, not an error
    stages = settling_stages(today[today["run"] != 2], _record(y_before_run2=None), ["y"])
    assert [s.label for s in stages][0] == "runs"


def _ccd_stages(rng):
    """Two stages of a 25-run CCD: y = 3 + 0.5 A - 0.2 B + noise, then the sign of A turned
    (seeded noise, none along C and D)."""
    coded = central_composite(4).coded
    runs = np.arange(1, len(coded) + 1)
    noise = rng.normal(0.0, 0.02, len(coded))
    cd = coded[:, 2:]  # C and D have no effect: the noise made orthogonal to them
    noise -= cd @ np.linalg.lstsq(cd, noise, rcond=None)[0]
    first = 3.0 + 0.5 * coded[:, 0] - 0.2 * coded[:, 1] + noise
    second = 3.0 - 0.5 * coded[:, 0] - 0.2 * coded[:, 1] + noise
    today = pd.DataFrame({"run": runs, "y": second})
    passes = [{"pass": 1, "complete": True, "designs": [
        _design(int(r), 1.0, 0.99, "n.json", float(v)) for r, v in zip(runs, first, strict=True)]}]
    frame = pd.DataFrame(coded, index=runs, columns=["A", "B", "C", "D"])
    return settling_stages(today, passes, ["y"]), frame


def test_effects_by_stage_recover_known_slopes_and_the_summary_reads_them():
    stages, coded = _ccd_stages(np.random.default_rng(0))
    effects = effects_by_stage(stages, coded, "y", "m")
    assert list(effects["stage"].unique()) == ["runs", "pass 1"]
    a = effects[effects["factor"] == "A"].set_index("stage")
    assert a.loc["runs", "effect"] == pytest.approx(0.5, abs=0.02)
    assert a.loc["pass 1", "effect"] == pytest.approx(-0.5, abs=0.02)
    for _, row in effects.iterrows():  # every interval holds its own estimate
        assert row["ci_lower"] < row["effect"] < row["ci_upper"]
    assert (a["p_value"] < 1e-6).all()
    assert (effects["unit"] == "m per coded unit").all()
    assert effects[effects["factor"] == "C"]["effect"].abs().max() < 1e-12
    summary = effects_summary(effects)
    assert "resolved with this sign from pass 1 on" in summary["A"]
    assert "the opposite sign was resolved at runs" in summary["A"]
    assert "resolved with this sign at every stage, its size unchanged throughout" in summary["B"]
    assert "not resolved at the last stage" in summary["C"]


def test_the_report_section_needs_a_settling_pass(tmp_path):
    space = default_design_space()
    stages, coded = _ccd_stages(np.random.default_rng(1))
    table = pd.DataFrame({"run": coded.index})
    for name, column in zip(space.names, coded.columns, strict=True):
        table[f"{name}_coded"] = coded[column].to_numpy()
    table["y"] = stages[-1].values["y"].to_numpy()
    assert settling_effects_section(tmp_path, table, space, {"y": "m"}) is None
    passes = [{"pass": 1, "complete": True, "designs": [
        _design(int(r), 1.0, 0.99, "n.json", float(v))
        for r, v in stages[0].values["y"].items()]}]
    (tmp_path / "settling.json").write_text(json.dumps({"passes": passes}))
    section = settling_effects_section(tmp_path, table, space, {"y": "m", "absent": "s"})
    assert section is not None and len(section["figures"]) == 1
    (_, frame), = section["tables"]
    assert set(frame["response"]) == {"y"} and len(frame) == 2 * len(space.names)
    assert f"{space.names[0]}: -0.5" in section["text"]


def test_the_last_stage_says_how_far_it_moved_the_answer():
    """moved_se is the change from the stage before in standard errors; last_stage_moves
    says whether the set of resolved effects (with their signs) changed."""
    stages, coded = _ccd_stages(np.random.default_rng(2))
    effects = effects_by_stage(stages, coded, "y", "m")
    a = effects[effects["factor"] == "A"]
    assert np.isnan(a["moved_se"].iloc[0])
    assert a["moved_se"].iloc[1] == pytest.approx(
        abs(a["effect"].iloc[1] - a["effect"].iloc[0]) / a["std_error"].iloc[1])
    largest, same = last_stage_moves(effects)
    assert largest == pytest.approx(a["moved_se"].iloc[1]) and not same  # A's sign turned
    again = dataclasses.replace(stages[-1], label="pass 2")  # a pass that changed nothing
    steady = effects_by_stage([stages[-1], again], coded, "y", "m")
    assert last_stage_moves(steady) == (0.0, True)
    assert last_stage_moves(effects_by_stage(stages[:1], coded, "y")) is None
