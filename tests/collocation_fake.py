"""A collocation 'solution' built from a template guess, without solving (for cheap tests of
the solution file, its summary and conversions, the CLI's resume and the report), and a fake
solve that returns it (for the speed continuation and the sweep)."""

from __future__ import annotations

import dataclasses

import numpy as np

from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.dynamics import stride_dynamics
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.nlp_solution import NLPSolution
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import check_model_spec, model_label
from bladelab.predict.collocation.stride_guess import periodic_derivative
from bladelab.runner import build_runner

SPEED = 3.5  # m/s
MARK = 3  # the coordinate column each fake solve shifts (not pelvis_tx, column 0)


def fake_nlp(runner, cm, n: int, *, sink_m: float = 0.01, success: bool = True) -> NLPSolution:
    """The template stride at 3.5 m/s on ``n`` intervals, the pelvis lowered by ``sink_m`` [m]
    so that the stance feet carry load, activations 0.05 and static tendon forces."""
    g = template_guess(runner, speed=SPEED, n=n)
    q = g.q.copy()
    q[:, runner.dof("pelvis_tz")] -= sink_m
    act = np.full((n + 1, len(runner.muscle_names)), 0.05)
    ft = stride_dynamics(cm).static_tendon_force(q, act)
    return NLPSolution(
        time=np.linspace(0.0, g.period, n + 1), q=q, qd=g.qd, activation=act, tendon_force=ft,
        qdd=periodic_derivative(g.qd, g.period), excitation=act,
        tendon_force_rate=periodic_derivative(ft, g.period), period=g.period, objective=1.25,
        objective_terms={"effort": 0.25, "metabolic": 1.0}, success=success,
        status="Solve_Succeeded" if success else "Maximum_Iterations_Exceeded", iterations=7,
        wall_s=1.5, timings={"build_s": 0.1}, max_violation=float("nan"),
        worst_constraints=(("path dynamics pelvis_tz@3", 0.5),),
    )


def fake_solution(kind: str = "able", n: int = 12, **kwargs):
    """(runner, collocation model, CollocationSolution) of :func:`fake_nlp`."""
    runner = build_runner("able") if kind == "able" else build_runner("amputee", blade="Cat6")
    cm = build_collocation_model(runner)
    nlp = fake_nlp(runner, cm, n, **kwargs)
    sol = CollocationSolution.from_nlp(
        runner, nlp, settings=CollocationSettings(mesh_intervals=n, speed_m_per_s=SPEED),
        model_spec={"model": kind, "blade": "Cat6"}, guess_source="template (test)",
        tracking={"success": True, "status": "Solve_Succeeded", "iterations": 3, "wall_s": 0.5,
                  "objective": 0.1, "max_violation": 1e-9}, cm=cm)
    # the template is not dynamically consistent (its residual is 100-150 %); a fake stands
    # for a clean solve, whose residual is below RESIDUAL_WARNING_PCT
    sol = dataclasses.replace(sol, residual={**sol.residual, "dynamics_residual_pct": 0.5})
    # the sunk template barely loads the amputee's blade (0.14 body weights); a fake stands for
    # a running stride, whose every leg carries the body: such a leg's forces are scaled up
    forces = sol.contact_forces.copy()
    peaks = sol.leg_vertical_force().max(axis=0) / sol.body_weight_N
    for leg, peak in enumerate(peaks):
        if 0 < peak < 1.5:
            forces[:, sol.contact_legs == leg, :] *= 1.5 / peak
    return runner, cm, dataclasses.replace(sol, contact_forces=forces)


def fake_models(n: int) -> dict:
    """Per model kind (able, amputee): (runner, a converged-looking solution on ``n``
    intervals at 3.5 m/s)."""
    out = {}
    for kind in ("able", "amputee"):
        runner, _, sol = fake_solution(kind, n)
        out[kind] = (runner, sol)
    return out


