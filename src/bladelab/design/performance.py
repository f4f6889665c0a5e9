"""Performance functions of seed 002 from ground reaction forces.

Seed 002 judges a blade by four functions of one gait period: the horizontal velocity change over
the period, the average horizontal velocity, and the horizontal and vertical GRF impulses, plus an
*evaluation parameter* from a bouncing-ball analogy (its figure 8). Our reading of that analogy,
per stance:

- vertical take-off and touch-down velocities have the same magnitude (the ball bounces), so the
  vertical impulse gives the take-off velocity and the aerial time t_a = I_z / (m·g);
- the horizontal impulse changes the horizontal velocity: Δv_x = I_x / m;
- the distance flown after take-off is (v_x0 + Δv_x)·t_a; omitting the initial-velocity term
  v_x0·t_a leaves the evaluation parameter E = Δv_x·t_a = I_x·I_z / (m²·g) [m].

**Gross or net vertical impulse.** The momentum balance over a stance of duration t_c reads
m·(v_z,off − v_z,on) = ∫(F_z − m·g) dt, so with v_z,off = −v_z,on = v the *net* impulse
I_z,net = ∫(F_z − m·g) dt = 2·m·v and the ballistic aerial time 2·v/g equals I_z,net/(m·g)
exactly. The *gross* impulse ∫F_z dt (what a force plate integrates) is larger by m·g·t_c, and
I_z,gross/(m·g) = t_a + t_c is the step time (over a periodic step the gross impulse is m·g·T).
Seed 002 derives the aerial time "by using the relation between impulse and momentum", which is
the net impulse; we therefore take **net of body weight as the default** for t_a and E
(``net_of_body_weight=True``). ``net_of_body_weight=False`` gives the gross reading, i.e. E over
the whole step time. The vertical impulse reported as a performance function is the gross one
(``impulse_z``, the usual biomechanics convention), with the net one beside it (``impulse_z_net``).

Inputs are sampled signals: ``time`` [s], ``grf_x`` and ``grf_z`` [N] (the force on the runner,
x forward, z up), ``mass`` [kg] and boolean stance masks (one per leg; in running only one leg is
on the ground at a time, so the masks select each leg's stances from the total GRF). Impulses
are integrated with the trapezoidal rule over each contiguous stance window.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from bladelab.constants import STANDARD_GRAVITY
from bladelab.errors import DataError

__all__ = [
    "StancePerformance",
    "CyclePerformance",
    "stance_windows",
    "impulse",
    "bouncing_ball",
    "stance_performance",
    "performance_by_stance",
    "performance_by_leg",
    "horizontal_velocity_change",
    "average_horizontal_velocity",
    "cycle_performance",
]



def _trapz(y: np.ndarray, x: np.ndarray) -> float:
    """Trapezoidal rule (numpy < 2 has no ``np.trapezoid``)."""
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def _check_signals(time: np.ndarray, **channels: np.ndarray) -> tuple[np.ndarray, dict]:
    t = np.asarray(time, dtype=float).reshape(-1)
    if t.size < 2:
        raise DataError("need at least two samples", where="time")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise DataError(
            "time must be finite and strictly increasing", where="time",
            hint="remove duplicated or unsorted samples",
        )
    out = {}
    for name, arr in channels.items():
        a = np.asarray(arr, dtype=float).reshape(-1)
        if a.shape != t.shape:
            raise DataError(f"has {a.size} samples, time has {t.size}", where=name)
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            raise DataError(
                f"non-finite value at t = {t[bad[0]]:.4f} s", where=name,
                hint="fill or cut the gap before computing performance",
            )
        out[name] = a
    return t, out


def _check_mass(mass: float) -> float:
    m = float(mass)
    if not np.isfinite(m) or m <= 0:
        raise DataError(f"mass must be positive, got {mass}", where="mass")
    return m


def _mask(mask: np.ndarray | None, n: int, name: str = "stance mask") -> np.ndarray:
    if mask is None:
        return np.ones(n, dtype=bool)
    m = np.asarray(mask).reshape(-1)
    if m.shape[0] != n:
        raise DataError(f"has {m.shape[0]} samples, time has {n}", where=name)
    return m.astype(bool)


def stance_windows(mask: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous ``True`` runs of a boolean mask as ``(start, stop)`` index pairs (stop excl.)."""
    m = np.asarray(mask, dtype=bool).reshape(-1).astype(np.int8)
    edges = np.diff(np.concatenate([[0], m, [0]]))
    starts = np.flatnonzero(edges == 1)
    stops = np.flatnonzero(edges == -1)
    return list(zip(starts.tolist(), stops.tolist(), strict=True))


