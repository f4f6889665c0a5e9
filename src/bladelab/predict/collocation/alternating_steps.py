"""Alternating steps: the phase between the legs' stances and the constraint that holds it.

:func:`step_phase` reads, from the legs' vertical ground forces [N] over one stride, how far
the right (prosthetic) leg's stance lies after the left (intact) leg's [fraction of the
stride]: 0.5 for alternating steps of equal time, near 0 or 1 for a gallop.
:func:`alternation_rows` are the stride NLP's rows of the same quantity
(``step_phase_tolerance`` of :class:`~bladelab.predict.collocation.transcription.StrideNLP`):
the phase within half a stride ± the tolerance and a stance on each leg, with the legs' force
centroids in body weights [BW].
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

__all__ = ["MIN_CENTROID_BW", "alternation_rows", "step_phase"]

#: Added to the squared force centroids [BW²] of :func:`alternation_rows` so that their norm stays
#: differentiable at 0 (a leg without stance).
_CENTROID_EPS = 1e-8
#: The least force centroid |C_j| [BW] of each leg under the alternating-steps constraint:
#: about a quarter of a leg's share in running (0.42–0.53 BW measured on the human body's
#: strides), so that a one-legged hop (|C| = 0 on one leg, where the phase constraint holds
#: up to ε) is ruled out with it.
MIN_CENTROID_BW = 0.1


def step_phase(leg_forces: np.ndarray) -> float:
    """The right (prosthetic) leg's stance after the left (intact) leg's [fraction of the
    stride, 0–1]: the difference of the circular means of the legs' vertical ground forces
    ``leg_forces`` (n nodes of one period, without the repeated last node; columns left,
    right) [N]. 0.5 for alternating steps of equal time; near 0 or 1 for a gallop."""
    f = np.asarray(leg_forces, float)
    ph = np.exp(2j * np.pi * np.arange(f.shape[0]) / f.shape[0])
    c = ph @ f
    return float(np.angle(c[1] * np.conj(c[0])) / (2 * np.pi) % 1.0)


def alternation_rows(legs, body_weight: float, tolerance: float):
    """The alternating-steps constraint rows (each ≤ 0) of the legs' vertical forces ``legs``
    (2, n nodes of one period) [N] and the body weight [N]: with the legs' force centroids
    C_j = Σ_k F_j,k·e^{2πik/n} / (n·BW), Re(C₀·C̄₁) + cos(2π·tolerance)·|C₀|·|C₁| ≤ 0, i.e.
    the phase between them within π ± 2π·tolerance (:func:`step_phase` within 0.5 ±
    tolerance); and :data:`MIN_CENTROID_BW`² − |C_j|² ≤ 0 for each leg."""
    n = legs.shape[1]
    k = 2 * np.pi * np.arange(n) / n
    a = ca.mtimes(legs, ca.DM(np.cos(k))) / (n * body_weight)
    b = ca.mtimes(legs, ca.DM(np.sin(k))) / (n * body_weight)
    sq = [a[j] ** 2 + b[j] ** 2 for j in (0, 1)]
    norm = [ca.sqrt(v + _CENTROID_EPS) for v in sq]
    phase = a[0] * a[1] + b[0] * b[1] + math.cos(2 * math.pi * tolerance) * norm[0] * norm[1]
    return ca.vertcat(phase, MIN_CENTROID_BW**2 - sq[0], MIN_CENTROID_BW**2 - sq[1])
