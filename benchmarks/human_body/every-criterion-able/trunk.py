"""The able runner's stride with stronger trunk muscles (a measuring probe; changes nothing in src).

Usage (repository root; one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/human_body/every-criterion-able/trunk.py \\
        START.json FACTOR OUT

Solves the library's default problem of the able human body (people's joint angles and swing
knee, people's stride time) at the speed and on the mesh of the stride START.json, from it, with
the trunk's three muscle types (rectus abdominis, internal oblique, erector spinae) FACTOR
times as large (their volume fraction; their maximum isometric force follows). Writes
OUT/solution.json and prints the cost of transport [J/(kg·m)], the criteria missed and the
trunk muscles' share.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.runner import build_runner
from bladelab.runner.params import default_runner_params, runner_params_from_dict

TRUNK = ("rect_abd", "int_obl", "erect_sp")


def main(start: str, factor: float, out: str) -> None:
    data = json.loads(default_runner_params("able", body="human").model_dump_json())
    for name in TRUNK:
        data["muscle_types"][name]["volume_fraction"] *= factor
    runner = build_runner(runner_params_from_dict(data))
    first = CollocationSolution.read(start)
    settings = CollocationSettings(mesh_intervals=first.settings.mesh_intervals,
                                   speed_m_per_s=first.settings.speed_m_per_s,
                                   stride_time_people=True,
                                   **people_settings("human", kind="able"))
    guess = first.to_guess()
    sol = predict_stride(runner, settings, guess, track=False,
                         model_spec={"model": "able", "body": "human"})
    Path(out).mkdir(parents=True, exist_ok=True)
    sol.write(Path(out) / "solution.json")
    crit = human_running_criteria(sol)
    print(json.dumps({"factor": factor, "speed_mps": settings.speed_m_per_s,
                      "converged": sol.converged, "iterations": sol.nlp.iterations,
                      "cost_of_transport_J_per_kg_m": sol.cost_of_transport_J_per_kg_m,
                      "criteria_met": f"{sum(c.met for c in crit)} of {len(crit)}",
                      "missed": [c.line() for c in crit if not c.met]}))


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]), sys.argv[3])
