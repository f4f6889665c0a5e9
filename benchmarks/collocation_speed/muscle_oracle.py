"""What the template's tracking stage spends its iterations on: the muscles or the motion.

Usage (repository root; one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/muscle_oracle.py RECORDS.jsonl

Solves the able runner's tracking stage from the template (the library's default problem:
people's angles and swing knee, 3.5 m/s, 50 intervals) and then the same tracking stage again
from three starts built from the template and that first solution (the "oracle"):

- ``muscles``: the template's coordinates and speeds, the oracle's activations, tendon forces
  and excitations (what a perfect muscle guess would give);
- ``motion``: the oracle's coordinates and speeds, the library's muscle guess (activations
  0.05, tendon forces of static equilibrium);
- ``both``: the oracle's states without its controls or multipliers.

The tracking stage follows its start's angles and force pattern, so ``motion`` and ``both``
solve an easier problem (the oracle's angles are already consistent); ``muscles`` solves the
template's own.

An upper bound of what a better muscle guess (e.g. static optimisation over the template)
could save: if ``muscles`` needs nearly as many iterations as the template, the muscles are not
what the tracking stage spends its iterations on. Appends one JSON line per start: tracking
iterations, objective, wall time [s].
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import sys
import time

from bladelab.predict.collocation import solve
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.solve import predict_stride
from bladelab.runner import build_runner
from bladelab.runner.params import default_runner_params

MESH = 50


class _Tracked(Exception):
    pass


def _tracking_only(runner, settings, guess, spec):
    """The tracking stage's solution and its iterations and wall time [s]."""
    stage_solve, held = solve._solve_stage, {}

    def stop_after_tracking(nlp, x0, settings_, stage, progress, **kw):
        if stage != "tracking":
            raise _Tracked
        t0 = time.perf_counter()
        held["sol"] = sol = stage_solve(nlp, x0, settings_, stage, progress, **kw)
        held["wall_s"] = time.perf_counter() - t0
        return sol

    solve._solve_stage = stop_after_tracking
    try:
        predict_stride(runner, settings, guess, model_spec=spec)
    except _Tracked:
        pass
    finally:
        solve._solve_stage = stage_solve
    sol = held["sol"]
    return sol, solve._stage_info(sol), held["wall_s"]


def main() -> None:
    out = sys.argv[1]
    runner = build_runner(default_runner_params("able", body="human"))
    settings = CollocationSettings(mesh_intervals=MESH, speed_m_per_s=3.5,
                                   **people_settings("human", kind="able"))
    spec = {"model": "able", "body": "human"}
    template = template_guess(runner, speed=3.5, n=MESH)
    oracle_sol, info, wall = _tracking_only(runner, settings, template, spec)
    oracle = dataclasses.replace(oracle_sol.to_guess("oracle"), multipliers=None)
    starts = {
        "template": None,
        "muscles": dataclasses.replace(template, activation=oracle.activation,
                                       tendon_force=oracle.tendon_force,
                                       excitation=oracle.excitation),
        "motion": dataclasses.replace(template, q=oracle.q, qd=oracle.qd),
        "both": dataclasses.replace(oracle, qdd=None, excitation=None, tendon_force_rate=None),
    }
    for name, start in starts.items():
        if start is not None:
            _, info, wall = _tracking_only(runner, settings, start, spec)
        record = {"start": name, "tracking_iterations": info.get("iterations"),
                  "tracking_objective": info.get("objective"), "status": info.get("status"),
                  "wall_s": wall, "date": datetime.date.today().isoformat()}
        with open(out, "a") as f:
            f.write(json.dumps(record) + "\n")
        print(json.dumps(record), flush=True)


if __name__ == "__main__":
    main()
