"""Probe: the transfemoral runner on the human body started from the transtibial runner's
person-like stride, its prosthetic knee made straight in stance (changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/design/transfemoral-gait-2026-11-29/from_transtibial.py \\
        OUT.json STEP_PHASE_TOLERANCE [KNEE_FIELD=VALUE ...] [from=START.json] [raw=1] \\
        [set:SETTING=VALUE ...] [body:FIELD=JSON ...] [speed=V]

``raw=1``: the transtibial stride's knee angles as they are (not made straight in stance).
The last two arguments were added on 2026-11-30 (``../transfemoral-gait-2026-11-30/``).
``set:SETTING=VALUE``: a ``CollocationSettings`` field (a number, or ``none``), e.g.
``set:swing_clearance_m=0`` or ``set:knee_flexion_max_loaded_deg=10``; since 2026-12-08 the
value is read as JSON, so ``set:stride_time_people=true`` and
``set:pelvis_tilt_range_deg=[-15,5]`` work too.
``body:FIELD=JSON`` (added on 2026-11-30, later): a field of the transfemoral parameter set, e.g.
``body:residual_muscle_strength={"hamstrings":0.5}``. ``speed=V`` (added on 2026-11-30, later
still): the prescribed speed [m/s] (default 4).

The start is ``../human-body-2026-11-29/transtibial-centre-people10.json`` (the design box's
centre blade, 4 m/s) mapped onto the transfemoral runner by coordinate name, the prosthetic
knee's angle shifted by its least stance flexion and clipped at straight (stance 0–12°, swing
up to 63°), speeds by periodic differences, the stride's vertical force pattern kept; a
tracking stage (angles and force pattern), then the predictive stage: people's angles at
weight 10, swing clearance 2 cm, the blade by backward Euler, mesh 50, and the alternating
steps at STEP_PHASE_TOLERANCE (``none``: free). KNEE_FIELD=VALUE overrides a field of the
prosthetic knee (``bladelab.runner.prosthetic_knee.ProstheticKnee``, e.g.
``flexion_damping=30``) in every transfemoral parameter set the process builds (the
solution's consistency check included). ``from=START.json``: start from that collocation
solution as it is instead, with no tracking stage. The body's own parameter file decides the
myodesis.
Prints the summary, the tracking stage's record and the criteria of people's running; writes
OUT.json.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np

import bladelab.predict.collocation.stored as stored
from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.design.space import default_design_space
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.predict.collocation.stride_guess import periodic_derivative
from bladelab.runner.params import runner_params_from_dict

START = (Path(__file__).resolve().parents[1] / "human-body-2026-11-29"
         / "transtibial-centre-people10.json")


def _with_knee(overrides: dict[str, float], body: dict | None = None):
    """``default_runner_params`` with the transfemoral knee's fields and the parameter set's
    fields ``body`` overridden."""
    original = stored.default_runner_params

    def patched(kind, **kw):
        params = original(kind, **kw)
        if kind != "transfemoral" or not (overrides or body):
            return params
        data = params.model_dump()
        data["prosthetic_knee"].update(overrides)
        data.update(body or {})
        return runner_params_from_dict(data)

    return patched


def _setting(text: str):
    """A ``set:`` value read as JSON: a number, true/false, or a list (a range: a tuple)."""
    value = json.loads(text)
    return tuple(value) if isinstance(value, list) else value


def main(out: str, step_tol: str, *extra: str) -> None:
    fields = dict(kv.split("=", 1) for kv in extra)
    start = fields.pop("from", None)
    raw = fields.pop("raw", None)
    speed = float(fields.pop("speed", 4.0))
    sets = {k[4:]: (None if v == "none" else _setting(v))
            for k, v in list(fields.items()) if k.startswith("set:")}
    for k in sets:
        fields.pop("set:" + k)
    body = {k[5:]: json.loads(v) for k, v in list(fields.items()) if k.startswith("body:")}
    for k in body:
        fields.pop("body:" + k)
    stored.default_runner_params = _with_knee({k: float(v) for k, v in fields.items()}, body)
    space = default_design_space()
    blade = CollocationEvaluator().blade_spec(space.point([0.0] * len(space.names)))
    spec = {"model": "transfemoral", "blade": blade["name"], "blade_spec": blade,
            "body": "human"}
    runner = stored.runner_from_spec(spec)
    settings = CollocationSettings(
        mesh_intervals=50, speed_m_per_s=speed, blade_backward_euler=True,
        step_phase_tolerance=None if step_tol == "none" else float(step_tol),
        **{"swing_clearance_m": 0.02, **people_term(10.0), **sets})
    if start is not None:
        guess = make_guess(runner, start, n=50, speed=speed)
        _solve(runner, settings, guess, spec, out, track=False)
        return
    transtibial = CollocationSolution.read(START)
    guess = make_guess(runner, str(START), n=50, speed=speed)
    j = list(guess.dof_names or runner.dof_names).index("knee_angle_r")
    force = transtibial.leg_vertical_force()
    q = guess.q.copy()
    if not raw:
        q[:, j] = np.minimum(q[:, j] - q[force[:, 1] > 50.0, j].max(), 0.0)
    guess = dataclasses.replace(
        guess, q=q, qd=periodic_derivative(q, guess.period), qdd=None, excitation=None,
        tendon_force_rate=None, multipliers=None, activation=None, tendon_force=None,
        vertical_grf_bw=force.sum(axis=1) / transtibial.body_weight_N,
        source=f"{guess.source}, prosthetic knee straight in stance")
    _solve(runner, settings, guess, spec, out, track=True)


def _solve(runner, settings, guess, spec: dict, out: str, *, track: bool) -> None:
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, guess, model_spec=spec, track=track)
    print(f"wall {time.perf_counter() - t0:.0f} s")
    print(json.dumps(sol.summary()))
    print("objective", sol.nlp.objective, "tracking stage", json.dumps(sol.tracking))
    for c in human_running_criteria(sol):
        print(c.met, c.name, c.value_text())
    sol.write(out)


if __name__ == "__main__":
    main(*sys.argv[1:])