def impulse(time: np.ndarray, force: np.ndarray, *, mask: np.ndarray | None = None) -> float:
    """Impulse ∫F dt [N·s] over the samples selected by ``mask`` (all by default).

    Each contiguous window is integrated with the trapezoidal rule; windows are summed.
    """
    t, ch = _check_signals(time, force=force)
    m = _mask(mask, t.size)
    total = 0.0
    for a, b in stance_windows(m):
        if b - a >= 2:
            total += float(_trapz(ch["force"][a:b], t[a:b]))
    return total


def bouncing_ball(
    impulse_x: float, impulse_z: float, mass: float, *, g: float = STANDARD_GRAVITY
) -> tuple[float, float, float]:
    """Seed 002's bouncing-ball parameter from the impulses of one stance.

    Parameters
    ----------
    impulse_x
        Horizontal impulse I_x [N·s].
    impulse_z
        Vertical impulse I_z [N·s] (net of body weight for the ballistic aerial time).
    mass
        Body mass m [kg].
    g
        Gravity [m/s²].

    Returns
    -------
    aerial_time, delta_vx, evaluation
        t_a = I_z/(m·g) [s], Δv_x = I_x/m [m/s], E = Δv_x·t_a = I_x·I_z/(m²·g) [m].
    """
    m = _check_mass(mass)
    t_a = float(impulse_z) / (m * g)
    dv = float(impulse_x) / m
    return t_a, dv, dv * t_a


@dataclass(frozen=True)
class StancePerformance:
    """Performance of one stance.

    Attributes
    ----------
    leg
        Leg label (e.g. ``"prosthetic"``, ``"sound"``).
    index
        Stance number of that leg (0-based).
    t_start, t_end, duration
        Stance window [s].
    impulse_x
        Horizontal impulse [N·s].
    impulse_z, impulse_z_net
        Gross vertical impulse ∫F_z dt and net ∫(F_z − m·g) dt [N·s].
    aerial_time
        t_a = I_z/(m·g) [s] (net or gross impulse per ``basis``).
    delta_vx
        Δv_x = I_x/m [m/s].
    evaluation
        E = Δv_x·t_a [m].
    basis
        ``"net"`` or ``"gross"``: the vertical impulse used for t_a and E.
    """

    leg: str
    index: int
    t_start: float
    t_end: float
    duration: float
    impulse_x: float
    impulse_z: float
    impulse_z_net: float
    aerial_time: float
    delta_vx: float
    evaluation: float
    basis: str

    def to_dict(self) -> dict:
        return asdict(self)


def stance_performance(
    time: np.ndarray,
    grf_x: np.ndarray,
    grf_z: np.ndarray,
    mass: float,
    *,
    mask: np.ndarray | None = None,
    net_of_body_weight: bool = True,
    g: float = STANDARD_GRAVITY,
    leg: str = "",
    index: int = 0,
) -> StancePerformance:
    """Impulses and the bouncing-ball parameter of one stance.

    Parameters
    ----------
    time, grf_x, grf_z
        Samples [s], [N], [N].
    mass
        Body mass [kg].
    mask
        Selects the stance (one contiguous window); default all samples.
    net_of_body_weight
        Aerial time from the net vertical impulse (default, see the module notes) or the gross.
    g
        Gravity [m/s²].
    """
    t, ch = _check_signals(time, grf_x=grf_x, grf_z=grf_z)
    m_kg = _check_mass(mass)
    m = _mask(mask, t.size)
    win = stance_windows(m)
    if len(win) != 1:
        raise DataError(
            f"the stance mask selects {len(win)} windows; one stance needs exactly one",
            where="stance mask",
            hint="use performance_by_stance for several stances",
        )
    a, b = win[0]
    if b - a < 2:
        raise DataError("the stance has fewer than two samples", where="stance mask")
    tt = t[a:b]
    i_x = float(_trapz(ch["grf_x"][a:b], tt))
    i_z = float(_trapz(ch["grf_z"][a:b], tt))
    dur = float(tt[-1] - tt[0])
    i_z_net = i_z - m_kg * g * dur
    t_a, dv, e = bouncing_ball(i_x, i_z_net if net_of_body_weight else i_z, m_kg, g=g)
    return StancePerformance(
        leg=leg, index=int(index), t_start=float(tt[0]), t_end=float(tt[-1]), duration=dur,
        impulse_x=i_x, impulse_z=i_z, impulse_z_net=i_z_net, aerial_time=t_a, delta_vx=dv,
        evaluation=e, basis="net" if net_of_body_weight else "gross",
    )


