"""Where a predicted stride lies against measured human running, criterion by criterion.

A converged stride is a gait of the model; whether a person runs like it is a separate
question. :func:`human_running_criteria` answers it for one collocation stride with the numbers
people show at that speed: contact time and peak vertical ground force per leg, stride time,
peak knee flexion in swing, mean pelvis tilt, a flight phase, alternating steps (no gallop), one
contact per leg per stride (no swinging foot or blade striking the ground) and, up to 5 m/s, the
gross cost of transport.

The reference bands are those of
:mod:`~bladelab.predict.collocation.running_bands` (people at 3.5 m/s and at 9 m/s,
interpolated in speed; their sources there; no cost band above
:data:`COST_BAND_MAX_SPEED_MPS`). The step phase's band is this module's: running people
alternate their legs with steps of nearly equal time (the Fukuchi trial's left and right
stances half a stride apart), and so do runners with a transfemoral amputation on
running-specific prostheses (the same step frequency on both legs, nine athletes at 30–70 % of
their maximum speed, ISBS proceedings 36, 2018); the band 40–60 % of the stride is ours, wide
enough for an amputee's asymmetry, and excludes a gallop.

The prosthetic leg's contact band is people's, its lower edge widened to 0.15 s where people's
is higher (below 6.25 m/s). At top speed the blade's contact is not shorter than the intact
leg's: six sprinters with a unilateral transtibial amputation swung their two legs for times
that did not differ (Grabowski et al. 2010), so, sharing one stride, they stood on both about
as long; runners with a transfemoral amputation step as often on both legs, with a longer
contact length on the prosthetic one at their faster speeds (ISBS proceedings 36, 2018). The
widened edge at slower speeds is ours: no measured band of the blade's contact there was in
reach. Its peak
vertical force is held below the intact leg's: runners with a unilateral transtibial
amputation land softer on the blade than on their intact leg at every speed measured
(Grabowski et al. 2010, 3 m/s to maximum speed; Hobara et al. 2013, 2.5–3.5 m/s). Runners with
a transfemoral amputation have no such criterion here (their peaks are near-symmetric at the
preferred step frequency, Kobayashi et al. 2022).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bladelab.predict.collocation.alternating_steps import step_phase
from bladelab.predict.collocation.running_bands import (
    ANCHOR_SPEEDS_MPS,
    REFERENCE_BANDS,
    reference_band,
)
from bladelab.predict.collocation.solution import CONTACT_THRESHOLD_N
from bladelab.predict.collocation.swing_knee import biological_knees

__all__ = [
    "COMPARED_JOINTS",
    "REFERENCE_BANDS",
    "Criterion",
    "angle_agreement",
    "gallop_sentence",
    "human_running_criteria",
    "reference_band",
    "stride_from_left_touchdown",
]

#: The lower contact-time bound of a prosthetic leg [s] (module docstring).
PROSTHETIC_CONTACT_MIN_S = 0.15
#: Least flight [% of the stride] that counts as a flight phase.
FLIGHT_MIN_PCT = 1.0
#: The band of the step phase [% of the stride] (module docstring).
STEP_PHASE_BAND_PCT = (40.0, 60.0)
#: A stride this close to an anchor speed [m/s] is at it (no "band held" note).
SPEED_TOLERANCE_MPS = 0.01
#: Above this speed [m/s] no cost-of-transport band is given.
COST_BAND_MAX_SPEED_MPS = 5.0


def gallop_sentence(step_phases_pct) -> str:
    """One sentence naming how many of these strides gallop (step phase [% of the stride]
    outside :data:`STEP_PHASE_BAND_PCT`; NaN: not known, not counted), and what a result
    built on them then describes; "" when none does."""
    pct = np.asarray(step_phases_pct, float)
    known = pct[np.isfinite(pct)]
    lo, hi = STEP_PHASE_BAND_PCT
    gallop = known[(known < lo) | (known > hi)]
    if not gallop.size:
        return ""
    return (f"{gallop.size} of {known.size} strides gallop (the second leg's stance "
            f"{gallop.min():.0f}–{gallop.max():.0f} % of a stride after the first's; people "
            f"running alternate at {lo:g}–{hi:g} %): what is built on them describes "
            "galloping strides, not running as people run it.")


#: Relative widening of a band's edges: a stride held on a band's edge by a bound (e.g.
#: ``--stride-time 0.64,0.78``) sits up to IPOPT's bound relaxation (1e-8 relative) outside it.
BAND_EDGE_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Criterion:
    """One measure of a stride against the band people show at its speed."""

    name: str
    value: float
    unit: str
    low: float | None
    high: float | None
    note: str = ""

    @property
    def met(self) -> bool:
        """Inside the band, its edges widened by :data:`BAND_EDGE_TOLERANCE` (a nan value is
        not)."""
        if not math.isfinite(self.value):
            return False
        tol = BAND_EDGE_TOLERANCE
        return ((self.low is None or self.value >= self.low - tol * max(abs(self.low), 1.0))
                and (self.high is None
                     or self.value <= self.high + tol * max(abs(self.high), 1.0)))

    def band_text(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        if self.low is not None and self.low == self.high:
            return f"{self.low:.3g}{unit}"
        if self.low is not None and self.high is not None:
            sep = " to " if self.low < 0 else "–"
            return f"{self.low:.3g}{sep}{self.high:.3g}{unit}"
        if self.low is not None:
            return f"≥ {self.low:.3g}{unit}"
        return f"≤ {self.high:.3g}{unit}"

    def value_text(self) -> str:
        """The value with its unit (``"0.106 s"``)."""
        if not math.isfinite(self.value):
            return "none"
        return f"{self.value:.3g} {self.unit}".rstrip()

    def line(self) -> str:
        """``"contact time, left leg: 0.106 s (people: 0.2–0.3 s): OUTSIDE"``."""
        verdict = "within" if self.met else "OUTSIDE"
        note = f"; {self.note}" if self.note else ""
        return f"{self.name}: {self.value_text()} (people: {self.band_text()}{note}): {verdict}"

    def to_dict(self) -> dict:
        return {"name": self.name, "value": self.value, "unit": self.unit, "low": self.low,
                "high": self.high, "met": self.met, "note": self.note}


def human_running_criteria(solution) -> list[Criterion]:
    """The criteria of module docstring for a
    :class:`~bladelab.predict.collocation.solution.CollocationSolution`, legs in the solution's
    order; speed [m/s] is the stride's mean speed."""
    speed = solution.mean_speed_mps
    v0, v1 = ANCHOR_SPEEDS_MPS
    tol = SPEED_TOLERANCE_MPS
    note = ("" if v0 - tol <= speed <= v1 + tol
            else f"band held from {v0 if speed < v0 else v1:g} m/s")
    phases = solution.contact_phases()
    prosthetic = solution.model_spec.get("model") in ("amputee", "transfemoral")
    out = []
    lo, hi, unit = reference_band("contact time", speed)
    for j, leg in enumerate(solution.leg_names):
        leg_lo = min(lo, PROSTHETIC_CONTACT_MIN_S) if prosthetic and j == 1 else lo
        out.append(Criterion(f"contact time, {leg} leg",
                             phases["legs"][leg]["contact_time_s"], unit, leg_lo, hi, note))
    lo, hi, unit = reference_band("peak vertical ground force", speed)
    peaks = [phases["legs"][leg]["peak_vertical_grf_N"] / solution.body_weight_N
             for leg in solution.leg_names]
    for leg, peak in zip(solution.leg_names, peaks, strict=True):
        out.append(Criterion(f"peak vertical ground force, {leg} leg", peak, unit, lo, hi, note))
    if solution.model_spec.get("model") == "amputee":
        intact, blade = peaks
        out.append(Criterion("peak vertical ground force, prosthetic minus intact leg",
                             blade - intact, "BW", None, 0.0,
                             "runners land softer on the blade (Grabowski 2010, Hobara 2013)"))
    lo, hi, unit = reference_band("stride time", speed)
    imposed = solution.settings.imposed_stride_time
    if imposed is not None:
        imposed = f"imposed: {imposed}"
    out.append(Criterion("stride time", solution.period_s, unit, lo, hi,
                         "; ".join(t for t in (note, imposed) if t)))
    q = np.asarray(solution.nlp.q)  # (nodes, coordinates)
    lo, hi, unit = reference_band("peak swing knee flexion", speed)
    knee_min = solution.settings.swing_knee_min_deg
    knee_imposed = (None if knee_min is None else
                    f"imposed: at least {knee_min:g} deg (a smooth peak: within about 1 deg)")
    knees = biological_knees(solution.dof_names, solution.model_spec.get("model"))
    for side, leg in zip(("l", "r"), solution.leg_names, strict=True):
        name = f"knee_angle_{side}"
        if name not in knees:  # absent, or a transfemoral runner's prosthetic knee
            continue
        flexion = -math.degrees(float(q[:, solution.dof_names.index(name)].min()))
        out.append(Criterion(f"peak swing knee flexion, {leg} leg", flexion, unit, lo, hi,
                             "; ".join(t for t in (note, knee_imposed) if t)))
    lo, hi, unit = reference_band("mean pelvis tilt", speed)
    tilt = math.degrees(float(np.mean(q[:-1, solution.dof_names.index("pelvis_tilt")])))
    out.append(Criterion("mean pelvis tilt", tilt, unit, lo, hi, "forward lean negative"))
    out.append(Criterion("flight phase", 100.0 * phases["flight_fraction"], "% of the stride",
                         FLIGHT_MIN_PCT, None, "running has one"))
    out.append(Criterion("step phase", 100.0 * step_phase(solution.leg_vertical_force()[:-1]),
                         "% of the stride", *STEP_PHASE_BAND_PCT,
                         f"the {solution.leg_names[1]} leg's stance after the "
                         f"{solution.leg_names[0]} leg's; a gallop lands both close together"))
    for leg in solution.leg_names:
        out.append(Criterion(f"ground contacts per stride, {leg} leg",
                             float(phases["legs"][leg]["contacts"]), "", 1.0, 1.0,
                             "more: a swinging foot or blade strikes the ground"))
    if speed <= COST_BAND_MAX_SPEED_MPS + tol:  # a 5 m/s stride is 5 m/s to round-off
        lo, hi, unit = reference_band("gross cost of transport", speed)
        out.append(Criterion("gross cost of transport", solution.cost_of_transport_J_per_kg_m,
                             unit, lo, hi, ""))
    return out


