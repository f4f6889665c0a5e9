"""The node-level helpers of a collocation stride (bladelab.predict.collocation.nodes)."""

from __future__ import annotations

import numpy as np

from bladelab.predict.collocation.nodes import force_zigzag_steps, periodic_runs


def _stance(n: int = 60, start: int = 10, length: int = 24, peak: float = 2.5) -> np.ndarray:
    """A periodic vertical force [BW]: one half-sine stance, zero elsewhere."""
    f = np.zeros(n)
    f[start:start + length] = peak * np.sin(np.pi * (np.arange(length) + 0.5) / length)
    return f


def test_a_smooth_stance_and_an_impact_do_not_zigzag():
    f = _stance()
    assert force_zigzag_steps(f, 0.25, 0.05) <= 1
    impact = f.copy()
    impact[11:13] += (1.5, 0.8)  # a landing spike: up, down, then the stance's own rise
    assert force_zigzag_steps(impact, 0.25, 0.05) <= 3


def test_a_force_that_alternates_node_to_node_zigzags_over_the_stance():
    f = _stance()
    zig = f + np.where(f > 0.5, 0.4 * (-1.0) ** np.arange(f.size), 0.0)
    steps = force_zigzag_steps(zig, 0.25, 0.05)
    loaded = periodic_runs(f > 0.5)[0][1]
    assert steps >= loaded - 2
    # below the step size it is not counted; a stance across the period's end is one run
    assert force_zigzag_steps(f + np.where(f > 0.5, 0.1 * (-1.0) ** np.arange(f.size), 0.0),
                              0.25, 0.05) <= 1
    assert force_zigzag_steps(np.roll(zig, 45), 0.25, 0.05) == steps
