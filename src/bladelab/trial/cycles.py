"""Gait cycles of a measured trial: sagittal joint angles cut at touch-downs of one leg.

A cycle runs from a touch-down of ``leg`` to its next touch-down: consecutive force-platform
stances of that leg (:func:`~bladelab.trial.joint_angles.stance_legs`), at most
``max_period_s`` apart, with at most one stance of the other leg between them. Each cycle's
angles (:func:`~bladelab.trial.joint_angles.sagittal_angles`: ``trunk_pitch``, ``hip_left``,
``knee_left``, ``ankle_left``, ``hip_right`` ... [rad], flexion / dorsiflexion / forward lean
positive) are sampled at ``n`` equally spaced phases of the cycle (cubic spline of the marker
time base); a cycle with a marker gap is left out. Used by the transfemoral runner's gait cycles
(:mod:`bladelab.design.gait_cycle`) and the collocation initial guess from measured running
(:mod:`bladelab.predict.collocation`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from bladelab.errors import DataError, SpecError
from bladelab.trial.events import detect_stances
from bladelab.trial.joint_angles import sagittal_angles, stance_legs

__all__ = ["AngleCycle", "joint_angle_cycles"]

SIDES = ("left", "right")


@dataclass(frozen=True)
class AngleCycle:
    """One measured cycle: ``period`` [s], ``phase`` (n,) in [0, 1), ``angles`` name -> (n,)
    [rad] (the names of :func:`~bladelab.trial.joint_angles.sagittal_angles`), ``start_s`` the
    touch-down time [s] in the trial and ``source`` a description."""

    period: float
    phase: np.ndarray
    angles: Mapping[str, np.ndarray]
    start_s: float
    source: str


def joint_angle_cycles(
    trial,
    *,
    leg: str = "right",
    markers=None,
    static=None,
    cutoff_hz: float | None = 20.0,
    n: int = 100,
    stances: Sequence | None = None,
    max_period_s: float = 2.0,
) -> list[AngleCycle]:
    """Every complete cycle of ``leg`` in a trial with markers and force platforms.

    Parameters
    ----------
    trial
        A :class:`~bladelab.trial.Trial` (lab frame).
    leg
        ``"left"`` or ``"right"``: the leg whose touch-down starts the cycle.
    markers
        :class:`~bladelab.trial.joint_angles.JointMarkerMap` (default: the Fukuchi marker set).
    static
        Standing trial for the neutral offsets (same lab frame).
    cutoff_hz
        Marker low-pass [Hz].
    n
        Samples per cycle.
    stances
        Stance events (default :func:`~bladelab.trial.detect_stances` of the trial).
    max_period_s
        Longest accepted cycle [s].

    Raises
    ------
    SpecError
        ``leg`` is not left/right.
    DataError
        Missing markers or platforms, or no complete cycle of ``leg``.
    """
    if leg not in SIDES:
        raise SpecError(f"leg must be 'left' or 'right', got {leg!r}", where="--leg")
    other = SIDES[1 - SIDES.index(leg)]
    src = trial.source or "trial"
    events = detect_stances(trial) if stances is None else list(stances)
    legs = stance_legs(trial, events, markers=markers)
    ja = sagittal_angles(trial, markers=markers, static=static, cutoff_hz=cutoff_hz)
    t = ja.time
    series = {}
    for k, a in ja.angles.items():
        series[k] = CubicSpline(t, a) if np.all(np.isfinite(a)) else (
            lambda x, a=a: np.interp(x, t, a, left=np.nan, right=np.nan))
    mine = [i for i, s in enumerate(legs) if s == leg]
    phase = np.arange(n) / n
    cycles = []
    for i, j in zip(mine[:-1], mine[1:], strict=True):
        a, b = events[i].start_s, events[j].start_s
        between = sum(1 for s in legs[i + 1:j] if s == other)
        if b - a > max_period_s or between > 1 or j - i - 1 != between:
            continue
        tt = a + phase * (b - a)
        if tt[0] < t[0] or b > t[-1]:
            continue
        vals = {k: np.asarray(f(tt), float) for k, f in series.items()}
        cycles.append(AngleCycle(float(b - a), phase, vals, float(a),
                                 f"{src}: {leg} touch-down at {a:.3f} s"))
    if not cycles:
        raise DataError(
            f"no complete gait cycle of the {leg} leg ({len(mine)} {leg} stance(s) among "
            f"{len(events)})", file=src, where=f"{leg} leg",
            hint="a cycle needs two consecutive touch-downs of the leg on force platforms")
    return cycles
