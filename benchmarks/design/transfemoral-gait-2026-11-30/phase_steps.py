"""Probe: the transfemoral runner on the human body led from a gallop towards alternating
steps by narrowing the alternating-steps band one step at a time (changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/design/transfemoral-gait-2026-11-30/phase_steps.py \\
        OUT_PREFIX START.json CLEARANCE_M TOL [TOL ...]

For each tolerance in turn (e.g. 0.33 0.27 0.21 0.15 0.10), the stride at 4 m/s on the design
box's centre blade (mesh 50, the blade by backward Euler, people's angles at weight 10, swing
clearance CLEARANCE_M [m]) with ``CollocationSettings.step_phase_tolerance`` = TOL, started
from the previous tolerance's stride (the first from START.json, e.g.
``../transfemoral-gait-2026-11-29/gallop-myodesis.json``) without a tracking stage. Writes
``OUT_PREFIX-<TOL>.json`` (a best iterate where IPOPT did not converge; the chain goes on from
it) and prints each solve's wall time, summary and criteria of people's running.
"""

from __future__ import annotations

import json
import sys
import time

from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.design.space import default_design_space
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.predict.collocation.stored import runner_from_spec


def main(prefix: str, start: str, clearance: str, *tolerances: str) -> None:
    space = default_design_space()
    blade = CollocationEvaluator().blade_spec(space.point([0.0] * len(space.names)))
    spec = {"model": "transfemoral", "blade": blade["name"], "blade_spec": blade,
            "body": "human"}
    runner = runner_from_spec(spec)
    for tol in tolerances:
        settings = CollocationSettings(
            mesh_intervals=50, speed_m_per_s=4.0, swing_clearance_m=float(clearance),
            blade_backward_euler=True, step_phase_tolerance=float(tol), **people_term(10.0))
        guess = make_guess(runner, start, n=50, speed=4.0)
        t0 = time.perf_counter()
        sol = predict_stride(runner, settings, guess, model_spec=spec, track=False)
        print(f"tolerance {tol}: wall {time.perf_counter() - t0:.0f} s, objective "
              f"{sol.nlp.objective:.4f}", json.dumps(sol.summary()), flush=True)
        for c in human_running_criteria(sol):
            print(" ", c.met, c.name, c.value_text())
        start = f"{prefix}-{tol}.json"
        sol.write(start)


if __name__ == "__main__":
    main(*sys.argv[1:])
