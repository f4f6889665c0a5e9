"""Signals over the percentage of the gait cycle, mean ± SD over strides (seed 001 §3 figures).

A *stride* of a leg runs from one of its touch-downs to the next, a *stance* from a touch-down to
the lift-off; both are taken from the real steps of :func:`bladelab.runner.analyses.gait_events`
and :func:`~bladelab.runner.analyses.stances` (strikes of the swinging foot are not steps).
:func:`cycle_average` resamples each window onto 0–100 % and averages across windows;
:class:`GaitCycles` gathers, for one trajectory, every signal the report plots over the cycle
(joint angles, moments and powers, muscle–tendon powers and excitations, GRF, power balance,
centre-of-mass height), each as a :class:`CycleAverage`.

Everything is computed from a :class:`~bladelab.runner.RunnerResult`; a trajectory from another
method (e.g. a collocation solution of one periodic stride) is averaged the same way, and one
stride gives its curve with no SD.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pandas as pd

from bladelab.runner.analyses import (
    com_trajectory,
    gait_events,
    joint_moments,
    joint_powers,
    power_balance,
    stances,
)
from bladelab.runner.simulate import RunnerResult, leg_names

__all__ = ["N_POINTS", "CycleAverage", "GaitCycles", "cycle_average", "stride_windows",
           "stance_windows"]

#: Points of the 0–100 % grid (every 1 %).
N_POINTS = 101


@dataclasses.dataclass(frozen=True)
class CycleAverage:
    """A signal over the cycle: ``pct`` (0–100 %), ``mean`` and ``sd`` (standard deviation over
    the ``n`` cycles, NaN when n < 2) in the signal's unit."""

    pct: np.ndarray
    mean: np.ndarray
    sd: np.ndarray
    n: int

    def scaled(self, factor: float) -> CycleAverage:
        """The same curve times ``factor`` (e.g. 1/body mass)."""
        return CycleAverage(self.pct, self.mean * factor, self.sd * abs(factor), self.n)


def cycle_average(
    time: np.ndarray, values: np.ndarray, windows: np.ndarray, *, n_points: int = N_POINTS
) -> CycleAverage:
    """Mean and SD of ``values`` over the cycles ``windows`` after resampling each onto
    ``n_points`` equally spaced percentages.

    Parameters
    ----------
    time
        (n,) sample times [s], increasing.
    values
        (n,) samples of the signal (any unit).
    windows
        (k, 2) start and end time [s] of each cycle; windows not inside ``time`` are skipped.
    n_points
        Points of the 0–100 % grid.

    Returns
    -------
    CycleAverage
        Linear interpolation at ``start + pct/100·(end − start)``: exact for samples that fall on
        the grid.
    """
    time = np.asarray(time, dtype=float)
    values = np.asarray(values, dtype=float)
    pct = np.linspace(0.0, 100.0, n_points)
    rows = []
    for t0, t1 in np.asarray(windows, dtype=float).reshape(-1, 2):
        if t1 <= t0 or t0 < time[0] - 1e-12 or t1 > time[-1] + 1e-12:
            continue
        rows.append(np.interp(t0 + pct / 100.0 * (t1 - t0), time, values))
    if not rows:
        nan = np.full(n_points, math.nan)
        return CycleAverage(pct, nan, nan.copy(), 0)
    stack = np.array(rows)
    sd = stack.std(axis=0, ddof=1) if len(rows) > 1 else np.full(n_points, math.nan)
    return CycleAverage(pct, stack.mean(axis=0), sd, len(rows))


def stride_windows(result: RunnerResult, leg: str) -> np.ndarray:
    """(k, 2) strides of ``leg`` [s]: consecutive touch-downs (real steps)."""
    ev = gait_events(result)
    td = ev.time[(ev.leg == leg) & (ev.event == "touchdown")].to_numpy()
    return np.stack([td[:-1], td[1:]], axis=1) if len(td) > 1 else np.zeros((0, 2))


def stance_windows(result: RunnerResult, leg: str) -> np.ndarray:
    """(k, 2) complete stances of ``leg`` [s]: touch-down and lift-off."""
    st = stances(result)
    st = st[st.leg == leg]
    return st[["touchdown_s", "liftoff_s"]].to_numpy(dtype=float).reshape(-1, 2)


def _side(leg_index: int) -> str:
    return "_l" if leg_index == 0 else "_r"