class FakeSolve:
    """Stands in for ``predict_stride``: the fake solution with the guess's coordinates at the
    prescribed speed (the maximum speed: 1.2 × the guess's), coordinate ``MARK`` shifted by
    1 mrad so that a solve's output differs from its input; fails for (model label, speed)
    in ``fail`` (None: the maximum speed), and for a prescribed speed more than ``max_step``
    [m/s] from the last speed solved successfully (None: any step)."""

    def __init__(self, fakes, fail=(), max_step=None):
        self.fakes, self.fail, self.calls = fakes, set(fail), []
        self.max_step, self.last_ok_speed = max_step, None

    def __call__(self, runner, settings, guess, *, model_spec, progress=None, speed_floor=None):
        spec = check_model_spec(model_spec)
        base = self.fakes[spec["model"]][1]
        v = settings.speed_m_per_s
        g = guess.resample(settings.mesh_intervals)
        last = self.last_ok_speed
        step = abs(v - last) if v is not None and last is not None else 0.0
        g = g.with_speed(v if v is not None else 1.2 * g.speed)
        q = g.q.copy()
        q[:, MARK] += 1e-3
        label = model_label(spec)
        ok = (label, v) not in self.fail and (self.max_step is None
                                              or step <= self.max_step + 1e-9)
        if ok and v is not None:
            self.last_ok_speed = v
        nlp = dataclasses.replace(
            base.nlp, q=q, qd=g.qd, period=g.period, success=ok,
            status="Solve_Succeeded" if ok else "Maximum_Iterations_Exceeded")
        sol = dataclasses.replace(base, nlp=nlp, settings=settings, model_spec=spec,
                                  guess_source=guess.source, stage="predictive")
        self.calls.append({"label": label, "speed": v, "guess": guess, "solution": sol,
                           "speed_floor": speed_floor})
        return sol


def install_fake_solve(fakes: dict, monkeypatch) -> FakeSolve:
    """Replace the continuation's solve by a :class:`FakeSolve` (returned; set ``.fail`` to make
    solves fail); runners come from ``fakes`` (:func:`fake_models`) instead of being built."""
    from bladelab.predict.collocation import continuation

    fake = FakeSolve(fakes)
    monkeypatch.setattr(continuation, "predict_stride", fake)
    monkeypatch.setattr(continuation, "runner_from_spec",
                        lambda spec: fakes[check_model_spec(spec)["model"]][0])
    return fake


def start_of(settings, guess) -> str:
    """Which start of ``bladelab.predict.collocation.starts`` a solve is, from its guess and
    settings: ``iterate`` (a stored best iterate's warm start), ``template``,
    ``previous-but-one``, ``from-<category>`` (a sweep's settling start from a neighbouring
    category's stride), ``warm-mu-1e-4`` or ``warm``."""
    from bladelab.predict.collocation.stride_guess import COLLOCATION_SOURCE

    if guess.source.startswith(COLLOCATION_SOURCE + " ("):  # a stored iterate's to_guess()
        return "iterate"
    if "(from-" in guess.source:
        return "from-" + guess.source.split("(from-")[1].split(":")[0]
    if guess.source.startswith("template"):
        return "template"
    if "previous but one" in guess.source:
        return "previous-but-one"
    return "warm-mu-1e-4" if settings.warm_start_mu == 1e-4 else "warm"


def objectives_by_start(fake: FakeSolve, monkeypatch, objective) -> None:
    """Wrap the installed :class:`FakeSolve`: each solve's objective is
    ``objective(start, speed)`` (:func:`start_of`; speed None for the maximum speed), None: it
    does not converge. Each call records its start under ``"start"``."""
    from bladelab.predict.collocation import continuation

    def solve(runner, settings, guess, *, model_spec, progress=None, speed_floor=None):
        sol = fake(runner, settings, guess, model_spec=model_spec, progress=progress,
                   speed_floor=speed_floor)
        call = fake.calls[-1]
        call["start"] = start_of(settings, guess)
        obj = objective(call["start"], settings.speed_m_per_s)
        nlp = dataclasses.replace(sol.nlp, objective=1.0 if obj is None else obj)
        if obj is None:
            nlp = dataclasses.replace(nlp, success=False, status="Maximum_Iterations_Exceeded")
        call["solution"] = sol = dataclasses.replace(sol, nlp=nlp)
        return sol

    monkeypatch.setattr(continuation, "predict_stride", solve)
