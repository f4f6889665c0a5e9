"""Reduced quadratic surfaces: the hierarchical backward elimination, the nested predicted R²,
and a study fitted with the reduced model."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bladelab.design.doe import central_composite
from bladelab.design.reduction import backward_terms, fit_reduced, fit_response
from bladelab.design.space import default_design_space
from bladelab.design.study import run_design
from bladelab.design.surfaces import fit_surface
from bladelab.design.terms import model_terms

CODED = central_composite(4).coded  # 25 runs, face-centred
NAMES = ("A", "B", "C", "D")


def _noise(seed: int) -> np.ndarray:
    return np.random.default_rng(seed).normal(0.0, 0.01, CODED.shape[0])


def test_the_elimination_keeps_the_terms_that_matter_and_their_parents():
    a, b, c, d = CODED.T
    y = 1.0 + 0.8 * a + 0.5 * a * b - 0.3 * d**2 + _noise(1)
    kept = backward_terms(CODED, y, 4)
    assert {(0,), (0, 1), (3, 3)} <= set(kept)
    assert (1,) in kept and (3,) in kept  # parents of A*B and D²: the model stays hierarchical
    assert (2,) not in kept and (2, 2) not in kept and (1, 2) not in kept  # C plays no part
    assert kept[0] == ()


def test_the_nested_predicted_r2_equals_press_when_every_fold_keeps_the_full_quadratic():
    """Every term strong: each fold's elimination keeps all 15 terms, so repeating the choice
    without each run changes nothing, and the refits' PRESS must equal the hat-matrix one."""
    x = np.column_stack([np.ones(len(CODED))] + [
        np.prod(CODED[:, list(t)], axis=1) for t in model_terms(4, "quadratic")[1:]])
    beta = np.linspace(1.0, 3.0, x.shape[1])
    y = x @ beta + _noise(2)
    s = fit_reduced(CODED, y, factor_names=NAMES)
    assert len(s.terms) == 15
    full = fit_surface(CODED, y, factor_names=NAMES)
    assert s.r2_pred_selected == pytest.approx(full.r2_pred, rel=1e-9)


def test_on_noise_the_choice_flatters_and_the_nested_r2_says_so():
    y = _noise(3)
    s = fit_reduced(CODED, y, factor_names=NAMES)
    assert s.r2_pred_selected < s.r2_pred
    assert s.r2_pred_selected < 0.2
    assert "backward elimination" in s.selection
    assert "r2_pred_selected" in s.to_dict()
    plain = fit_response(CODED, y, model="quadratic", factor_names=NAMES)
    assert np.isnan(plain.r2_pred_selected) and "r2_pred_selected" not in plain.to_dict()


def test_a_study_with_the_reduced_model_fits_each_response_its_own_terms(tmp_path):
    space = default_design_space()

    def evaluator(point):
        k, w, h, t = space.code([point[n] for n in space.names])
        return {"speed": 5.0 + 0.1 * k - 0.05 * t**2 + 0.001 * np.sin(7 * h + 3 * w),
                "knee": 10.0 + 25.0 * t}

    res = run_design(space, runs="ccd", evaluator=evaluator, out_dir=tmp_path,
                     model="reduced", objective="speed", sense="max", progress=False)
    speed, knee = res.surfaces["speed"], res.surfaces["knee"]
    assert ("stiffness_kN_per_m" in speed.term_names
            and "toe_length_m^2" in speed.term_names)
    assert knee.term_names == ("1", "toe_length_m")
    assert res.optimum.coded["stiffness_kN_per_m"] == pytest.approx(1.0, abs=1e-6)
    saved = json.loads((tmp_path / "surfaces.json").read_text())
    assert saved["knee"]["terms"] == ["1", "toe_length_m"]
    assert json.loads((tmp_path / "study.json").read_text())["model"] == "reduced"


def test_the_elimination_and_its_press_work_on_runs_that_alias_a_term():
    """The clean runs of a study can alias a term of the full quadratic (a CCD missing runs):
    the elimination still chooses terms, and the nested R² is computed, where a full-quadratic
    fit of the same runs is refused."""
    a, b, c, d = CODED.T
    y = 1.0 + 0.8 * a - 0.3 * d**2 + _noise(4)
    keep = np.ones(len(y), bool)
    keep[[0, 3, 5, 6, 9, 10, 12, 15, 18]] = False  # 16 runs: the factorial part half gone
    with pytest.raises(Exception, match="cannot estimate"):
        fit_surface(CODED[keep], y[keep], factor_names=NAMES, model="quadratic")
    kept = backward_terms(CODED[keep], y[keep], 4)
    assert (0,) in kept and (3, 3) in kept
    surface = fit_reduced(CODED[keep], y[keep], factor_names=NAMES)
    assert np.isfinite(surface.r2_pred_selected)


def test_the_report_of_a_reduced_study_leaves_a_constant_response_unfitted(tmp_path):
    """A prescribed (constant) response is left out of the fit table; each fitted response
    keeps its own term count and its nested R²pred, to three decimals."""
    from bladelab.report.design import design_report_sections

    space = default_design_space()

    def evaluator(point):
        k, w, h, t = space.code([point[n] for n in space.names])
        return {"speed": 5.0 + 0.1 * k - 0.05 * t**2 + 0.001 * np.sin(7 * h + 3 * w),
                "knee": 10.0 + 25.0 * t, "prescribed": 4.0}

    run_design(space, runs="ccd", evaluator=evaluator, out_dir=tmp_path, model="reduced",
               objective="speed", sense="max", progress=False)
    fit = design_report_sections(tmp_path)[0]["tables"][0][1]
    assert list(fit["response"]) == ["speed", "knee"]
    assert list(fit["terms"]) == [len(json.loads((tmp_path / "surfaces.json").read_text())[r]
                                      ["terms"]) for r in ("speed", "knee")]
    assert all(v == round(v, 3) for v in fit["R2_pred (selection in each fold)"])
