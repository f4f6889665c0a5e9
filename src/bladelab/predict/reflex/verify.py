"""Checks of a reflex gait (:func:`verify_solution`): it runs, at its speed, with
flight and alternating steps, and so do copies of it moved along unseen directions and started
at other initial speeds."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from bladelab._io import read_json
from bladelab.errors import SpecError
from bladelab.predict.reflex.controller import read_parameters
from bladelab.predict.reflex.objective import PUSH_AFTER, ObjectiveSettings, simulate_controlled
from bladelab.predict.reflex.optimize import runner_and_layout, stored_body, stored_settings
from bladelab.predict.reflex.robust import VERIFY_JITTER_SEED, jittered_parameters
from bladelab.runner.analyses import (
    CONTACT_THRESHOLD_N,
    power_balance_residual_pct,
    step_touchdowns,
    swing_contacts,
)

__all__ = ["verify_solution"]


def verify_solution(
    path: str | Path,
    *,
    model: str | None = None,
    blade: str | None = None,
    speed: float | str | None = None,
    duration: float = 10.0,
    speed_tolerance: float = 0.1,
    max_power_residual_pct: float = 2.0,
    jittered_copies: int = 0,
    jitter: float = 1e-9,
    initial_speed_change: float = 0.0,
    push_change: float = 0.0,
    push_phases: int = 5,
    refined_step: int = 0,
) -> dict:
    """Re-simulate a parameter file and check the gait criteria.

    The simulation uses the objective settings the file was optimised with (its ``settings``:
    time step, initial speed, weights; without robust sampling), at ``speed`` for ``duration``;
    ``speed`` changes what the run is judged against, not its start (a file without an initial
    speed starts at the speed it was optimised at). ``speed="reached"`` judges the gait at the
    speed its nominal run reaches, rounded to 0.01 m/s (the nominal's ``cost`` is then the
    objective at the file's own prescribed speed; the other runs' at the reached one): one
    nominal simulation serves both.

    Criteria (all recomputed from the file, nothing trusted from it): ``duration`` [s] without a
    fall; mean speed within ``speed_tolerance`` [m/s] of ``speed`` (default: the file's
    ``speed_m_per_s``); steps (SCONE's definition, :func:`bladelab.runner.analyses.step_touchdowns`:
    bounces, scuffs below 0.1 body weight and strikes of the swinging foot are not steps)
    alternating between the legs after the first (``same_leg_steps`` 0: no hop or gallop); a
    flight phase (no leg loaded above 20 N) in every stride (one step of a leg to its next);
    reported, not criteria: ``swing_contacts`` (a swinging foot striking the ground,
    :func:`bladelab.runner.analyses.swing_contacts`) and the largest one's peak force [N] and
    [body weights], the pelvis tilt's mean, minimum and maximum [deg];
    power-balance residual below
    ``max_power_residual_pct`` % (runner analyses). With ``jittered_copies`` = n > 0 the same
    criteria must also hold for n copies of the parameters moved by ``jitter`` (relative,
    :func:`jittered_parameters`, along directions other than the objective's robust copies;
    only the parameters the file holds move, each along a direction drawn from its name, so
    the copies do not change when the controller layout grows):
    a gait that survives only on one floating-point path (another
    CPU, compiler or library version) is not a solution. With ``initial_speed_change`` c > 0
    they must also hold from an initial speed [m/s] (1 + c) and (1 − c) times the file's (the
    stable-gait acceptance: ±5 %). With ``push_change`` p > 0 they must hold after a push (forward speed times
    1 + p and 1 − p) at each of ``push_phases`` times spread over the second after
    :data:`~bladelab.predict.reflex.objective.PUSH_AFTER` (the stride's phases; the basin of
    the gait, not of its start). With ``refined_step`` = n > 0 (True: 1) they must also hold
    at the file's time step halved n times (dt/2, ..., dt/2ⁿ), same scheme: a gait that runs
    only at the step it was optimised at lives on the discretisation, not on the model (the
    step is a budget; a result must have settled in it). Returns the measured values (the
    copies' under ``"jittered"``, the changed starts' under ``"initial_speed"``, the pushed
    runs' under ``"pushed"``, the refined runs under ``"refined"``, finest last),
    ``judged_at_m_per_s`` (the speed judged at [m/s]),
    ``judged_at_reached_speed`` (whether that is the reached speed: not for a nominal run that
    falls, judged at the prescribed one), ``nominal_ok`` (the nominal run alone) and ``ok``
    (every run).
    """

    data = read_json(path, what="parameter file")
    model = model or data.get("model", "able")
    blade = blade or data.get("blade")
    own_speed = float(data.get("speed_m_per_s", 3.5))
    reached = speed == "reached"
    if isinstance(speed, str) and not reached:
        raise SpecError(f"speed must be a number [m/s], None or 'reached', not {speed!r}",
                        where="speed")
    speed = own_speed if speed is None or reached else float(speed)
    body = stored_body(data, path)
    runner, layout = runner_and_layout(model, blade, body)
    x = read_parameters(path, layout, body=body)
    # the copies move the file's own parameters, each along a direction of its name: the same
    # copies whatever parameters a later layout adds (at their defaults, unmoved)
    own = np.array([name in (data.get("parameters") or {}) for name in layout.names])
    settings = stored_settings(data, speed=speed, duration=duration, nominal=True)
    if settings.initial_speed is None:  # judged at another speed, it starts as it was run
        settings = replace(settings, initial_speed=float(
            (data.get("settings") or {}).get("speed", own_speed)))
    limits = (duration, speed, speed_tolerance, max_power_residual_pct)
    out = _check_gait(runner, layout, x, settings, limits)
    if reached and not out["fell"]:
        # the trajectory does not depend on the speed judged at (only the cost's speed window
        # does): re-judge the nominal run at its own speed instead of simulating it again
        speed = round(float(out["mean_speed_m_per_s"]), 2)
        settings = replace(settings, speed=speed)
        limits = (duration, speed, speed_tolerance, max_power_residual_pct)
        out["ok"] = _meets(out, limits)
    out["judged_at_m_per_s"] = speed
    out["judged_at_reached_speed"] = bool(reached and not out["fell"])
    out["nominal_ok"] = out["ok"]  # "ok" below: the nominal and every added run

    def also(key: str, runs: list[tuple[dict, np.ndarray, ObjectiveSettings]]) -> None:
        # more runs under ``key`` (each: what it changed, parameters, settings); all must pass
        out[key] = [{**what, **_check_gait(runner, layout, xr, sr, limits)}
                    for what, xr, sr in runs]
        out["ok"] = bool(out["ok"] and all(c["ok"] for c in out[key]))

    if jittered_copies > 0:
        also("jittered", [({}, xj, settings) for xj in
                          jittered_parameters(x, jittered_copies, jitter, VERIFY_JITTER_SEED,
                                              names=layout.names, moved=own)])
    if initial_speed_change > 0:
        speeds = [settings.start_speed * (1 + c)
                  for c in (initial_speed_change, -initial_speed_change)]
        also("initial_speed", [({"initial_speed_m_per_s": v}, x,
                                replace(settings, initial_speed=v)) for v in speeds])
    if push_change > 0:
        pushes = [(float(t), c) for t in PUSH_AFTER + np.arange(push_phases) / push_phases
                  for c in (push_change, -push_change)]
        also("pushed", [({"push_time_s": t, "push_change": c}, x, replace(settings, push=(t, c)))
                        for t, c in pushes])
    if refined_step:
        steps = [settings.dt / 2 ** h for h in range(1, int(refined_step) + 1)]
        also("refined", [({"dt_s": dt}, x, replace(settings, dt=dt)) for dt in steps])
    return out


def _check_gait(runner, layout, x, settings: ObjectiveSettings, limits: tuple) -> dict:
    """Simulate ``x`` and measure the gait criteria (:func:`verify_solution`)."""
    ev, res = simulate_controlled(runner, x, layout=layout, settings=settings, record_every=2)
    leg = res.model.contact_params[:, 6]
    forces = np.stack([res.contacts[:, leg == i, 1].sum(axis=1) for i in (0, 1)], axis=1)
    loaded = forces > CONTACT_THRESHOLD_N
    airborne = ~(loaded[:, 0] | loaded[:, 1])
    steps = step_touchdowns(res.time, forces, runner.body_weight)
    flights = [bool(np.any(airborne[a:b])) for a, b in _strides(res.time, steps)]
    same_leg = _same_leg_steps(steps)
    residual = power_balance_residual_pct(
        res, skip_times=() if settings.push is None else (settings.push[0],))
    tilt = np.degrees(res.qpos[:, runner.dof("pelvis_tilt")])
    out = {
        "fell": ev.fell,
        "duration_s": ev.duration,
        "mean_speed_m_per_s": ev.mean_speed,
        "strides": len(flights),
        "strides_with_flight": int(sum(flights)),
        "same_leg_steps": same_leg,
        "swing_contacts": int(len(swings := swing_contacts(res))),
        "swing_contact_peak_N": float(swings.peak_N.max()) if len(swings) else 0.0,
        "swing_contact_peak_bw": (float(swings.peak_N.max()) / runner.body_weight
                                  if len(swings) else 0.0),
        "pelvis_tilt_mean_deg": float(tilt.mean()),
        "pelvis_tilt_min_deg": float(tilt.min()),
        "pelvis_tilt_max_deg": float(tilt.max()),
        "power_balance_residual_pct": residual,
        "cost": ev.cost,
    }
    out["ok"] = _meets(out, limits)
    return out


def _meets(run: dict, limits: tuple) -> bool:
    """Whether a measured run (:func:`_check_gait`) meets the gait criteria with
    ``limits`` (duration [s], speed [m/s], speed tolerance [m/s], power residual [%])."""
    duration, speed, tolerance, max_residual = limits
    return bool(
        not run["fell"]
        and run["duration_s"] >= duration - 1e-9
        and abs(run["mean_speed_m_per_s"] - speed) <= tolerance
        and run["strides"] >= 2
        and run["strides_with_flight"] == run["strides"]
        and run["same_leg_steps"] == 0
        and run["power_balance_residual_pct"] <= max_residual
    )


def _same_leg_steps(steps: list[tuple[float, int, float]]) -> int:
    """Steps after the second by the same leg as the step before (hops, gallops, a scuff
    counted as a step), of :func:`bladelab.runner.analyses.step_touchdowns`' ``steps``."""
    order = [leg for _, leg, _ in steps]
    return sum(1 for i in range(2, len(order)) if order[i] == order[i - 1])


def _strides(time: np.ndarray, steps: list[tuple[float, int, float]]) -> list[tuple[int, int]]:
    """Sample ranges of every stride of both legs: from one step of a leg (``steps`` of
    :func:`bladelab.runner.analyses.step_touchdowns`, time [s] and leg) to its next step."""
    out = []
    for leg in (0, 1):
        t = [ts for ts, side, _ in steps if side == leg]
        idx = np.searchsorted(time, t)
        out += list(zip(idx[:-1].tolist(), idx[1:].tolist(), strict=True))
    return out
