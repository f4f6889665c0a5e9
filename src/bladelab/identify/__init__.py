"""Identification of K* and D* from sprint stances: costs, optimisers, bounds, identifiability.

See ``docs/identification.md``.
"""

from bladelab.identify.bounds import (
    DAMPING_BOUNDS_NMS_PER_DEG,
    ParameterBounds,
    instantaneous_stiffness,
    make_bounds,
    parameter_bounds,
    stiffness_bounds,
)
from bladelab.identify.cost import CostTerms, StanceCost, contact_window, nrmse
from bladelab.identify.formulations import DEFAULT_FORMULATION, FORMULATIONS, formulation_drive
from bladelab.identify.identifiability import (
    Identifiability,
    assess_identifiability,
    cost_landscape,
)
from bladelab.identify.identify import (
    Identification,
    compare_spring_locations,
    compare_spring_models,
    identification_landscape,
    identify_stance,
)
from bladelab.identify.optimizers import (
    CMAES,
    OptimizeResult,
    ParticleSwarm,
    make_optimizer,
    minimize,
    polish,
)
from bladelab.identify.quality import QualityThresholds, TrialQuality, assess_quality

__all__ = [
    "CMAES",
    "DAMPING_BOUNDS_NMS_PER_DEG",
    "DEFAULT_FORMULATION",
    "FORMULATIONS",
    "CostTerms",
    "Identifiability",
    "Identification",
    "OptimizeResult",
    "ParameterBounds",
    "ParticleSwarm",
    "QualityThresholds",
    "TrialQuality",
    "StanceCost",
    "assess_identifiability",
    "assess_quality",
    "compare_spring_locations",
    "compare_spring_models",
    "contact_window",
    "cost_landscape",
    "formulation_drive",
    "identification_landscape",
    "identify_stance",
    "instantaneous_stiffness",
    "make_bounds",
    "make_optimizer",
    "minimize",
    "nrmse",
    "parameter_bounds",
    "polish",
    "stiffness_bounds",
]