#: Joints compared with a measured stride: (coordinate base, label, sign); the knee as flexion.
COMPARED_JOINTS = (("hip_flexion", "hip flexion", 1.0), ("knee_angle", "knee flexion", -1.0),
                   ("ankle_angle", "ankle dorsiflexion", 1.0))
#: Largest joint-angle RMSE [deg] and smallest knee correlation [-] against a measured stride.
ANGLE_RMSE_MAX_DEG = 15.0
KNEE_CORRELATION_MIN = 0.9


def stride_from_left_touchdown(solution, threshold_n: float = CONTACT_THRESHOLD_N,
                               values=None) -> np.ndarray:
    """The stride's node values of q (n + 1, coordinates), or of ``values`` (n + 1, ...) if
    given, rolled to start at the left (intact) leg's touch-down: the first node loaded above
    ``threshold_n`` [N] after an unloaded one (no roll if the leg is never unloaded); the last
    node repeats the first (periodic)."""
    q = np.asarray(solution.nlp.q if values is None else values)
    loaded = solution.leg_vertical_force()[:-1, 0] > threshold_n
    starts = np.flatnonzero(loaded & ~np.roll(loaded, 1))
    rolled = np.roll(q[:-1], -(int(starts[0]) if starts.size else 0), axis=0)
    return np.vstack([rolled, rolled[:1]])


