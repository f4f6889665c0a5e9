"""A warm start with and without IPOPT's stop at an acceptable level (a measuring probe;
changes nothing in src: it empties ``STALL_STOP_OPTIONS`` in this process for the "full" solve;
the own-speed solve before it keeps the library's options).

Usage (repository root, one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/warm_stop.py CASE [CASE ...]

Cases (``CASES``): a stride at its own speed (the shipped stride, or a committed file solved
again from its primal values with the barrier at 1e-4), then the next speed from its primal and
dual values, once with IPOPT's full convergence (tol 1e-4) and once with the library's
``STALL_STOP_OPTIONS``. Prints and appends to ``warm_stop_records.jsonl`` one JSON line per
case: iterations, wall [s], IPOPT's own time [s], objective, cost of transport [J/(kg·m)], the
dynamics residual [% of the peak force], the largest constraint violation, criteria met, the
objective's relative difference [%] and the largest joint-angle difference [deg].
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

from bladelab.predict import defaults
from bladelab.predict.collocation import ipopt_options
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.runner import build_runner

HERE = Path(__file__).parent
STUDY = "benchmarks/collocation/study-human-toes-2026-12-02"
#: name: (kind, blade, start file or "stored", its speed, the next speed [m/s], mesh, people's
#: stride time)
CASES = {
    "amputee-Cat6-50": ("amputee", "Cat6", "stored", 4.0, 4.2, 50, False),
    "able-50": ("able", None, "stored", 3.5, 3.7, 50, False),
    "amputee-Cat7-100": ("amputee", "Cat7", f"{STUDY}/every-criterion/Cat7-every-criterion.json",
                         4.0, 4.25, 100, True),
    "able-100": ("able", None, f"{STUDY}/every-criterion/able-every-criterion.json",
                 3.75, 4.0, 100, True),
    "amputee-Cat4-100-5": ("amputee", "Cat4", f"{STUDY}/speed-5/Cat4-best.json",
                           5.0, 5.25, 100, True),
}


def solve_row(sol) -> dict:
    """The record's fields of one solve (units in the module docstring)."""
    crit = human_running_criteria(sol)
    return {"status": sol.nlp.status, "iterations": sol.nlp.iterations,
            "wall_s": round(sol.nlp.wall_s, 1),
            "ipopt_own_s": round(sol.nlp.timings.get("ipopt_own_s", float("nan")), 1),
            "objective": sol.nlp.objective,
            "cost_of_transport_J_per_kg_m": sol.cost_of_transport_J_per_kg_m,
            "dynamics_residual_pct": sol.dynamics_residual_pct,
            "max_violation": sol.nlp.max_violation,
            "criteria_met": f"{sum(c.met for c in crit)}/{len(crit)}"}


def full_and_stopped(solve) -> tuple:
    """``solve()`` with ``STALL_STOP_OPTIONS`` emptied, then with the library's; the two
    solutions and their differences (objective [%], largest joint angle [deg])."""
    stop = dict(ipopt_options.STALL_STOP_OPTIONS)
    ipopt_options.STALL_STOP_OPTIONS.clear()
    try:
        full = solve()
    finally:
        ipopt_options.STALL_STOP_OPTIONS.update(stop)
    stopped = solve()
    angle = float(np.max(np.abs(np.degrees(full.nlp.q[:, 3:] - stopped.nlp.q[:, 3:]))))
    return full, stopped, {
        "objective_difference_pct": 100 * (stopped.nlp.objective / full.nlp.objective - 1),
        "largest_angle_difference_deg": angle}


def append_record(path: Path, rec: dict) -> None:
    with open(path, "a", encoding="utf-8") as fh:
        fh.write(json.dumps(rec) + "\n")


def run(name: str) -> dict:
    kind, blade, start, speed, target, mesh, people_time = CASES[name]
    spec = {"model": kind, "blade": blade, "body": "human"}
    runner = build_runner(kind, blade=blade, body="human")
    settings = CollocationSettings(mesh_intervals=mesh, speed_m_per_s=speed,
                                   stride_time_people=people_time,
                                   **people_term(defaults.people_weight_for("human")))
    if start == "stored":
        guess = make_guess(runner, "stored", n=mesh, speed=speed)
    else:
        guess = CollocationSolution.read(start).to_guess()
        settings = dataclasses.replace(settings, warm_start_mu=1e-4)
    own = predict_stride(runner, settings, guess, model_spec=spec)
    if not own.converged:
        return {"case": name, "own_speed": "not converged"}
    nxt = dataclasses.replace(settings, speed_m_per_s=target, warm_start_mu=None)
    full, stopped, diff = full_and_stopped(
        lambda: predict_stride(runner, nxt, own.to_guess(), model_spec=spec))
    rec = {"case": name, "speed": speed, "next_speed": target, "mesh": mesh,
           "own_iterations": own.nlp.iterations, "full": solve_row(full),
           "stopped": solve_row(stopped),
           **diff}
    append_record(HERE / "warm_stop_records.jsonl", rec)
    return rec


if __name__ == "__main__":
    for case in sys.argv[1:] or list(CASES):
        print(json.dumps(run(case)), flush=True)
