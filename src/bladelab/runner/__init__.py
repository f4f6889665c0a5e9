"""Planar musculoskeletal runners wearing a running blade (seed 001 §2.1, §2.3, §2.4).

Build a model with :func:`build_runner` (``"able"`` or ``"amputee"``, a blade category from
:func:`blade_catalogue`), simulate it with :func:`simulate_runner` (MuJoCo multibody dynamics,
bladelab's numba muscles, ligaments and Hunt–Crossley contact) and analyse the result with
:mod:`bladelab.runner.analyses`. Geometry and muscle paths are ported from SCONE's H0918 model
(Apache-2.0); masses, inertias and muscle strengths follow seed 001 Tables 2.1–2.3.
"""

from bladelab.runner.analyses import (
    gait_events,
    joint_angles,
    joint_powers,
    leg_grf,
    power_balance,
    power_balance_residual_pct,
    spatiotemporal,
    summary,
    swing_contacts,
)
from bladelab.runner.blade_categories import (
    BladeCategory,
    blade_catalogue,
    blade_category,
    blade_modulus,
)
from bladelab.runner.clearance import swing_clearance
from bladelab.runner.model import RunnerModel, build_runner, contact_heights
from bladelab.runner.params import (
    RunnerParams,
    default_runner_params,
    load_runner_params,
    runner_params_from_dict,
)
from bladelab.runner.scaling import muscle_max_force
from bladelab.runner.simulate import (
    ControllerState,
    RunnerResult,
    initial_qpos,
    integrator_for,
    simulate_runner,
)
from bladelab.runner.stance_mechanics import leg_energy, leg_stiffness

__all__ = [
    "BladeCategory",
    "ControllerState",
    "RunnerModel",
    "RunnerParams",
    "RunnerResult",
    "blade_catalogue",
    "blade_category",
    "blade_modulus",
    "build_runner",
    "contact_heights",
    "default_runner_params",
    "gait_events",
    "initial_qpos",
    "joint_angles",
    "joint_powers",
    "leg_energy",
    "leg_grf",
    "leg_stiffness",
    "load_runner_params",
    "muscle_max_force",
    "power_balance",
    "power_balance_residual_pct",
    "runner_params_from_dict",
    "integrator_for",
    "simulate_runner",
    "spatiotemporal",
    "summary",
    "swing_clearance",
    "swing_contacts",
]
