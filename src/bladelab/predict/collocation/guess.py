"""Initial guesses of one periodic stride for the collocation problems.

A stride starts at a touch-down of the left leg (the intact leg of the amputee) and ends at its
next one; a guess gives the runner's coordinates and speeds at ``n + 1`` equally spaced times
(the last node one period after the first, pelvis_tx advanced by the stride length) and, when
known, muscle activations and normalised tendon forces (a
:class:`~bladelab.predict.collocation.stride_guess.StrideGuess`). Three sources:

- :func:`template_guess`: people's running as a template (people's mean hip, knee and ankle
  angles at 3.5 m/s, time-warped to people's stance share and stride time at the speed, the
  other leg half a period later; the transfemoral runner's passive knee straight in stance,
  :func:`prosthetic_knee_template`), the stance foot on the ground and ballistic flights
  between the stances;
- :func:`guess_from_trial`: measured running (e.g. the Fukuchi et al. 2017 treadmill trial at
  3.5 m/s): sagittal angles from markers (:mod:`bladelab.trial.cycles`), averaged over the
  trial's left-leg cycles, the pelvis placed the same way; the amputee's socket held at 0;
- :func:`guess_from_result`: a forward simulation (a reflex-controller solution re-simulated,
  :func:`guess_from_reflex`): the last complete left-leg stride with its muscle states.

Sign conventions are the runner model's (:mod:`bladelab.runner.model`): hip flexion +, knee
0 straight and negative flexed, ankle dorsiflexion +, pelvis tilt + backward.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np

from bladelab._io import read_json
from bladelab.constants import STANDARD_GRAVITY
from bladelab.datasets import (
    MEASURED_TRIAL_SPEED_M_PER_S,
    measured_running_trial,
    measured_static_trial,
)
from bladelab.errors import DataError, SpecError
from bladelab.predict.collocation.people import people_joint_angles
from bladelab.predict.collocation.running_bands import reference_band
from bladelab.predict.collocation.stride_guess import StrideGuess, periodic_derivative
from bladelab.predict.reflex.controller import read_parameters
from bladelab.predict.reflex.objective import simulate_controlled
from bladelab.predict.reflex.optimize import runner_and_layout, stored_body, stored_settings
from bladelab.runner.analyses import step_touchdowns
from bladelab.runner.layout import CP_LEG
from bladelab.runner.model import RunnerModel, contact_heights
from bladelab.runner.simulate import RC_FZ
from bladelab.trial import read_c3d
from bladelab.trial.cycles import joint_angle_cycles

__all__ = [
    "prosthetic_stride_on",
    "guess_from_reflex",
    "guess_from_result",
    "guess_from_trial",
    "hinge_toes",
    "measured_trial_guess",
    "template_guess",
    "template_vertical_grf",
]

#: Fraction of the stride at which people's stance ends in the mean curves of
#: :func:`~bladelab.predict.collocation.people.people_joint_angles` (the measured vertical
#: force of RBDS002 and RBDS003 at 3.5 m/s falls to zero at 31–32 % of the stride).
PEOPLE_TOE_OFF = 0.315


def prosthetic_stride_on(model: RunnerModel, guess: StrideGuess, *, depth_m: float = 0.01,
                         source: RunnerModel | None = None,
                         source_grf_bw: np.ndarray | None = None) -> StrideGuess:
    """A stride of one amputee runner kind as the start of another (the transtibial runner's
    stride as the transfemoral runner's: docs/design.md "Predicted transfemoral gaits"):
    coordinates and muscles matched by name (:meth:`StrideGuess.on_model`), then the pelvis
    moved up or down and speeds taken from the new coordinates.

    With ``source`` (the runner ``guess`` is a stride of) the stride keeps its flights: at every
    node where the source's lowest contact is on the ground the pelvis moves so that this
    runner's lowest contact is as deep, and the shift is interpolated (periodically) through
    the flights; the vertical force pattern is ``source_grf_bw`` [body weights] when given.
    Without it every node is lowered until its lowest contact is ``depth_m`` deep (no flight is
    left) and the force pattern is :func:`template_vertical_grf`. Measured on the transfemoral
    runner from the transtibial stride: the grounded start never led to alternating steps, the
    start with its flights did (benchmarks/design/transfemoral-gait-2026-12-01)."""
    g = guess.on_model(model)
    if source is None:
        q = _grounded(model, g.q)
        q[:, model.dof("pelvis_tz")] -= depth_m
        return replace(g, q=q, qd=periodic_derivative(q, g.period),
                       vertical_grf_bw=template_vertical_grf(np.linspace(0.0, 1.0, q.shape[0])),
                       source=f"{g.source}, grounded")
    heights = _lowest_contacts(source, guess.q)
    shift = heights - _lowest_contacts(model, g.q)
    ground = heights <= 0.0
    if ground.any() and not ground.all():
        n = shift.size - 1  # the last node repeats the first
        k = np.flatnonzero(ground[:n])
        shift[:n] = np.interp(np.arange(n), np.concatenate([k - n, k, k + n]),
                              np.tile(shift[k], 3))
        shift[n] = shift[0]
    q = g.q.copy()
    q[:, model.dof("pelvis_tz")] += shift
    grf = g.vertical_grf_bw if source_grf_bw is None else np.asarray(source_grf_bw, float)
    return replace(g, q=q, qd=periodic_derivative(q, g.period), vertical_grf_bw=grf,
                   source=f"{g.source}, its flights kept")


def _lowest_contacts(model: RunnerModel, q: np.ndarray) -> np.ndarray:
    """Height [m] of the lowest contact point at each node of ``q`` (negative: penetrating)."""
    return np.array([contact_heights(model, qk).min() for qk in q])


def _grounded(model: RunnerModel, q: np.ndarray) -> np.ndarray:
    """``q`` with pelvis_tz lowered (or raised) at every node until the lowest contact point is
    on the ground."""
    q = q.copy()
    q[:, model.dof("pelvis_tz")] -= _lowest_contacts(model, q)
    return q


def _angles_to_q(model: RunnerModel, time_frac: np.ndarray, period: float, speed: float,
                 angles: dict[str, np.ndarray]) -> np.ndarray:
    """Model coordinates from sagittal angles [rad] (trial names: hip_left, knee_left (flexion
    +), ankle_left, ..., trunk_pitch (forward lean +)) at fractions of the stride."""
    q = np.zeros((time_frac.size, len(model.dof_names)))
    q[:, model.dof("pelvis_tx")] = speed * period * time_frac
    q[:, model.dof("pelvis_tilt")] = -angles.get("trunk_pitch", np.zeros(time_frac.size))
    for side, s in (("left", "l"), ("right", "r")):
        q[:, model.dof(f"hip_flexion_{s}")] = angles[f"hip_{side}"]
        q[:, model.dof(f"knee_angle_{s}")] = -angles[f"knee_{side}"]
        if f"ankle_angle_{s}" in model.dof_names:
            q[:, model.dof(f"ankle_angle_{s}")] = angles[f"ankle_{side}"]
    return _grounded(model, q)


def template_guess(model: RunnerModel, *, speed: float = 3.5, n: int = 50,
                   period: float | None = None, toes: str | None = None) -> StrideGuess:
    """People's running as a template stride at ``speed`` [m/s] on ``n`` intervals.

    The hip, knee and ankle follow people's mean angles at 3.5 m/s
    (:func:`~bladelab.predict.collocation.people.people_joint_angles`: RBDS002 and RBDS003 of
    Fukuchi et al. 2017), the right leg half a stride later, the trunk 5° forward, the
    transfemoral runner's passive knee :func:`prosthetic_knee_template`. The stride time
    defaults to the middle of people's band at ``speed``
    (:func:`~bladelab.predict.collocation.running_bands.reference_band`: 0.71 s at 3.5 m/s);
    each leg's stance lasts people's share of the stride at that speed (0.315 at 3.5 m/s,
    shorter when faster, as the contact-time band) and the angles are time-warped so that
    people's toe-off falls at its end. The force pattern is :func:`template_vertical_grf` of
    that stance. The pelvis keeps the stance foot on the ground and flies a ballistic arc
    between the stances (:func:`_stances_and_flights`).

    ``toes`` (feet with a toe hinge only): ``"hinge"`` moves them as their passive hinge
    moves them (:func:`hinge_toes`, set after the pelvis is placed), ``"neutral"`` holds them
    at 0. The default is per runner, as measured on cold starts
    (benchmarks/collocation_speed/README.md, "The template's tracking stage"): the hinge's
    toes for the able runner (its tracking stage a quarter as long, to a clean stride where
    neutral toes end on a stride whose feet strike twice), neutral toes on an amputee's intact
    foot (the hinge's toes gave flagged or dear strides in three of five categories).
    """
    if toes is None:
        toes = "hinge" if model.kind == "able" else "neutral"
    if toes not in ("hinge", "neutral"):
        raise SpecError(f"toes must be 'hinge' or 'neutral', got {toes!r}", where="toes")
    if not (speed > 0 and math.isfinite(speed)):
        raise SpecError(f"speed must be > 0 m/s, got {speed}", where="speed")
    stride_lo, stride_hi, _ = reference_band("stride time", speed)
    period = float(period) if period is not None else 0.5 * (stride_lo + stride_hi)
    if not (period > 0 and math.isfinite(period)):
        raise SpecError(f"stride time must be > 0 s, got {period}", where="period")
    duty = PEOPLE_TOE_OFF * _contact_share(speed) / _contact_share(MEASURED_TRIAL_SPEED_M_PER_S)
    frac = np.linspace(0.0, 1.0, n + 1)
    curves = people_joint_angles()
    q = np.zeros((n + 1, len(model.dof_names)))
    q[:, model.dof("pelvis_tx")] = speed * period * frac
    q[:, model.dof("pelvis_tilt")] = -math.radians(5.0)
    for side, lag in (("l", 0.0), ("r", 0.5)):
        phase = np.mod(frac - lag, 1.0)
        people_phase = np.where(phase < duty, phase / duty * PEOPLE_TOE_OFF,
                                PEOPLE_TOE_OFF + (phase - duty) / (1.0 - duty)
                                * (1.0 - PEOPLE_TOE_OFF))
        for base, curve in curves.items():
            name = f"{base}_{side}"
            if name in model.dof_names:
                q[:, model.dof(name)] = np.interp(people_phase, np.arange(100) / 100.0, curve,
                                                  period=1.0)
    if model.kind == "transfemoral":  # a passive knee: straight in stance, flexed in swing
        q[:, model.dof("knee_angle_r")] = -prosthetic_knee_template(frac + 0.5)
    grf = template_vertical_grf(frac, duty=duty)
    q = _stances_and_flights(model, q, period, duty)
    if toes == "hinge":
        q = hinge_toes(model, q, period, duty)
    return StrideGuess(f"template at {speed:g} m/s", period, q, periodic_derivative(q, period),
                       vertical_grf_bw=grf)


def _contact_share(speed: float) -> float:
    """People's contact time over their stride time at ``speed`` [m/s] (the bands' middles)."""
    contact_lo, contact_hi, _ = reference_band("contact time", speed)
    stride_lo, stride_hi, _ = reference_band("stride time", speed)
    return (contact_lo + contact_hi) / (stride_lo + stride_hi)


def _stances_and_flights(model: RunnerModel, q: np.ndarray, period: float,
                         duty: float) -> np.ndarray:
    """``q`` with the pelvis height of a running stride: during each leg's stance (the left
    leg's from 0 to ``duty`` of the stride, the right leg's half a stride later) the pelvis
    is moved so that that leg's lowest contact point is on the ground; between the stances it
    flies a ballistic arc (gravity, no contact) joining the heights at their ends, raised
    where a foot would be in the ground."""
    q = q.copy()
    n = q.shape[0] - 1
    iz = model.dof("pelvis_tz")
    legs = model.contact_params[:, CP_LEG]
    frac = np.arange(n) / n
    stance_leg = np.full(n, -1)
    stance_leg[frac < duty] = 0
    stance_leg[np.mod(frac - 0.5, 1.0) < duty] = 1
    for k in np.flatnonzero(stance_leg >= 0):
        q[k, iz] -= contact_heights(model, q[k])[legs == stance_leg[k]].min()
    grounded = np.flatnonzero(stance_leg >= 0)
    h = period / n
    for j, a in enumerate(grounded):  # each flight: from stance node a to the next one, b
        b = grounded[j + 1] if j + 1 < grounded.size else grounded[0] + n
        if b - a < 2:
            continue
        za, zb, span = q[a, iz], q[b % n, iz], (b - a) * h
        nodes = np.arange(a + 1, b) % n
        t = (np.arange(a + 1, b) - a) * h
        arc = za + (zb - za) * t / span + 0.5 * STANDARD_GRAVITY * t * (span - t)
        q[nodes, iz] = np.maximum(arc, q[nodes, iz] - _lowest_contacts(model, q[nodes]))
    q[n, iz] = q[0, iz]
    return q


def hinge_toes(model: RunnerModel, q: np.ndarray, period: float, duty: float) -> np.ndarray:
    """``q`` (a stride on ``q.shape[0] - 1`` intervals of ``period`` [s], the left leg's stance
    from 0 to ``duty`` of it, the right leg's half a stride later) with the toes of each foot
    that has them (``mtp_angle_<side>``) moved as their passive hinge moves them: towards the
    angle that keeps the toes flat on the ground while the heel rises in stance (the toe tip as
    low as the ball, never flexed) and towards neutral in swing, through the hinge's
    first-order lag of time constant D/K (``RunnerParams.toe_hinge``; the toes' inertia is
    negligible), periodic over the stride. The pelvis is not moved: with the lag the toe tip
    may sit a few millimetres in the ground late in stance."""
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
        q[:n, j] = _periodic_lag(flat, period / n, tau)
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
    held at its end value, started from the one state that the period returns to."""
    decay = math.exp(-h / max(tau, 1e-12))

    def one_period(x: float) -> np.ndarray:
        out = np.empty(target.size)
        for k in range(target.size):
            x = decay * x + (1.0 - decay) * target[k]
            out[k] = x
        return out

    # linear in the start: x_end = decay**n · x_0 + x_end(from 0); periodic when x_end = x_0
    return one_period(one_period(0.0)[-1] / (1.0 - decay ** target.size))


#: Upper end [deg] of the search for the toes' flat angle (the hinge's ligament begins at 60°).
_TOE_FLAT_MAX_DEG = 60.0


def prosthetic_knee_template(phase: np.ndarray) -> np.ndarray:
    """Flexion [rad] of a passive prosthetic knee over a stride (``phase`` 0–1 from that leg's
    touch-down): 5° through a stance of 35 % of the stride (the knee on its extension stop, as
    transfemoral sprinters run), a smooth rise to 65° at mid-swing and back before touch-down."""
    swing = np.clip((np.mod(np.asarray(phase, float), 1.0) - 0.35) / 0.65, 0.0, 1.0)
    return np.radians(5.0 + 30.0 * (1.0 - np.cos(2.0 * math.pi * swing)))


def template_vertical_grf(phase: np.ndarray, *, duty: float = 0.34) -> np.ndarray:
    """Vertical ground force [body weights] of a template stride at ``phase`` (0–1, left
    touch-down at 0): a half-sine stance of ``duty`` (fraction of the stride) per leg, the right
    leg half a stride later, scaled so that the stride's mean is one body weight (peak
    π/(4·duty) = 2.3 BW at the default, as measured at 3.5 m/s: Fukuchi trial 2.3–2.6 BW,
    contact 0.22–0.25 s of a 0.70 s stride)."""
    if not 0.05 <= duty <= 0.5:
        raise SpecError(f"stance duty must be within 0.05–0.5 of the stride, got {duty}",
                        where="duty")
    peak = math.pi / (4.0 * duty)
    out = np.zeros_like(np.asarray(phase, float))
    for start in (0.0, 0.5):
        p = np.mod(np.asarray(phase, float) - start, 1.0)
        inside = p < duty
        out[inside] += peak * np.sin(math.pi * p[inside] / duty)
    return out


def guess_from_trial(model: RunnerModel, path: str | Path, *, static: str | Path | None = None,
                     n: int = 50, speed: float | None = None, markers=None) -> StrideGuess:
    """The mean left-leg stride of a measured running trial (C3D with markers and force
    platforms) on ``n`` intervals.

    ``speed`` [m/s] is the treadmill's (or the runner's) mean speed: required, since a
    treadmill trial's markers do not travel. ``static``: a standing trial, so that standing is
    the model's zero posture.
    """
    if speed is None or not (speed > 0 and math.isfinite(speed)):
        raise SpecError("a trial guess needs the running speed", where="speed",
                        hint="give the treadmill speed in m/s (3.5 for RBDS001runT35)")
    trial = read_c3d(path)
    axes = trial.metadata.get("axes", {})
    st = None
    if static is not None:
        st = read_c3d(static, forward=axes.get("forward", "auto"), up=axes.get("up", "auto"))
    cycles = joint_angle_cycles(trial, leg="left", markers=markers, static=st, n=n)
    names = [k for k in cycles[0].angles if k.split("_")[0] in ("hip", "knee", "ankle", "trunk")]
    good = [c for c in cycles if all(np.all(np.isfinite(c.angles[k])) for k in names)]
    if not good:
        raise DataError("every left-leg cycle has a marker gap", file=path, where="left leg")
    period = float(np.mean([c.period for c in good]))
    mean = {k: np.mean([c.angles[k] for c in good], axis=0) for k in names}
    closed = {k: np.append(v, v[0]) for k, v in mean.items()}  # node n = node 0 (periodic)
    frac = np.linspace(0.0, 1.0, n + 1)
    q = _angles_to_q(model, frac, period, speed, closed)
    force = _measured_grf(trial, good, frac)
    return StrideGuess(f"{Path(path).name}: mean of {len(good)} left-leg cycles at {speed:g} m/s",
                       period, q, periodic_derivative(q, period),
                       vertical_grf_bw=None if force is None else force[1],
                       horizontal_grf_bw=None if force is None else force[0])


def measured_trial_guess(model: RunnerModel, *, n: int = 50) -> StrideGuess:
    """:func:`guess_from_trial` of the measured running trial shipped with bladelab (Fukuchi et
    al. 2017, subject RBDS001 on a treadmill at
    :data:`~bladelab.datasets.MEASURED_TRIAL_SPEED_M_PER_S` m/s, its standing trial as the zero
    posture; :mod:`bladelab.datasets`, which names a missing file) on ``n`` intervals."""
    return guess_from_trial(model, measured_running_trial(), static=measured_static_trial(),
                            n=n, speed=MEASURED_TRIAL_SPEED_M_PER_S)


def _measured_grf(trial, cycles, frac: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The trial's total horizontal (forward) and vertical platform force over its mean cycle
    [body weights: divided by the cycle's mean vertical force, which over a periodic stride is
    the runner's weight]; None without platforms."""
    if not trial.platforms:
        return None
    curves = []
    for c in cycles:
        tt = c.start_s + frac * c.period
        fx = sum(np.interp(tt, p.time, p.force[:, 0]) for p in trial.platforms)
        fz = sum(np.interp(tt, p.time, p.force[:, 2]) for p in trial.platforms)
        fine = c.start_s + np.linspace(0.0, 1.0, 401) * c.period
        mean = np.mean(sum(np.interp(fine, p.time, p.force[:, 2]) for p in trial.platforms))
        if mean > 0:
            curves.append((fx / mean, fz / mean))
    return tuple(np.mean(curves, axis=0)) if curves else None


def guess_from_result(result, *, n: int = 50) -> StrideGuess:
    """The last complete left-leg stride of a forward simulation (a
    :class:`~bladelab.runner.RunnerResult`) on ``n`` intervals, with its activations and
    tendon forces (steps as :func:`bladelab.runner.analyses.step_touchdowns` counts them)."""
    model = result.model
    cp = model.contact_params
    forces = np.stack([result.contacts[:, cp[:, CP_LEG] == leg, RC_FZ].sum(axis=1)
                       for leg in (0, 1)], axis=1)
    left = [t for t, leg, _ in step_touchdowns(result.time, forces, model.body_weight)
            if leg == 0]
    if len(left) < 2:
        raise DataError(f"the simulation has {len(left)} left-leg step(s); a stride needs two",
                        where="guess from a simulation",
                        hint="simulate longer, or use a solution that runs")
    t0, t1 = left[-2], left[-1]
    tt = np.linspace(t0, t1, n + 1)

    def at(y: np.ndarray) -> np.ndarray:
        return np.stack([np.interp(tt, result.time, y[:, j]) for j in range(y.shape[1])], axis=1)

    fmax = model.muscle_params[:, 0]
    return StrideGuess(
        f"forward simulation, stride {t0:.3f}–{t1:.3f} s", float(t1 - t0),
        at(result.qpos), at(result.qvel),
        activation=at(result.muscles[:, :, 0]),
        tendon_force=at(result.muscles[:, :, 3] / fmax),
        vertical_grf_bw=at(forces.sum(axis=1, keepdims=True))[:, 0] / model.body_weight,
        dof_names=tuple(model.dof_names), muscle_names=tuple(model.muscle_names),
    )


def guess_from_reflex(path: str | Path, *, n: int = 50, duration: float = 5.0) -> StrideGuess:
    """Re-simulate a reflex-controller parameter file (its own model, blade, speed and settings)
    for ``duration`` [s] and take :func:`guess_from_result` of it."""
    data = read_json(path, what="parameter file")
    body = stored_body(data, path)
    model, layout = runner_and_layout(data.get("model", "able"), data.get("blade"), body)
    settings = stored_settings(data, speed=float(data.get("speed_m_per_s", 3.5)),
                               duration=duration, nominal=True)
    _, result = simulate_controlled(model, read_parameters(path, layout, body=body),
                                    layout=layout,
                                    settings=settings, record_every=4)
    guess = guess_from_result(result, n=n)
    return replace(guess, source=f"{Path(path).name} re-simulated: {guess.source}")
