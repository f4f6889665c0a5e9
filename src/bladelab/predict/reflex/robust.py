"""Robust evaluation of a reflex controller: jittered copies of its parameters.

A candidate's cost with ``ObjectiveSettings.robust_samples`` = n > 1 is the mean over the
nominal simulation and n − 1 copies (:func:`robust_copies`): the parameters moved by
``robust_jitter`` (relative) along seeded directions, and with ``robust_speed_change`` s > 0
started at (1 ± s) × the initial speed, and with ``robust_push`` p > 0 pushed once in mid-run
(forward speed times 1 ± p at a seeded time), and with ``robust_half_step`` the last copy
runs at half the time step. The directions and push times are the same for every candidate of a
generation (:func:`generation_jitter_seed`: fixed for the run, or new every generation).
:func:`bladelab.predict.reflex.verify.verify_solution` checks along other directions
(:data:`VERIFY_JITTER_SEED`).
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from bladelab.predict.reflex.controller import ControllerLayout
from bladelab.predict.reflex.objective import (
    Evaluation,
    ObjectiveSettings,
    push_window,
    simulate_controlled,
)
from bladelab.runner.model import RunnerModel

__all__ = [
    "OBJECTIVE_JITTER_SEED",
    "VERIFY_JITTER_SEED",
    "generation_jitter_seed",
    "jittered_parameters",
    "push_times",
    "robust_copies",
    "robust_evaluation",
]

#: Seed of the directions of the objective's jittered copies (``robust_samples``).
OBJECTIVE_JITTER_SEED = 20261121
#: Seed of :func:`~bladelab.predict.reflex.verify.verify_solution`'s copies: other directions than the objective's, so that a
#: solution optimised to survive its copies is checked on copies it has not seen (measured on
#: 2026-11-26: a run that survived its 4 objective copies at 1e-3 fell in 5 of 8 others).
VERIFY_JITTER_SEED = 20261126
#: Appended to a copies' seed for their push times (a stream apart from their directions).
PUSH_STREAM = 1


def jittered_parameters(x: np.ndarray, n: int, jitter: float,
                        seed: int | Sequence[int] = OBJECTIVE_JITTER_SEED, *,
                        names: Sequence[str] | None = None,
                        moved: np.ndarray | None = None) -> list[np.ndarray]:
    """``n`` copies of ``x`` moved by ``jitter`` (relative; absolute 1e-3·jitter near zero)
    along directions seeded by ``seed`` (the same for every candidate given the same seed).

    With ``names`` (the layout's parameter names) each parameter's moves are drawn from
    ``seed`` and its name, so they do not depend on which other parameters the layout has or
    in what order; ``moved`` (bool per parameter, default all) leaves the others unmoved."""
    scale = jitter * (np.abs(x) + 1e-3)
    if names is None:
        rng = np.random.default_rng(seed)
        z = np.stack([rng.standard_normal(x.shape) for _ in range(n)]) if n else np.zeros((0,))
    else:
        base = np.atleast_1d(seed).tolist()
        z = np.stack([np.random.default_rng([*base, zlib.crc32(name.encode())]).standard_normal(n)
                      for name in names], axis=1)
    if moved is not None:
        scale = np.where(moved, scale, 0.0)
    return [x + scale * z[k] for k in range(n)]


def generation_jitter_seed(settings: ObjectiveSettings, run_seed: int,
                           generation: int) -> int | list[int]:
    """The seed of the robust copies' directions in ``generation`` (0: the warm start's
    evaluation): the objective's fixed seed, or with ``robust_directions="per-generation"`` one
    of the run's seed and the generation (new directions every generation, the same on resume)."""
    if settings.robust_directions == "per-generation":
        return [OBJECTIVE_JITTER_SEED, int(run_seed), int(generation)]
    return OBJECTIVE_JITTER_SEED


def robust_copies(x: np.ndarray, settings: ObjectiveSettings,
                  seed: int | Sequence[int] = OBJECTIVE_JITTER_SEED,
                  ) -> list[tuple[np.ndarray, ObjectiveSettings]]:
    """The ``settings.robust_samples`` − 1 copies of a candidate: its parameters jittered
    (:func:`jittered_parameters`); with ``robust_speed_change`` s > 0 the initial speed [m/s]
    times 1 + s, 1 − s, 1 + s, ...; with ``robust_push`` p > 0 a push changing the forward
    speed by +p, −p, +p, ... (relative) at times drawn uniformly in
    :func:`~bladelab.predict.reflex.objective.push_window` from ``seed``; with
    ``robust_half_step`` the last copy at half the time step (nominal settings otherwise)."""
    n = settings.robust_samples - 1
    xs = jittered_parameters(x, n, settings.robust_jitter, seed)
    s, p = settings.robust_speed_change, settings.robust_push
    v0 = settings.start_speed
    times = push_times(n, settings.duration, seed)
    copies = []
    for k, xj in enumerate(xs):
        sign = 1.0 if k % 2 == 0 else -1.0
        changes = {}
        if s > 0:
            changes["initial_speed"] = v0 * (1 + sign * s)
        if p > 0:
            changes["push"] = (float(times[k]), sign * p)
        if settings.robust_half_step and k == n - 1:
            changes["dt"] = settings.dt / 2
        copies.append((xj, replace(settings, **changes) if changes else settings))
    return copies


def push_times(n: int, duration: float, seed: int | Sequence[int] = OBJECTIVE_JITTER_SEED,
               ) -> np.ndarray:
    """``n`` push times [s], uniform in :func:`~bladelab.predict.reflex.objective.push_window`
    of a ``duration`` [s] simulation, drawn from ``seed`` (independently of the copies' jitter
    directions)."""
    lo, hi = push_window(duration)
    rng = np.random.default_rng([*np.atleast_1d(seed).tolist(), PUSH_STREAM])
    return rng.uniform(lo, max(lo, hi), n)


def robust_evaluation(
    nominal: Evaluation, model: RunnerModel, x: np.ndarray, layout: ControllerLayout,
    settings: ObjectiveSettings, seed: int | Sequence[int] = OBJECTIVE_JITTER_SEED,
) -> Evaluation:
    """The nominal evaluation of ``x`` with the cost averaged over ``settings.robust_samples``
    − 1 copies (:func:`robust_copies` with directions seeded by ``seed``; any fall counts)."""
    costs, fell = [nominal.cost], nominal.fell
    for xj, copy_settings in robust_copies(x, settings, seed):
        ev, _ = simulate_controlled(model, xj, layout=layout, settings=copy_settings)
        costs.append(ev.cost)
        fell = fell or ev.fell
    return replace(nominal, cost=float(np.mean(costs)), fell=fell)
