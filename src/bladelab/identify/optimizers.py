"""Bounded black-box optimisers behind one ask/tell interface, and the :func:`minimize` driver.

Every optimiser works on a box ``lower ≤ x ≤ upper`` and never proposes a candidate outside it:

- :class:`ParticleSwarm`: our own particle swarm (seed 000 §2.3: 20 particles × 30 iterations).
- :class:`CMAES`: CMA-ES from the ``cma`` package, searching the box scaled to the unit cube,
  seeded through a :class:`numpy.random.Generator` and writing no log files.

An optimiser is used as ``X = opt.ask()`` → evaluate all rows of ``X`` at once → ``opt.tell(X, f)``
until ``opt.stop()``; the caller owns evaluation, so one iteration's candidates can be simulated as
one batch. :func:`minimize` runs that loop and optionally polishes the best point with a bounded
local method (:func:`polish`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import Literal, Protocol

import numpy as np

from bladelab.errors import OptimizationError

FunBatch = Callable[[np.ndarray], np.ndarray]
"""A batch objective: ``(n, d)`` candidates -> ``(n,)`` costs (non-finite = infeasible)."""


def as_bounds(bounds) -> np.ndarray:
    """Validate ``bounds`` and return a float array of shape (d, 2) (columns lower, upper).

    Raises
    ------
    OptimizationError
        A bound is not finite, or a lower bound is not below its upper bound.
    """
    arr = np.asarray(bounds, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1:
        raise OptimizationError(
            f"bounds have shape {arr.shape}, expected (d, 2) rows of (lower, upper)", where="bounds"
        )
    if not np.all(np.isfinite(arr)):
        raise OptimizationError("bounds must be finite numbers", where="bounds")
    bad = np.flatnonzero(arr[:, 0] >= arr[:, 1])
    if bad.size:
        i = int(bad[0])
        raise OptimizationError(
            f"parameter {i}: lower bound {arr[i, 0]:.6g} is not below upper bound {arr[i, 1]:.6g}",
            where="bounds", hint="give each parameter as (min, max) with min < max",
        )
    return arr


def _generator(seed: int | np.random.Generator | None) -> np.random.Generator:
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None:
        raise OptimizationError("a seed is required (an int or a numpy Generator)", where="seed")
    return np.random.default_rng(seed)


def _clean_costs(f, n: int) -> np.ndarray:
    f = np.asarray(f, dtype=float).reshape(-1)
    if f.shape != (n,):
        raise OptimizationError(
            f"the objective returned {f.shape[0]} values for {n} candidates", where="fun_batch",
            hint="fun_batch must map an (n, d) array to an (n,) array",
        )
    return np.where(np.isfinite(f), f, np.inf)


class AskTellOptimizer(Protocol):
    """What every optimiser offers (all arrays in the caller's parameter units)."""

    def ask(self) -> np.ndarray: ...  # (n, d) candidates inside the bounds

    def tell(self, X: np.ndarray, f: np.ndarray) -> None: ...

    def stop(self) -> bool: ...

    @property
    def best_x(self) -> np.ndarray: ...

    @property
    def best_f(self) -> float: ...


class ParticleSwarm:
    """Global-best particle swarm optimisation in a box, with reflecting walls.

    Update of particle i (all arrays element-wise, r1, r2 ~ U(0, 1) per coordinate)::

        v ← w·v + c1·r1·(p_i − x) + c2·r2·(g − x)      (then |v| ≤ v_max per coordinate)
        x ← x + v                                      (then reflected into the box)

    with inertia ``w``, cognitive ``c1`` and social ``c2`` coefficients (defaults: Clerc's
    constriction values w = 0.7298, c1 = c2 = 1.49618), p_i the particle's best position, g the
    swarm's best position. A coordinate that crosses a wall is mirrored back into the box and its
    velocity reversed (``boundary="reflect"``), or set on the wall with zero velocity
    (``boundary="clip"``); it never wraps around to the other side. The velocity is limited to
    ``max_velocity`` × (upper − lower) so that one reflection always lands inside.

    Parameters
    ----------
    bounds
        (d, 2) lower and upper bounds.
    n_particles, n_iterations
        Swarm size and number of iterations (each iteration evaluates every particle once; the
        first evaluates the initial positions). Seed 000: 20 × 30 = 600 evaluations.
    inertia, cognitive, social
        w, c1, c2 above.
    max_velocity
        Velocity limit as a fraction of the box width (0 < max_velocity ≤ 1).
    boundary
        ``"reflect"`` or ``"clip"``.
    seed
        Seed or Generator; initial positions are uniform in the box, initial velocities uniform in
        ±v_max/2; the same seed gives the same history.
    initial
        Optional (k, d) positions used for the first k particles (e.g. a previous optimum).
    """

    def __init__(
        self,
        bounds,
        *,
        n_particles: int = 20,
        n_iterations: int = 30,
        inertia: float = 0.7298,
        cognitive: float = 1.49618,
        social: float = 1.49618,
        max_velocity: float = 0.5,
        boundary: Literal["reflect", "clip"] = "reflect",
        seed: int | np.random.Generator | None = 0,
        initial: np.ndarray | None = None,
    ) -> None:
        self.bounds = as_bounds(bounds)
        if n_particles < 2 or n_iterations < 1:
            raise OptimizationError(
                f"n_particles={n_particles}, n_iterations={n_iterations}: need ≥ 2 particles and ≥ 1 iteration",
                where="pso",
            )
        if boundary not in ("reflect", "clip"):
            raise OptimizationError(f"unknown boundary handling {boundary!r}", where="pso.boundary",
                                    hint="use 'reflect' or 'clip'")
        if not 0.0 < max_velocity <= 1.0:
            raise OptimizationError(f"max_velocity={max_velocity} must be in (0, 1]", where="pso.max_velocity")
        self.n_particles = int(n_particles)
        self.n_iterations = int(n_iterations)
        self.inertia, self.cognitive, self.social = float(inertia), float(cognitive), float(social)
        self.boundary = boundary
        self._rng = _generator(seed)
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        self._width = hi - lo
        self._vmax = max_velocity * self._width
        d = len(lo)
        self.x = lo + self._rng.random((self.n_particles, d)) * self._width
        if initial is not None:
            init = np.clip(np.atleast_2d(np.asarray(initial, dtype=float)), lo, hi)
            k = min(len(init), self.n_particles)
            self.x[:k] = init[:k]
        self.v = (self._rng.random((self.n_particles, d)) - 0.5) * self._vmax
        self.p = self.x.copy()
        self.pf = np.full(self.n_particles, np.inf)
        self._g = self.x[0].copy()
        self._gf = math.inf
        self.iteration = 0

    def ask(self) -> np.ndarray:
        """The current positions, shape (n_particles, d)."""
        return self.x.copy()

    def tell(self, X: np.ndarray, f: np.ndarray) -> None:
        """Record the costs of the positions returned by :meth:`ask` and move the swarm."""
        f = _clean_costs(f, self.n_particles)
        better = f < self.pf
        self.p[better] = X[better]
        self.pf[better] = f[better]
        i = int(np.argmin(self.pf))
        if self.pf[i] < self._gf:
            self._gf = float(self.pf[i])
            self._g = self.p[i].copy()
        self.iteration += 1
        if not self.stop():
            self._move()

    def _move(self) -> None:
        shape = self.x.shape
        r1, r2 = self._rng.random(shape), self._rng.random(shape)
        v = (self.inertia * self.v + self.cognitive * r1 * (self.p - self.x)
             + self.social * r2 * (self._g - self.x))
        v = np.clip(v, -self._vmax, self._vmax)
        x = self.x + v
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        below, above = x < lo, x > hi
        if self.boundary == "reflect":
            x = np.where(below, 2 * lo - x, x)
            x = np.where(above, 2 * hi - x, x)
            v = np.where(below | above, -v, v)
        else:
            v = np.where(below | above, 0.0, v)
        self.x = np.clip(x, lo, hi)  # guards rounding only: |v| ≤ width, so one mirror suffices
        self.v = v

    def stop(self) -> bool:
        """True after ``n_iterations`` iterations."""
        return self.iteration >= self.n_iterations

    @property
    def best_x(self) -> np.ndarray:
        """Best position found so far."""
        return self._g.copy()

    @property
    def best_f(self) -> float:
        """Best cost found so far."""
        return self._gf


class CMAES:
    """CMA-ES (``cma`` package) on the box, scaled to the unit cube; no files, no console output.

    The search runs in u = (x − lower)/(upper − lower) ∈ [0, 1]^d with ``cma``'s bound
    transformation, so every asked candidate is inside the box. Normal samples come from a
    :class:`numpy.random.Generator` built from ``seed`` (``cma``'s own seeding of NumPy's global
    generator is switched off). Options ``verbose=-9``, ``verb_log=0``, ``verb_disp=0``: nothing is
    printed and no ``outcmaes/`` folder is written.

    Parameters
    ----------
    bounds
        (d, 2) lower and upper bounds (d ≥ 2 for ``cma``; a 1-D problem is padded internally).
    popsize
        Candidates per iteration (``cma``'s default 4 + 3·ln d when None).
    max_evals
        Evaluation budget; the optimiser stops once it is reached (or on ``cma``'s own criteria).
    sigma0
        Initial step size in unit-cube coordinates.
    x0
        Initial mean in the caller's units (the box centre when None).
    seed
        Seed or Generator.
    """

    def __init__(
        self,
        bounds,
        *,
        popsize: int | None = None,
        max_evals: int = 600,
        sigma0: float = 0.3,
        x0: np.ndarray | None = None,
        seed: int | np.random.Generator | None = 0,
    ) -> None:
        import cma  # imported lazily: it is only needed when CMA-ES is chosen

        self.bounds = as_bounds(bounds)
        self._d = len(self.bounds)
        self._pad = self._d == 1  # cma does not run 1-D problems
        rng = _generator(seed)
        lo, width = self.bounds[:, 0], self.bounds[:, 1] - self.bounds[:, 0]
        self._lo, self._width = lo, width
        u0 = np.full(self._d, 0.5) if x0 is None else np.clip((np.asarray(x0, float) - lo) / width, 0, 1)
        if self._pad:
            u0 = np.append(u0, 0.5)
        opts = {
            "bounds": [0.0, 1.0],
            "maxfevals": int(max_evals),
            "seed": float("nan"),  # never touch NumPy's global generator
            "randn": lambda *shape: rng.standard_normal(shape),
            "verbose": -9,
            "verb_log": 0,
            "verb_disp": 0,
            "verb_filenameprefix": "",
            "tolfun": 1e-12,
            "tolx": 1e-9,
        }
        if popsize is not None:
            opts["popsize"] = int(popsize)
        self._es = cma.CMAEvolutionStrategy(u0.tolist(), float(sigma0), opts)
        self.max_evals = int(max_evals)
        self.evaluations = 0
        self._best_x = self._from_unit(np.asarray([u0]))[0]
        self._best_f = math.inf
        self._asked: list[np.ndarray] = []

    def _from_unit(self, U: np.ndarray) -> np.ndarray:
        U = np.clip(np.asarray(U, dtype=float)[:, : self._d], 0.0, 1.0)
        return self._lo + U * self._width

    def ask(self) -> np.ndarray:
        """The next population, shape (popsize, d), inside the box."""
        self._asked = self._es.ask()
        return self._from_unit(np.asarray(self._asked))

    def tell(self, X: np.ndarray, f: np.ndarray) -> None:
        """Record the costs of the population returned by :meth:`ask`."""
        f = _clean_costs(f, len(self._asked))
        self.evaluations += len(f)
        i = int(np.argmin(f))
        if f[i] < self._best_f:
            self._best_f, self._best_x = float(f[i]), np.asarray(X[i], dtype=float).copy()
        finite_max = np.max(f[np.isfinite(f)]) if np.any(np.isfinite(f)) else 1e300
        penalised = np.where(np.isfinite(f), f, 10.0 * abs(finite_max) + 1e3)
        self._es.tell(self._asked, penalised.tolist())

    def stop(self) -> bool:
        """True when the budget is spent or ``cma`` reports convergence."""
        return self.evaluations >= self.max_evals or bool(self._es.stop())

    @property
    def best_x(self) -> np.ndarray:
        """Best position found so far."""
        return self._best_x.copy()

    @property
    def best_f(self) -> float:
        """Best cost found so far."""
        return self._best_f


@dataclasses.dataclass(frozen=True)
class OptimizeResult:
    """Outcome of :func:`minimize`.

    Attributes
    ----------
    x
        Best parameters found (caller's units).
    fun
        Cost at ``x``.
    evaluations
        Objective evaluations used (all candidates, including the polish).
    iterations
        Optimiser iterations (batches) before the polish.
    history_evaluations, history_best
        After each batch: evaluations so far and the best cost so far (monotone non-increasing).
    optimizer
        ``"pso"`` or ``"cmaes"`` (``+polish`` when polished).
    seed
        The seed given.
    wall_s
        Wall-clock time [s].
    """

    x: np.ndarray
    fun: float
    evaluations: int
    iterations: int
    history_evaluations: np.ndarray
    history_best: np.ndarray
    optimizer: str
    seed: int | None
    wall_s: float

    def to_dict(self) -> dict:
        """JSON-ready dictionary."""
        return {
            "x": [float(v) for v in self.x],
            "fun": float(self.fun),
            "evaluations": int(self.evaluations),
            "iterations": int(self.iterations),
            "history_evaluations": [int(v) for v in self.history_evaluations],
            "history_best": [float(v) for v in self.history_best],
            "optimizer": self.optimizer,
            "seed": self.seed,
            "wall_s": float(self.wall_s),
        }


def make_optimizer(
    optimizer: str,
    bounds,
    *,
    seed: int | np.random.Generator,
    max_evals: int | None = None,
    n_particles: int = 20,
    popsize: int | None = None,
    x0: np.ndarray | None = None,
) -> AskTellOptimizer:
    """Build an ask/tell optimiser by name (``"pso"`` or ``"cmaes"``).

    ``max_evals`` (default 600, seed 000's budget) becomes ``max_evals // n_particles`` PSO
    iterations, or CMA-ES's ``maxfevals``.
    """
    budget = 600 if max_evals is None else int(max_evals)
    if budget < 1:
        raise OptimizationError(f"max_evals={budget} must be positive", where="max_evals")
    if optimizer == "pso":
        return ParticleSwarm(bounds, n_particles=n_particles,
                             n_iterations=max(1, budget // n_particles), seed=seed, initial=x0)
    if optimizer == "cmaes":
        return CMAES(bounds, popsize=popsize, max_evals=budget, seed=seed, x0=x0)
    raise OptimizationError(f"unknown optimizer {optimizer!r}", where="optimizer", hint="use 'pso' or 'cmaes'")


def polish(
    fun_batch: FunBatch,
    bounds,
    x0: np.ndarray,
    *,
    max_evals: int = 120,
    rel_step: float = 1e-4,
) -> tuple[np.ndarray, float, int]:
    """Bounded local refinement by L-BFGS-B, gradients by central differences in one batch.

    The search runs in unit-cube coordinates; each gradient evaluation is one batch call with the
    point and its 2·d central-difference neighbours (steps ``rel_step`` × box width, pulled inside
    the box at a wall). Returns ``(x, f, evaluations)``; never returns a point worse than ``x0``.
    """
    from scipy.optimize import minimize as _scipy_minimize

    b = as_bounds(bounds)
    lo, width = b[:, 0], b[:, 1] - b[:, 0]
    d = len(lo)
    count = [0]
    best = [np.asarray(x0, float).copy(), math.inf]

    def fun_grad(u: np.ndarray) -> tuple[float, np.ndarray]:
        u = np.clip(u, 0.0, 1.0)
        h = np.full(d, rel_step)
        plus = np.minimum(u + h, 1.0)
        minus = np.maximum(u - h, 0.0)
        U = np.vstack([u, u + np.diag(plus - u), u + np.diag(minus - u)])
        f = _clean_costs(fun_batch(lo + U * width), len(U))
        count[0] += len(U)
        if f[0] < best[1]:
            best[0], best[1] = lo + u * width, float(f[0])
        if not np.all(np.isfinite(f)):
            return float(f[0]) if np.isfinite(f[0]) else 1e300, np.zeros(d)
        grad = (f[1 : d + 1] - f[d + 1 :]) / np.maximum(plus - minus, 1e-300)
        return float(f[0]), grad

    u0 = np.clip((np.asarray(x0, float) - lo) / width, 0.0, 1.0)
    max_iter = max(1, max_evals // (2 * d + 1))
    _scipy_minimize(fun_grad, u0, jac=True, method="L-BFGS-B", bounds=[(0.0, 1.0)] * d,
                    options={"maxiter": max_iter, "maxfun": max_iter, "ftol": 1e-12, "gtol": 1e-10})
    return best[0], best[1], count[0]


def minimize(
    fun_batch: FunBatch,
    bounds,
    *,
    optimizer: Literal["pso", "cmaes"] = "pso",
    polish: bool = False,
    seed: int | np.random.Generator = 0,
    max_evals: int | None = None,
    n_particles: int = 20,
    popsize: int | None = None,
    x0: np.ndarray | None = None,
    polish_max_evals: int = 120,
    progress: bool = False,
) -> OptimizeResult:
    """Minimise a batch objective in a box.

    Parameters
    ----------
    fun_batch
        ``(n, d) -> (n,)``; called once per iteration with all of that iteration's candidates.
        Non-finite costs count as infeasible (+inf).
    bounds
        (d, 2) lower and upper bounds.
    optimizer
        ``"pso"`` (:class:`ParticleSwarm`) or ``"cmaes"`` (:class:`CMAES`).
    polish
        Follow with :func:`polish` (bounded L-BFGS-B), ``polish_max_evals`` evaluations at most.
    seed
        Seed or Generator (same seed, same result).
    max_evals
        Evaluation budget of the global phase (default 600 = 20 particles × 30 iterations).
    n_particles, popsize
        PSO swarm size; CMA-ES population size.
    x0
        Optional starting point (first PSO particle, CMA-ES initial mean).
    progress
        Show a tqdm progress bar over iterations.

    Raises
    ------
    OptimizationError
        Bad bounds or options, or every evaluation was non-finite.
    """
    t0 = time.perf_counter()
    opt = make_optimizer(optimizer, bounds, seed=seed, max_evals=max_evals,
                         n_particles=n_particles, popsize=popsize, x0=x0)
    b = as_bounds(bounds)
    evals, iters = 0, 0
    hist_e: list[int] = []
    hist_f: list[float] = []
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(desc=f"{optimizer}", unit="it", leave=False)
    try:
        while not opt.stop():
            X = opt.ask()
            f = _clean_costs(fun_batch(X), len(X))
            opt.tell(X, f)
            evals += len(X)
            iters += 1
            hist_e.append(evals)
            hist_f.append(opt.best_f)
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    x, fx = opt.best_x, opt.best_f
    if not math.isfinite(fx):
        raise OptimizationError(
            f"all {evals} evaluations returned non-finite costs", where=optimizer,
            hint="check the bounds: the simulation may diverge everywhere inside them",
        )
    name = optimizer
    if polish:
        xp, fp, n = polish_fn(fun_batch, b, x, max_evals=polish_max_evals)
        evals += n
        if fp < fx:
            x, fx = xp, fp
        hist_e.append(evals)
        hist_f.append(fx)
        name += "+polish"
    seed_out = int(seed) if isinstance(seed, (int, np.integer)) else None
    return OptimizeResult(
        x=np.asarray(x, float), fun=float(fx), evaluations=evals, iterations=iters,
        history_evaluations=np.asarray(hist_e, dtype=int), history_best=np.asarray(hist_f),
        optimizer=name, seed=seed_out, wall_s=time.perf_counter() - t0,
    )


polish_fn = polish  # ``minimize``'s ``polish`` flag shadows the function name inside it
