"""The start spread of a predicted-gait design study (bladelab.design.start_spread): distinct
strides per design from the settling record, the pooled within-design spread, the ceiling it
puts on R², and the report's section."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from bladelab.design.doe import central_composite
from bladelab.design.start_spread import design_strides, r2_pred_ceiling, start_spread
from bladelab.design.surfaces import fit_surface


def _row(run, before, y_before, tries):
    return {"run": run, "before": before,
            "responses_before": None if y_before is None else {"y": y_before},
            "tries": [{"from": f"n{i}.json", "converged": y is not None, "objective": obj,
                       "responses": None if y is None else {"y": y}}
                      for i, (obj, y) in enumerate(tries)]}


def _record():
    return {"passes": [
        {"pass": 1, "designs": [_row(1, 2.0, 1.0, [(1.9, 3.0), (2.1, None)]),
                                _row(2, 5.0, 2.0, [(5.0, 2.0)])]},  # the same stride again
        # pass 2: design 1's stored stride is pass 1's kept try (the same stride: counted once)
        {"pass": 2, "designs": [_row(1, 1.9, 3.0, [(1.95, 2.0)]),
                                _row(2, 5.0, 2.0, [(5.5, 2.0), (6.0, 5.0)])]},
    ]}


def test_design_strides_are_distinct_clean_and_sorted():
    strides = design_strides(_record())
    assert [o for o, _ in strides[1]] == [1.9, 1.95, 2.0]  # 1.9 once; the unclean try left out
    assert [r["y"] for _, r in strides[1]] == [3.0, 2.0, 1.0]
    assert [r["y"] for _, r in strides[2]] == [2.0, 2.0, 5.0]
    # the objective is a response of its own (records written before it was one lack it)
    assert [r["stride_objective"] for _, r in strides[1]] == [1.9, 1.95, 2.0]


def test_pooled_spread_and_ceiling(tmp_path):
    (tmp_path / "settling.json").write_text(json.dumps(_record()))
    across = [0.0, 2.0, 4.0, 6.0, 8.0]
    pd.DataFrame({"run": range(1, 6), "y": across}).to_csv(tmp_path / "results.csv",
                                                          index=False)
    out = start_spread(tmp_path, units={"y": "m"}, near_pct=5.0).set_index("response")
    # design 1: {3, 2, 1}, SS 2; design 2: {2, 2, 5}, SS 6; 4 degrees of freedom
    within = math.sqrt(8.0 / 4.0)
    assert out.loc["y", "within_sd"] == pytest.approx(within)
    assert out.loc["y", "designs"] == 2 and out.loc["y", "strides"] == 6
    assert out.loc["y", "unit"] == "m"
    assert out.loc["y", "across_sd"] == pytest.approx(np.std(across, ddof=1))
    assert out.loc["y", "r2_ceiling"] == pytest.approx(1 - within ** 2 / np.var(across, ddof=1))
    # within 5 % of each design's best: design 1 {3 (1.9), 2 (1.95)}; design 2 only 5.0
    assert out.loc["y", "designs_near"] == 1
    assert out.loc["y", "within_sd_near"] == pytest.approx(math.sqrt(0.5))
    assert out.loc["y", "r2_ceiling_near"] == pytest.approx(1 - 0.5 / np.var(across, ddof=1))
    # only the fitted runs count across designs
    part = start_spread(tmp_path, fitted_runs=[1, 2]).set_index("response")
    assert part.loc["y", "across_sd"] == pytest.approx(np.std([0.0, 2.0], ddof=1))
    assert part.loc["y", "r2_ceiling"] == 0.0  # the start spread exceeds it: clipped at 0


def test_no_record_or_single_strides_give_an_empty_table(tmp_path):
    pd.DataFrame({"run": [1, 2], "y": [0.0, 1.0]}).to_csv(tmp_path / "results.csv", index=False)
    assert start_spread(tmp_path).empty
    one = {"passes": [{"pass": 1, "designs": [_row(1, 2.0, 1.0, [(2.2, None)])]}]}
    (tmp_path / "settling.json").write_text(json.dumps(one))
    assert start_spread(tmp_path).empty


def test_predicted_r2_ceiling_matches_a_simulated_start_error():
    """On a 25-run face-centred design, a quadratic response plus independent noise: the
    mean PRESS R² of the fitted quadratic equals the ceiling from the leverages, and sits
    well below the R² ceiling (which ignores them)."""
    coded = central_composite(4).coded
    names = ["a", "b", "c", "d"]
    signal = 1.0 * coded[:, 0] - 0.5 * coded[:, 1] + 0.4 * coded[:, 0] ** 2
    sigma = 0.25
    rng = np.random.default_rng(7)
    observed, predicted, r2_ceil = [], [], []
    for _ in range(400):
        y = signal + rng.normal(0.0, sigma, len(signal))
        surface = fit_surface(coded, y, factor_names=names, model="quadratic")
        across = float(np.std(y, ddof=1))
        observed.append(surface.r2_pred)
        predicted.append(r2_pred_ceiling(sigma, across, surface.leverage))
        r2_ceil.append(1.0 - sigma ** 2 / across ** 2)
    assert np.mean(surface.leverage) == pytest.approx(15 / 25)
    assert np.mean(observed) == pytest.approx(np.mean(predicted), abs=0.03)
    assert np.mean(r2_ceil) - np.mean(predicted) > 0.1  # the leverages matter


def test_predicted_r2_ceiling_is_undefined_with_leverage_one():
    assert math.isnan(r2_pred_ceiling(0.1, 1.0, [0.5, 1.0, 0.2]))
    assert math.isnan(r2_pred_ceiling(0.1, 0.0, [0.5, 0.5, 0.2]))
    # no start error: a surface of the right form predicts perfectly
    assert r2_pred_ceiling(0.0, 1.0, [0.5, 0.5, 0.2]) == 1.0
