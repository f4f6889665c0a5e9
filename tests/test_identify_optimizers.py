"""Optimisers: convergence on analytic functions, determinism, bound handling, no log files."""

from __future__ import annotations

import os

import numpy as np
import pytest

from bladelab.errors import OptimizationError
from bladelab.identify.optimizers import CMAES, ParticleSwarm, as_bounds, minimize

CENTER = np.array([0.3, -0.7, 1.2])


def sphere(X):
    return np.sum((X - CENTER) ** 2, axis=1)


def rosenbrock_shifted(X):
    Y = X - 0.5  # minimum at (1.5, 1.5)
    return np.sum(100 * (Y[:, 1:] - Y[:, :-1] ** 2) ** 2 + (1 - Y[:, :-1]) ** 2, axis=1)


@pytest.mark.parametrize("optimizer", ["pso", "cmaes"])
def test_shifted_sphere(optimizer):
    res = minimize(sphere, [(-2, 2)] * 3, optimizer=optimizer, seed=1)
    assert np.allclose(res.x, CENTER, atol=0.02)
    assert res.evaluations <= 620


def test_pso_default_budget_is_seed_000():
    calls = []
    res = minimize(lambda X: calls.append(len(X)) or sphere(X), [(-2, 2)] * 3, seed=0)
    assert calls == [20] * 30 and res.evaluations == 600 and res.iterations == 30


@pytest.mark.parametrize("optimizer", ["pso", "cmaes"])
def test_shifted_rosenbrock(optimizer):
    res = minimize(rosenbrock_shifted, [(-2, 3)] * 2, optimizer=optimizer, seed=3, max_evals=3000)
    assert np.allclose(res.x, [1.5, 1.5], atol=0.03)


def test_polish_improves_pso():
    plain = minimize(sphere, [(-2, 2)] * 3, seed=5, max_evals=200)
    polished = minimize(sphere, [(-2, 2)] * 3, seed=5, max_evals=200, polish=True)
    assert polished.fun <= plain.fun
    assert polished.fun < 1e-10
    assert polished.optimizer == "pso+polish"


@pytest.mark.parametrize("optimizer", ["pso", "cmaes"])
def test_same_seed_same_history(optimizer):
    seen = {0: [], 1: []}

    def recorder(k):
        return lambda X: seen[k].append(X.copy()) or sphere(X)

    a = minimize(recorder(0), [(-2, 2)] * 3, optimizer=optimizer, seed=42, max_evals=300)
    b = minimize(recorder(1), [(-2, 2)] * 3, optimizer=optimizer, seed=42, max_evals=300)
    assert len(seen[0]) == len(seen[1])
    assert all(np.array_equal(x, y) for x, y in zip(seen[0], seen[1], strict=True))
    assert np.array_equal(a.history_best, b.history_best) and np.array_equal(a.x, b.x)
    c = minimize(sphere, [(-2, 2)] * 3, optimizer=optimizer, seed=43, max_evals=300)
    assert not np.array_equal(a.history_best, c.history_best)


def test_global_numpy_rng_untouched():
    state = np.random.get_state()[1].copy()
    minimize(sphere, [(-2, 2)] * 3, optimizer="cmaes", seed=1, max_evals=100)
    minimize(sphere, [(-2, 2)] * 3, optimizer="pso", seed=1, max_evals=100)
    assert np.array_equal(np.random.get_state()[1], state)


@pytest.mark.parametrize("optimizer", ["pso", "cmaes"])
def test_optimum_on_a_bound(optimizer):
    # unconstrained minimum at (3, -3) outside the box [-1, 1]^2: the answer is the corner (1, -1)
    f = lambda X: (X[:, 0] - 3.0) ** 2 + (X[:, 1] + 3.0) ** 2  # noqa: E731
    res = minimize(f, [(-1, 1), (-1, 1)], optimizer=optimizer, seed=2)
    assert np.allclose(res.x, [1.0, -1.0], atol=1e-3)


@pytest.mark.parametrize("boundary", ["reflect", "clip"])
def test_pso_never_leaves_the_box_nor_wraps(boundary):
    # optimum at the upper wall; a wrap-around would teleport particles next to the lower wall
    lo, hi = np.array([0.0, 10.0]), np.array([1.0, 20.0])
    pso = ParticleSwarm(np.column_stack([lo, hi]), n_particles=15, n_iterations=40,
                        boundary=boundary, seed=7)
    prev = None
    while not pso.stop():
        X = pso.ask()
        assert np.all(X >= lo) and np.all(X <= hi)
        if prev is not None:
            # each coordinate moves by at most v_max = 0.5 width: never across the box
            assert np.all(np.abs(X - prev) <= 0.5 * (hi - lo) + 1e-12)
        # pulled hard against the upper walls
        pso.tell(X, -(X[:, 0] + X[:, 1]))
        prev = X
    assert np.allclose(pso.best_x, hi, rtol=1e-3)


def test_pso_reflection_is_a_mirror():
    pso = ParticleSwarm([(0.0, 1.0)], n_particles=2, n_iterations=5, seed=0,
                        inertia=1.0, cognitive=0.0, social=0.0, max_velocity=1.0)
    pso.x = np.array([[0.9], [0.2]])
    pso.v = np.array([[0.3], [-0.5]])
    pso._move()
    assert np.allclose(pso.x[:, 0], [0.8, 0.3])  # 1.2 -> 0.8, -0.3 -> 0.3 (not 0.2 / 0.7)
    assert np.allclose(pso.v[:, 0], [-0.3, 0.5])


def test_cmaes_writes_no_files(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    es = CMAES([(-2, 2)] * 3, max_evals=200, seed=0)
    assert es._es.opts["verb_log"] == 0 and es._es.opts["verb_disp"] == 0
    minimize(sphere, [(-2, 2)] * 3, optimizer="cmaes", seed=0, max_evals=200)
    assert os.listdir(tmp_path) == []


def test_cmaes_candidates_inside_box():
    es = CMAES([(0, 1), (5, 6)], max_evals=300, seed=3)
    while not es.stop():
        X = es.ask()
        assert np.all(X[:, 0] >= 0) and np.all(X[:, 0] <= 1)
        assert np.all(X[:, 1] >= 5) and np.all(X[:, 1] <= 6)
        es.tell(X, -X[:, 0] - X[:, 1])
    assert np.allclose(es.best_x, [1, 6], atol=1e-2)


def test_bad_bounds_and_options():
    with pytest.raises(OptimizationError, match="not below"):
        as_bounds([(1.0, 0.5)])
    with pytest.raises(OptimizationError, match="finite"):
        as_bounds([(0.0, np.inf)])
    with pytest.raises(OptimizationError, match="unknown optimizer"):
        minimize(sphere, [(-1, 1)] * 3, optimizer="ga")
    with pytest.raises(OptimizationError, match="returned 1 values"):
        minimize(lambda X: np.zeros(1), [(-1, 1)] * 3)


def test_non_finite_costs_are_infeasible():
    f = lambda X: np.where(X[:, 0] < 0, np.nan, sphere(X))  # noqa: E731
    res = minimize(f, [(-2, 2)] * 3, seed=0)
    assert res.x[0] >= 0 and np.isfinite(res.fun)
    with pytest.raises(OptimizationError, match="non-finite"):
        minimize(lambda X: np.full(len(X), np.nan), [(-1, 1)] * 2, seed=0, max_evals=40)
