"""The able runner's stride with its trunk changed (a measuring probe; changes nothing in src).

Usage (repository root; one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/human_body/every-criterion-able/trunk.py \\
        START.json VARIANT OUT

Solves the library's default problem of the able human body (people's joint angles and swing
knee, people's stride time) at the speed and on the mesh of the stride START.json, from it, with
the body changed by VARIANT, a number or a JSON object: a number (or ``"factor"``) makes the
trunk's three muscle types (rectus abdominis, internal oblique, erector spinae) that many times
as large (their volume fraction; their maximum isometric force follows); ``"lumbar"``:
[stiffness N·m/rad, damping N·m·s/rad] of the lumbar joint's spring–damper in place of the
library's 500 and 5 (``bladelab.runner.joints.LIGAMENTS``); ``"people_weight"``: people's
joint angles in the objective at this weight [1/rad²] instead of the body's 10;
``"stride_time_people"``: false to leave the stride time free. Writes
OUT/solution.json and prints the cost of transport [J/(kg·m)] and the criteria missed.
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


def main(start: str, variant: str, out: str) -> None:
    v = json.loads(variant)
    v = {"factor": float(v)} if isinstance(v, int | float) else v
    data = json.loads(default_runner_params("able", body="human").model_dump_json())
    for name in TRUNK:
        data["muscle_types"][name]["volume_fraction"] *= float(v.get("factor", 1.0))
    if "lumbar" in v:
        from bladelab.runner import joints

        joints.LIGAMENTS["lumbar_extension"] = (0.0, 0.0, *map(float, v["lumbar"]))
    runner = build_runner(runner_params_from_dict(data))
    first = CollocationSolution.read(start)
    settings = CollocationSettings(mesh_intervals=first.settings.mesh_intervals,
                                   speed_m_per_s=first.settings.speed_m_per_s,
                                   stride_time_people=bool(v.get("stride_time_people", True)),
                                   **people_settings("human", v.get("people_weight"),
                                                     kind="able"))
    guess = first.to_guess()
    sol = predict_stride(runner, settings, guess, track=False,
                         model_spec={"model": "able", "body": "human"})
    Path(out).mkdir(parents=True, exist_ok=True)
    sol.write(Path(out) / "solution.json")
    crit = human_running_criteria(sol)
    print(json.dumps({"variant": v, "speed_mps": settings.speed_m_per_s,
                      "converged": sol.converged, "iterations": sol.nlp.iterations,
                      "cost_of_transport_J_per_kg_m": sol.cost_of_transport_J_per_kg_m,
                      "criteria_met": f"{sum(c.met for c in crit)} of {len(crit)}",
                      "missed": [c.line() for c in crit if not c.met]}))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3])
