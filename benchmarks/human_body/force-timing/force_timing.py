"""Where in stance the vertical force peaks, against the foot's contact law (a measuring probe;
changes nothing in src).

Usage (repository root)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/human_body/force-timing/force_timing.py \\
        RECORDS.jsonl '{"set": {"foot_contact": {...}}}' [SOLUTION.json]

The shipped able stride (human body, 3.5 m/s, mesh 50, people's angles and swing knee) solved
again from its primal and dual values on the human body changed by the variant
(``../solve_variant.py``'s ``apply_variant``: ``set``, ``force_factor``, ``muscle``), with the
stride's own settings (``settings``: fields of them changed, e.g. ``{"reference_weight": 30}``,
``{"weights": {"acceleration": 1.0}}``;
``lumbar``: [stiffness N·m/rad, damping N·m·s/rad] of the lumbar joint's spring–damper in place
of the library's 500 and 5, ``bladelab.runner.joints.LIGAMENTS``): a continuation step from the shipped optimum to the changed body's
nearest one. Appends one line to RECORDS.jsonl: the variant, converged, iterations, objective,
cost of transport [J/(kg·m)], per leg the stance's peak vertical force [BW] and where it lies
[% of the stance, node-wise], the contact time [s] and the knee's flexion at touch-down [deg],
the gait warnings, the criteria of people's running met (the gait's and the joint angles'
against the measured trial), the wall time [s] and the date; with SOLUTION.json, writes the
stride there too.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from solve_variant import variant_runner  # noqa: E402

from bladelab.predict.collocation.guess import measured_trial_guess  # noqa: E402
from bladelab.predict.collocation.human_running import (  # noqa: E402
    angle_agreement,
    human_running_criteria,
)
from bladelab.predict.collocation.solution import CollocationSolution  # noqa: E402
from bladelab.predict.collocation.solve import predict_stride  # noqa: E402
from bladelab.runner.params import RUNNER_DATA_DIR  # noqa: E402

SHIPPED = RUNNER_DATA_DIR / "collocation" / "able-3.5-human.json"


def stance_shape(sol) -> dict:
    """Per leg: peak vertical force [BW], its place [% of the stance's nodes], the knee's
    flexion at the first loaded node [deg]."""
    fz = sol.leg_vertical_force()[:-1] / sol.body_weight_N
    n = fz.shape[0]
    out = {}
    for j, leg in enumerate(sol.leg_names):
        on = fz[:, j] > 20.0 / sol.body_weight_N
        k0 = next(k for k in range(n) if on[k] and not on[k - 1])
        length = next(k for k in range(1, n + 1) if not on[(k0 + k) % n])
        stance = np.array([fz[(k0 + k) % n, j] for k in range(length)])
        knee = sol.dof_names.index(f"knee_angle_{'l' if j == 0 else 'r'}")
        out[leg] = {"peak_bw": float(stance.max()),
                    "peak_at_pct_of_stance": float(100.0 * np.argmax(stance) / length),
                    "knee_flexion_at_touchdown_deg": float(-np.degrees(sol.nlp.q[k0, knee]))}
    return out


def main() -> None:
    out, variant = sys.argv[1], json.loads(sys.argv[2])
    shipped = CollocationSolution.read(SHIPPED)
    if "lumbar" in variant:
        from bladelab.runner import joints

        joints.LIGAMENTS["lumbar_extension"] = (0.0, 0.0, *map(float, variant["lumbar"]))
    runner = variant_runner({"kind": "able", **{k: v for k, v in variant.items()
                                                if k not in ("settings", "lumbar")}})
    t0 = time.perf_counter()
    changes = dict(variant.get("settings", {}))
    if "weights" in changes:  # the objective's weights: only the named ones change
        changes["weights"] = dataclasses.replace(shipped.settings.weights, **changes["weights"])
    settings = dataclasses.replace(shipped.settings, **changes)
    sol = predict_stride(runner, settings, shipped.to_guess(),
                         model_spec={"model": "able", "body": "human"})
    s = sol.summary()
    criteria = human_running_criteria(sol) + angle_agreement(sol, measured_trial_guess(runner,
                                                                                       n=100).q)
    record = {"variant": variant, "converged": sol.converged, "iterations": sol.nlp.iterations,
              "objective": sol.nlp.objective,
              "cost_of_transport_J_per_kg_m": sol.cost_of_transport_J_per_kg_m,
              "contact_time_s": s.get("contact_time_s"), "legs": stance_shape(sol),
              "warnings": sol.gait_warnings(),
              "criteria_met": f"{sum(c.met for c in criteria)} of {len(criteria)}",
              "criteria_missed": [c.line() for c in criteria if not c.met],
              "wall_s": time.perf_counter() - t0,
              "date": datetime.date.today().isoformat()}
    with open(out, "a") as f:
        f.write(json.dumps(record) + "\n")
    print(json.dumps(record))
    if len(sys.argv) > 3:
        sol.write(sys.argv[3])


if __name__ == "__main__":
    main()
