"""Probe: a start stride of the design study on the human body (changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/design/human-body-2026-11-29/human_start.py \\
        BLADE START PEOPLE_WEIGHT OUT.json [track|notrack] [backward|trapezoidal] [MODEL]
        [MIN_STRIDE_S] [HESSIAN] [STEP_PHASE_TOLERANCE]

BLADE ``sphere`` (the Cat4 contact sphere) or ``centre`` (the design box's centre blade, as the
collocation evaluator generates it, 10⁵ N/m soles); START a collocation solution file (mapped
onto the runner by name); PEOPLE_WEIGHT the weight of people's joint angles [1/rad²]; ``track``:
a tracking stage of START first; the blade's joints by backward Euler (default) or the
trapezoidal rule; MODEL ``transfemoral`` (default) or ``amputee``; MIN_STRIDE_S the stride
time's lower bound [s] (default the library's, 0.4 s); HESSIAN ``limited-memory`` (default) or
``exact``; STEP_PHASE_TOLERANCE the alternating-steps constraint's tolerance [fraction of the
stride] (default ``none``: free). The human body at 4 m/s,
mesh 50, swing clearance 2 cm; prints the summary, the gait's warnings, the criteria of people's
running and seed 002's responses, and writes OUT.json.
"""

from __future__ import annotations

import json
import sys
import time

from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.design.predicted import stride_responses
from bladelab.design.space import default_design_space
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.predict.collocation.transcription import PERIOD_BOUNDS_S, StrideNLP


def main(blade_kind: str, start: str, weight: str, out: str, track: str = "notrack",
         rule: str = "backward", model: str = "transfemoral", min_stride: str = "0.4",
         hessian: str = "limited-memory", step_tol: str = "none") -> None:
    speed = 4.0
    # the stride time's bounds are the NLP's keyword default (not a setting)
    StrideNLP.__init__.__kwdefaults__["period_bounds"] = (float(min_stride), PERIOD_BOUNDS_S[1])
    if blade_kind == "centre":
        space = default_design_space()
        blade = CollocationEvaluator().blade_spec(space.point([0.0] * len(space.names)))
        spec = {"model": model, "blade": blade["name"], "blade_spec": blade, "body": "human"}
        extra = {"blade_backward_euler": rule != "trapezoidal"}
    else:
        spec, extra = {"model": model, "blade": "Cat4", "body": "human"}, {}
    runner = runner_from_spec(spec)
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=speed,
                                   swing_clearance_m=0.02, hessian=hessian, **extra,
                                   step_phase_tolerance=None if step_tol == "none"
                                   else float(step_tol),
                                   **people_term(float(weight)))
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, make_guess(runner, start, n=50, speed=speed),
                         model_spec=spec, track=track == "track")
    print(f"wall {time.perf_counter() - t0:.0f} s")
    print(json.dumps(sol.summary()))
    print(sol.gait_warnings() if sol.converged else "not converged")
    for c in human_running_criteria(sol):
        print(c.met, c.name, c.value_text())
    if sol.converged and blade_kind == "centre":
        print(json.dumps(stride_responses(sol, runner)))
    sol.write(out)


if __name__ == "__main__":
    main(*sys.argv[1:11])