def performance_by_stance(
    time: np.ndarray,
    grf_x: np.ndarray,
    grf_z: np.ndarray,
    mass: float,
    *,
    stance_masks: Mapping[str, np.ndarray],
    net_of_body_weight: bool = True,
    g: float = STANDARD_GRAVITY,
) -> pd.DataFrame:
    """One row per stance per leg (columns of :class:`StancePerformance`, SI units).

    ``stance_masks`` maps a leg label to its boolean stance mask; each contiguous window is one
    stance. Windows touching the first or last sample are kept (the caller chooses the data).
    """
    t, ch = _check_signals(time, grf_x=grf_x, grf_z=grf_z)
    if not stance_masks:
        raise DataError("no stance masks given", where="stance_masks")
    rows = []
    for leg, mask in stance_masks.items():
        m = _mask(mask, t.size, f"stance mask {leg}")
        for i, (a, b) in enumerate(stance_windows(m)):
            single = np.zeros(t.size, dtype=bool)
            single[a:b] = True
            if b - a < 2:
                continue
            rows.append(
                stance_performance(
                    t, ch["grf_x"], ch["grf_z"], mass, mask=single,
                    net_of_body_weight=net_of_body_weight, g=g, leg=str(leg), index=i,
                ).to_dict()
            )
    cols = list(StancePerformance.__dataclass_fields__)
    return pd.DataFrame(rows, columns=cols)


def performance_by_leg(per_stance: pd.DataFrame) -> pd.DataFrame:
    """Mean per leg of the per-stance table (``n_stances`` and the means of the numbers)."""
    num = ["duration", "impulse_x", "impulse_z", "impulse_z_net", "aerial_time", "delta_vx",
           "evaluation"]
    g = per_stance.groupby("leg", sort=True)
    out = g[num].mean()
    out.insert(0, "n_stances", g.size())
    return out.reset_index()


def _window(t: np.ndarray, window: tuple[float, float] | None) -> np.ndarray:
    if window is None:
        return np.ones(t.size, dtype=bool)
    t0, t1 = (float(v) for v in window)
    sel = (t >= t0 - 1e-12) & (t <= t1 + 1e-12)
    if sel.sum() < 2 or t1 <= t0:
        raise DataError(f"window {t0}..{t1} s selects fewer than two samples", where="window")
    return sel


def horizontal_velocity_change(
    time: np.ndarray, grf_x: np.ndarray, mass: float, *, window: tuple[float, float] | None = None
) -> float:
    """Δv_x = ∫F_x dt / m [m/s] over ``window`` (default all samples: one gait period)."""
    t, ch = _check_signals(time, grf_x=grf_x)
    sel = _window(t, window)
    return float(_trapz(ch["grf_x"][sel], t[sel])) / _check_mass(mass)


def average_horizontal_velocity(
    time: np.ndarray,
    grf_x: np.ndarray,
    mass: float,
    *,
    v_x0: float,
    window: tuple[float, float] | None = None,
) -> float:
    """Mean horizontal velocity [m/s] over ``window`` from v_x0 at its start and the GRF.

    v_x(t) = v_x0 + ∫F_x/m dt; the mean is ∫v_x dt / T (no air resistance).
    """
    t, ch = _check_signals(time, grf_x=grf_x)
    sel = _window(t, window)
    tt, fx = t[sel], ch["grf_x"][sel]
    m = _check_mass(mass)
    dv = np.concatenate([[0.0], np.cumsum(0.5 * (fx[1:] + fx[:-1]) * np.diff(tt))]) / m
    v = float(v_x0) + dv
    return float(_trapz(v, tt) / (tt[-1] - tt[0]))


