"""Probe: the two L-BFGS update routes on a 100-interval stride (measuring only).

``prepare FILE OUT`` solves the stored stride FILE again at its own speed from its primal
values (the library's route) and writes the solution with its multipliers to OUT;
``solve ROUTE SPEED FILE`` solves FILE's problem at SPEED [m/s] from FILE (from its primal
and dual values where FILE carries them), ROUTE ``sm`` (IPOPT's default L-BFGS update,
Sherman-Morrison) or ``ext`` (the library's ``PREDICTIVE_LBFGS_OPTIONS``). One JSON line per
solve printed and appended to ``lowrank_records.jsonl`` (``lowrank_update.record``).

    F=benchmarks/collocation/study-human-swing-knee-2026-12-03/speed-4/Cat6-best.json
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/lowrank_mesh100.py \\
        prepare $F /tmp/cat6-100.json
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/lowrank_mesh100.py \\
        solve ext 4.25 /tmp/cat6-100.json
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

from lowrank_update import per_stage, record

from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.stored import runner_from_spec


def solve(route: str, speed: float | None, path: str) -> CollocationSolution:
    if route == "sm":
        per_stage({"predictive": {}})
    stored = CollocationSolution.read(path)
    settings = stored.settings if speed is None else dataclasses.replace(
        stored.settings, speed_m_per_s=speed)
    t0 = time.perf_counter()
    sol = predict_stride(runner_from_spec(stored.model_spec), settings, stored.to_guess(),
                         model_spec=stored.model_spec)
    row = {"case": "mesh 100", "file": Path(path).name, "route": route,
           "start": "primal" if stored.nlp.multipliers is None else "primal-dual",
           "speed_mps": settings.speed_m_per_s, "mesh": settings.mesh_intervals,
           "converged": bool(sol.converged), "iterations": sol.nlp.iterations,
           "wall_s": round(time.perf_counter() - t0, 1),
           "ipopt_own_s": round(sol.nlp.timings.get("ipopt_own_s", 0.0), 1),
           "objective": sol.nlp.objective, "start_objective": stored.nlp.objective}
    record(row)
    return sol


if __name__ == "__main__":
    if sys.argv[1:2] == ["prepare"]:
        solve("ext", None, sys.argv[2]).write(sys.argv[3])
    elif sys.argv[1:2] == ["solve"]:
        solve(sys.argv[2], float(sys.argv[3]), sys.argv[4])
    else:
        sys.exit(__doc__)
