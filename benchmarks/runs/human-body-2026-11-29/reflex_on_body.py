"""Probe: seed 001's reflex controller on the other runner bodies (changes nothing in src).

The reflex route builds its runners with seed 001's body; this probe swaps the body in by
replacing the route's model builder in this process (``--jobs 1`` only). Usage (repository
root)::

    .venv/bin/python benchmarks/runs/human-body-2026-11-29/reflex_on_body.py nominal
    .venv/bin/python ... reflex_on_body.py cmaes BODY INIT.json OUT GENERATIONS
    .venv/bin/python ... reflex_on_body.py track OUT
    .venv/bin/python ... reflex_on_body.py stride-start LEAD_S

``nominal``: the shipped amputee Cat6 solution re-simulated 10 s at its own settings on the bodies
seed001, toes and human. ``cmaes``: CMA-ES of seed 001's objective (the file's settings, 10 s,
3.5 m/s, λ 16, σ 0.1, seed 1) on BODY from INIT. ``track``: the stable-gait recipe's stages on
the human body, tracking the shipped human amputee Cat6 stride at 4 m/s. ``stride-start``: the
closed loop started in that stride's state (pose and velocities LEAD_S before leg 0's
touch-down; the muscles start as the closed loop's always do, at activation 0.05, and the
stride's activations there are printed) under the shipped and SCONE's parameters.
"""

from __future__ import annotations

import functools
import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

import bladelab.predict.reflex.objective as objective
import bladelab.predict.reflex.optimize as optimize
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.reflex.controller import controller_layout, read_parameters
from bladelab.runner.model import build_runner
from bladelab.runner.params import REFLEX_STARTS_DIR, RUNNER_DATA_DIR

SHIPPED = REFLEX_STARTS_DIR / "amputee-Cat6-3.5.json"
HUMAN_STRIDE = RUNNER_DATA_DIR / "collocation" / "amputee-Cat6-4-human.json"


def use_body(body: str) -> None:
    """Make the reflex route build its runners on ``body``."""
    optimize.build_runner = functools.partial(build_runner, body=body)
    optimize._MODELS.clear()


def nominal() -> None:
    data = json.loads(SHIPPED.read_text())
    settings = optimize.stored_settings(data, speed=3.5, duration=10.0, nominal=True)
    for body in ("seed001", "toes", "human"):
        model = build_runner("amputee", blade="Cat6", body=body)
        layout = controller_layout(model)
        ev, _ = objective.simulate_controlled(model, read_parameters(SHIPPED, layout),
                                              layout=layout, settings=settings)
        print(f"{body}: fell {ev.fell} after {ev.duration:.2f} s, {ev.n_steps} steps")


def cmaes(body: str, init: str, out: str, generations: str) -> None:
    use_body(body)
    data = json.loads(Path(init).read_text())
    _, layout = optimize.runner_and_layout("amputee", "Cat6")
    settings = optimize.stored_settings(data, speed=3.5, duration=10.0, nominal=True)
    res = optimize.optimize_controller(
        "amputee", blade="Cat6", speed=3.5, x0=read_parameters(init, layout),
        generations=int(generations), popsize=16, sigma=0.1, seed=1, out=out, force=True,
        settings=settings, progress=lambda g, b, m: print(g, round(b, 3), flush=True))
    print(json.dumps(res.to_dict()))


def track(out: str) -> None:
    use_body("human")
    from bladelab.predict.reflex.recipe import run_recipe

    study = Path(tempfile.mkdtemp())
    (study / "amputee-Cat6").mkdir()
    shutil.copy(HUMAN_STRIDE, study / "amputee-Cat6" / "speed-4.json")
    run_recipe("Cat6", 1, out=out, track_study=study,
               progress=lambda level, row: print(level, json.dumps(row), flush=True))


def stride_start(lead: str) -> None:
    use_body("human")
    model, layout = optimize.runner_and_layout("amputee", "Cat6")
    sol = CollocationSolution.read(HUMAN_STRIDE)
    t, period = np.asarray(sol.nlp.time), float(sol.period_s)
    fz = sol.leg_vertical_force()[:, 0]
    i = int(np.argmax((fz[:-1] <= 0.1 * sol.body_weight_N) & (fz[1:] > 0.1 * sol.body_weight_N)))
    t0 = (t[i] - float(lead)) % period

    def at(values):
        values = np.asarray(values)
        return np.array([np.interp(t0, t, values[:, j], period=period)
                         for j in range(values.shape[1])])

    q0, qd0, act = at(sol.nlp.q), at(sol.nlp.qd), at(sol.nlp.activation)
    assert list(sol.muscle_names) == list(model.muscle_names)
    scone_state = objective.initial_state

    def stride_state(model, layout, x, speed):
        q, v = scone_state(model, layout, x, speed)
        for j, name in enumerate(sol.dof_names):
            if name != "pelvis_tx":
                q[model.dof(name)] = q0[j]
                v[model.dof(name)] = qd0[j] * speed / sol.mean_speed_mps
        q[model.dof("pelvis_tz")] -= objective.contact_heights(model, q).min()
        return q, v

    objective.initial_state = stride_state
    settings = objective.ObjectiveSettings(speed=4.0, initial_speed=3.5, duration=4.0,
                                           integrator="newmark", dt=1e-3)
    print("activations at the start:", dict(zip(model.muscle_names, np.round(act, 2), strict=True)))
    for name, x in (("shipped", read_parameters(SHIPPED, layout, transfer=True)),
                    ("SCONE", layout.x0)):
        ev, res = objective.simulate_controlled(model, x, layout=layout, settings=settings,
                                                record_every=10)
        z = res.qpos[:, model.dof("pelvis_tz")]
        print(f"{name}: fell {ev.fell} after {ev.duration:.3f} s, pelvis height "
              f"{z[0]:.3f} -> {z[-1]:.3f} m")


if __name__ == "__main__":
    {"nominal": nominal, "cmaes": cmaes, "track": track,
     "stride-start": stride_start}[sys.argv[1]](*sys.argv[2:])
