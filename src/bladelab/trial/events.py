"""Stance detection from force platforms, and which stance is the prosthetic one.

Method (``detect_stances``)
    1. Every platform's vertical force is low-pass filtered (zero-lag Butterworth, default
       4th order at 75 Hz, as in seed 002; skipped when the cut-off is not below Nyquist).
    2. A platform is in contact while its vertical force exceeds ``threshold`` (default 20 N).
       Contacts shorter than ``min_duration`` are dropped (noise); off-periods shorter than
       ``bridge`` are bridged (noise dips near the threshold).
    3. Contacts on different platforms that overlap in time, with their centres of pressure
       closer than ``merge_distance`` during the overlap, are the same foot crossing two plates:
       they become one stance whose force is the sum of the plates and whose COP is the
       force-weighted mean. (Two feet on two plates, as in walking double support, are farther
       apart and stay separate stances.)
    4. Stances that touch the start or end of the recording are incomplete and dropped unless
       ``include_partial``.

Per stance: start (touch-down) and end (toe-off) [s], contact time [s], peak vertical force [N]
and its time, impulses [N·s] (trapezoidal integral of the combined GRF over the contact).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from bladelab.errors import DataError
from bladelab.trial.filters import lowpass
from bladelab.trial.trial import Trial

__all__ = ["StanceEvent", "check_forces", "classify_stances", "combined_grf", "detect_stances"]


@dataclasses.dataclass(frozen=True)
class StanceEvent:
    """One detected stance (times in seconds from the first analog sample).

    Attributes
    ----------
    index
        0-based number of the stance in the trial, in time order.
    plates
        1-based numbers of the platforms the foot touched.
    start_s, end_s
        Touch-down and toe-off [s].
    peak_fz_N, peak_time_s
        Peak combined vertical force [N] and its time [s].
    impulse_x_Ns, impulse_y_Ns, impulse_z_Ns
        Impulses of the combined GRF over the contact [N·s].
    start_sample, end_sample
        Analog sample indices (end exclusive).
    complete
        False when the contact touches the start or end of the recording.
    prosthetic
        True/False when classified by :func:`classify_stances`, else None.
    tip_cop_distance_m
        Median horizontal distance blade tip – COP during mid-stance [m] (when classified).
    """

    index: int
    plates: tuple[int, ...]
    start_s: float
    end_s: float
    peak_fz_N: float
    peak_time_s: float
    impulse_x_Ns: float
    impulse_y_Ns: float
    impulse_z_Ns: float
    start_sample: int
    end_sample: int
    complete: bool = True
    prosthetic: bool | None = None
    tip_cop_distance_m: float | None = None

    @property
    def contact_time_s(self) -> float:
        """Contact time [s]."""
        return self.end_s - self.start_s

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict: index, plates, start_s, end_s, contact_time_s, peak_fz_N, impulse_z_Ns, ..."""
        d: dict[str, Any] = {
            "index": self.index,
            "plates": list(self.plates),
            "start_s": round(self.start_s, 6),
            "end_s": round(self.end_s, 6),
            "contact_time_s": round(self.contact_time_s, 6),
            "peak_fz_N": round(self.peak_fz_N, 3),
            "impulse_z_Ns": round(self.impulse_z_Ns, 4),
            "peak_time_s": round(self.peak_time_s, 6),
            "impulse_x_Ns": round(self.impulse_x_Ns, 4),
            "impulse_y_Ns": round(self.impulse_y_Ns, 4),
            "complete": self.complete,
        }
        if self.prosthetic is not None:
            d["prosthetic"] = self.prosthetic
            d["tip_cop_distance_m"] = (
                None if self.tip_cop_distance_m is None else round(self.tip_cop_distance_m, 4)
            )
        return d


def check_forces(trial: Trial) -> None:
    """Raise :class:`DataError` when the trial has no platforms or a platform has NaN forces."""
    if not trial.platforms:
        raise DataError(
            "the trial has no force platforms, so no stance can be found", file=trial.source,
            where="FORCE_PLATFORM", hint="use a trial recorded with force platforms, or a stance CSV",
        )
    rates = {p.rate for p in trial.platforms}
    if len(rates) > 1:
        raise DataError(f"platforms have different rates {sorted(rates)}", file=trial.source)
    for p in trial.platforms:
        bad = np.flatnonzero(~np.all(np.isfinite(p.force), axis=1))
        if bad.size:
            raise DataError(
                f"{bad.size} sample(s) with NaN/inf force, first at analog frame {bad[0]} "
                f"(t = {bad[0] / p.rate:.4f} s)",
                file=trial.source, where=f"{p.name} ({', '.join(p.channels)})",
                hint="the force channels must be complete; re-export or repair them",
            )


