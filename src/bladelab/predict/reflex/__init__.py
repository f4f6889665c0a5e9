"""Seed 001's predictive method: a reflex controller tuned by CMA-ES (seed 001 §2.2).

The runner (:mod:`bladelab.runner`) is driven by Geyer & Herr's reflex controller ported from
SCONE (:mod:`~bladelab.predict.reflex.controller`), simulated in closed loop
(:mod:`~bladelab.predict.reflex.closed_loop`), scored by seed 001's objective
(:mod:`~bladelab.predict.reflex.objective`) and optimised with CMA-ES
(:mod:`~bladelab.predict.reflex.optimize`); :mod:`~bladelab.predict.reflex.sweep` runs
categories × speeds. Method and file formats: docs/predictive.md.
"""

from bladelab.predict.reflex.controller import (
    ControllerLayout,
    controller_layout,
    read_parameters,
    write_parameters,
)
from bladelab.predict.reflex.objective import Evaluation, ObjectiveSettings, simulate_controlled
from bladelab.predict.reflex.optimize import (
    OptimizationResult,
    load_checkpoint,
    optimize_controller,
    runner_and_layout,
    stored_settings,
)
from bladelab.predict.reflex.sweep import finished_cell, run_sweep, summarise
from bladelab.predict.reflex.verify import verify_solution

__all__ = [
    "ControllerLayout",
    "Evaluation",
    "ObjectiveSettings",
    "OptimizationResult",
    "controller_layout",
    "finished_cell",
    "load_checkpoint",
    "optimize_controller",
    "read_parameters",
    "run_sweep",
    "runner_and_layout",
    "simulate_controlled",
    "stored_settings",
    "summarise",
    "verify_solution",
    "write_parameters",
]
