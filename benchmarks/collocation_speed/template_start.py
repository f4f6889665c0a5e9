"""Probe: a cold start from the library's template guess (people's running), mesh 50.

Usage (from the repository root)::

    .venv/bin/python benchmarks/collocation_speed/template_start.py MODEL BLADE SPEED OUT [--no-track]

MODEL ``able``, ``amputee`` or ``transfemoral``, BLADE a category or ``none``, SPEED [m/s].
Solves on the human body with people's angles in the objective at the default weight, the
tracking stage first (``--no-track``: the predictive stage straight from the template), writes
the solution to OUT and prints one JSON line: each stage's iterations, wall time and status,
the objective, the summary and the criteria against measured running that the stride misses.
"""

from __future__ import annotations

import json
import sys
import time

from bladelab.predict import defaults
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solve import predict_stride
from bladelab.runner import build_runner


def main(argv: list[str]) -> int:
    model, blade, speed, out = argv[:4]
    track = "--no-track" not in argv[4:]
    speed = float(speed)
    blade = None if blade == "none" else blade
    runner = build_runner(model, blade=blade, body="human")
    stages = []

    def progress(p) -> None:
        if p.event == "end":
            stages.append({"stage": p.stage, "iterations": p.iteration,
                           "wall_s": round(p.elapsed_s, 1), "status": p.message})

    settings = CollocationSettings(speed_m_per_s=speed, mesh_intervals=50,
                                   **people_term(defaults.people_weight_for("human")))
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, template_guess(runner, speed=speed, n=50),
                         model_spec={"model": model, "blade": blade, "body": "human"},
                         progress=progress, track=track)
    sol.write(out)
    missed = [c.line() for c in human_running_criteria(sol) if not c.met]
    print(json.dumps({"model": model, "blade": blade, "speed_mps": speed, "track": track,
                      "wall_s": round(time.perf_counter() - t0, 1), "stages": stages,
                      "objective": sol.nlp.objective, "summary": sol.summary(),
                      "criteria_missed": missed}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
