"""The template's toes: the tracking stage of a cold start from the template, by toe motion.

Usage (repository root; one solve, one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/template_toes.py \\
        RECORDS.jsonl '{"toes": "hinge"}'

``toes``: ``"hinge"`` (the library's template: the toes moved as their passive hinge moves
them), ``"neutral"`` (held at 0 throughout, the template before), or ``[peak_deg]`` (a
sin² rise over the second half of each stance to ``peak_deg`` at toe-off, then the hinge's
own lag in swing). ``damping`` [N·m·s/rad]: the toes' damper (default the human body's).
Solves the able runner (human body) at 3.5 m/s on 50 intervals from the template, tracking
then predictive stage, as ``bench_collocation.py``'s template row, and appends one line to
RECORDS.jsonl: iterations per stage, objective, cost of transport [J/(kg·m)], stride time
[s], wall time [s].
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import time

import numpy as np

from bladelab.predict import defaults
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.stride_guess import periodic_derivative
from bladelab.runner import build_runner
from bladelab.runner.params import default_runner_params, runner_params_from_dict

SPEED_MPS, MESH = 3.5, 50


def _runner(damping: float | None):
    data = json.loads(default_runner_params("able", body="human").model_dump_json())
    if damping is not None:
        data["toe_hinge"]["damping_Nms_per_rad"] = float(damping)
    return build_runner(runner_params_from_dict(data))


def _toes(runner, guess, toes):
    """The template ``guess`` with the toes of ``toes`` (module docstring)."""
    if toes == "hinge":
        return guess
    q = guess.q.copy()
    n = q.shape[0] - 1
    frac = np.linspace(0.0, 1.0, n + 1)
    stance = float(np.mean(guess.vertical_grf_bw[:-1] > 0)) / 2  # one leg's share
    hinge = runner.params.toe_hinge
    tau = hinge.damping_Nms_per_rad / hinge.stiffness_Nm_per_rad
    for side, lag in (("l", 0.0), ("r", 0.5)):
        j = runner.dof(f"mtp_angle_{side}")
        if toes == "neutral":
            q[:, j] = 0.0
            continue
        peak = math.radians(float(toes[0]))
        phase = np.mod(frac - lag, 1.0)
        rise = np.clip((phase - 0.5 * stance) / (0.5 * stance), 0.0, 1.0)
        q[:, j] = np.where(phase <= stance, peak * np.sin(0.5 * np.pi * rise) ** 2,
                           peak * np.exp(-(phase - stance) * guess.period / tau))
    return dataclasses.replace(guess, q=q, qd=periodic_derivative(q, guess.period))


def main() -> None:
    out, variant = sys.argv[1], json.loads(sys.argv[2])
    runner = _runner(variant.get("damping"))
    settings = CollocationSettings(mesh_intervals=MESH, speed_m_per_s=SPEED_MPS,
                                   **people_term(defaults.people_weight_for("human")))
    guess = _toes(runner, template_guess(runner, speed=SPEED_MPS, n=MESH),
                  variant.get("toes", "hinge"))
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, guess, model_spec={"model": "able", "body": "human"})
    record = {"variant": variant, "converged": sol.converged,
              "tracking_iterations": (sol.tracking or {}).get("iterations"),
              "predictive_iterations": sol.nlp.iterations,
              "objective": sol.nlp.objective,
              "cost_of_transport_J_per_kg_m": sol.cost_of_transport_J_per_kg_m,
              "stride_time_s": sol.period_s, "wall_s": time.perf_counter() - t0}
    with open(out, "a") as f:
        f.write(json.dumps(record) + "\n")
    print(json.dumps(record))


if __name__ == "__main__":
    main()
