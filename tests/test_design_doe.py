"""Designs of experiments: sizes, levels, D-optimality, estimability, run lists, coding."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from bladelab.design.doe import (
    box_behnken,
    central_composite,
    d_optimal,
    estimability,
    log_det_information,
    make_design,
    read_runs_csv,
    require_estimable,
)
from bladelab.design.space import DesignSpace, Factor, default_design_space
from bladelab.design.terms import model_terms, parse_terms
from bladelab.errors import DataError, InputFileError, SpecError


def test_ccd_face_centred_four_factors():
    d = central_composite(4, n_center=3)
    assert d.n_runs == 2**4 + 2 * 4 + 3
    assert set(np.unique(d.coded)) == {-1.0, 0.0, 1.0}
    corners = {tuple(r) for r in d.coded if np.all(np.abs(r) == 1)}
    assert corners == set(itertools.product((-1.0, 1.0), repeat=4))
    axial = [r for r in d.coded if np.count_nonzero(r) == 1]
    assert len(axial) == 8 and all(np.abs(r).max() == 1.0 for r in axial)
    assert sum(1 for r in d.coded if not r.any()) == 3
    assert central_composite(4).n_runs == 25  # default: one centre point


def test_bbd_four_factors():
    d = box_behnken(4, n_center=3)
    assert d.n_runs == 24 + 3
    edge = d.coded[np.count_nonzero(d.coded, axis=1) > 0]
    assert len(edge) == 24
    assert np.all(np.count_nonzero(edge, axis=1) == 2)  # two factors at ±1, the others at 0
    assert len({tuple(r) for r in edge}) == 24
    assert estimability(d, model_terms(4), "abcd").estimable
    with pytest.raises(SpecError, match="at least 3 factors"):
        box_behnken(2)


def test_d_optimal_nonsingular_and_beats_random():
    terms = model_terms(4)
    d = d_optimal(4, 20, seed=11)
    assert d.n_runs == 20
    ld = log_det_information(d.coded, terms)
    assert np.isfinite(ld)
    grid = np.array(list(itertools.product((-1.0, 0.0, 1.0), repeat=4)))
    rng = np.random.default_rng(5)
    for _ in range(50):
        rand = grid[rng.choice(len(grid), 20, replace=False)]
        assert ld >= log_det_information(rand, terms)
    # same seed, same design
    np.testing.assert_array_equal(d.coded, d_optimal(4, 20, seed=11).coded)
    with pytest.raises(SpecError, match="at least 15 runs"):
        d_optimal(4, 9)


def test_rank_refusal_of_9_runs_by_15_terms():
    d = d_optimal(4, 9, model="pure_quadratic", seed=0)  # what 9 blades can support
    names = ("stiffness", "width", "height", "toe")
    rep = estimability(d, model_terms(4), names)
    assert not rep.estimable and rep.rank <= 9 and len(rep.aliased_terms) >= 6
    with pytest.raises(SpecError, match="9 runs cannot estimate the 15-term model") as err:
        require_estimable(d, model_terms(4), names)
    assert "reduced model" in err.value.hint
    # a saturated model (0 residual df) is refused too, the linear model is accepted
    with pytest.raises(SpecError, match="residual degrees of freedom"):
        require_estimable(d, parse_terms("pure_quadratic", names), names)
    assert require_estimable(d, model_terms(4, "linear"), names).df_resid == 4


def test_estimability_report_detects_aliasing():
    # a 2-level factorial cannot separate the squares from the intercept
    d = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))
    rep = estimability(d, model_terms(3), "abc")
    assert set(rep.aliased_terms) == {"a^2", "b^2", "c^2"}
    assert rep.condition_number == float("inf")


def test_space_coding_round_trip_and_errors():
    s = default_design_space()
    user = np.array([[18.0, 0.08, 0.44, 0.22], [32.0, 0.05, 0.40, 0.25]])
    coded = s.code(user)
    np.testing.assert_allclose(coded, [[-1, 1, 0, 0], [1, -1, -1, 1]], atol=1e-12)
    np.testing.assert_allclose(s.decode(coded), user)
    assert s.point([0, 0, 0, 0])["stiffness_kN_per_m"] == pytest.approx(25.0)
    with pytest.raises(SpecError, match="stiffness_kN_per_m = 40 kN/m lies outside"):
        s.code([40.0, 0.06, 0.44, 0.22])
    with pytest.raises(SpecError, match="low"):
        Factor("a", 2.0, 1.0)
    with pytest.raises(SpecError, match="invalid factor name"):
        Factor("1bad", 0.0, 1.0)
    with pytest.raises(SpecError, match="duplicate"):
        DesignSpace((Factor("a", 0, 1), Factor("a", 0, 2)))
    p = DesignSpace.parse("stiffness=18:32 kN/m, width_m=0.05:0.08 m")
    assert p.factors[0].unit == "kN/m" and p.factors[1].high == 0.08
    with pytest.raises(SpecError, match="name=low:high"):
        DesignSpace.parse(["stiffness 18-32"])


def test_user_run_list(tmp_path):
    s = default_design_space()
    f = tmp_path / "blades.csv"
    f.write_text("blade,stiffness_kN_per_m,width_m,height_m,toe_length_m\n"
                 "A,18,0.05,0.40,0.19\nB,25,0.065,0.44,0.22\nC,32,0.08,0.48,0.25\n")
    d = read_runs_csv(f, s)
    assert d.kind == "user" and d.n_runs == 3
    np.testing.assert_allclose(d.coded[1], 0.0, atol=1e-12)
    assert make_design(str(f), s).n_runs == 3
    bad = tmp_path / "bad.csv"
    bad.write_text("stiffness_kN_per_m,width_m,height_m\n18,0.05,0.44\n")
    with pytest.raises(DataError, match="missing factor column"):
        read_runs_csv(bad, s)
    out = tmp_path / "out.csv"
    out.write_text("stiffness_kN_per_m,width_m,height_m,toe_length_m\n18,0.05,0.44,0.3\n")
    with pytest.raises(SpecError, match="toe_length_m") as err:
        read_runs_csv(out, s)
    assert err.value.file == str(out)
    nan = tmp_path / "nan.csv"
    nan.write_text("stiffness_kN_per_m,width_m,height_m,toe_length_m\n18,x,0.44,0.22\n")
    with pytest.raises(DataError, match="not a number"):
        read_runs_csv(nan, s)
    with pytest.raises(InputFileError):
        read_runs_csv(tmp_path / "missing.csv", s)
    with pytest.raises(SpecError, match="unknown design"):
        make_design("latin", s)
