"""The design report's sections on a collocation study's strides."""

from __future__ import annotations

import json

from bladelab.report.design_strides import settling_text


def test_the_report_says_whether_a_study_has_settled(tmp_path):
    """The settling sentence of a collocation study's report: no record, a last pass below
    1 %, and an unfinished pass after it (not settled, its largest drop named)."""
    assert settling_text(tmp_path).startswith("Not settled: no settling pass")
    done = {"pass": 1, "complete": True, "largest_objective_drop": 0.004, "designs": []}
    (tmp_path / "settling.json").write_text(json.dumps({"passes": [done]}))
    assert settling_text(tmp_path).endswith("settled (below 1 %).")
    assert "the last lowered no objective:" in settling_text(tmp_path)  # "improved" absent
    lowered = done | {"improved": 2}
    (tmp_path / "settling.json").write_text(json.dumps({"passes": [lowered]}))
    assert "the last lowered 2 objectives, the largest by 0.40 %" in settling_text(tmp_path)
    later = {"pass": 2, "complete": False,
             "designs": [{"before": 2.0, "after": 1.96}, {"before": 1.0, "after": 1.0}]}
    (tmp_path / "settling.json").write_text(json.dumps({"passes": [done, later]}))
    text = settling_text(tmp_path)
    assert "pass 2 stopped after 2 designs (largest drop 2.00 %)" in text
    assert "not settled" in text and "cheapest" not in text and "took" not in text
    # a pass from the study's cheapest stride says so; the recorded wall time is summed
    later["from_cheapest"] = True
    (tmp_path / "settling.json").write_text(json.dumps({"passes": [done, later]}))
    (tmp_path / "timing.json").write_text(json.dumps({"segments": [
        {"stage": "runs", "wall_s": 600.0, "designs": 25, "jobs": 2},
        {"stage": "settling pass 1", "wall_s": 1200.0, "designs": 20, "jobs": 2},
        {"stage": "settling pass 1", "wall_s": 300.0, "designs": 5, "jobs": 2}]}))
    text = settling_text(tmp_path)
    assert "(pass 2 also from the study's cheapest stride" in text
    assert ("took 35 min of wall time with 2 workers (runs 10 min; settling pass 1 25 min)"
            in text)
