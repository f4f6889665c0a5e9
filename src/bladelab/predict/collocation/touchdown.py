"""How a foot lands: the slide of a collocation stride's contacts at touch-down.

The collocation friction is smooth, ``−μ·Fn·tanh(v/v_t)`` (:mod:`~bladelab.predict.collocation.
contact`): a contact that meets the ground while its material point still moves forward carries
a friction force at its limit (μ times its normal force) until it stops. Every stride of the
human body solved so far lands that way: the loaded contact moves forward at 1–2.5 m/s at the
first loaded node and sticks within one or two mesh intervals, a slide of about a centimetre
that shows as a braking spike at the start of the stance in the horizontal force. People's feet
land with such a spike too (the measured 3.5 m/s trial's force platform: about −0.6 body
weights some 13 ms after touch-down on alternate steps); a shoe's sole and a heel pad take the
foot's speed in shear, which a rigid contact sphere can only take by sliding.

:func:`touchdown_slides` measures it per touch-down: the loaded contact's speed, how long and
how far it slides before it sticks, the leg's strongest braking force meanwhile, and the work
friction takes from the runner over the stride.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.nodes import evaluate_nodes, periodic_runs
from bladelab.predict.collocation.solution import CONTACT_THRESHOLD_N
from bladelab.predict.collocation.stored import runner_from_spec

__all__ = ["LOADED_CONTACT_N", "STICK_SPEED_MPS", "TouchdownSlide", "touchdown_slides"]

#: A contact carrying more than this [N] is on the ground (each contact of a loaded leg).
LOADED_CONTACT_N = 1.0
#: A loaded contact slower than this [m/s] sticks (the forward model's bristle sticks below the
#: same speed: docs/collocation.md, "Dynamic consistency").
STICK_SPEED_MPS = 0.1


@dataclass(frozen=True)
class TouchdownSlide:
    """One touch-down of one leg.

    Attributes
    ----------
    leg
        The leg's name (``intact``/``prosthetic`` or ``left``/``right``).
    node
        The first loaded node (the leg's vertical force above the contact threshold).
    speed_mps
        Horizontal speed of the fastest loaded contact there [m/s] (forward positive).
    slide_ms, slide_mm
        How long [ms] and how far [mm] the leg's loaded contacts slide from that node until
        every one sticks (trapezoidal over the nodes; 0 when the foot lands sticking).
    braking_bw
        The leg's most negative horizontal force while it slides [body weights] (0 without a
        slide).
    """

    leg: str
    node: int
    speed_mps: float
    slide_ms: float
    slide_mm: float
    braking_bw: float


def _fastest_loaded(forces: np.ndarray, speed: np.ndarray, rows: np.ndarray, k: int) -> int:
    """The contact (index into all contacts) among ``rows`` that carries more than
    :data:`LOADED_CONTACT_N` at node ``k`` and moves fastest horizontally; -1 if none does."""
    on = rows[forces[k, rows, 1] > LOADED_CONTACT_N]
    return int(on[np.argmax(np.abs(speed[k, on]))]) if on.size else -1


def touchdown_slides(solution, runner=None, cm=None) -> tuple[list[TouchdownSlide], dict]:
    """Every touch-down of ``solution`` (a
    :class:`~bladelab.predict.collocation.solution.CollocationSolution`) with its slide, and the
    work [J] friction takes from the runner over the stride per leg (``{leg: J}``, ≥ 0: the
    friction power −F·v integrated over the nodes)."""
    runner = runner if runner is not None else runner_from_spec(solution.model_spec)
    cm = cm if cm is not None else build_collocation_model(runner)
    nlp = solution.nlp
    nodes = evaluate_nodes(cm, np.asarray(nlp.q, float), np.asarray(nlp.qd, float),
                           np.asarray(nlp.tendon_force, float),
                           np.asarray(nlp.tendon_force_rate, float))
    n = nodes["forces"].shape[0] - 1  # the last node repeats the first
    forces, speed = nodes["forces"][:n], nodes["point_velocities"][:n, :, 0]
    h = solution.period_s / n
    fx_legs = solution.leg_horizontal_force()[:n]
    loaded_legs = solution.leg_vertical_force()[:n] > CONTACT_THRESHOLD_N
    slides, work = [], {}
    for j, leg in enumerate(solution.leg_names):
        rows = np.flatnonzero(np.asarray(solution.contact_legs) == j)
        work[leg] = float(-h * (forces[:, rows, 0] * speed[:, rows]).sum())
        fastest = [_fastest_loaded(forces, speed, rows, k) for k in range(n)]
        # the fastest loaded contact's speed at each node [m/s] (0 where none is loaded)
        moving = np.array([abs(float(speed[k, c])) if c >= 0 else 0.0
                           for k, c in enumerate(fastest)])
        loaded = loaded_legs[:, j]
        touchdowns = [] if loaded.all() else sorted(k for k, _ in periodic_runs(loaded))
        for k0 in touchdowns:
            steps, dist, braking = 0, 0.0, 0.0
            while steps < n and moving[(k0 + steps) % n] >= STICK_SPEED_MPS:
                k = (k0 + steps) % n
                dist += 0.5 * h * (moving[k] + moving[(k + 1) % n])
                braking = min(braking, float(fx_legs[k, j]) / solution.body_weight_N)
                steps += 1
            first = fastest[k0]
            slides.append(TouchdownSlide(
                leg=leg, node=int(k0), speed_mps=float(speed[k0, first]) if first >= 0 else 0.0,
                slide_ms=1e3 * h * steps, slide_mm=1e3 * dist, braking_bw=braking))
    return slides, work
