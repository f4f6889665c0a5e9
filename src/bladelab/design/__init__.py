"""Design studies (seed 002): design space, DOE, response surfaces, performance, constraints.

The pieces, each usable on its own:

- :mod:`~bladelab.design.space`: factors coded to [-1, 1] over user ranges;
- :mod:`~bladelab.design.doe`: central composite, Box–Behnken, D-optimal, user run lists, and the
  rank/conditioning report of a design for a model;
- :mod:`~bladelab.design.surfaces`: second-order response surfaces with R², PRESS, ANOVA and
  intervals;
- :mod:`~bladelab.design.optimum`: the constrained optimum over the coded box;
- :mod:`~bladelab.design.performance`: seed 002's performance functions and the bouncing-ball
  evaluation parameter;
- :mod:`~bladelab.design.constraints`: knee buckling and blade clearance;
- :mod:`~bladelab.design.plots`: main-effect and contour plots;
- :mod:`~bladelab.design.study`: :func:`run_design` ties them to an evaluator;
- :mod:`~bladelab.design.blade_generator`: design point -> multi-link blade spec;
- :mod:`~bladelab.design.compression`: the virtual compression test of a blade;
- :mod:`~bladelab.design.evaluators`: design point -> blade -> simulation -> responses.
"""

from bladelab.design.blade_generator import GeneratedBlade, generate_blade
from bladelab.design.compression import (
    CompressionTestResult,
    compression_test,
    vertical_stiffness,
)
from bladelab.design.constraints import (
    ClearanceResult,
    KneeBucklingResult,
    blade_clearance,
    knee_buckling,
    knee_extension_moment,
)
from bladelab.design.doe import (
    Design,
    EstimabilityReport,
    box_behnken,
    central_composite,
    d_optimal,
    estimability,
    make_design,
    read_runs_csv,
    require_estimable,
)
from bladelab.design.evaluators import BladeEvaluator, make_evaluator, swing_clearance
from bladelab.design.motion import load_motion_model, read_motion_file
from bladelab.design.motion_model import MotionModel, fit_motion_model
from bladelab.design.optimum import OptimumResult, SurfaceConstraint, constrained_optimum
from bladelab.design.performance import (
    CyclePerformance,
    StancePerformance,
    bouncing_ball,
    cycle_performance,
    performance_by_leg,
    performance_by_stance,
    stance_performance,
)
from bladelab.design.space import DesignSpace, Factor, default_design_space
from bladelab.design.study import DesignStudyResult, run_design
from bladelab.design.surfaces import ResponseSurface, SurfacePrediction, fit_surface
from bladelab.design.terms import model_terms, parse_terms
from bladelab.design.trends import SEED002_TRENDS, TrendVerdict, evaluate_trends, trends_frame

__all__ = [
    "BladeEvaluator",
    "ClearanceResult",
    "CompressionTestResult",
    "CyclePerformance",
    "Design",
    "DesignSpace",
    "DesignStudyResult",
    "EstimabilityReport",
    "Factor",
    "GeneratedBlade",
    "KneeBucklingResult",
    "MotionModel",
    "OptimumResult",
    "ResponseSurface",
    "SEED002_TRENDS",
    "StancePerformance",
    "SurfaceConstraint",
    "SurfacePrediction",
    "TrendVerdict",
    "blade_clearance",
    "bouncing_ball",
    "box_behnken",
    "central_composite",
    "compression_test",
    "constrained_optimum",
    "cycle_performance",
    "d_optimal",
    "default_design_space",
    "estimability",
    "evaluate_trends",
    "fit_motion_model",
    "fit_surface",
    "generate_blade",
    "knee_buckling",
    "knee_extension_moment",
    "load_motion_model",
    "make_design",
    "make_evaluator",
    "model_terms",
    "parse_terms",
    "performance_by_leg",
    "performance_by_stance",
    "read_motion_file",
    "read_runs_csv",
    "require_estimable",
    "run_design",
    "stance_performance",
    "swing_clearance",
    "trends_frame",
    "vertical_stiffness",
]