def angle_agreement(solution, measured_q: np.ndarray,
                    threshold_n: float = CONTACT_THRESHOLD_N) -> list[Criterion]:
    """Hip, knee and ankle angles of the stride against a measured stride ``measured_q``
    (samples, coordinates) [rad] on the same coordinates, starting at the left touch-down:
    the RMSE [deg] per joint and leg (≤ :data:`ANGLE_RMSE_MAX_DEG`) and the knee's
    correlation (≥ :data:`KNEE_CORRELATION_MIN`), the measured stride interpolated onto the
    stride's nodes over % of the stride. Joints a leg does not have (a prosthesis) are left
    out."""
    q = stride_from_left_touchdown(solution, threshold_n)
    pct = np.linspace(0.0, 1.0, q.shape[0])
    pct_m = np.linspace(0.0, 1.0, measured_q.shape[0])
    out = []
    for side, leg in zip(("l", "r"), solution.leg_names, strict=True):
        for base, label, sign in COMPARED_JOINTS:
            name = f"{base}_{side}"
            if name not in solution.dof_names:
                continue
            j = solution.dof_names.index(name)
            model = sign * np.degrees(q[:, j])
            measured = sign * np.degrees(np.interp(pct, pct_m, measured_q[:, j]))
            rmse = float(np.sqrt(np.mean((model - measured)[:-1] ** 2)))
            out.append(Criterion(f"{label} RMSE against the measured stride, {leg} leg", rmse,
                                 "deg", None, ANGLE_RMSE_MAX_DEG))
            if base == "knee_angle":
                r = float(np.corrcoef(model[:-1], measured[:-1])[0, 1])
                out.append(Criterion(f"knee flexion correlation with the measured stride, "
                                     f"{leg} leg", r, "", KNEE_CORRELATION_MIN, None))
    return out
