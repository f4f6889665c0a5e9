"""Does the stride-time column make IPOPT's linear algebra slow? (a measuring probe)

Usage (repository root)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/fixed_period.py free|fixed [OUT]

The stride time T enters every defect constraint (h = T/n): a dense column of the constraint
Jacobian, which can make the KKT factorisation fill in. This solves the able runner's 3.5 m/s
predictive stride on the human body from the shipped stride's primal values moved by 0.1 %
(seeded), once with T free and once with T fixed at its start (period bounds equal: IPOPT
removes a fixed variable, and with it the column), and prints IPOPT's iterations, wall time
and the time in our functions, as one JSON line; with ``OUT``, writes the stride there
(``OUT/solution.json``).
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.dynamics import stride_dynamics
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.predict.collocation.transcription import PERIOD_BOUNDS_S, StrideNLP
from bladelab.runner import build_runner


def main() -> None:
    mode = sys.argv[1]
    runner = build_runner("able", body="human")
    cm = build_collocation_model(runner)
    dyn = stride_dynamics(cm)
    guess = replace(make_guess(runner, "stored", n=50, speed=3.5), multipliers=None)
    bounds = (guess.period, guess.period) if mode == "fixed" else PERIOD_BOUNDS_S
    nlp = StrideNLP(dyn, n=50, speed=3.5, period_bounds=bounds)
    x0 = nlp.initial_vector(guess)
    x0 = x0 * (1.0 + 1e-3 * np.random.default_rng(0).standard_normal(x0.size))
    sol = nlp.solve(x0, max_iter=3000)
    if len(sys.argv) > 2:
        out = Path(sys.argv[2])
        out.mkdir(parents=True, exist_ok=True)
        CollocationSolution.from_nlp(
            runner, sol, stage="predictive", tracking=None,
            metabolic_energy_J=nlp.energy_and_distance(sol)[0],
            settings=CollocationSettings(speed_m_per_s=3.5),
            model_spec={"model": "able", "blade": None, "body": "human"},
            guess_source=f"{guess.source}, primal values moved by 0.1 %, stride time {mode}",
            cm=cm).write(out / "solution.json")
    functions = sum(v for k, v in sol.timings.items() if k.startswith("nlp_"))
    solve_s = sol.wall_s - sol.timings["build_s"]
    print(json.dumps({"mode": mode, "status": sol.status, "iterations": sol.iterations,
                      "objective": sol.objective, "build_s": sol.timings["build_s"],
                      "solve_s": solve_s, "functions_s": functions,
                      "ipopt_own_ms_per_iteration":
                          1e3 * (solve_s - functions) / max(sol.iterations, 1)}))


if __name__ == "__main__":
    main()