@dataclass(frozen=True)
class CyclePerformance:
    """Seed 002's performance functions over one gait period.

    Attributes
    ----------
    period
        T [s].
    delta_vx
        Horizontal velocity change over the period [m/s].
    mean_vx
        Average horizontal velocity [m/s] (NaN if neither v_x0 nor com_x was given).
    impulse_x, impulse_z, impulse_z_net
        GRF impulses over the period [N·s] (gross and net of body weight for z).
    per_leg
        Per leg: mean over its stances of the :class:`StancePerformance` numbers.
    basis
        ``"net"`` or ``"gross"`` vertical impulse for the aerial time.
    """

    period: float
    delta_vx: float
    mean_vx: float
    impulse_x: float
    impulse_z: float
    impulse_z_net: float
    per_leg: dict[str, dict[str, float]]
    basis: str

    def to_dict(self) -> dict:
        return asdict(self)

    def responses(self) -> dict[str, float]:
        """Flat ``{name_with_unit: value}`` for a design study (what an evaluator returns)."""
        out = {
            "period_s": self.period,
            "delta_vx_m_per_s": self.delta_vx,
            "mean_vx_m_per_s": self.mean_vx,
            "impulse_x_Ns": self.impulse_x,
            "impulse_z_Ns": self.impulse_z,
        }
        for leg, d in self.per_leg.items():
            out[f"evaluation_{leg}_m"] = d["evaluation"]
            out[f"impulse_x_{leg}_Ns"] = d["impulse_x"]
            out[f"impulse_z_{leg}_Ns"] = d["impulse_z"]
        return out


def cycle_performance(
    time: np.ndarray,
    grf_x: np.ndarray,
    grf_z: np.ndarray,
    mass: float,
    *,
    stance_masks: Mapping[str, np.ndarray],
    v_x0: float | None = None,
    com_x: np.ndarray | None = None,
    net_of_body_weight: bool = True,
    g: float = STANDARD_GRAVITY,
) -> CyclePerformance:
    """All performance functions of one gait period (the samples given span the period).

    Parameters
    ----------
    time, grf_x, grf_z
        One period of samples [s], [N], [N].
    mass
        Body mass [kg].
    stance_masks
        Leg label -> boolean stance mask.
    v_x0
        Horizontal velocity of the centre of mass at the start [m/s], for the mean velocity.
    com_x
        Horizontal position of the centre of mass [m]; if given, the mean velocity is
        (x(T) − x(0)) / T (takes precedence over ``v_x0``).
    net_of_body_weight
        Vertical impulse basis of the aerial time (see the module notes).
    g
        Gravity [m/s²].
    """
    t, ch = _check_signals(time, grf_x=grf_x, grf_z=grf_z)
    m = _check_mass(mass)
    period = float(t[-1] - t[0])
    i_x = float(_trapz(ch["grf_x"], t))
    i_z = float(_trapz(ch["grf_z"], t))
    if com_x is not None:
        _, c = _check_signals(t, com_x=com_x)
        mean_vx = float((c["com_x"][-1] - c["com_x"][0]) / period)
    elif v_x0 is not None:
        mean_vx = average_horizontal_velocity(t, ch["grf_x"], m, v_x0=v_x0)
    else:
        mean_vx = float("nan")
    table = performance_by_stance(
        t, ch["grf_x"], ch["grf_z"], m, stance_masks=stance_masks,
        net_of_body_weight=net_of_body_weight, g=g,
    )
    per_leg = {}
    if not table.empty:
        for _, row in performance_by_leg(table).iterrows():
            per_leg[str(row["leg"])] = {
                k: float(v) for k, v in row.items() if k != "leg"
            }
    return CyclePerformance(
        period=period,
        delta_vx=i_x / m,
        mean_vx=mean_vx,
        impulse_x=i_x,
        impulse_z=i_z,
        impulse_z_net=i_z - m * g * period,
        per_leg=per_leg,
        basis="net" if net_of_body_weight else "gross",
    )
