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

import importlib

# Public name -> the module that defines it. The names load on first use (PEP 562), so that
# importing a light module of the package (``bladelab.design.defaults``, which the command
# line's help reads) does not load pandas and scipy.
_EXPORTS: dict[str, str] = {
    "blade_clearance": "constraints",
    "BladeEvaluator": "evaluators",
    "bouncing_ball": "performance",
    "box_behnken": "doe",
    "central_composite": "doe",
    "ClearanceResult": "constraints",
    "compression_test": "compression",
    "CompressionTestResult": "compression",
    "constrained_optimum": "optimum",
    "cycle_performance": "performance",
    "CyclePerformance": "performance",
    "d_optimal": "doe",
    "default_design_space": "space",
    "Design": "doe",
    "DesignSpace": "space",
    "DesignStudyResult": "study",
    "estimability": "doe",
    "EstimabilityReport": "doe",
    "evaluate_trends": "trends",
    "Factor": "space",
    "fit_motion_model": "motion_model",
    "fit_surface": "surfaces",
    "generate_blade": "blade_generator",
    "GeneratedBlade": "blade_generator",
    "knee_buckling": "constraints",
    "knee_extension_moment": "constraints",
    "KneeBucklingResult": "constraints",
    "load_motion_model": "motion",
    "make_design": "doe",
    "make_evaluator": "evaluators",
    "model_terms": "terms",
    "MotionModel": "motion_model",
    "OptimumResult": "optimum",
    "parse_terms": "terms",
    "performance_by_leg": "performance",
    "performance_by_stance": "performance",
    "read_motion_file": "motion",
    "read_runs_csv": "doe",
    "require_estimable": "doe",
    "ResponseSurface": "surfaces",
    "run_design": "study",
    "SEED002_TRENDS": "trends",
    "SPEED_TRENDS": "trends",
    "stance_performance": "performance",
    "StancePerformance": "performance",
    "SurfaceConstraint": "optimum",
    "SurfacePrediction": "surfaces",
    "swing_clearance": "evaluators",
    "trends_frame": "trends",
    "TrendVerdict": "trends",
    "vertical_stiffness": "compression",
}

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
    "SPEED_TRENDS",
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


def __getattr__(name: str):
    """A public name (or a submodule) of the package, imported on first use."""
    if name.startswith("__"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module = _EXPORTS.get(name)
    if module is not None:
        value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
        globals()[name] = value
        return value
    try:
        return importlib.import_module(f"{__name__}.{name}")
    except ModuleNotFoundError as err:
        if err.name != f"{__name__}.{name}":
            raise
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
