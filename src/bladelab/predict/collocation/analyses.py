"""Seed 001's per-stride quantities of a collocation solution (Tables 3.2, 3.3, D.1).

:func:`stride_analyses` repeats the solved stride :data:`N_STRIDES` times
(:meth:`~bladelab.predict.collocation.solution.CollocationSolution.to_runner_result`,
:data:`REFINE` samples per mesh interval) and runs the forward simulation's analyses
(:mod:`bladelab.runner.analyses`) on it; what it returns comes from the middle stride only, so
that no stance is cut by the ends of the record: the stances whose touch-down lies in the
middle stride [T, 2T), and the joint powers integrated over [T, 2T] exactly.

Keys (units in the names; ``<leg>``: ``intact``/``prosthetic`` or ``left``/``right``):

- ``leg_stiffness_<leg>_kN_per_m``: K_leg (seed 001 eq. 2.19–2.21, Fig. 3.12a);
- ``positive_power_<joint>_<leg>_W_per_kg`` and ``negative_power_<joint>_<leg>_W_per_kg``
  (≤ 0): the joint's positive and negative work over the stride divided by the stride time and
  the body mass (Table 3.2's P+ and P−); joints ``hip``, ``knee``, ``ankle`` (intact, left,
  right), ``socket`` and ``rsp`` (the blade: the power its ground contact delivers to the
  body); ``positive_power_<leg>_W_per_kg``, ``negative_power_<leg>_W_per_kg`` sum a leg's
  joints, ``positive_power_total_W_per_kg``, ``negative_power_total_W_per_kg`` both legs
  (Table 3.2's TOTAL);
- ``leg_energy_stored_<leg>_J``, ``leg_energy_generated_<leg>_J``, ``leg_hysteresis_<leg>_J``,
  ``leg_recoil_<leg>_pct``: the GRF–vertical COM displacement loop of the leg's stance
  (Table 3.3), and ``leg_energy_generated_total_J`` (both legs);
- amputee only: ``blade_energy_stored_J``, ``blade_energy_returned_J``,
  ``blade_hysteresis_J``, ``blade_recoil_pct`` (Table D.1, the compression being the contact's
  penetration).

A quantity that the stride does not have (no stance of a leg in the middle stride) is NaN.
Definitions, thresholds and the legs' names are those of :mod:`bladelab.runner.analyses`.
"""

from __future__ import annotations

import math

import numpy as np

from bladelab.errors import SpecError
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.runner import analyses as an
from bladelab.runner.params import PROSTHETIC_KINDS

__all__ = ["JOINT_LABELS", "N_STRIDES", "REFINE", "stride_analyses"]

#: Strides of the record that the analyses see; the middle one is reported.
N_STRIDES = 3
#: Samples per mesh interval (the trapezoidal rule's interpolant between nodes). Touch-downs
#: are found by a force threshold on the samples, so K_leg and the leg energies need them fine:
#: measured on the Cat6 solution at 4 m/s (50 intervals), the intact K_leg is 146, 114, 107 and
#: 106 kN/m with 1, 4, 16 and 32 samples per interval, its stored energy 31.1, 40.5, 40.9 and
#: 40.9 J.
REFINE = 16
#: Joint coordinate (without its side) -> the joint's name in the keys.
JOINT_LABELS = {"hip_flexion": "hip", "knee_angle": "knee", "ankle_angle": "ankle",
                "socket_angle": "socket", "blade": "rsp"}


def _middle(df, column: str, period: float, leg: str):
    """Rows of ``leg`` whose ``column`` (touch-down time [s]) lies in the middle stride."""
    t = df[column].to_numpy(float)
    return df[(df["leg"] == leg).to_numpy() & (t >= period * (1 - 1e-9))
              & (t < 2 * period * (1 - 1e-9))]


def _mean(values) -> float:
    v = np.asarray(values, float)
    return float(v.mean()) if v.size else math.nan


