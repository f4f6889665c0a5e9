"""The transfemoral runner wearing the design box's centre blade, from the sphere blade's clean
4 m/s run: the common coordinates and muscle states copied by name, the blade's joints at
their static deflection (``stride_guess.deflected_blade``), predictive stage only.

    python benchmarks/collocation/transfemoral-2026-11-26/multilink_centre.py \\
        benchmarks/collocation/transfemoral-2026-11-26/speed-4.from-transtibial-tracked.json \\
        SOLE_SCALE SPEED OUT.json [KNEE_MOMENT_MIN_NM|none] [trapezoidal|backward-euler]

On 2026-11-26 it made ``src/bladelab/data/runner/collocation/transfemoral-design-centre-4.json``
(the collocation evaluator's default start) in two steps: from the sphere stride with
SOLE_SCALE 0.1, SPEED 4 (trapezoidal), then from that stride with ``none backward-euler``;
SOLE_SCALE 1 (the generator's 10⁶ N/m soles) gave the 12-BW gait of docs/design.md.
"""

from __future__ import annotations

import json
import sys
import time

from bladelab.blade.spec import spec_from_dict
from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.design.predicted import stride_responses
from bladelab.design.space import default_design_space
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.runner import build_runner


def main(source: str, sole_scale: str, speed: str, out: str, knee: str | None = None,
         blade_rule: str = "trapezoidal") -> None:
    space = default_design_space()
    centre = space.point([0.0] * len(space.names))
    blade = CollocationEvaluator(start=source, sole_stiffness_scale=float(sole_scale)
                                 ).blade_spec(centre)
    runner = build_runner("transfemoral", blade_model=spec_from_dict(blade).build())
    src = CollocationSolution.read(source)
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=float(speed),
                                   swing_clearance_m=0.02,
                                   knee_moment_min_nm=None if knee in (None, "none")
                                   else float(knee),
                                   blade_backward_euler=blade_rule == "backward-euler")
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, src.to_guess(f"collocation solution {source}"),
                         model_spec={"model": "transfemoral", "blade": blade["name"],
                                     "blade_spec": blade}, track=False)
    print(f"wall {time.perf_counter() - t0:.0f} s")
    print(json.dumps(sol.summary()))
    if sol.converged:
        print(json.dumps(stride_responses(sol, runner)))
    sol.write(out)


if __name__ == "__main__":
    main(*sys.argv[1:7])
