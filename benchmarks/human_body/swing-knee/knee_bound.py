"""What people's swing knee costs: a stride solved with its swing knee held at a flexion
(a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/swing-knee/knee_bound.py OUT START SPEED \
        [DEG[,DEG_R]] [BLADE] [people] [mesh=N]

Solves the able runner (with ``BLADE``, e.g. ``Cat4``, the transtibial amputee wearing it;
``able``: the able runner) on the shipped body, people's angles at the default weight, the
start's mesh, the stride time free, at ``SPEED`` [m/s] from the stride ``START`` (its primal
values), with each leg's knee flexed at least ``DEG`` [deg] (the right, i.e. prosthetic, leg
``DEG_R`` if given) at the mesh node where the start's knee flexes most in swing (a bound on
that node's knee coordinate); ``DEG`` ``-``: the same problem unbounded (the control). A last
argument ``people`` holds the stride time within people's band at the speed
(``CollocationSettings.stride_time_people``); an argument ``mesh=N`` solves on N intervals
(the start resampled, the held node scaled). Writes ``OUT/solution.json`` (or
``best_iterate.json``) and prints its summary, its objective and the criteria it misses.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from bladelab.predict import defaults
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.transcription import StrideNLP
from bladelab.runner import build_runner


def main() -> None:
    mesh = next((int(a[5:]) for a in sys.argv if a.startswith("mesh=")), None)
    sys.argv = [a for a in sys.argv if not a.startswith("mesh=")]
    out, start, speed = Path(sys.argv[1]), Path(sys.argv[2]), float(sys.argv[3])
    arg = sys.argv[4] if len(sys.argv) > 4 else "-"
    degs = None if arg == "-" else [float(v) for v in arg.split(",")]
    if degs is not None and len(degs) == 1:
        degs *= 2
    blade = sys.argv[5] if len(sys.argv) > 5 and sys.argv[5] != "able" else None
    people_stride = len(sys.argv) > 6 and sys.argv[6] == "people"
    kind = "able" if blade is None else "amputee"
    spec = {"model": kind, "blade": blade, "body": "human"} if blade else {"model": kind,
                                                                             "body": "human"}
    sol0 = CollocationSolution.read(start)
    runner = build_runner(kind, body="human", blade=blade)
    guess = dataclasses.replace(sol0.to_guess(f"{start.name}, primal values"), multipliers=None)
    names = list(sol0.dof_names)
    knees = [names.index("knee_angle_l"), names.index("knee_angle_r")]
    # the node of each knee's deepest flexion (knee angles are negative in flexion)
    n0 = sol0.nlp.q.shape[0] - 1
    n = n0 if mesh is None else mesh
    nodes = [round(int(np.argmin(sol0.nlp.q[:-1, j])) * n / n0) for j in knees]
    bounds = StrideNLP.bounds

    def held(self):
        lbx, ubx, lbg, ubg = bounds(self)
        if degs is not None:
            nx = len(self.sx)
            for j, k, deg in zip(knees, nodes, degs, strict=True):
                ubx[k * nx + j] = min(ubx[k * nx + j], -math.radians(deg) / self.sx[j])
        return lbx, ubx, lbg, ubg

    StrideNLP.bounds = held
    settings = CollocationSettings(mesh_intervals=n, speed_m_per_s=speed,
                                   stride_time_people=people_stride,
                                   **people_term(defaults.people_weight_for("human")))
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, guess, model_spec=spec, track=False)
    out.mkdir(parents=True, exist_ok=True)
    sol.write(out / ("solution.json" if sol.converged else "best_iterate.json"))
    crit = human_running_criteria(sol)
    missed = [c.line() for c in crit if not c.met]
    print(json.dumps({"bound_deg": degs, "blade": blade, "nodes": nodes, "objective": sol.nlp.objective,
                      "iterations": sol.nlp.iterations, **sol.summary(), "missed": missed,
                      "wall_s": time.perf_counter() - t0}, default=str))


if __name__ == "__main__":
    main()
