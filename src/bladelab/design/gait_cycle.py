"""Gait cycles for the kinematics-driven transfemoral runner.

A :class:`GaitCycle` is one period of sagittal joint angles, starting at touch-down of the
prosthetic leg. Angles [rad] inside, flexion positive:

=====================  ==============================================================
``hip_sound``          thigh relative to pelvis, flexion +
``knee_sound``         flexion +
``ankle_sound``        dorsiflexion +
``hip_prosthetic``     thigh relative to pelvis, flexion +
``knee_prosthetic``    prosthetic knee flexion + (the knee is passive: only its value at the
                       start is used, as initial condition; kept for motion adaptation)
``trunk_pitch``        pelvis/trunk forward lean + (tracked by a residual servo)
=====================  ==============================================================

Gait-cycle CSV (:func:`read_gait_csv`): a column ``time_s`` (one period, starting at 0 at
prosthetic touch-down; the last row may repeat the first at t = T) and the angle columns with the
suffix ``_deg`` (``hip_sound_deg`` ...); ``trunk_pitch_deg`` is optional (default 10°). The period
is the time span (last − first + one sample, or the last time if its row equals the first).

From a measured trial (:func:`gait_cycle_from_trial`): sagittal angles from markers
(:mod:`bladelab.trial.joint_angles`), one cycle from each touch-down of the chosen (prosthetic)
leg to its next one (force-platform stances, each assigned to the leg whose foot is over the
centre of pressure), time-normalised and averaged over the trial's cycles; the other leg is the
sound leg.

Motion adaptation (seed 002), the cycles as response surfaces of the design factors:
:mod:`bladelab.design.motion_model`.

The default cycle (:func:`default_gait_cycle`) is a **smooth template, not a measurement**: a
periodic cubic spline through literature-typical sagittal joint angles of sprinting at about
7 m/s (touch-down hip flexion ~40°, toe-off hip extension ~10°, stance knee flexion ~40°, swing
knee flexion ~115°; stride 0.52 s, contact ~23 % of the cycle), mirrored half a period for the
other leg; the prosthetic knee lands nearly straight (5°), as transfemoral runners do. Use your
own measured cycles for real studies.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.interpolate import CubicSpline

from bladelab._io import atomic_path
from bladelab.errors import DataError, InputFileError, SpecError
from bladelab.trial.c3d import read_c3d
from bladelab.trial.cycles import joint_angle_cycles
from bladelab.trial.joint_angles import load_joint_marker_map

__all__ = [
    "ANGLE_NAMES",
    "GaitCycle",
    "average_gait_cycle",
    "default_gait_cycle",
    "gait_cycle_from_runner",
    "gait_cycle_from_trial",
    "gait_cycles_from_trial",
    "MeasuredGaitCycle",
    "measured_gait_cycle",
    "read_gait_csv",
    "write_gait_csv",
]

ANGLE_NAMES: tuple[str, ...] = ("hip_sound", "knee_sound", "ankle_sound", "hip_prosthetic",
                                "knee_prosthetic", "trunk_pitch")
_REQUIRED = ANGLE_NAMES[:5]


@dataclass(frozen=True, eq=False)
class GaitCycle:
    """One period of joint angles.

    Attributes
    ----------
    period
        Cycle duration T [s].
    phase
        Normalised times in [0, 1) of the samples (increasing).
    angles
        Name -> angles [rad] at ``phase`` (see the module table).
    source
        Where the cycle came from.
    """

    period: float
    phase: np.ndarray
    angles: Mapping[str, np.ndarray]
    source: str = ""

    def __post_init__(self) -> None:
        if not (self.period > 0 and math.isfinite(self.period)):
            raise DataError(f"the period must be > 0 s, got {self.period}", where=self.source)
        ph = np.asarray(self.phase, float)
        if ph.ndim != 1 or ph.size < 4 or np.any(np.diff(ph) <= 0) or ph[0] < 0 or ph[-1] >= 1:
            raise DataError("phase must increase within [0, 1) with at least 4 samples",
                            where=self.source)
        missing = [n for n in _REQUIRED if n not in self.angles]
        if missing:
            raise DataError(f"missing joint angles {missing}", where=self.source,
                            hint=f"a gait cycle needs {list(_REQUIRED)}")
        ang = {n: np.asarray(self.angles.get(n, np.full(ph.size, math.radians(10.0))), float)
               for n in ANGLE_NAMES}
        for n, a in ang.items():
            if a.shape != ph.shape or not np.all(np.isfinite(a)):
                raise DataError(f"{n}: needs {ph.size} finite values", where=self.source)
        object.__setattr__(self, "phase", ph)
        object.__setattr__(self, "angles", ang)

    def _splines(self) -> dict[str, CubicSpline]:
        ph = np.append(self.phase, self.phase[0] + 1.0)
        return {n: CubicSpline(ph, np.append(a, a[0]), bc_type="periodic")
                for n, a in self.angles.items()}

    def at(self, t: np.ndarray | float, *, derivative: int = 0) -> dict[str, np.ndarray]:
        """Angles [rad] (or their time derivatives [rad/s^k]) at times ``t`` [s] (periodic)."""
        s = self._splines()
        ph = np.mod(np.asarray(t, float) / self.period, 1.0)
        return {n: sp(ph, derivative) / self.period**derivative for n, sp in s.items()}

    def resampled(self, n: int) -> GaitCycle:
        """The cycle at ``n`` equally spaced phases."""
        ph = np.arange(n) / n
        vals = self.at(ph * self.period)
        return GaitCycle(self.period, ph, vals, self.source)

    def to_frame(self) -> pd.DataFrame:
        """Tidy CSV layout: ``time_s`` and ``<angle>_deg``."""
        df = pd.DataFrame({"time_s": self.phase * self.period})
        for n, a in self.angles.items():
            df[f"{n}_deg"] = np.degrees(a)
        return df

    def to_dict(self) -> dict:
        return {"period_s": self.period, "n_samples": int(self.phase.size), "source": self.source}


def _template(keys: Sequence[tuple[float, float]], shift: float = 0.0):
    ph = np.array([k[0] for k in keys]) / 100.0
    val = np.radians([k[1] for k in keys])
    sp = CubicSpline(np.append(ph, ph[0] + 1.0), np.append(val, val[0]), bc_type="periodic")
    return lambda p: sp(np.mod(p - shift, 1.0))


# (phase % from that leg's touch-down, angle deg): literature-typical sprint values (template)
_HIP = [(0, 30), (12, 12), (23, -12), (35, 0), (55, 45), (75, 62), (90, 42)]
_KNEE = [(0, 25), (10, 40), (23, 22), (45, 115), (65, 90), (82, 35), (92, 20)]
_ANKLE = [(0, 0), (10, 18), (23, -25), (40, -12), (60, 5), (85, 5)]
_PROS_KNEE = [(0, 5), (23, 5), (45, 90), (68, 60), (85, 12)]


def default_gait_cycle(*, period_s: float = 0.52, trunk_pitch_deg: float = 10.0,
                       n: int = 104) -> GaitCycle:
    """The built-in template cycle (see the module notes: a template, not a measurement)."""
    ph = np.arange(n) / n
    angles = {
        "hip_sound": _template(_HIP, 0.5)(ph),
        "knee_sound": _template(_KNEE, 0.5)(ph),
        "ankle_sound": _template(_ANKLE, 0.5)(ph),
        "hip_prosthetic": _template(_HIP)(ph),
        "knee_prosthetic": _template(_PROS_KNEE)(ph),
        "trunk_pitch": np.full(n, math.radians(trunk_pitch_deg)),
    }
    return GaitCycle(period_s, ph, angles, "bladelab template (literature-typical sprint angles)")


def write_gait_csv(cycle: GaitCycle, path: str | Path) -> Path:
    """Write ``cycle`` as a gait-cycle CSV (:meth:`GaitCycle.to_frame`'s layout, the one
    :func:`read_gait_csv` reads; 6 significant digits), atomically; returns the path."""
    with atomic_path(path) as tmp:
        cycle.to_frame().to_csv(tmp, index=False, float_format="%.6g")
    return Path(path)


def read_gait_csv(path: str | Path) -> GaitCycle:
    """Read a gait-cycle CSV (see the module notes)."""
    path = Path(path)
    try:
        df = pd.read_csv(path)
    except (OSError, ValueError) as err:
        raise InputFileError(f"cannot read the gait cycle: {err}", file=path) from None
    cols = ["time_s", *(f"{n}_deg" for n in _REQUIRED)]
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise InputFileError(f"missing columns {missing}", file=path,
                             hint=f"a gait-cycle CSV needs {cols} (trunk_pitch_deg optional)")
    try:
        t = df["time_s"].to_numpy(float)
    except ValueError:
        raise InputFileError("time_s must be numeric", file=path) from None
    if t.size < 5 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise InputFileError("time_s must increase (at least 5 rows)", file=path)
    names = [n for n in ANGLE_NAMES if f"{n}_deg" in df.columns]
    vals = {n: np.radians(df[f"{n}_deg"].to_numpy(float)) for n in names}
    closes = all(abs(v[-1] - v[0]) < 1e-9 for v in vals.values())
    if closes:
        period = float(t[-1] - t[0])
        t, vals = t[:-1], {n: v[:-1] for n, v in vals.items()}
    else:
        period = float(t[-1] - t[0] + np.median(np.diff(t)))
    try:
        return GaitCycle(period, (t - t[0]) / period, vals, str(path))
    except DataError as err:
        raise InputFileError(err.message, file=path, hint=err.hint) from None


def gait_cycle_from_runner(result, *, cycle: int = -1, threshold_N: float = 50.0) -> GaitCycle:
    """One gait cycle from a runner simulation (e.g. a predictive run's ``RunnerResult``).

    The cycle runs from a touch-down of the right (prosthetic) leg to its next one (``cycle``
    picks which complete cycle; default the last). Angles map from the runner's coordinates
    (``bladelab.runner.model`` conventions): ``hip_flexion_r/l`` -> ``hip_prosthetic/sound``,
    −``knee_angle_r/l`` -> ``knee_prosthetic/sound`` (flexion positive), ``ankle_angle_l`` ->
    ``ankle_sound``, −``pelvis_tilt`` -> ``trunk_pitch``. A transtibial runner's biological
    right knee becomes the prosthetic knee's starting angle (the transfemoral knee is passive).

    Parameters
    ----------
    result
        An object with ``states()`` (time + coordinates, rad) and ``leg_grf()`` (tidy: time,
        leg, Fz), such as :class:`bladelab.runner.simulate.RunnerResult`.
    cycle
        Index of the complete cycle (Python indexing).
    threshold_N
        Vertical force that counts as contact [N].
    """
    states = result.states()
    grf = result.leg_grf()
    legs = [str(v) for v in pd.unique(grf["leg"])]
    right = "prosthetic" if "prosthetic" in legs else "right"
    if right not in legs:
        raise DataError(f"no right/prosthetic leg in the GRF table (legs: {legs})",
                        where="runner result")
    fz = grf.loc[grf["leg"] == right, "Fz"].to_numpy(float)
    t = states["time"].to_numpy(float)
    on = fz > threshold_N
    td = np.flatnonzero(on[1:] & ~on[:-1]) + 1
    if td.size < 2:
        raise DataError("fewer than two touch-downs of the right leg: no complete cycle",
                        where="runner result", hint="simulate longer, or check that it runs")
    starts = list(zip(td[:-1], td[1:], strict=True))
    try:
        a, b = starts[cycle]
    except IndexError:
        raise DataError(f"cycle {cycle} does not exist ({len(starts)} complete cycles)",
                        where="runner result") from None
    need = ["hip_flexion_l", "knee_angle_l", "ankle_angle_l", "hip_flexion_r", "knee_angle_r",
            "pelvis_tilt"]
    missing = [c for c in need if c not in states.columns]
    if missing:
        raise DataError(f"missing coordinates {missing}", where="runner result")
    sl = slice(a, b)
    period = float(t[b] - t[a])
    angles = {
        "hip_sound": states["hip_flexion_l"].to_numpy(float)[sl],
        "knee_sound": -states["knee_angle_l"].to_numpy(float)[sl],
        "ankle_sound": states["ankle_angle_l"].to_numpy(float)[sl],
        "hip_prosthetic": states["hip_flexion_r"].to_numpy(float)[sl],
        "knee_prosthetic": -states["knee_angle_r"].to_numpy(float)[sl],
        "trunk_pitch": -states["pelvis_tilt"].to_numpy(float)[sl],
    }
    return GaitCycle(period, (t[sl] - t[a]) / period, angles, "runner simulation")


_OTHER = {"left": "right", "right": "left"}


def gait_cycles_from_trial(
    trial,
    *,
    leg: str = "right",
    markers=None,
    static=None,
    cutoff_hz: float | None = 20.0,
    n: int = 100,
    stances=None,
    max_period_s: float = 2.0,
) -> list[GaitCycle]:
    """Every complete gait cycle of a measured trial as :class:`GaitCycle` s of the
    transfemoral runner, ``leg`` being the prosthetic one.

    The cycles and every parameter are those of :func:`bladelab.trial.cycles.joint_angle_cycles`
    (a touch-down of ``leg`` to its next, ``n`` samples); the angles are renamed
    ``hip/knee_<leg>`` -> prosthetic, ``hip/knee/ankle_<other>`` -> sound, the pelvis lean ->
    ``trunk_pitch``. Cycles with a marker gap are left out.

    Raises
    ------
    SpecError
        ``leg`` is not left/right.
    DataError
        Missing markers or platforms, the sound leg has no foot markers, or no complete cycle.
    """
    if leg not in _OTHER:
        raise SpecError(f"leg must be 'left' or 'right', got {leg!r}", where="--leg")
    sound = _OTHER[leg]
    names = {"hip_sound": f"hip_{sound}", "knee_sound": f"knee_{sound}",
             "ankle_sound": f"ankle_{sound}", "hip_prosthetic": f"hip_{leg}",
             "knee_prosthetic": f"knee_{leg}", "trunk_pitch": "trunk_pitch"}
    measured = joint_angle_cycles(trial, leg=leg, markers=markers, static=static,
                                  cutoff_hz=cutoff_hz, n=n, stances=stances,
                                  max_period_s=max_period_s)
    if names["ankle_sound"] not in measured[0].angles:
        raise DataError(f"the {sound} (sound) leg has no foot markers, so no ankle angle",
                        file=trial.source or "trial", where=f"{sound} foot",
                        hint="map foot_anterior / foot_posterior of the sound side")
    cycles = []
    for c in measured:
        vals = {k: c.angles[v] for k, v in names.items()}
        if all(np.all(np.isfinite(v)) for v in vals.values()):
            cycles.append(GaitCycle(c.period, c.phase, vals, c.source))
    if not cycles:
        raise DataError(f"every cycle of the {leg} leg has a marker gap",
                        file=trial.source or "trial", where=f"{leg} leg",
                        hint="fill the gaps, or use a trial with complete marker data")
    return cycles


def average_gait_cycle(cycles: Sequence[GaitCycle], *, n: int | None = None,
                       source: str | None = None) -> GaitCycle:
    """Mean of time-normalised cycles: mean period, mean angle at each normalised time.

    ``n`` samples (default: those of the first cycle, whose phases are used).
    """
    if not cycles:
        raise DataError("no cycles to average", where="gait cycles")
    phase = cycles[0].phase if n is None else np.arange(n) / n
    period = float(np.mean([c.period for c in cycles]))
    sampled = [c.angles if (n is None and c.phase.shape == phase.shape
                            and np.allclose(c.phase, phase)) else c.at(phase * c.period)
               for c in cycles]
    mean = {k: np.mean([s[k] for s in sampled], axis=0) for k in ANGLE_NAMES}
    return GaitCycle(period, phase, mean, source or f"mean of {len(cycles)} cycles")


def gait_cycle_from_trial(trial, *, leg: str = "right", markers=None, static=None,
                          cutoff_hz: float | None = 20.0, n: int = 100,
                          max_period_s: float = 2.0) -> GaitCycle:
    """The mean gait cycle of a measured trial (:func:`gait_cycles_from_trial`, averaged).

    Returns a :class:`GaitCycle` whose period is the mean stride time [s] from the force
    platform and whose angles are the time-normalised means over the trial's cycles.
    """
    cycles = gait_cycles_from_trial(trial, leg=leg, markers=markers, static=static,
                                    cutoff_hz=cutoff_hz, n=n, max_period_s=max_period_s)
    src = trial.source or "trial"
    return average_gait_cycle(cycles, source=f"{src}: mean of {len(cycles)} {leg}-leg cycles")


@dataclass(frozen=True)
class MeasuredGaitCycle:
    """The mean gait cycle of a measured trial and the cycles behind it.

    Attributes
    ----------
    mean
        The time-normalised mean cycle (:func:`average_gait_cycle`).
    cycles
        The trial's cycles of the chosen leg.
    zeroed_at_standing
        Whether a standing trial set the angles' zeros (else they are the marker axes' angles).
    path
        The gait-cycle CSV written, or None.
    """

    mean: GaitCycle
    cycles: tuple[GaitCycle, ...]
    zeroed_at_standing: bool
    path: Path | None = None

    @property
    def periods_s(self) -> np.ndarray:
        """The cycles' periods [s]."""
        return np.array([c.period for c in self.cycles])

    def angle_ranges_deg(self) -> dict[str, tuple[float, float, float]]:
        """Angle name -> (min, max) of the mean cycle [deg] and the between-cycle standard
        deviation, averaged over the cycle [deg]."""
        out = {}
        for k, a in self.mean.angles.items():
            deg = np.degrees(a)
            sd = np.mean(np.degrees(np.std([c.angles[k] for c in self.cycles], axis=0)))
            out[k] = (float(deg.min()), float(deg.max()), float(sd))
        return out