def stride_analyses(solution, runner=None, *, refine: int = REFINE, cm=None) -> dict:
    """K_leg, joint powers P+/P−, leg energies and the blade's energy of the solved stride
    (module docstring: keys and units), from the middle of :data:`N_STRIDES` repeated strides.

    Parameters
    ----------
    solution
        A :class:`~bladelab.predict.collocation.solution.CollocationSolution`.
    runner
        Its forward model (built from ``solution.model_spec`` if None).
    refine
        Samples per mesh interval (:data:`REFINE`).
    cm
        Its collocation model (built if None).

    Raises
    ------
    SpecError
        ``refine`` < 1.
    DataError
        ``runner`` is not the solution's model.
    """
    if isinstance(refine, bool) or int(refine) != refine or refine < 1:
        raise SpecError(f"need refine >= 1, got {refine!r}", where="refine")
    runner = runner if runner is not None else runner_from_spec(solution.model_spec)
    res = solution.to_runner_result(N_STRIDES, refine=int(refine), runner=runner, cm=cm)
    period = solution.period_s
    mass = float(runner.total_mass)
    legs = tuple(solution.leg_names)
    out: dict[str, float] = {}

    k = an.leg_stiffness(res)
    for leg in legs:
        out[f"leg_stiffness_{leg}_kN_per_m"] = _mean(
            _middle(k, "touchdown", period, leg)["K_leg"]) / 1e3

    # joint powers over the middle stride: samples n·refine … 2·n·refine (times T … 2T)
    per_stride = (len(res.time) - 1) // N_STRIDES
    i0, i1 = per_stride, 2 * per_stride
    pw = an.joint_powers(res)
    totals = {leg: [0.0, 0.0] for leg in legs}
    for joint, df in pw.groupby("joint", sort=False):
        base, side = joint.rsplit("_", 1)
        leg = legs[0] if side == "l" else legs[1]
        name = JOINT_LABELS.get(base, base)
        t = df["time"].to_numpy(float)[i0:i1 + 1]
        p = df["power"].to_numpy(float)[i0:i1 + 1]
        pos = float(np.trapezoid(np.maximum(p, 0.0), t)) / period / mass
        neg = float(np.trapezoid(np.minimum(p, 0.0), t)) / period / mass
        out[f"positive_power_{name}_{leg}_W_per_kg"] = pos
        out[f"negative_power_{name}_{leg}_W_per_kg"] = neg
        totals[leg][0] += pos
        totals[leg][1] += neg
    for leg in legs:
        out[f"positive_power_{leg}_W_per_kg"] = totals[leg][0]
        out[f"negative_power_{leg}_W_per_kg"] = totals[leg][1]
    out["positive_power_total_W_per_kg"] = sum(v[0] for v in totals.values())
    out["negative_power_total_W_per_kg"] = sum(v[1] for v in totals.values())

    e = an.leg_energy(res)
    generated = 0.0
    for leg in legs:
        rows = _middle(e, "touchdown", period, leg)
        out[f"leg_energy_stored_{leg}_J"] = _mean(rows["E_stored"])
        out[f"leg_energy_generated_{leg}_J"] = _mean(rows["E_generated"])
        out[f"leg_hysteresis_{leg}_J"] = _mean(rows["hysteresis"])
        out[f"leg_recoil_{leg}_pct"] = _mean(rows["recoil_pct"])
        generated += out[f"leg_energy_generated_{leg}_J"]
    out["leg_energy_generated_total_J"] = generated

    if solution.model_spec["model"] in PROSTHETIC_KINDS:
        rows = _middle(an.blade_energy(res), "touchdown_s", period, legs[1])
        out["blade_energy_stored_J"] = _mean(rows["E_stored_J"])
        out["blade_energy_returned_J"] = _mean(rows["E_returned_J"])
        out["blade_hysteresis_J"] = _mean(rows["hysteresis_J"])
        out["blade_recoil_pct"] = _mean(rows["recoil_pct"])
    return out
