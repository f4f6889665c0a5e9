"""Where a predicted stride lies against measured human running, criterion by criterion.

A converged stride is a gait of the model; whether a person runs like it is a separate
question. :func:`human_running_criteria` answers it for one collocation stride with the numbers
people show at that speed: contact time and peak vertical ground force per leg, stride time,
peak knee flexion in swing, mean pelvis tilt, a flight phase, one contact per leg per stride (no
swinging foot or blade striking the ground) and, up to 5 m/s, the gross cost of transport.

The reference bands (:data:`REFERENCE_BANDS`) are given at 3.5 m/s and at 9 m/s and
interpolated linearly in speed between them (held constant outside, where the line says the
band was extrapolated). Sources:

- 3.5 m/s: the Fukuchi et al. (2017) trial shipped with bladelab (85 stances: contacts
  0.22–0.25 s, peaks 2.3–2.6 BW, strides 0.70 s, about 100° of swing knee flexion), Novacheck
  (1998) for the knee in swing;
- 9 m/s: Weyand et al. (2000) and Nummela et al. (2007) (contacts 0.10–0.13 s, peaks 2.5–4 BW,
  stride times about 0.45–0.5 s);
- pelvis tilt: seed 001's acceptance window of a running posture, −16…−2° (forward lean
  negative);
- cost of transport: about 4 J/(kg·m) gross for people running at 3–5 m/s (Margaria 1963;
  Kram & Taylor 1990 give the cost per distance nearly independent of speed).

The prosthetic leg of a transtibial runner is held to a wider contact band at the low end
(0.15 s): its blade shortens the contact (Grabowski et al. 2010, Hobara et al. 2013).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["REFERENCE_BANDS", "Criterion", "human_running_criteria", "reference_band"]

#: Anchor speeds [m/s] of the reference bands (the cost band is given up to
#: :data:`COST_BAND_MAX_SPEED_MPS` only).
ANCHOR_SPEEDS_MPS = (3.5, 9.0)
#: Reference bands of measured human running at the anchor speeds: name -> (unit, band at
#: 3.5 m/s, band at 9 m/s); a bound of None is open.
REFERENCE_BANDS: dict[str, tuple[str, tuple, tuple]] = {
    "contact time": ("s", (0.20, 0.30), (0.10, 0.13)),
    "peak vertical ground force": ("BW", (2.2, 3.0), (2.5, 4.0)),
    "stride time": ("s", (0.64, 0.78), (0.40, 0.55)),
    "peak swing knee flexion": ("deg", (85.0, 140.0), (105.0, 140.0)),
    "mean pelvis tilt": ("deg", (-16.0, -2.0), (-16.0, -2.0)),
    "gross cost of transport": ("J/(kg·m)", (3.5, 5.0), (3.5, 5.0)),
}
#: The lower contact-time bound of a prosthetic leg [s] (module docstring).
PROSTHETIC_CONTACT_MIN_S = 0.15
#: Above this speed [m/s] no cost-of-transport band is given.
COST_BAND_MAX_SPEED_MPS = 5.0


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
        """Inside the band (a nan value is not)."""
        if not math.isfinite(self.value):
            return False
        return ((self.low is None or self.value >= self.low)
                and (self.high is None or self.value <= self.high))

    def band_text(self) -> str:
        if self.low is not None and self.high is not None:
            return f"{self.low:g}–{self.high:g} {self.unit}"
        if self.low is not None:
            return f"≥ {self.low:g} {self.unit}"
        return f"≤ {self.high:g} {self.unit}"

    def line(self) -> str:
        """``"contact time, left leg: 0.11 s (people: 0.20–0.30 s): outside"``."""
        value = f"{self.value:.3g} {self.unit}" if math.isfinite(self.value) else "none"
        verdict = "within" if self.met else "OUTSIDE"
        note = f"; {self.note}" if self.note else ""
        return f"{self.name}: {value} (people: {self.band_text()}{note}): {verdict}"

    def to_dict(self) -> dict:
        return {"name": self.name, "value": self.value, "unit": self.unit, "low": self.low,
                "high": self.high, "met": self.met, "note": self.note}


def reference_band(name: str, speed_mps: float) -> tuple[float | None, float | None, str]:
    """(low, high, unit) of a :data:`REFERENCE_BANDS` entry at ``speed_mps`` [m/s]."""
    unit, slow, fast = REFERENCE_BANDS[name]
    v0, v1 = ANCHOR_SPEEDS_MPS
    w = min(max((speed_mps - v0) / (v1 - v0), 0.0), 1.0)

    def mix(a, b):
        return None if a is None or b is None else (1.0 - w) * a + w * b

    return mix(slow[0], fast[0]), mix(slow[1], fast[1]), unit


def human_running_criteria(solution) -> list[Criterion]:
    """The criteria of module docstring for a
    :class:`~bladelab.predict.collocation.solution.CollocationSolution`, legs in the solution's
    order; speed [m/s] is the stride's mean speed."""
    speed = solution.mean_speed_mps
    v0, v1 = ANCHOR_SPEEDS_MPS
    note = "" if v0 <= speed <= v1 else f"band held from {v0 if speed < v0 else v1:g} m/s"
    phases = solution.contact_phases()
    prosthetic = solution.model_spec.get("model") in ("amputee", "transfemoral")
    out = []
    lo, hi, unit = reference_band("contact time", speed)
    for j, leg in enumerate(solution.leg_names):
        leg_lo = min(lo, PROSTHETIC_CONTACT_MIN_S) if prosthetic and j == 1 else lo
        out.append(Criterion(f"contact time, {leg} leg",
                             phases["legs"][leg]["contact_time_s"], unit, leg_lo, hi, note))
    lo, hi, unit = reference_band("peak vertical ground force", speed)
    for leg in solution.leg_names:
        peak = phases["legs"][leg]["peak_vertical_grf_N"] / solution.body_weight_N
        out.append(Criterion(f"peak vertical ground force, {leg} leg", peak, unit, lo, hi, note))
    lo, hi, unit = reference_band("stride time", speed)
    out.append(Criterion("stride time", solution.period_s, unit, lo, hi, note))
    q = np.asarray(solution.nlp.q)
    lo, hi, unit = reference_band("peak swing knee flexion", speed)
    for side, leg in zip(("l", "r"), solution.leg_names, strict=True):
        name = f"knee_angle_{side}"
        if name not in solution.dof_names or (prosthetic and side == "r"
                                              and solution.model_spec["model"] == "transfemoral"):
            continue
        flexion = -math.degrees(float(q[solution.dof_names.index(name)].min()))
        out.append(Criterion(f"peak swing knee flexion, {leg} leg", flexion, unit, lo, hi, note))
    lo, hi, unit = reference_band("mean pelvis tilt", speed)
    tilt = math.degrees(float(np.mean(q[solution.dof_names.index("pelvis_tilt")][:-1])))
    out.append(Criterion("mean pelvis tilt", tilt, unit, lo, hi, "forward lean negative"))
    out.append(Criterion("flight phase", 100.0 * phases["flight_fraction"], "% of the stride",
                         1e-9, None, "running has one"))
    for leg in solution.leg_names:
        out.append(Criterion(f"ground contacts per stride, {leg} leg",
                             float(phases["legs"][leg]["contacts"]), "", 1.0, 1.0,
                             "more: a swinging foot or blade strikes the ground"))
    if speed <= COST_BAND_MAX_SPEED_MPS:
        lo, hi, unit = reference_band("gross cost of transport", speed)
        out.append(Criterion("gross cost of transport", solution.cost_of_transport_J_per_kg_m,
                             unit, lo, hi, ""))
    return out
