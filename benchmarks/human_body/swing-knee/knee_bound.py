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


def deepest_flexion_nodes(start: CollocationSolution, knees, mesh: int | None = None
                          ) -> dict[str, int]:
    """{knee coordinate: the mesh node where the stride ``start`` flexes it most}, scaled to
    ``mesh`` intervals (default the start's); knee angles are negative in flexion."""
    names = list(start.dof_names)
    n0 = start.nlp.q.shape[0] - 1
    n = n0 if mesh is None else mesh
    return {knee: round(int(np.argmin(start.nlp.q[:-1, names.index(knee)])) * n / n0)
            for knee in knees}


def hold_knees(nodes: dict[str, int], degrees: dict[str, float]) -> None:
    """Make every :class:`StrideNLP` built from now on hold each knee coordinate of
    ``degrees`` flexed at least that many degrees at its node of ``nodes`` (a bound on that
    node's coordinate)."""
    bounds = StrideNLP.bounds

    def with_knees_held(self):
        lbx, ubx, lbg, ubg = bounds(self)
        nx = len(self.sx)
        for knee, deg in degrees.items():
            j = self.dyn.dof_names.index(knee)
            i = nodes[knee] * nx + j
            ubx[i] = min(ubx[i], -math.radians(deg) / self.sx[j])
        return lbx, ubx, lbg, ubg

    StrideNLP.bounds = with_knees_held


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
    spec = {"model": kind, "body": "human", **({"blade": blade} if blade else {})}
    sol0 = CollocationSolution.read(start)
    runner = build_runner(kind, body="human", blade=blade)
    guess = dataclasses.replace(sol0.to_guess(f"{start.name}, primal values"), multipliers=None)
    knees = ("knee_angle_l", "knee_angle_r")
    n = sol0.nlp.q.shape[0] - 1 if mesh is None else mesh
    nodes = deepest_flexion_nodes(sol0, knees, n)
    if degs is not None:
        hold_knees(nodes, dict(zip(knees, degs, strict=True)))
    settings = CollocationSettings(mesh_intervals=n, speed_m_per_s=speed,
                                   stride_time_people=people_stride,
                                   **people_term(defaults.people_weight_for("human")))
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, guess, model_spec=spec, track=False)
    out.mkdir(parents=True, exist_ok=True)
    sol.write(out / ("solution.json" if sol.converged else "best_iterate.json"))
    crit = human_running_criteria(sol)
    missed = [c.line() for c in crit if not c.met]
    print(json.dumps({"bound_deg": degs, "blade": blade, "nodes": [nodes[k] for k in knees],
                      "objective": sol.nlp.objective, "iterations": sol.nlp.iterations, **sol.summary(), "missed": missed,
                      "wall_s": time.perf_counter() - t0}, default=str))


if __name__ == "__main__":
    main()
