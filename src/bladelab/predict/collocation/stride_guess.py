"""An initial guess of one periodic stride: :class:`StrideGuess`, and what it needs on another
model.

A stride starts at a touch-down of the left leg (the intact leg of the amputee) and ends at its
next one; a guess gives the runner's coordinates and speeds at ``n + 1`` equally spaced times
(the last node one period after the first, pelvis_tx advanced by the stride length) and, when
known, muscle activations and normalised tendon forces. The guesses themselves (template,
measured trial, forward simulation) are made by :mod:`bladelab.predict.collocation.guess`; a
collocation solution gives one too (its ``to_guess``, source :data:`COLLOCATION_SOURCE`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import mujoco
import numpy as np
from scipy.interpolate import CubicSpline

from bladelab.errors import SpecError
from bladelab.runner.layout import CP_BLADE, CP_SITE
from bladelab.runner.model import RunnerModel, contact_heights

__all__ = [
    "COLLOCATION_SOURCE",
    "DROPPABLE_COORDINATES",
    "StrideGuess",
    "deflected_blade",
    "periodic_derivative",
]

#: The guess source prefix that marks a collocation solution (no tracking stage needed).
COLLOCATION_SOURCE = "collocation solution"

#: Coordinates of a guess that another model may lack (prefixes): the toe and arch hinges (the seed-001
#: body has none) and the transtibial prosthesis's socket hinge (the transfemoral runner has
#: none: its prosthesis hangs from the knee). Any other lost coordinate refuses the mapping.
DROPPABLE_COORDINATES = ("mtp_angle", "midtarsal_angle", "socket_angle")


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
    qdd, excitation, tendon_force_rate
        (n + 1, ·) the controls of a collocation solution (accelerations [m/s², rad/s²],
        excitations [-], normalised tendon-force rates [1/s]), or None: derived from the
        states by :meth:`~bladelab.predict.collocation.transcription.StrideNLP.
        initial_vector`. With them (and the states) a solution's own point is restored
        exactly. Kept by :meth:`with_speed` (pelvis_tx's acceleration scaled), dropped by
        :meth:`resample` to another mesh and by :meth:`on_model` when it moves columns.
    multipliers
        IPOPT's multipliers (variable bounds, constraints) of the stride NLP this guess solves,
        or None: the dual half of a warm start
        (:meth:`~bladelab.predict.collocation.transcription.StrideNLP.initial_multipliers`
        takes them only if they fit the NLP). Kept by :meth:`with_speed`; dropped by
        :meth:`resample` to another mesh and by :meth:`on_model` when it moves columns.
    horizontal_grf_bw
        (n + 1,) total horizontal ground force [body weights, forward positive] of a measured
        trial, or None: drawn beside a stride's in reports, never tracked.
    reference_phase
        The phase [fraction of the stride] of people's joint angles that the stride was solved
        against (:mod:`~bladelab.predict.collocation.people`), or None: a solve from it with
        people's reference keeps that phase, so that a solution is its own optimum again.
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
    qdd: np.ndarray | None = None
    excitation: np.ndarray | None = None
    tendon_force_rate: np.ndarray | None = None
    multipliers: tuple[np.ndarray, np.ndarray] | None = None
    reference_phase: float | None = None
    horizontal_grf_bw: np.ndarray | None = None

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
            dof_names=None, muscle_names=None, multipliers=None, qdd=None, excitation=None,
            tendon_force_rate=None,
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
            horizontal_grf_bw=None if self.horizontal_grf_bw is None
            else _resample(self.horizontal_grf_bw[:, None], old, new)[:, 0],
            qdd=None, excitation=None, tendon_force_rate=None, multipliers=None,
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
        qdd = None if self.qdd is None else self.qdd.copy()
        if qdd is not None:
            qdd[:, 0] *= scale
        return replace(self, q=q, qd=qd, qdd=qdd,
                       source=f"{self.source}, scaled to {speed:g} m/s")


def _resample(y: np.ndarray, old: np.ndarray, new: np.ndarray,
              advance: np.ndarray | None = None) -> np.ndarray:
    """Periodic cubic interpolation of columns ``y`` (rows at ``old``) at ``new``; columns with
    a net ``advance`` over the period (pelvis_tx) are interpolated after removing it."""
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
