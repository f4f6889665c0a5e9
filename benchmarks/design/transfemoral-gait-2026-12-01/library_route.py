"""Probe: the transfemoral runner on the human body started from the transtibial runner's
stride as ``bladelab predict --guess`` maps it (changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/design/transfemoral-gait-2026-12-01/library_route.py \\
        OUT.json {pred|track|map} [grounded]

The design box's centre blade by backward Euler, 4 m/s, mesh 50, people's angles at weight 10,
swing clearance 2 cm, free steps. ``pred``: the predictive stage only (the library's route for a
collocation solution as the guess); ``track``: a tracking stage first; ``map``: print the mapped
start's lowest contacts and stop. ``grounded``: the earlier mapping (every node lowered until its
lowest contact is 1 cm deep). Prints the summary; writes OUT.json.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

import bladelab.predict.collocation.stored as stored
from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.design.space import default_design_space
from bladelab.predict.collocation.guess import prosthetic_stride_on
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.runner.model import contact_heights

START = "benchmarks/design/human-body-2026-11-29/transtibial-centre-people10.json"


def main(out: str, mode: str, *flags: str) -> None:
    space = default_design_space()
    blade = CollocationEvaluator().blade_spec(space.point([0.0] * len(space.names)))
    spec = {"model": "transfemoral", "blade": blade["name"], "blade_spec": blade,
            "body": "human"}
    runner = stored.runner_from_spec(spec)
    if "grounded" in flags:
        source = CollocationSolution.read(START)
        guess = prosthetic_stride_on(runner, source.to_guess(f"collocation solution {START}"))
    else:
        guess = make_guess(runner, START, n=50, speed=4.0)
    low = np.array([contact_heights(runner, q).min() for q in guess.q])
    print(f"start: {guess.source}; lowest contact {low.min():.3f}..{low.max():.3f} m, "
          f"{int((low > 0.002).sum())} nodes in the air")
    if mode == "map":
        return
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=4.0,
                                   blade_backward_euler=True, swing_clearance_m=0.02,
                                   **people_term(10.0))
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, guess, model_spec=spec, track=mode == "track")
    print(f"wall {time.perf_counter() - t0:.0f} s", json.dumps(sol.summary()))
    print("objective", sol.nlp.objective)
    sol.write(out)


if __name__ == "__main__":
    main(*sys.argv[1:])
