"""The template's toes: the tracking stage of a cold start from the template, by toe motion.

Usage (repository root; one solve, one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/template_toes.py \\
        RECORDS.jsonl '{"toes": "hinge"}'

``toes``: ``"hinge"`` (the toes moved as their passive hinge moves them:
:func:`~bladelab.predict.collocation.guess.hinge_toes`; the default and the library's
template for the able runner), ``"neutral"`` (held at 0; the library's for amputees),
or ``[peak_deg]`` (a sin² rise over the second half of each stance to ``peak_deg`` at
toe-off, then the hinge's own lag in swing), each set on the library's template after its
pelvis is placed on the lowest contact (the flattened toes then lift the stance foot up to
about a centimetre above the ground late in stance). ``damping`` [N·m·s/rad]: the toes' damper (default the human body's); ``blade``:
the amputee wearing that category at 4 m/s instead of the able runner at 3.5 m/s;
``swing_knee``: true to solve the library's default problem of today (people's angles and
people's swing knee, ``people_settings``, as ``make bench``) instead of people's angles alone;
``tracking_update``: a history m to solve the tracking stage too with the predictive stages'
L-BFGS update inside IPOPT's augmented system (``extended``, m for both stages) instead of
IPOPT's default; ``jitter``: a seed, to add N(0, (10⁻⁶ rad)²) to every joint angle of the
template (the cold start's sensitivity to its start, measured over several seeds);
``clearance``: a swing clearance [m] (``swing_clearance_m``) in both stages;
``tracking_clearance``: the tracking stage's own swing clearance [m]
(``solve.TRACKING_SWING_CLEARANCE_M``; records without the key were solved before the
library had one, i.e. at 0); ``tracking_tol``: IPOPT's ``tol`` of the tracking stage alone
(the settings' 1e-4 otherwise); ``tracking_obj_change``: the tracking stage's
``acceptable_obj_change_tol`` (the stall stop's 1e-5 otherwise); ``tracking_options``: IPOPT
options of the tracking stage alone (e.g. ``{"ipopt.acceptable_constr_viol_tol": 1e-3}``);
``speed``: the prescribed
speed [m/s] instead of 3.5 (able) or 4 (amputee); ``tracking_mesh``: the tracking stage
solved on that many intervals (the template resampled to it), its solution resampled to the
50 intervals of the predictive stage, which starts from it cold (its primal values, no
multipliers, the predictive stage's own options), people's reference phase taken from it; ``settings``: further ``CollocationSettings`` fields
(e.g. ``{"tracking_weight": 30}``, the tracking stage's weight of the template's angles);
``options``: IPOPT options of every stage (e.g. ``{"ipopt.nlp_scaling_max_gradient": 10}``).
Solves on 50 intervals from the template, tracking then predictive stage, as
``bench_collocation.py``'s template row, and appends one line to RECORDS.jsonl: iterations
per stage, objective, cost of transport [J/(kg·m)], stride time [s], gait warnings, wall
time [s], date.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import math
import sys
import time

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
from bladelab.runner.params import default_runner_params, runner_params_from_dict

MESH = 50


def _runner(damping: float | None, blade: str | None):
    kind = "amputee" if blade else "able"
    data = json.loads(default_runner_params(kind, body="human", blade=blade).model_dump_json())
    if damping is not None:
        data["toe_hinge"]["damping_Nms_per_rad"] = float(damping)
    return build_runner(runner_params_from_dict(data))


def _template(runner, speed, toes):
    """The template at ``speed`` [m/s] with the toes of ``toes`` (module docstring)."""
    if isinstance(toes, str):
        return template_guess(runner, speed=speed, n=MESH, toes=toes)
    guess = template_guess(runner, speed=speed, n=MESH, toes="neutral")
    q = guess.q.copy()
    n = q.shape[0] - 1
    frac = np.linspace(0.0, 1.0, n + 1)
    stance = (np.count_nonzero(guess.vertical_grf_bw[: n // 2] > 0) + 1) / n  # one leg's share
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


def _extended_tracking(history: int) -> None:
    """Give the tracking stage the predictive stages' IPOPT options (the library applies
    them to every stage but the one named "tracking"), with L-BFGS history ``history``."""
    from bladelab.predict.collocation import solve

    solve.PREDICTIVE_LBFGS_OPTIONS = {**solve.PREDICTIVE_LBFGS_OPTIONS,
                                      "ipopt.limited_memory_max_history": history}
    stage_solve = solve._solve_stage

    def extended(nlp, x0, settings, stage, progress, **kw):
        return stage_solve(nlp, x0, settings,
                           "tracking (extended)" if stage == "tracking" else stage, progress, **kw)

    solve._solve_stage = extended


def _tracking_stop(tol: float | None, options: dict, every_stage: bool = False) -> None:
    """Solve the tracking stage (``every_stage``: every stage) to IPOPT's ``tol`` = ``tol``
    (None: as set) and with the IPOPT ``options`` added (e.g. its acceptable level's), the
    other stages as set."""
    from bladelab.predict.collocation import solve

    stage_solve = solve._solve_stage

    def loosened(nlp, x0, settings, stage, progress, **kw):
        if stage != "tracking" and not every_stage:
            return stage_solve(nlp, x0, settings, stage, progress, **kw)
        if tol is not None:
            settings = dataclasses.replace(settings, tol=tol)
        if not options:
            return stage_solve(nlp, x0, settings, stage, progress, **kw)
        own = nlp.solve

        def solve_(x, **k):
            k["options"] = {**(k.get("options") or {}), **options}
            return own(x, **k)

        nlp.solve = solve_
        try:
            return stage_solve(nlp, x0, settings, stage, progress, **kw)
        finally:
            del nlp.solve

    solve._solve_stage = loosened


class _Tracked(Exception):
    pass


def _coarse_tracking(runner, settings, guess, spec, n_track: int):
    """The tracking stage on ``n_track`` intervals, then the predictive stage on the
    settings' mesh from it (module docstring, ``tracking_mesh``)."""
    from bladelab.predict.collocation import solve

    stage_solve, held = solve._solve_stage, {}

    def stop_after_tracking(nlp, x0, settings_, stage, progress, **kw):
        if stage != "tracking":
            raise _Tracked
        held["sol"] = sol_t = stage_solve(nlp, x0, settings_, stage, progress, **kw)
        held["info"] = solve._stage_info(sol_t)
        return sol_t

    solve._solve_stage = stop_after_tracking
    try:
        coarse = dataclasses.replace(settings, mesh_intervals=n_track)
        predict_stride(runner, coarse, guess.resample(n_track), model_spec=spec)
    except _Tracked:
        pass
    finally:
        solve._solve_stage = stage_solve
    start = dataclasses.replace(held["sol"].to_guess(f"tracking stage on {n_track} intervals"),
                                multipliers=None)
    sol = predict_stride(runner, settings, start.resample(settings.mesh_intervals),
                         model_spec=spec, track=False)
    return dataclasses.replace(sol, tracking=held["info"])


def main() -> None:
    out, variant = sys.argv[1], json.loads(sys.argv[2])
    blade = variant.get("blade")
    runner = _runner(variant.get("damping"), blade)
    speed = float(variant.get("speed", 4.0 if blade else 3.5))
    people = (people_settings("human", kind=runner.kind) if variant.get("swing_knee")
              else people_term(defaults.people_weight_for("human")))
    settings = CollocationSettings(mesh_intervals=MESH, speed_m_per_s=speed,
                                   swing_clearance_m=float(variant.get("clearance", 0.0)),
                                   **people, **variant.get("settings", {}))
    guess = _template(runner, speed, variant.get("toes", "hinge"))
    if variant.get("jitter") is not None:
        q = guess.q + np.random.default_rng(int(variant["jitter"])).normal(0.0, 1e-6, guess.q.shape)
        q[-1] = q[0] + (guess.q[-1] - guess.q[0])  # periodic as the template is
        guess = dataclasses.replace(guess, q=q, qd=periodic_derivative(q, guess.period))
    if variant.get("tracking_clearance") is not None:
        from bladelab.predict.collocation import solve

        solve.TRACKING_SWING_CLEARANCE_M = float(variant["tracking_clearance"])
    if variant.get("tracking_update"):
        _extended_tracking(int(variant["tracking_update"]))
    options = dict(variant.get("tracking_options") or {})
    if variant.get("tracking_obj_change"):
        options["ipopt.acceptable_obj_change_tol"] = float(variant["tracking_obj_change"])
    if variant.get("tracking_tol") or options:
        _tracking_stop(variant.get("tracking_tol"), options)
    if variant.get("options"):
        _tracking_stop(None, dict(variant["options"]), every_stage=True)
    t0 = time.perf_counter()
    spec = {"model": runner.kind, "body": "human"} | ({"blade": blade} if blade else {})
    if variant.get("tracking_mesh"):
        sol = _coarse_tracking(runner, settings, guess, spec, int(variant["tracking_mesh"]))
    else:
        sol = predict_stride(runner, settings, guess, model_spec=spec)
    record = {"variant": variant, "converged": sol.converged,
              "tracking_iterations": (sol.tracking or {}).get("iterations"),
              "predictive_iterations": sol.nlp.iterations,
              "objective": sol.nlp.objective,
              "cost_of_transport_J_per_kg_m": sol.cost_of_transport_J_per_kg_m,
              "stride_time_s": sol.period_s, "warnings": sol.gait_warnings(),
              "wall_s": time.perf_counter() - t0, "date": datetime.date.today().isoformat()}
    with open(out, "a") as f:
        f.write(json.dumps(record) + "\n")
    print(json.dumps(record))


if __name__ == "__main__":
    main()