class GaitCycles:
    """The gait-cycle curves of one trajectory (computed on first use, then cached).

    Parameters
    ----------
    result
        The trajectory.
    n_points
        Points of the 0–100 % grid.
    """

    def __init__(self, result: RunnerResult, *, n_points: int = N_POINTS) -> None:
        self.result = result
        self.n_points = n_points
        self.legs: tuple[str, str] = leg_names(result.model)
        self.mass = result.model.total_mass
        self.body_weight = result.model.body_weight

    @functools.cached_property
    def strides(self) -> dict[str, np.ndarray]:
        """Strides per leg, (k, 2) [s]."""
        return {leg: stride_windows(self.result, leg) for leg in self.legs}

    @functools.cached_property
    def stances(self) -> dict[str, np.ndarray]:
        """Complete stances per leg, (k, 2) [s]."""
        return {leg: stance_windows(self.result, leg) for leg in self.legs}

    def _avg(self, values: np.ndarray, windows: np.ndarray) -> CycleAverage:
        return cycle_average(self.result.time, values, windows, n_points=self.n_points)

    def toe_off_pct(self, leg: str) -> float:
        """Mean lift-off of ``leg`` in % of its stride (NaN without a complete stride)."""
        out = []
        for t0, t1 in self.strides[leg]:
            lo = self.stances[leg][:, 1]
            inside = lo[(lo > t0) & (lo < t1)]
            if len(inside):
                out.append(100.0 * (inside[0] - t0) / (t1 - t0))
        return float(np.mean(out)) if out else math.nan

    def leg_dofs(self, leg: str, kinds: tuple[str, ...] = ("hip", "knee", "ankle", "socket")
                 ) -> list[str]:
        """Rotational coordinates of ``leg`` (hip, knee, ankle or socket), in model order."""
        side = _side(self.legs.index(leg))
        return [d for d in self.result.model.dof_names
                if d.endswith(side) and d.startswith(kinds)]

    def angle(self, dof: str) -> CycleAverage:
        """Coordinate ``dof`` [deg] (or [m] for a translation) over the stride of its leg; trunk
        coordinates over the first leg's stride."""
        j = self.result.model.dof(dof)
        q = self.result.qpos[:, j]
        q = q if dof in ("pelvis_tx", "pelvis_tz") else np.degrees(q)
        return self._avg(q, self.strides[self._leg_of(dof)])

    def _leg_of(self, name: str) -> str:
        return self.legs[1] if name.endswith("_r") else self.legs[0]

    @functools.cached_property
    def _moments(self) -> pd.DataFrame:
        return joint_moments(self.result).pivot(index="time", columns="joint", values="moment_Nm")

    @functools.cached_property
    def _powers(self) -> pd.DataFrame:
        return joint_powers(self.result).pivot(index="time", columns="joint", values="power")

    def moment(self, dof: str) -> CycleAverage:
        """Joint moment of ``dof`` [N·m/kg] over its leg's stride."""
        return self._avg(self._moments[dof].to_numpy() / self.mass, self.strides[self._leg_of(dof)])

    def joint_power(self, joint: str) -> CycleAverage:
        """Joint (or blade, ``blade_r``) power [W/kg] over its leg's stride."""
        p = self._powers[joint].to_numpy() / self.mass
        return self._avg(p, self.strides[self._leg_of(joint)])

    def has_joint_power(self, joint: str) -> bool:
        return joint in self._powers.columns

    def muscle_power(self, muscle: str) -> CycleAverage:
        """Muscle–tendon power ``F_t·(−v_mtu)`` [W/kg] of ``muscle`` over its leg's stride
        (positive: the muscle–tendon unit shortens under tension, generating)."""
        i = self.result.model.muscle_names.index(muscle)
        p = -self.result.muscles[:, i, 3] * self.result.mtu[:, i, 1] / self.mass
        return self._avg(p, self.strides[self._leg_of(muscle)])

    def excitation(self, muscle: str) -> CycleAverage:
        """Excitation [0–1] of ``muscle`` over its leg's stride."""
        i = self.result.model.muscle_names.index(muscle)
        return self._avg(self.result.excitation[:, i], self.strides[self._leg_of(muscle)])

    @functools.cached_property
    def _grf(self) -> pd.DataFrame:
        return self.result.leg_grf()

    def grf(self, leg: str, component: str) -> CycleAverage:
        """``Fx`` or ``Fz`` of ``leg`` [body weights] over its stances."""
        g = self._grf[self._grf.leg == leg]
        return cycle_average(g.time.to_numpy(), g[f"{component}_bw"].to_numpy(),
                             self.stances[leg], n_points=self.n_points)

    @functools.cached_property
    def _balance(self) -> pd.DataFrame:
        return power_balance(self.result)

    def power_balance(self, term: str) -> CycleAverage:
        """A power-balance term (``muscle``, ``ligament``, ``contact``, ``gravity``,
        ``external``, ``kinetic``) [W/kg] over the first leg's stride (seed Fig. 3.4)."""
        return self._avg(self._balance[term].to_numpy() / self.mass, self.strides[self.legs[0]])

    @functools.cached_property
    def _com(self) -> pd.DataFrame:
        return com_trajectory(self.result)

    def stance_loop(self, leg: str) -> tuple[CycleAverage, CycleAverage]:
        """(vertical GRF [body weights], vertical COM displacement from touch-down [m]) over the
        stances of ``leg``: the GRF–displacement loop of seed Fig. 3.12."""
        t = self.result.time
        z = self._com.z_m.to_numpy()
        fz = self.grf(leg, "Fz")
        rows = []
        for t0, t1 in self.stances[leg]:
            dz = z - np.interp(t0, t, z)
            rows.append(cycle_average(t, dz, np.array([[t0, t1]]), n_points=self.n_points).mean)
        pct = fz.pct
        if not rows:
            nan = np.full(len(pct), math.nan)
            return fz, CycleAverage(pct, nan, nan.copy(), 0)
        stack = np.array(rows)
        sd = stack.std(axis=0, ddof=1) if len(rows) > 1 else np.full(len(pct), math.nan)
        return fz, CycleAverage(pct, stack.mean(axis=0), sd, len(rows))
