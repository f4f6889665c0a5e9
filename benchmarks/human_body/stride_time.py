"""The cost of a stride held at a longer stride time (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/stride_time.py OUT GUESS MIN_STRIDE_S [KIND SPEED]

Solves the predictive stride of the human body (``KIND`` able or amputee with Cat6, default
able at 3.5 m/s) from the stride file ``GUESS`` with the stride time bounded below by
``MIN_STRIDE_S`` [s] (the NLP's period bounds; the library's default lower bound is 0.4 s), so
that the objective's rise says how flat the body's optimum is in cadence. Writes
``OUT/solution.json`` (or ``best_iterate.json``) and prints the summary.
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.dynamics import stride_dynamics
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.predict.collocation.transcription import PERIOD_BOUNDS_S, StrideNLP
from bladelab.runner import build_runner


def main() -> None:
    out, guess_file, t_min = Path(sys.argv[1]), sys.argv[2], float(sys.argv[3])
    kind = sys.argv[4] if len(sys.argv) > 4 else "able"
    speed = float(sys.argv[5]) if len(sys.argv) > 5 else 3.5
    blade = "Cat6" if kind == "amputee" else None
    runner = build_runner(kind, body="human", blade=blade)
    settings = CollocationSettings(speed_m_per_s=speed)
    cm = build_collocation_model(runner)
    dyn = stride_dynamics(cm)
    nlp = StrideNLP(dyn, n=settings.mesh_intervals, speed=speed, weights=settings.weights,
                    period_bounds=(t_min, PERIOD_BOUNDS_S[1]))
    guess = make_guess(runner, guess_file, n=settings.mesh_intervals, speed=speed)
    guess = replace(guess.on_model(runner), multipliers=None)
    if abs(guess.speed - speed) > 1e-9:
        guess = guess.with_speed(speed)
    sol = nlp.solve(nlp.initial_vector(guess), max_iter=settings.max_iter, tol=settings.tol,
                    speed=speed)
    result = CollocationSolution.from_nlp(
        runner, sol, stage="predictive", tracking=None,
        metabolic_energy_J=nlp.energy_and_distance(sol)[0], settings=settings,
        model_spec={"model": kind, "blade": blade, "body": "human"},
        guess_source=f"{guess.source}, stride ≥ {t_min:g} s", cm=cm)
    out.mkdir(parents=True, exist_ok=True)
    result.write(out / ("solution.json" if result.converged else "best_iterate.json"))
    print(json.dumps(result.summary() | {"objective": sol.objective}))


if __name__ == "__main__":
    main()
