"""The responses of each design evaluator and their units (for tables, plots and reports).

- :data:`BLADE_RESPONSE_UNITS`: :class:`~bladelab.design.evaluators.BladeEvaluator` (one
  simulated stance of the blade);
- :data:`RUNNER_RESPONSE_UNITS`: :class:`~bladelab.design.transfemoral.RunnerEvaluator` (one
  gait cycle of the kinematics-driven transfemoral runner);
- :data:`PREDICTED_RESPONSE_UNITS`: :class:`~bladelab.design.collocation_evaluator.
  CollocationEvaluator` (:func:`~bladelab.design.predicted.stride_responses` of a predicted
  stride).

The evaluators' modules describe each response.
"""

from __future__ import annotations

from bladelab.predict.collocation.loads import PEAK_LOAD_UNITS

__all__ = ["BLADE_RESPONSE_UNITS", "MAX_SPEED_RESPONSE_UNITS", "PREDICTED_RESPONSE_UNITS",
           "RUNNER_RESPONSE_UNITS"]

#: Units of the blade evaluator's responses (for tables and plots).
BLADE_RESPONSE_UNITS: dict[str, str] = {
    "delta_vx_m_per_s": "m/s",
    "avg_vx_m_per_s": "m/s",
    "impulse_x_Ns": "N·s",
    "impulse_z_Ns": "N·s",
    "impulse_z_net_Ns": "N·s",
    "evaluation_E_m": "m",
    "peak_grf_z_N": "N",
    "contact_time_s": "s",
    "compression_m": "m",
    "knee_moment_min_Nm": "N·m",
    "swing_clearance_m": "m",
    "blade_mass_kg": "kg",
}

#: Units of the transfemoral runner evaluator's responses.
RUNNER_RESPONSE_UNITS: dict[str, str] = {
    "delta_vx_m_per_s": "m/s",
    "avg_vx_m_per_s": "m/s",
    "impulse_x_Ns": "N·s",
    "impulse_z_Ns": "N·s",
    "evaluation_E_m": "m",
    "peak_grf_z_prosthetic_N": "N",
    "contact_time_prosthetic_s": "s",
    "knee_moment_min_Nm": "N·m",
    "swing_clearance_m": "m",
    "knee_flexion_max_stance_deg": "deg",
}

#: Units of :func:`~bladelab.design.predicted.stride_responses`' values (seed 002's, named as
#: the blade evaluator's).
PREDICTED_RESPONSE_UNITS: dict[str, str] = {
    **{k: BLADE_RESPONSE_UNITS[k] for k in (
        "delta_vx_m_per_s", "avg_vx_m_per_s", "impulse_x_Ns", "impulse_z_Ns",
        "impulse_z_net_Ns", "evaluation_E_m", "knee_moment_min_Nm", "swing_clearance_m")},
    "contact_time_prosthetic_s": "s",
    "cost_of_transport_J_per_kg_m": "J/(kg·m)",
    "stride_objective": "-",
    **PEAK_LOAD_UNITS,
}

#: The response added by the collocation evaluator's maximum-speed problem
#: (``CollocationEvaluator(max_speed=True)``): the stride's mean speed.
MAX_SPEED_RESPONSE_UNITS: dict[str, str] = {"max_speed_m_per_s": "m/s"}