def combined_grf(trial: Trial, plates: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Sum of the platforms' GRF [N] and force-weighted COP [m] (lab frame), shape (n, 3) each."""
    sel = [p for p in trial.platforms if p.index in plates]
    force = np.sum([p.force for p in sel], axis=0)
    weights = np.array([np.clip(p.force[:, 2], 0.0, None) for p in sel])  # (k, n)
    cops = np.array([np.nan_to_num(p.cop) for p in sel])  # (k, n, 3)
    wsum = weights.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        cop = np.einsum("kn,knj->nj", weights, cops) / wsum[:, None]
    cop[~(wsum > 0)] = np.nan
    has_cop = np.any([np.all(np.isfinite(p.cop), axis=1) for p in sel], axis=0)
    cop[~has_cop] = np.nan
    return force, cop


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return edges[::2], edges[1::2]


def detect_stances(
    trial: Trial,
    *,
    threshold: float = 20.0,
    min_duration: float = 0.05,
    bridge: float = 0.01,
    cutoff: float | None = 75.0,
    order: int = 4,
    merge_distance: float = 0.3,
    include_partial: bool = False,
) -> list[StanceEvent]:
    """Find the stances of a trial (see the module docstring for the method).

    Parameters
    ----------
    trial
        A trial with force platforms.
    threshold
        Vertical force [N] above which a platform is loaded.
    min_duration
        Shortest contact [s]; shorter ones are noise.
    bridge
        Off-periods shorter than this [s] inside a contact are ignored.
    cutoff, order
        Low-pass of the vertical force before thresholding [Hz]; None: no filtering.
    merge_distance
        Overlapping contacts on two platforms with COPs closer than this [m] are one foot.
    include_partial
        Keep contacts that touch the start or end of the recording.

    Returns
    -------
    list of StanceEvent
        In time order, ``index`` 0, 1, ...

    Raises
    ------
    DataError
        No platforms, NaN forces, or no stance found (the message gives the peak force).
    """
    check_forces(trial)
    rate = trial.platforms[0].rate
    n = trial.platforms[0].n_samples
    contacts: list[tuple[int, int, int]] = []  # (plate index, start, end)
    fz_filtered: dict[int, np.ndarray] = {}
    for p in trial.platforms:
        fz = p.force[:, 2]
        if cutoff is not None and cutoff < rate / 2.0:
            fz = lowpass(fz, rate, cutoff, order=order, where=p.name, file=trial.source)
        fz_filtered[p.index] = fz
        loaded = fz > threshold
        starts, ends = _runs(loaded)
        # bridge short dips
        for k in range(len(starts) - 1):
            if (starts[k + 1] - ends[k]) / rate < bridge:
                loaded[ends[k] : starts[k + 1]] = True
        starts, ends = _runs(loaded)
        for s, e in zip(starts, ends, strict=True):
            if (e - s) / rate >= min_duration:
                contacts.append((p.index, int(s), int(e)))
    contacts.sort(key=lambda c: c[1])
    groups = _merge_contacts(trial, contacts, merge_distance)

    events: list[StanceEvent] = []
    partial: list[tuple[tuple[int, ...], int, int]] = []  # dropped contacts at the ends
    for group in groups:
        plates = tuple(sorted({c[0] for c in group}))
        s = min(c[1] for c in group)
        e = max(c[2] for c in group)
        complete = s > 0 and e < n
        if not complete and not include_partial:
            if s > 0 or e < n:  # a load all along is a zero problem, not a cut contact
                partial.append((plates, s, e))
            continue
        force, _ = combined_grf(trial, plates)
        fz_f = np.sum([fz_filtered[i] for i in plates], axis=0)
        k = s + int(np.argmax(fz_f[s:e]))
        t = np.arange(s, e) / rate
        seg = force[s:e]
        imp = np.trapezoid(seg, t, axis=0) if len(t) > 1 else np.zeros(3)
        events.append(
            StanceEvent(
                index=len(events), plates=plates, start_s=s / rate, end_s=e / rate,
                peak_fz_N=float(fz_f[k]), peak_time_s=k / rate,
                impulse_x_Ns=float(imp[0]), impulse_y_Ns=float(imp[1]), impulse_z_Ns=float(imp[2]),
                start_sample=s, end_sample=e, complete=complete,
            )
        )
    if not events:
        raise _no_stance(trial, fz_filtered, threshold, min_duration, partial, rate)
    return events


def _no_stance(
    trial: Trial, fz_filtered: dict[int, np.ndarray], threshold, min_duration, partial=(), rate=1.0
) -> DataError:
    """The error for a trial without stances; its hint follows what the forces look like."""
    if partial:  # contacts were found, but each touches the start or end of the recording
        spans = "; ".join(
            f"platform{'s' if len(pl) > 1 else ''} {', '.join(map(str, pl))}: "
            f"{s / rate:.2f}–{e / rate:.2f} s" for pl, s, e in partial
        )
        return DataError(
            f"no complete stance: every contact touches the start or end of the recording "
            f"({spans}, recording 0–{trial.platforms[0].n_samples / rate:.2f} s)",
            file=trial.source,
            where="platforms " + ", ".join(str(p.index) for p in trial.platforms),
            hint="include_partial=True keeps incomplete contacts; or record the whole contact",
        )
    peak = max(float(np.max(v)) for v in fz_filtered.values())
    low = min(float(np.min(v)) for v in fz_filtered.values())
    message = (
        f"no stance found: the vertical force peaks at {peak:.1f} N (lowest {low:.1f} N) against "
        f"a threshold of {threshold:g} N and a minimum contact of {min_duration:g} s"
    )
    if all(float(np.min(v)) > threshold for v in fz_filtered.values()):
        hint = ("the force never falls below the threshold: the plates are loaded all along or "
                "not zeroed; read the file with zero-offset removal (the default) or zero the plates")
    elif low < -max(threshold, 50.0):
        hint = ("the force goes well below zero: a plate is not zeroed or its sign is inverted; "
                "read the file with zero-offset removal (the default) or check its calibration")
    else:
        hint = "lower --threshold, or check the platform calibration"
    return DataError(
        message, file=trial.source,
        where="platforms " + ", ".join(str(p.index) for p in trial.platforms), hint=hint,
    )


def _merge_contacts(trial, contacts, merge_distance):
    """Group overlapping contacts on different plates whose COPs are close (one foot)."""
    cops = {p.index: p.cop for p in trial.platforms}
    parent = list(range(len(contacts)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, (pi, si, ei) in enumerate(contacts):
        for j in range(i + 1, len(contacts)):
            pj, sj, ej = contacts[j]
            if sj >= ei:
                break
            if pj == pi:
                continue
            a, b = max(si, sj), min(ei, ej)
            d = np.linalg.norm(cops[pi][a:b, :2] - cops[pj][a:b, :2], axis=1)
            d = d[np.isfinite(d)]
            if d.size == 0 or np.median(d) < merge_distance:
                parent[find(j)] = find(i)
    groups: dict[int, list] = {}
    for i, c in enumerate(contacts):
        groups.setdefault(find(i), []).append(c)
    return sorted(groups.values(), key=lambda g: min(c[1] for c in g))


def classify_stances(
    trial: Trial,
    stances: list[StanceEvent],
    *,
    tip: str = "BLADE_TIP",
    max_distance: float = 0.2,
) -> list[StanceEvent]:
    """Mark each stance prosthetic when the blade tip marker is over the COP.

    The horizontal distance between the tip marker and the combined COP is taken as the median
    over the middle half of the contact; the stance is prosthetic when it is under
    ``max_distance`` [m].

    Raises
    ------
    DataError
        The tip marker does not exist (the message lists the markers that do).
    """
    tip_xyz = trial.marker(tip)
    mt = trial.marker_time
    out = []
    for ev in stances:
        _, cop = combined_grf(trial, ev.plates)
        rate = trial.platforms[0].rate
        a = ev.start_sample + (ev.end_sample - ev.start_sample) // 4
        b = ev.end_sample - (ev.end_sample - ev.start_sample) // 4
        t = np.arange(a, b) / rate
        tip_xy = np.column_stack([np.interp(t, mt, tip_xyz[:, i]) for i in range(2)])
        d = np.linalg.norm(tip_xy - cop[a:b, :2], axis=1)
        d = d[np.isfinite(d)]
        dist = float(np.median(d)) if d.size else None
        out.append(
            dataclasses.replace(
                ev, prosthetic=bool(dist is not None and dist < max_distance), tip_cop_distance_m=dist
            )
        )
    return out
