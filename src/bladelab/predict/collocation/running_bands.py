"""What people's running looks like at a speed: the bands of measured human running.

:data:`REFERENCE_BANDS` gives, per measure, the band people show at 3.5 m/s and at 9 m/s
(:data:`ANCHOR_SPEEDS_MPS`); :func:`reference_band` interpolates it linearly in speed between
them and holds it constant outside. Sources:

- 3.5 m/s: the Fukuchi et al. (2017) trial shipped with bladelab (85 stances: contacts
  0.22–0.25 s, peaks 2.3–2.6 BW, strides 0.70 s, about 100° of swing knee flexion), Novacheck
  (1998) for the knee in swing;
- 9 m/s: Weyand et al. (2000) and Nummela et al. (2007) (contacts 0.10–0.13 s, peaks 2.5–4 BW,
  stride times about 0.45–0.5 s);
- pelvis tilt: seed 001's acceptance window of a running posture, −16…−2° (forward lean
  negative);
- cost of transport: about 4 J/(kg·m) gross for people running at 3–5 m/s (Margaria 1963;
  Kram & Taylor 1990 give the cost per distance nearly independent of speed).

The bands judge a predicted stride
(:func:`~bladelab.predict.collocation.human_running.human_running_criteria`), and the stride
time's band can be imposed on one (``CollocationSettings.stride_time_people``).
"""

from __future__ import annotations

__all__ = ["ANCHOR_SPEEDS_MPS", "REFERENCE_BANDS", "reference_band"]

#: Anchor speeds [m/s] of the reference bands.
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


def reference_band(name: str, speed_mps: float) -> tuple[float | None, float | None, str]:
    """(low, high, unit) of a :data:`REFERENCE_BANDS` entry at ``speed_mps`` [m/s]."""
    unit, slow, fast = REFERENCE_BANDS[name]
    v0, v1 = ANCHOR_SPEEDS_MPS
    w = min(max((speed_mps - v0) / (v1 - v0), 0.0), 1.0)

    def mix(a, b):
        return None if a is None or b is None else (1.0 - w) * a + w * b

    return mix(slow[0], fast[0]), mix(slow[1], fast[1]), unit
