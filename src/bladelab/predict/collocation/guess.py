"""Initial guesses of one periodic stride for the collocation problems.

A stride starts at a touch-down of the left leg (the intact leg of the amputee) and ends at its
next one; a guess gives the runner's coordinates and speeds at ``n + 1`` equally spaced times
(the last node one period after the first, pelvis_tx advanced by the stride length) and, when
known, muscle activations and normalised tendon forces. Three sources:

- :func:`template_guess`: a smooth template of running kinematics (sinusoidal hip, knee and
  ankle angles with literature-typical ranges at 3–5 m/s, the other leg half a period later;
  the transfemoral runner's passive knee straight in stance, :func:`prosthetic_knee_template`),
  the pelvis lowered at every node until its lowest contact point touches the ground (a guess
  that starts near the ground converges far better than a constant-height one, DESIGN.md);
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
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from bladelab.errors import DataError, SpecError
from bladelab.runner.model import RunnerModel, contact_heights

__all__ = [
    "DROPPABLE_COORDINATES",
    "StrideGuess",
    "deflected_blade",
    "periodic_derivative",
    "prosthetic_stride_on",
    "guess_from_reflex",
    "guess_from_result",
    "guess_from_trial",
    "template_guess",
    "template_vertical_grf",
]


#: Coordinates of a guess that another model may lack (prefixes): the toe hinges (the seed-001
#: body has none) and the transtibial prosthesis's socket hinge (the transfemoral runner has
#: none: its prosthesis hangs from the knee). Any other lost coordinate refuses the mapping.
DROPPABLE_COORDINATES = ("mtp_angle", "socket_angle")


def prosthetic_stride_on(model: RunnerModel, guess: StrideGuess, *,
                         depth_m: float = 0.01) -> StrideGuess:
    """A stride of one amputee runner kind as the start of another (the transtibial runner's
    alternating run as the transfemoral runner's: docs/design.md "Predicted transfemoral
    gaits"): coordinates and muscles matched by name (:meth:`StrideGuess.on_model`), the
    pelvis lowered at every node until the lowest contact is ``depth_m`` [m] deep, speeds
    from the new coordinates, the vertical force pattern of :func:`template_vertical_grf`."""
    g = guess.on_model(model)
    q = _grounded(model, g.q)
    q[:, model.dof("pelvis_tz")] -= depth_m
    return replace(g, q=q, qd=periodic_derivative(q, g.period),
                   vertical_grf_bw=template_vertical_grf(np.linspace(0.0, 1.0, q.shape[0])),
                   source=f"{g.source}, grounded")


@dataclass(frozen=True)
class StrideGuess:
    """Coordinates and speeds of one stride at ``n + 1`` equally spaced nodes.

    Attributes
    ----------
    source
        Where the guess comes from (for reports).
    period
        Stride time [s].
    q, qd
        (n + 1, n_dof) coordinates [m, rad] and speeds [m/s, rad/s] in ``model.dof_names``
        order; the last row is one period after the first.
    activation, tendon_force
        (n + 1, n_muscles) activations [-] and tendon forces normalised by Fmax [-], or None.
    vertical_grf_bw
        (n + 1,) total vertical ground force [body weights], or None: the stance pattern that
        the tracking stage follows besides the joint angles (measured, simulated, or a template
        of alternating stances). Without it, tracking the angles alone leaves the pelvis height
        free, and the measured angles were met by one-legged hops and 20-BW bounds (docs/
        collocation.md).
    dof_names, muscle_names
        The names of the columns of ``q``/``qd`` and of the muscle arrays, where the guess
        comes from another model (e.g. a seed-001 solution as the start of the toe body);
        None: the target model's own. :meth:`on_model` matches them by name.
    """

    source: str
    period: float
    q: np.ndarray
    qd: np.ndarray
    activation: np.ndarray | None = None
    tendon_force: np.ndarray | None = None
    vertical_grf_bw: np.ndarray | None = None
    dof_names: tuple[str, ...] | None = None
    muscle_names: tuple[str, ...] | None = None

    def on_model(self, model: RunnerModel) -> StrideGuess:
        """This guess on ``model``'s coordinates and muscles, matched by name: coordinates
        the guess lacks (a toe hinge) start at 0 (neutral), coordinates ``model`` lacks are
        dropped if they are :data:`DROPPABLE_COORDINATES`, a multi-link blade's joints the
        guess lacks at the blade's static deflection (:func:`deflected_blade`), muscles it
        lacks at activation 0.05 with tendon forces from static equilibrium. Raises if a
        coordinate of the guess other than a toe hinge has no place in ``model`` (a guess of
        the other model kind)."""
        dofs, muscles = tuple(model.dof_names), tuple(model.muscle_names)
        if self.dof_names is None or (self.dof_names == dofs and self.muscle_names == muscles):
            if self.q.shape[1] != len(dofs):
                raise SpecError(f"the guess has {self.q.shape[1]} coordinates, the model "
                                f"{len(dofs)}", where="guess",
                                hint="a guess of another model needs its dof_names")
            return self
        lost = [n for n in self.dof_names if n not in dofs
                and not n.startswith(DROPPABLE_COORDINATES)]
        if lost:
            raise SpecError(f"the guess's coordinates {lost} are not in the {model.kind} model",
                            where="guess", hint="start from a guess of the same model kind")

        def cols(a, names, new, fill):
            if a is None or names is None:
                return None
            out = np.full((a.shape[0], len(new)), fill)
            for j, name in enumerate(new):
                if name in names:
                    out[:, j] = a[:, names.index(name)]
            return out

        keep_muscles = self.muscle_names is not None and set(muscles) <= set(self.muscle_names)
        q, qd = cols(self.q, self.dof_names, dofs, 0.0), cols(self.qd, self.dof_names, dofs, 0.0)
        blade = [j for j, name in enumerate(dofs)
                 if name.startswith("blade_joint") and name not in self.dof_names]
        if blade:
            q = deflected_blade(model, q)
            qd[:, blade] = periodic_derivative(q, self.period)[:, blade]
        return replace(
            self, q=q, qd=qd,
            activation=cols(self.activation, self.muscle_names, muscles, 0.05),
            tendon_force=cols(self.tendon_force, self.muscle_names, muscles, 0.0)
            if keep_muscles else None,
            dof_names=None, muscle_names=None,
            source=f"{self.source}, on the {model.kind} model's coordinates")

    @property
    def n_intervals(self) -> int:
        """Mesh intervals n (nodes − 1)."""
        return self.q.shape[0] - 1

    @property
    def speed(self) -> float:
        """Mean forward speed [m/s] (pelvis travel over the period)."""
        return float((self.q[-1, 0] - self.q[0, 0]) / self.period)

    def resample(self, n: int) -> StrideGuess:
        """The same stride on ``n`` intervals (periodic cubic interpolation of each column)."""
        if n < 4:
            raise SpecError(f"need at least 4 mesh intervals, got {n}", where="mesh intervals")
        if n == self.n_intervals:
            return self
        old = np.linspace(0.0, 1.0, self.n_intervals + 1)
        new = np.linspace(0.0, 1.0, n + 1)
        return replace(
            self,
            q=_resample(self.q, old, new, advance=self.q[-1] - self.q[0]),
            qd=_resample(self.qd, old, new),
            activation=None if self.activation is None else _resample(self.activation, old, new),
            tendon_force=None if self.tendon_force is None
            else _resample(self.tendon_force, old, new),
            vertical_grf_bw=None if self.vertical_grf_bw is None
            else _resample(self.vertical_grf_bw[:, None], old, new)[:, 0],
        )

    def with_speed(self, speed: float) -> StrideGuess:
        """The same stride at another mean speed [m/s]: the stride length scales with the
        speed (same period), pelvis forward positions and speed accordingly."""
        if not (speed > 0 and math.isfinite(speed)):
            raise SpecError(f"speed must be > 0 m/s, got {speed}", where="speed")
        q, qd = self.q.copy(), self.qd.copy()
        scale = speed / self.speed
        q[:, 0] = q[0, 0] + (q[:, 0] - q[0, 0]) * scale
        qd[:, 0] *= scale
        return replace(self, q=q, qd=qd, source=f"{self.source}, scaled to {speed:g} m/s")


def _resample(y: np.ndarray, old: np.ndarray, new: np.ndarray,
              advance: np.ndarray | None = None) -> np.ndarray:
    """Periodic cubic interpolation of columns ``y`` (rows at ``old``) at ``new``; columns with
    a net ``advance`` over the period (pelvis_tx) are interpolated after removing it."""
    from scipy.interpolate import CubicSpline

    drift = np.zeros(y.shape[1]) if advance is None else np.asarray(advance, float)
    base = y - np.outer(old, drift)
    base[-1] = base[0]  # exactly periodic once the advance is removed
    return CubicSpline(old, base, bc_type="periodic")(new) + np.outer(new, drift)


def periodic_derivative(q: np.ndarray, period: float) -> np.ndarray:
    """Time derivative of node values (last row = first + advance) by periodic central
    differences [unit/s]."""
    n = q.shape[0] - 1
    h = period / n
    body = q[:-1]
    advance = q[-1] - q[0]
    nxt = np.vstack([body[1:], body[:1] + advance])
    prv = np.vstack([body[-1:] - advance, body[:-1]])
    d = (nxt - prv) / (2 * h)
    return np.vstack([d, d[:1]])


def deflected_blade(model: RunnerModel, q: np.ndarray, *, depth_m: float = 0.01) -> np.ndarray:
    """``q`` (rows of coordinates) with a multi-link blade's joints at the static deflection
    that leaves its lowest sole at most ``depth_m`` [m] deep: at each node where it is deeper,
    a vertical load F at that sole turns joint i by ``θ_i = J_i·F / K_i`` (J the sole point's
    vertical Jacobian column at the undeformed blade, K_i the joint's stiffness [N·m/rad]),
    with F found by bisection. The start of a blade's stride from a stride of the sphere
    blade, whose compression the undeformed links would otherwise meet 10 cm deep in the
    ground."""
    import mujoco

    from bladelab.runner.model import CP_BLADE, CP_SITE

    if model.blade_model is None:
        return q
    m = model.mj_model
    joints = [model.dof(f"blade_joint{i}") for i in range(len(model.blade_model.joints))]
    stiffness = np.array([j.stiffness for j in model.blade_model.joints])
    on_blade = model.contact_params[:, CP_BLADE] == 1
    soles = model.contact_params[on_blade]
    out = np.array(q, dtype=float, copy=True)
    d = mujoco.MjData(m)
    jac = np.zeros((3, m.nv))
    for k in range(out.shape[0]):
        out[k, joints] = 0.0
        depth = -contact_heights(model, out[k])[on_blade]
        if depth.max() <= depth_m:
            continue
        row = soles[int(depth.argmax())]
        site = int(row[CP_SITE])
        d.qpos[:] = out[k]
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_jacSite(m, d, jac, None, site)
        per_newton = jac[2, joints] / stiffness  # rad/N

        def deepest(force: float, k=k, per_newton=per_newton) -> float:
            trial = out[k].copy()
            trial[joints] = force * per_newton
            return float(-contact_heights(model, trial)[on_blade].min())

        lo, hi = 0.0, 1.0e3
        while deepest(hi) > depth_m and hi < 1.0e6:
            hi *= 2.0
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if deepest(mid) > depth_m else (lo, mid)
        out[k, joints] = hi * per_newton
    return out


def _grounded(model: RunnerModel, q: np.ndarray) -> np.ndarray:
    """``q`` with pelvis_tz lowered (or raised) at every node until the lowest contact point is
    on the ground."""
    q = q.copy()
    iz = model.dof("pelvis_tz")
    for k in range(q.shape[0]):
        q[k, iz] -= contact_heights(model, q[k]).min()
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
                   period: float | None = None) -> StrideGuess:
    """A smooth template stride at ``speed`` [m/s] on ``n`` intervals (module docstring).

    The period defaults to a typical stride time, 0.75 s at 3.5 m/s, shorter when faster
    (stride frequency rising ~5 %/(m/s)).
    """
    if not (speed > 0 and math.isfinite(speed)):
        raise SpecError(f"speed must be > 0 m/s, got {speed}", where="speed")
    period = float(period) if period is not None else 0.75 / (1.0 + 0.05 * (speed - 3.5))
    frac = np.linspace(0.0, 1.0, n + 1)
    deg = math.pi / 180.0

    def leg(phase: np.ndarray) -> dict[str, np.ndarray]:
        w = 2 * math.pi * phase
        # phase 0 = touch-down: hip flexed ~30°, knee ~15° flexed; swing knee flexion peaks
        # ~100° at 70 % of the cycle; ankle dorsiflexed in stance, plantarflexed at toe-off
        return {
            "hip": deg * (10.0 + 25.0 * np.cos(w - 0.15)),
            "knee": deg * (45.0 - 35.0 * np.cos(w - 4.3) + 15.0 * np.cos(2 * w - 1.2)),
            "ankle": deg * (-5.0 + 15.0 * np.cos(w - 0.9)),
        }

    left, right = leg(frac), leg(frac + 0.5)
    if model.kind == "transfemoral":  # a passive knee: straight in stance, flexed in swing
        right["knee"] = prosthetic_knee_template(frac + 0.5)
    angles = {"trunk_pitch": np.full(frac.size, 5.0 * deg)}
    for side, a in (("left", left), ("right", right)):
        angles.update({f"hip_{side}": a["hip"], f"knee_{side}": a["knee"],
                       f"ankle_{side}": a["ankle"]})
    q = _angles_to_q(model, frac, period, speed, angles)
    return StrideGuess(f"template at {speed:g} m/s", period, q, periodic_derivative(q, period),
                       vertical_grf_bw=template_vertical_grf(frac))


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


#: The measured running trial of ``--guess trial`` (Fukuchi et al. 2017, subject RBDS001 at
#: 3.5 m/s on a treadmill), its standing trial and its speed [m/s]: in the shared data folder
#: beside the project (absent from an installed package, then ``--guess trial`` says so).
MEASURED_TRIAL = (Path(__file__).resolve().parents[4].parent / "shared" / "data" / "real"
                  / "fukuchi2017" / "RBDS001runT35.c3d")
MEASURED_STATIC = MEASURED_TRIAL.with_name("RBDS001static.c3d")
MEASURED_TRIAL_SPEED_M_PER_S = 3.5


def guess_from_trial(model: RunnerModel, path: str | Path, *, static: str | Path | None = None,
                     n: int = 50, speed: float | None = None, markers=None) -> StrideGuess:
    """The mean left-leg stride of a measured running trial (C3D with markers and force
    platforms) on ``n`` intervals.

    ``speed`` [m/s] is the treadmill's (or the runner's) mean speed: required, since a
    treadmill trial's markers do not travel. ``static``: a standing trial, so that standing is
    the model's zero posture.
    """
    from bladelab.trial import read_c3d
    from bladelab.trial.cycles import joint_angle_cycles

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
    return StrideGuess(f"{Path(path).name}: mean of {len(good)} left-leg cycles at {speed:g} m/s",
                       period, q, periodic_derivative(q, period),
                       vertical_grf_bw=_measured_vertical_grf(trial, good, frac))


def _measured_vertical_grf(trial, cycles, frac: np.ndarray) -> np.ndarray | None:
    """The trial's total vertical platform force over its mean cycle [body weights: divided by
    the cycle's mean force, which over a periodic stride is the runner's weight]; None without
    platforms."""
    if not trial.platforms:
        return None
    curves = []
    for c in cycles:
        tt = c.start_s + frac * c.period
        fz = sum(np.interp(tt, p.time, p.force[:, 2]) for p in trial.platforms)
        fine = c.start_s + np.linspace(0.0, 1.0, 401) * c.period
        mean = np.mean(sum(np.interp(fine, p.time, p.force[:, 2]) for p in trial.platforms))
        if mean > 0:
            curves.append(fz / mean)
    return np.mean(curves, axis=0) if curves else None


def guess_from_result(result, *, n: int = 50) -> StrideGuess:
    """The last complete left-leg stride of a forward simulation (a
    :class:`~bladelab.runner.RunnerResult`) on ``n`` intervals, with its activations and
    tendon forces (steps as :func:`bladelab.runner.analyses.step_touchdowns` counts them)."""
    from bladelab.runner.analyses import step_touchdowns
    from bladelab.runner.model import CP_LEG
    from bladelab.runner.simulate import RC_FZ

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
    from bladelab._io import read_json
    from bladelab.predict.reflex import (
        read_parameters,
        runner_and_layout,
        simulate_controlled,
        stored_settings,
    )

    data = read_json(path, what="parameter file")
    model, layout = runner_and_layout(data.get("model", "able"), data.get("blade"))
    settings = stored_settings(data, speed=float(data.get("speed_m_per_s", 3.5)),
                               duration=duration, nominal=True)
    _, result = simulate_controlled(model, read_parameters(path, layout), layout=layout,
                                    settings=settings, record_every=4)
    guess = guess_from_result(result, n=n)
    return replace(guess, source=f"{Path(path).name} re-simulated: {guess.source}")
