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
- ``cost_of_transport_scone_J_per_kg_m``: the cost of transport as SCONE (seed 001's tool)
  counts it, :func:`cost_of_transport` with muscle masses from their strongest force over
  :data:`SCONE_SPECIFIC_TENSION_PA` and a basal rate of :data:`SCONE_BASAL_W_PER_KG`;
- amputee only: ``blade_energy_stored_J``, ``blade_energy_returned_J``,
  ``blade_hysteresis_J``, ``blade_recoil_pct`` (Table D.1, the compression being the contact's
  penetration); ``socket_force_max_N``, ``socket_moment_max_Nm``, ``blade_moment_max_Nm``: the
  loads the prosthesis carries (:func:`~bladelab.predict.collocation.loads.peak_loads`; not in
  seed 001).

A quantity that the stride does not have (no stance of a leg in the middle stride) is NaN.
Definitions, thresholds and the legs' names are those of :mod:`bladelab.runner.analyses`.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from bladelab.errors import SpecError
from bladelab.predict.collocation.loads import peak_loads
from bladelab.predict.collocation.metabolics import muscle_metabolic_rates
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.nodes import evaluate_nodes
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.runner import analyses as an
from bladelab.runner import stance_mechanics as sm
from bladelab.runner.layout import CP_LEG
from bladelab.runner.metabolics import BASAL_RATE_W_PER_KG
from bladelab.runner.params import PROSTHETIC_KINDS

__all__ = ["JOINT_LABELS", "N_STRIDES", "REFINE", "SCONE_BASAL_W_PER_KG",
           "SCONE_SPECIFIC_TENSION_PA", "cost_of_transport", "stride_analyses"]

#: SCONE's specific tension [Pa] for muscle mass (its default, 0.25 MPa; seed 001 §2.1.3).
SCONE_SPECIFIC_TENSION_PA = 0.25e6
#: SCONE's basal metabolic rate [W/kg] in its Uchida measure (seed 001 eq. 2.5).
SCONE_BASAL_W_PER_KG = 1.2

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


def cost_of_transport(solution, runner=None, *, specific_tension_pa: float | None = None,
                      basal_w_per_kg: float = BASAL_RATE_W_PER_KG, cm=None) -> float:
    """Gross cost of transport [J/(kg·m)] of a collocation stride, its metabolic rate (the
    collocation twin's, :func:`~bladelab.predict.collocation.metabolics.
    muscle_metabolic_rates`) integrated over the nodes by the trapezoidal rule, per body mass
    and stride length, with muscle masses from their strongest force over
    ``specific_tension_pa`` [Pa] (None: the model's) and a basal rate of
    ``basal_w_per_kg`` [W/kg]. With the defaults it is the solution's own cost; seed 001's
    SCONE counts muscle mass at :data:`SCONE_SPECIFIC_TENSION_PA` and basal
    :data:`SCONE_BASAL_W_PER_KG`."""
    runner = runner if runner is not None else runner_from_spec(solution.model_spec)
    cm = cm if cm is not None else build_collocation_model(runner)
    nv, nm = cm.nv, cm.n_muscles
    q, qd = ca.SX.sym("q", nv), ca.SX.sym("qd", nv)
    a, ft, dft, u = (ca.SX.sym(n, nm) for n in ("a", "ft", "dft", "u"))
    l_mt, v_mt = cm.mtu(q, qd)
    rate = ca.sum1(muscle_metabolic_rates(runner, u, a, ft, dft, l_mt, v_mt, cm.smoothing,
                                          specific_tension_pa=specific_tension_pa))
    f = ca.Function("muscle_rate", [q, qd, a, ft, dft, u], [rate]).map(
        solution.nlp.q.shape[0])
    s = solution.nlp
    muscles = np.asarray(f(s.q.T, s.qd.T, s.activation.T, s.tendon_force.T,
                           s.tendon_force_rate.T, s.excitation.T), float).ravel()
    mass = float(runner.total_mass)
    total = muscles + basal_w_per_kg * mass
    h = solution.period_s / (total.size - 1)
    energy = 0.5 * h * float(np.sum(total[:-1] + total[1:]))
    j = list(solution.dof_names).index("pelvis_tx")
    return energy / (mass * float(s.q[-1, j] - s.q[0, j]))


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

    k = sm.leg_stiffness(res)
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
    out["cost_of_transport_scone_J_per_kg_m"] = cost_of_transport(
        solution, runner, specific_tension_pa=SCONE_SPECIFIC_TENSION_PA,
        basal_w_per_kg=SCONE_BASAL_W_PER_KG, cm=cm)

    e = sm.leg_energy(res)
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
        rows = _middle(sm.blade_energy(res), "touchdown_s", period, legs[1])
        out["blade_energy_stored_J"] = _mean(rows["E_stored_J"])
        out["blade_energy_returned_J"] = _mean(rows["E_returned_J"])
        out["blade_hysteresis_J"] = _mean(rows["hysteresis_J"])
        out["blade_recoil_pct"] = _mean(rows["recoil_pct"])
        nodes = evaluate_nodes(cm or build_collocation_model(runner), solution.nlp.q,
                               solution.nlp.qd, solution.nlp.tendon_force,
                               solution.nlp.tendon_force_rate)
        out.update(peak_loads(runner, solution.nlp, nodes["forces"], nodes["passive"],
                              runner.contact_params[:, CP_LEG] == 1))
    return out
