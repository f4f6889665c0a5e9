"""Solve the able stride with longer thighs (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/thigh_length.py OUT FACTOR [SPEED] [PEOPLE_WEIGHT]
        [MASS_KG HEIGHT_M]

Every femur of the human body is scaled by FACTOR about its centre of mass (the hip and knee
joint positions, the muscle points on it; its inertia by FACTOR²; its mass as it is), and every
muscle's optimal fibre and tendon slack lengths follow its muscle–tendon length in the neutral
pose (OpenSim's scaling rule), as a per-segment scaling from a static trial would do. The stride
is solved at SPEED (default 3.5 m/s) with people's joint angles at PEOPLE_WEIGHT (default 10,
the body's default objective), optionally for an athlete of MASS_KG and HEIGHT_M (the
parameter set's 75 kg and 1.80 m otherwise; FACTOR then on the height-scaled femur), from the
shipped able stride, its pelvis raised by the legs'
extra length, straight to the predictive stage. Writes ``OUT/solution.json`` (or
``best_iterate.json``) and prints the summary.

Why: ``bladelab.trial.segments`` measures the Fukuchi subject's thighs (hip to knee joint
centre) at 0.457–0.465 m, the model's at 0.398 m for his 1.81 m: 15–17 % longer; his shanks
(0.432–0.434 m) are the model's.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

import bladelab.runner.geometry as geo
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import STORED_STRIDES, make_guess
from bladelab.runner import build_runner
from bladelab.runner.params import (
    RUNNER_DATA_DIR,
    athlete_params,
    default_runner_params,
    runner_params_from_dict,
)

FEMUR_LENGTH_M = 0.17 + 0.226  # hip to knee, 1.80 m


def _scale(p, k):
    return tuple(k * c for c in p)


def neutral_mtu_lengths(runner) -> np.ndarray:
    """Muscle–tendon lengths [m] with every coordinate at 0 (standing straight)."""
    m = runner.mj_analysis_model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return d.ten_length.copy()


def scaled_runner(k: float, athlete: dict | None = None):
    """The able human runner (of ``athlete``: ``{"body_mass_kg": kg, "height_m": m}``) with
    every femur scaled by ``k`` (module docstring)."""
    base = default_runner_params("able", body="human")
    if athlete:
        base = athlete_params(base, **athlete)
    ref = build_runner(base)
    for side in ("l", "r"):
        par, pp, pc = geo.JOINTS[f"hip_{side}"]
        geo.JOINTS[f"hip_{side}"] = (par, pp, _scale(pc, k))
        par, pp, pc = geo.JOINTS[f"knee_{side}"]
        geo.JOINTS[f"knee_{side}"] = (par, _scale(pp, k), pc)
    for points in geo._LEG_PATHS.values():
        for i, (body, p) in enumerate(points):
            if body == "femur":
                points[i] = (body, _scale(p, k))
    data = json.loads(base.model_dump_json())
    for side in ("l", "r"):
        seg = data["segments"][f"femur_{side}"]
        seg["inertia_kg_m2"] = [k * k * v for v in seg["inertia_kg_m2"]]
    runner = build_runner(runner_params_from_dict(data))
    ratio = neutral_mtu_lengths(runner) / neutral_mtu_lengths(ref)
    runner.muscle_params[:, 1] *= ratio
    runner.muscle_params[:, 2] *= ratio
    return runner, ratio


def main() -> None:
    out, k = Path(sys.argv[1]), float(sys.argv[2])
    speed = float(sys.argv[3]) if len(sys.argv) > 3 else 3.5
    weight = float(sys.argv[4]) if len(sys.argv) > 4 else 10.0
    athlete = ({"body_mass_kg": float(sys.argv[5]), "height_m": float(sys.argv[6])}
               if len(sys.argv) > 6 else None)
    runner, ratio = scaled_runner(k, athlete)
    s = runner.params.athlete.height_m / 1.80
    settings = CollocationSettings(speed_m_per_s=speed, **people_term(weight))
    stored = RUNNER_DATA_DIR / "collocation" / STORED_STRIDES["able"]
    guess = make_guess(runner, str(stored), n=settings.mesh_intervals, speed=speed)
    q = guess.q.copy()
    names = list(guess.dof_names or runner.dof_names)
    q[:, names.index("pelvis_tz")] *= s
    q[:, names.index("pelvis_tx")] *= s
    q[:, names.index("pelvis_tz")] += 0.95 * (k - 1.0) * FEMUR_LENGTH_M * s
    guess = dataclasses.replace(guess, q=q, multipliers=None)
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, guess,
                         model_spec={"model": "able", "blade": None, "body": "human"},
                         track=False)
    out.mkdir(parents=True, exist_ok=True)
    sol.write(out / ("solution.json" if sol.converged else "best_iterate.json"))
    (out / "variant.json").write_text(json.dumps({"femur_factor": k, "speed": speed,
                                                  "athlete": athlete,
                                                  "people_weight": weight,
                                                  "mtu_ratio": ratio.round(4).tolist()}))
    print(json.dumps(sol.summary()), f"{time.perf_counter() - t0:.0f} s")
    for c in human_running_criteria(sol):  # judged here, where the femurs are still scaled
        print("  " + c.line())


if __name__ == "__main__":
    main()
