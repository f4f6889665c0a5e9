"""Probe: a cold start on a given mesh (a coarse one: the first step of a mesh continuation).

Usage (from the repository root)::

    .venv/bin/python benchmarks/collocation_speed/coarse_start.py MODEL BLADE SPEED MESH START OUT [W] [--no-track]

MODEL ``able``, ``amputee`` or ``transfemoral``, BLADE a category or ``none``, SPEED [m/s],
MESH intervals,
START ``template`` (the library's template guess: a sine template until 2026-12-01, people's
running since) or ``people`` (a template from people's mean
joint angles, ``bladelab.predict.collocation.people.people_joint_angles``: RBDS002 and
RBDS003 of Fukuchi et al. 2017, the right leg half a stride later, the trunk 5° forward, the
template's stride time and vertical force pattern). W: the weight of people's joint angles in
the objective [1/rad²] (default: the human body's, 10). Solves the tracking stage and the
predictive stage on the human body (``--no-track``: the predictive stage straight from the
start), writes the solution to OUT and prints one JSON line: each stage's iterations, wall
time and status, the objective, the solve's summary and the criteria against measured
running that the stride misses.
"""

from __future__ import annotations

import json
import math
import sys
import time

import numpy as np

from bladelab.predict import defaults
from bladelab.predict.collocation.guess import template_guess, template_vertical_grf
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.people import people_joint_angles
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.stride_guess import StrideGuess, periodic_derivative
from bladelab.runner import build_runner
from bladelab.runner.model import contact_heights


def people_template(runner, speed: float, n: int) -> StrideGuess:
    """People's mean angles as a template stride (module docstring)."""
    period = 0.75 / (1.0 + 0.05 * (speed - 3.5))  # the library template's stride time
    frac = np.linspace(0.0, 1.0, n + 1)
    curves = people_joint_angles()
    q = np.zeros((n + 1, len(runner.dof_names)))
    q[:, runner.dof("pelvis_tx")] = speed * period * frac
    q[:, runner.dof("pelvis_tilt")] = -math.radians(5.0)
    for side, lag in (("l", 0.0), ("r", 0.5)):
        for base, curve in curves.items():
            name = f"{base}_{side}"
            if name in runner.dof_names:
                q[:, runner.dof(name)] = np.interp(np.mod(frac - lag, 1.0),
                                                   np.arange(100) / 100.0, curve, period=1.0)
    iz = runner.dof("pelvis_tz")
    for k in range(n + 1):  # the lowest contact on the ground at every node
        q[k, iz] -= contact_heights(runner, q[k]).min()
    return StrideGuess(f"people template at {speed:g} m/s", period, q,
                       periodic_derivative(q, period),
                       vertical_grf_bw=template_vertical_grf(frac))


def main(argv: list[str]) -> int:
    track = "--no-track" not in argv
    argv = [a for a in argv if a != "--no-track"]
    model, blade, speed, n, start, out = argv[:6]
    speed, n = float(speed), int(n)
    weight = defaults.people_weight_for("human", float(argv[6]) if len(argv) > 6 else None)
    blade = None if blade == "none" else blade
    runner = build_runner(model, blade=blade, body="human")
    guess = (template_guess(runner, speed=speed, n=n) if start == "template"
             else people_template(runner, speed, n))
    stages = []

    def progress(p) -> None:
        if p.event == "end":
            stages.append({"stage": p.stage, "iterations": p.iteration,
                           "wall_s": round(p.elapsed_s, 1), "status": p.message})

    t0 = time.perf_counter()
    settings = CollocationSettings(speed_m_per_s=speed, mesh_intervals=n, **people_term(weight))
    sol = predict_stride(runner, settings, guess, model_spec={"model": model, "blade": blade, "body": "human"},
                         progress=progress, track=track)
    sol.write(out)
    missed = [c.line() for c in human_running_criteria(sol) if not c.met]
    print(json.dumps({"model": model, "blade": blade, "start": start, "mesh": n,
                      "people_weight": weight, "track": track,
                      "wall_s": round(time.perf_counter() - t0, 1), "stages": stages,
                      "objective": sol.nlp.objective, "summary": sol.summary(),
                      "criteria_missed": missed}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