def measured_gait_cycle(trial_file: str | Path, *, leg: str = "right",
                        static_file: str | Path | None = None,
                        markers_file: str | Path | None = None, n: int = 100,
                        cutoff_hz: float | None = 20.0, forward: str = "auto", up: str = "auto",
                        out: str | Path | None = None) -> MeasuredGaitCycle:
    """Read a C3D trial (and its standing trial), find the cycles of ``leg`` and their mean
    (:func:`gait_cycles_from_trial`), and write the mean as a gait-cycle CSV to ``out``.

    ``n`` samples per cycle (at least 8); ``cutoff_hz`` the marker low-pass [Hz] (None: none);
    ``markers_file`` a YAML joint marker map (None: the Fukuchi set); the standing trial is read
    with the axes found in the running trial.
    """
    if n < 8:
        raise SpecError(f"needs at least 8 samples per cycle, got {n}", where="samples")
    for f in (trial_file, static_file):
        if f is not None and not Path(f).is_file():
            raise InputFileError("no such file", file=f)
    markers = load_joint_marker_map(markers_file) if markers_file is not None else None
    trial = read_c3d(trial_file, forward=forward, up=up)
    axes = trial.metadata.get("axes", {})
    static = None
    if static_file is not None:
        static = read_c3d(static_file, forward=axes.get("forward", forward),
                          up=axes.get("up", up))
    cycles = gait_cycles_from_trial(trial, leg=leg, markers=markers, static=static,
                                    cutoff_hz=cutoff_hz, n=n)
    mean = average_gait_cycle(cycles,
                              source=f"{trial_file}: mean of {len(cycles)} {leg}-leg cycles")
    path = write_gait_csv(mean, out) if out is not None else None
    return MeasuredGaitCycle(mean, tuple(cycles), static is not None, path)
