"""Tracking a collocation stride with the reflex controller (the reflex optimisation's warm start).

A reflex controller found by CMA-ES from SCONE's parameters has to discover a gait by itself;
a collocation stride (:mod:`bladelab.predict.collocation`) of the same runner at the same speed
is a gait it can be pulled towards first. :class:`GaitReference` holds that stride's joint
angles over one stride cycle starting at leg 0's touch-down; :func:`tracking_error` scores a
closed-loop simulation against it, stride by stride:

``J_track = mean over strides s of [ mean over phases φ and tracked coordinates j of
(q_j(t_s + φ·T_s) − q_ref,j(φ))² + ln(T_s / T_ref)² ]`` [rad²]

with the strides s running from one leg-0 touch-down to the next (the objective's own
touch-downs: 0.1 body weights, :mod:`bladelab.predict.reflex.closed_loop`), those that start
after ``skip`` seconds (the start transient is not tracked), φ at :data:`PHASES` points, T_s the
stride time. The mean is over at least the strides the reference would run in the tracked
time (``(duration − skip) / T_ref − 1``), each one missing scored :data:`NO_STRIDE` (1 rad², a
57° error): otherwise a gait that tracks two strides well and then falls would beat one that
tracks a little worse to the end.

The tracked coordinates (:func:`tracked_dofs`): pelvis tilt and every joint but the socket
(the pelvis translations are not angles, the socket is a stiff spring). The workflow:
``bladelab predict --track SOLUTION.json`` (seed 001's objective plus ``w_track``·J_track),
then ``bladelab predict --init OUT/best.json`` with seed 001's objective alone
(docs/predictive.md, "Warm start from a collocation stride").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from bladelab.errors import InputFileError
from bladelab.predict import defaults
from bladelab.predict.collocation.solution import CollocationSolution

#: Phase points per stride at which the angles are compared.
PHASES = 50
#: J_track of a simulation without one tracked stride [rad²].
NO_STRIDE = 1.0
#: Touch-down threshold of the reference [body weights], the closed loop's.
TOUCHDOWN_BW = 0.1
#: Default weight of the tracking term [1/rad²] (``bladelab predict --track-weight``): 10° of
#: rms error costs 30, as much as running 30 % of the simulation outside the speed window
#: (w_gait = 100).
DEFAULT_WEIGHT = defaults.TRACK_WEIGHT_PER_RAD2
#: Coordinates never tracked.
UNTRACKED = ("pelvis_tx", "pelvis_tz", "socket_angle_r")


def tracked_dofs(dof_names) -> tuple[str, ...]:
    """The coordinates a reference tracks: every rotation but the socket."""
    return tuple(n for n in dof_names if n not in UNTRACKED)


@dataclass(frozen=True)
class GaitReference:
    """Joint angles of one periodic stride, starting at leg 0's touch-down.

    Attributes
    ----------
    dof_names
        The tracked coordinates (columns of ``angles``).
    angles
        (PHASES, n) angles [rad] at phases ``(k + 0.5) / PHASES`` of the stride.
    period_s
        Stride time [s].
    speed_mps
        Mean speed [m/s].
    model_spec
        ``{"model": ..., "blade": ...}`` of the collocation solution.
    source
        The file it was read from.
    """

    dof_names: tuple[str, ...]
    angles: np.ndarray
    period_s: float
    speed_mps: float
    model_spec: dict
    source: str

    @classmethod
    def from_solution(cls, sol, source: str = "collocation solution") -> GaitReference:
        """The reference of a :class:`~bladelab.predict.collocation.solution.CollocationSolution`."""
        dofs = tracked_dofs(sol.dof_names)
        cols = [sol.dof_names.index(d) for d in dofs]
        q = np.asarray(sol.nlp.q)[:, cols]            # (n + 1, k), node n == node 0
        t = np.asarray(sol.nlp.time)
        period = float(sol.period_s)
        start = _leg0_touchdown(sol, source, "track a running stride")
        phase_t = start + (np.arange(PHASES) + 0.5) / PHASES * period
        angles = np.column_stack([np.interp(phase_t % period, t, q[:, j], period=period)
                                  for j in range(len(dofs))])
        return cls(dofs, angles, period, float(sol.mean_speed_mps), dict(sol.model_spec),
                   source)

    @classmethod
    def read(cls, path: str | Path) -> GaitReference:
        """The reference of a collocation solution file (``solution.json``, ``speed-4.json``);
        refused when the solve did not converge."""
        sol = _converged_solution(path, "track a converged solution, not a best iterate")
        return cls.from_solution(sol, source=str(path))

    def check_model(self, kind: str, blade: str | None, where: str, *,
                    body: str | None = None, dof_names: tuple[str, ...] | None = None) -> None:
        """Refuse a reference of another runner than (``kind``, ``blade``) on ``body`` (None:
        any body) whose tracked coordinates are not all among ``dof_names`` (None: no
        check)."""
        spec = self.model_spec
        own_body = spec.get("body", "seed001")
        same = (spec.get("model") == kind and (body is None or own_body == body)
                and (kind != "amputee" or spec.get("blade") == blade)
                and (dof_names is None or set(self.dof_names) <= set(dof_names)))
        if not same:
            raise InputFileError(
                f"the stride is of the {spec.get('model')} runner"
                + (f" with {spec.get('blade')}" if spec.get("blade") else "")
                + f" on the {own_body} body, the controller's runner is {kind}"
                + (f" with {blade}" if blade else "")
                + (f" on the {body} body" if body else " on a body with other coordinates"),
                file=self.source, where=where, hint="track a stride of the same runner")


def _converged_solution(path: str | Path, hint: str) -> CollocationSolution:
    """The collocation solution of ``path``; InputFileError with ``hint`` if the solve did not
    converge."""
    sol = CollocationSolution.read(path)
    if not sol.converged:
        raise InputFileError("the collocation solve did not converge", file=path, hint=hint)
    return sol


def _leg0_touchdown(sol: CollocationSolution, source: str | Path, hint: str) -> float:
    """Time [s] in the stride at which leg 0's vertical force rises through
    :data:`TOUCHDOWN_BW`; InputFileError naming ``source`` with ``hint`` if it never lands."""
    start = _periodic_rise(np.asarray(sol.nlp.time), sol.leg_vertical_force()[:, 0],
                           TOUCHDOWN_BW * sol.body_weight_N)
    if start is None:
        raise InputFileError(f"leg 0 ({sol.leg_names[0]}) never lands in the stride",
                             file=source, hint=hint)
    return start


def _periodic_rise(t: np.ndarray, f: np.ndarray, threshold: float) -> float | None:
    """Time [s] at which the periodic signal ``f`` (nodes ``t``, last == first) first rises
    through ``threshold``, interpolated linearly; None if it never does."""
    for i in range(len(t) - 1):
        a, b = f[i], f[i + 1]
        if a <= threshold < b:
            return float(t[i] + (threshold - a) / (b - a) * (t[i + 1] - t[i]))
    return None


@dataclass(frozen=True)
class StrideStart:
    """A collocation stride's state at leg 0's touch-down: the start of a reflex simulation
    (``ObjectiveSettings.start_stride``).

    Attributes
    ----------
    dof_names
        The stride's coordinates (columns of ``qpos``/``qvel``).
    qpos, qvel
        Coordinates [m, rad] and speeds [m/s, rad/s] at the touch-down (the pelvis's forward
        position as in the stride).
    speed_mps
        The stride's mean speed [m/s].
    model_spec
        ``{"model": ..., "blade": ..., "body": ...}`` of the collocation solution.
    """

    dof_names: tuple[str, ...]
    qpos: np.ndarray
    qvel: np.ndarray
    speed_mps: float
    model_spec: dict


@lru_cache(maxsize=4)
def stride_start(path: str) -> StrideStart:
    """The :class:`StrideStart` of a converged collocation solution file (linear interpolation
    between the nodes around leg 0's touch-down, :data:`TOUCHDOWN_BW`), once per process."""
    sol = _converged_solution(path, "start from a converged solution, not a best iterate")
    t = np.asarray(sol.nlp.time)
    start = _leg0_touchdown(sol, path, "start from a running stride")

    def at(values: np.ndarray) -> np.ndarray:
        return np.array([np.interp(start, t, values[:, j]) for j in range(values.shape[1])])

    return StrideStart(tuple(sol.dof_names), at(np.asarray(sol.nlp.q)),
                       at(np.asarray(sol.nlp.qd)), float(sol.mean_speed_mps),
                       dict(sol.model_spec))


@lru_cache(maxsize=4)
def cached_reference(path: str) -> GaitReference:
    """:meth:`GaitReference.read`, once per process (every candidate of a run tracks one file)."""
    return GaitReference.read(path)


def tracking_error(time: np.ndarray, qpos: np.ndarray, touchdowns: np.ndarray,
                   reference: GaitReference, dof_index: np.ndarray,
                   skip: float, duration: float) -> tuple[float, int]:
    """(J_track [rad²], strides tracked) of a simulation (module docstring).

    ``time`` (n,) [s] and ``qpos`` (n, nq) are its samples, ``touchdowns`` the closed loop's
    (rows time [s], pelvis x [m], leg, strike), ``dof_index`` the qpos columns of
    ``reference.dof_names``, ``skip`` [s] the untracked start, ``duration`` [s] the requested
    simulation time (a fall ends the samples sooner)."""
    legs = touchdowns[:, 2] if len(touchdowns) else np.zeros(0)
    starts = touchdowns[legs == 0, 0] if len(touchdowns) else np.zeros(0)
    starts = starts[starts >= skip]
    errors = []
    phases = (np.arange(PHASES) + 0.5) / PHASES
    for t0, t1 in zip(starts[:-1], starts[1:], strict=True):
        if t1 > time[-1]:
            break
        at = t0 + phases * (t1 - t0)
        q = np.column_stack([np.interp(at, time, qpos[:, j]) for j in dof_index])
        angle = float(np.mean((q - reference.angles) ** 2))
        errors.append(angle + math.log((t1 - t0) / reference.period_s) ** 2)
    expected = max(1, math.floor((duration - skip) / reference.period_s) - 1)
    missing = max(0, expected - len(errors))
    return (sum(errors) + NO_STRIDE * missing) / max(expected, len(errors)), len(errors)


__all__ = ["DEFAULT_WEIGHT", "GaitReference", "cached_reference", "tracked_dofs", "tracking_error"]
