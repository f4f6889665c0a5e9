"""The template's toes: the tracking stage of a cold start from the template, by toe motion.

Usage (repository root; one solve, one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/template_toes.py \\
        RECORDS.jsonl '{"toes": "hinge"}'

``toes``: ``"hinge"`` (the toes moved as their passive hinge moves them:
:func:`toes_on_the_ground`; the default), ``"neutral"`` (the library's template: held at 0),
or ``[peak_deg]`` (a sin² rise over the second half of each stance to ``peak_deg`` at
toe-off, then the hinge's own lag in swing), each set on the library's template after its
pelvis is placed on the lowest contact (the toe tip may then be a few millimetres in the
ground). ``damping`` [N·m·s/rad]: the toes' damper (default the human body's); ``blade``:
the amputee wearing that category at 4 m/s instead of the able runner at 3.5 m/s;
``swing_knee``: true to solve the library's default problem of today (people's angles and
people's swing knee, ``people_settings``, as ``make bench``) instead of people's angles alone.
Solves on 50 intervals from the template, tracking then predictive stage, as
``bench_collocation.py``'s template row, and appends one line to RECORDS.jsonl: iterations
per stage, objective, cost of transport [J/(kg·m)], stride time [s], gait warnings, wall
time [s].
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import time

import mujoco
import numpy as np

from bladelab.predict import defaults
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.settings import (
    CollocationSettings,
    people_settings,
    people_term,
)
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.stride_guess import periodic_derivative
from bladelab.runner import build_runner
from bladelab.runner.model import RunnerModel, contact_heights
from bladelab.runner.params import default_runner_params, runner_params_from_dict

MESH = 50


def _runner(damping: float | None, blade: str | None):
    kind = "amputee" if blade else "able"
    data = json.loads(default_runner_params(kind, body="human", blade=blade).model_dump_json())
    if damping is not None:
        data["toe_hinge"]["damping_Nms_per_rad"] = float(damping)
    return build_runner(runner_params_from_dict(data))


def _toes(runner, guess, toes):
    """The template ``guess`` with the toes of ``toes`` (module docstring)."""
    if toes == "neutral":
        return guess
    q = guess.q.copy()
    n = q.shape[0] - 1
    frac = np.linspace(0.0, 1.0, n + 1)
    stance = (np.count_nonzero(guess.vertical_grf_bw[: n // 2] > 0) + 1) / n  # one leg's share
    if toes == "hinge":
        q = toes_on_the_ground(runner, q, guess.period, stance)
        return dataclasses.replace(guess, q=q, qd=periodic_derivative(q, guess.period))
    hinge = runner.params.toe_hinge
    tau = hinge.damping_Nms_per_rad / hinge.stiffness_Nm_per_rad
    for side, lag in (("l", 0.0), ("r", 0.5)):
        if f"mtp_angle_{side}" not in runner.dof_names:  # the prosthetic leg
            continue
        j = runner.dof(f"mtp_angle_{side}")
        peak = math.radians(float(toes[0]))
        phase = np.mod(frac - lag, 1.0)
        rise = np.clip((phase - 0.5 * stance) / (0.5 * stance), 0.0, 1.0)
        q[:, j] = np.where(phase <= stance, peak * np.sin(0.5 * np.pi * rise) ** 2,
                           peak * np.exp(-(phase - stance) * guess.period / tau))
    return dataclasses.replace(guess, q=q, qd=periodic_derivative(q, guess.period))


def toes_on_the_ground(model: RunnerModel, q: np.ndarray, period: float,
                        duty: float) -> np.ndarray:
    """``q`` with the toes of each foot that has them (``mtp_angle_<side>``) moved as their
    passive hinge moves them: towards the angle that keeps the toes flat on the ground while
    the heel rises in stance (the toe tip as low as the ball, never flexed) and towards neutral
    in swing, through the hinge's first-order lag of time constant D/K
    (``RunnerParams.toe_hinge``; the toes' inertia is negligible), periodic over the stride
    (README.md, "The template's toes")."""
    hinge = model.params.toe_hinge
    tau = hinge.damping_Nms_per_rad / max(hinge.stiffness_Nm_per_rad, 1e-9)  # [s]
    names = list(model.contact_names)
    n = q.shape[0] - 1
    frac = np.arange(n + 1) / n
    q = q.copy()
    data = mujoco.MjData(model.mj_model)
    for side, lag in (("l", 0.0), ("r", 0.5)):
        name = f"mtp_angle_{side}"
        if name not in model.dof_names or f"toetip_{side}" not in names:
            continue
        j, tip, ball = model.dof(name), names.index(f"toetip_{side}"), names.index(f"toe_{side}")
        flat = np.zeros(n)
        for k in np.flatnonzero(np.mod(frac[:n] - lag, 1.0) < duty):
            flat[k] = _flat_toe_angle(model, q[k], j, tip, ball, data)
        q[:, j] = np.append(_periodic_lag(flat, period / n, tau), 0.0)
        q[n, j] = q[0, j]
    return q


def _flat_toe_angle(model: RunnerModel, qk: np.ndarray, j: int, tip: int, ball: int,
                    data) -> float:
    """The toe hinge's angle [rad] (coordinate ``j``, 0 to :data:`_TOE_FLAT_MAX_DEG`) that puts
    the toe tip (contact ``tip``) as low as the ball (contact ``ball``) at pose ``qk``."""
    qk = qk.copy()

    def tip_below_ball(angle: float) -> bool:
        qk[j] = angle
        h = contact_heights(model, qk, data)
        return h[tip] < h[ball]

    lo, hi = 0.0, math.radians(_TOE_FLAT_MAX_DEG)
    if not tip_below_ball(lo):
        return lo
    for _ in range(40):  # bisection to 1e-12 rad
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if tip_below_ball(mid) else (lo, mid)
    return hi


def _periodic_lag(target: np.ndarray, h: float, tau: float) -> np.ndarray:
    """The periodic response of ``ẋ = (target − x)/tau`` [tau in s] to ``target`` given at the
    ``target.size`` nodes of one period (spacing ``h`` [s]): each interval exact for a target
    held at its end value; three periods from 0 (the lag forgets its start within one)."""
    decay = math.exp(-h / max(tau, 1e-12))
    x, out = 0.0, np.empty(target.size)
    for _ in range(3):
        for k in range(target.size):
            x = decay * x + (1.0 - decay) * target[k]
            out[k] = x
    return out


#: Upper end [deg] of the search for the toes' flat angle (the hinge's ligament begins at 60°).
_TOE_FLAT_MAX_DEG = 60.0


def main() -> None:
    out, variant = sys.argv[1], json.loads(sys.argv[2])
    blade = variant.get("blade")
    runner = _runner(variant.get("damping"), blade)
    speed = 4.0 if blade else 3.5
    people = (people_settings("human", kind=runner.kind) if variant.get("swing_knee")
              else people_term(defaults.people_weight_for("human")))
    settings = CollocationSettings(mesh_intervals=MESH, speed_m_per_s=speed, **people)
    guess = _toes(runner, template_guess(runner, speed=speed, n=MESH),
                  variant.get("toes", "hinge"))
    t0 = time.perf_counter()
    spec = {"model": runner.kind, "body": "human"} | ({"blade": blade} if blade else {})
    sol = predict_stride(runner, settings, guess, model_spec=spec)
    record = {"variant": variant, "converged": sol.converged,
              "tracking_iterations": (sol.tracking or {}).get("iterations"),
              "predictive_iterations": sol.nlp.iterations,
              "objective": sol.nlp.objective,
              "cost_of_transport_J_per_kg_m": sol.cost_of_transport_J_per_kg_m,
              "stride_time_s": sol.period_s, "warnings": sol.gait_warnings(),
              "wall_s": time.perf_counter() - t0}
    with open(out, "a") as f:
        f.write(json.dumps(record) + "\n")
    print(json.dumps(record))


if __name__ == "__main__":
    main()
