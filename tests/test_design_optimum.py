"""Constrained optimum of response surfaces, against hand-derived optima."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.design.doe import central_composite
from bladelab.design.optimum import (
    SurfaceConstraint,
    constrained_optimum,
    read_bound,
    surface_constraints,
)
from bladelab.design.space import DesignSpace, Factor
from bladelab.design.surfaces import fit_surface
from bladelab.errors import OptimizationError, SpecError

NAMES = ("a", "b")
D = central_composite(2, n_center=1).coded
SPACE = DesignSpace((Factor("a", 10.0, 20.0, "kN/m"), Factor("b", 0.05, 0.08, "m")))


def _surf(values, name, **kw):
    return fit_surface(D, values, factor_names=NAMES, response=name, **kw)


def test_linear_objective_on_a_circular_constraint():
    obj = _surf(2 * D[:, 0] + D[:, 1], "speed", unit="m/s")
    disc = _surf(1.0 - D[:, 0] ** 2 - D[:, 1] ** 2, "margin")
    res = constrained_optimum(obj, constraints=[SurfaceConstraint(disc, 0.5)], space=SPACE,
                              seed=1)
    # maximum of 2a + b on the circle a² + b² = 0.5: along (2, 1)/√5
    expected = np.sqrt(0.5) * np.array([2.0, 1.0]) / np.sqrt(5.0)
    np.testing.assert_allclose([res.coded["a"], res.coded["b"]], expected, atol=1e-5)
    assert res.predicted == pytest.approx(np.sqrt(0.5) * np.sqrt(5.0), abs=1e-5)
    assert res.constraints["margin"]["slack"] == pytest.approx(0.0, abs=1e-6)
    assert res.point["a"] == pytest.approx(15.0 + 5.0 * expected[0], abs=1e-4)
    assert res.n_feasible >= 1 and res.unit == "m/s"
    # without the constraint, the corner (1, 1)
    free = constrained_optimum(obj, seed=1)
    assert free.coded == pytest.approx({"a": 1.0, "b": 1.0})
    # minimising: the opposite corner
    low = constrained_optimum(obj, sense="min", seed=1)
    assert low.coded == pytest.approx({"a": -1.0, "b": -1.0})


def test_interior_optimum_and_intervals():
    rng = np.random.default_rng(2)
    y = 5.0 - (D[:, 0] - 0.3) ** 2 - 2.0 * (D[:, 1] + 0.2) ** 2
    obj = _surf(y, "E", unit="m")
    res = constrained_optimum(obj, seed=0)
    assert res.coded == pytest.approx({"a": 0.3, "b": -0.2}, abs=1e-6)
    assert res.predicted == pytest.approx(5.0, abs=1e-9)
    # with noise: the prediction interval contains the confidence interval
    d5 = central_composite(2, n_center=5).coded
    yn = 5.0 - (d5[:, 0] - 0.3) ** 2 - 2.0 * (d5[:, 1] + 0.2) ** 2 + rng.normal(0, 0.05, len(d5))
    noisy = fit_surface(d5, yn, factor_names=NAMES, response="E")
    r = constrained_optimum(noisy, seed=0)
    assert r.pi[0] < r.ci[0] < r.predicted < r.ci[1] < r.pi[1]


def test_infeasible_constraints_are_reported():
    obj = _surf(D[:, 0], "speed")
    never = _surf(-1.0 - D[:, 0] ** 2, "clearance")
    with pytest.raises(OptimizationError, match="clearance"):
        constrained_optimum(obj, constraints=[SurfaceConstraint(never, 0.0)], seed=0)


def test_conservative_constraint_moves_inside():
    rng = np.random.default_rng(4)
    d5 = central_composite(2, n_center=5).coded
    obj = fit_surface(d5, d5[:, 0], factor_names=NAMES, model="linear", response="speed")
    g = 0.5 - d5[:, 0] + rng.normal(0, 0.05, len(d5))
    con = fit_surface(d5, g, factor_names=NAMES, model="linear", response="knee")
    mean_opt = constrained_optimum(obj, constraints=[SurfaceConstraint(con, 0.0)], seed=0)
    safe_opt = constrained_optimum(obj, constraints=[SurfaceConstraint(con, 0.0)], seed=0,
                                   conservative=True)
    assert safe_opt.coded["a"] < mean_opt.coded["a"]
    assert safe_opt.constraints["knee"]["pi_lower"] == pytest.approx(0.0, abs=1e-5)


def test_a_maximum_caps_the_response_and_its_conservative_form_its_upper_bound():
    """Maximise a; a load rising with a is capped at 0.3 by ``{"max": 0.3}``: the optimum
    sits on the cap (the load's slack 0); imposed on the prediction interval's upper end it
    moves inside, the upper end then at the cap."""
    rng = np.random.default_rng(5)
    d5 = central_composite(2, n_center=5).coded
    obj = fit_surface(d5, d5[:, 0], factor_names=NAMES, model="linear", response="speed")
    load = fit_surface(d5, d5[:, 0] + rng.normal(0, 0.05, len(d5)), factor_names=NAMES,
                       model="linear", response="socket_moment_max_Nm", unit="N·m")
    cons = surface_constraints({"socket_moment_max_Nm": load},
                               {"socket_moment_max_Nm": {"max": 0.3}})
    assert cons[0].upper and cons[0].relation == "≤" and cons[0].margin(0.1) == pytest.approx(0.2)
    mean_opt = constrained_optimum(obj, constraints=cons, seed=0)
    row = mean_opt.constraints["socket_moment_max_Nm"]
    assert row["maximum"] == 0.3 and row["slack"] == pytest.approx(0.0, abs=1e-6)
    assert row["predicted"] == pytest.approx(0.3, abs=1e-6) and "pi_upper" in row
    safe = constrained_optimum(obj, constraints=cons, seed=0, conservative=True)
    assert safe.coded["a"] < mean_opt.coded["a"]
    assert safe.constraints["socket_moment_max_Nm"]["pi_upper"] == pytest.approx(0.3, abs=1e-5)
    # a minimum of the same surface keeps the optimum at the box's edge
    low = constrained_optimum(obj, constraints=surface_constraints(
        {"socket_moment_max_Nm": load}, {"socket_moment_max_Nm": 0.3}), seed=0)
    assert low.coded["a"] == pytest.approx(1.0)


def test_a_study_constraint_reads_as_a_minimum_or_a_maximum():
    assert read_bound(0.5) == (0.5, False)
    assert read_bound({"min": 2}) == (2.0, False)
    assert read_bound({"max": 150}) == (150.0, True)
    for bad in ({"below": 1.0}, {"max": "x"}, {"max": float("nan")}, {"min": 1, "max": 2}):
        with pytest.raises(SpecError):
            read_bound(bad)
