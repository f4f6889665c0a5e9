"""The warm-started predictive stage with the exact Hessian against L-BFGS (a measuring
probe; changes nothing in src).

Usage (repository root)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/warm_hessian.py \
        {exact,limited-memory} SPEED

Solves the amputee Cat6 stride on the human body (default objective, people's term at the
default weight, mesh 50) at SPEED [m/s] from the shipped 4 m/s stride's primal and dual values,
as ``make bench``'s warm row does, with the Hessian named; prints one JSON line (iterations,
wall and build time [s], objective, IPOPT's function-evaluation times [s], peak memory [MB]).
"""

from __future__ import annotations

import dataclasses
import json
import os
import resource
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")

from bladelab.predict import defaults  # noqa: E402
from bladelab.predict.collocation.settings import CollocationSettings, people_term  # noqa: E402
from bladelab.predict.collocation.solve import predict_stride  # noqa: E402
from bladelab.predict.collocation.starting_guess import make_guess  # noqa: E402
from bladelab.runner import build_runner  # noqa: E402


def main() -> None:
    hessian, speed = sys.argv[1], float(sys.argv[2])
    spec = {"model": "amputee", "blade": "Cat6", "body": "human"}
    runner = build_runner("amputee", blade="Cat6", body="human")
    people = people_term(defaults.people_weight_for("human"))
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=4.0, **people)
    guess = make_guess(runner, "stored", n=50, speed=4.0)
    sol = predict_stride(runner, dataclasses.replace(settings, speed_m_per_s=speed,
                                                     hessian=hessian), guess, model_spec=spec)
    n = sol.nlp
    print(json.dumps({"hessian": hessian, "speed": speed, "converged": sol.converged,
                      "status": n.status, "iterations": n.iterations,
                      "wall_s": round(n.wall_s, 1), "build_s": round(n.timings["build_s"], 1),
                      "objective": n.objective,
                      "timings": {k: round(v, 2) for k, v in n.timings.items()},
                      "maxrss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024}))


if __name__ == "__main__":
    main()
