"""The example study and realistic measurement conditions.

- :mod:`bladelab.example.measurement`: what a lab records of a clean stance (noisy marker cluster,
  noisy force plates, touch-down jitter) and :func:`degrade_stance`, the stance the trial pipeline
  recovers from it.
- :mod:`bladelab.example.study`: the reproducible generator of the synthetic example study
  (``bladelab example make``, ``make demo``).
"""

from bladelab.example.measurement import (
    CLAMP_CLUSTER,
    TIP_MARKER,
    MeasuredTrial,
    clamp_cluster_positions,
    default_tip,
    degrade_stance,
    extend_flight,
    measure_stance,
)
from bladelab.example.study import (
    ExampleStudy,
    GeneratorSettings,
    TrialPlan,
    make_example_study,
    plan_trials,
    read_ground_truth,
)

__all__ = [
    "CLAMP_CLUSTER",
    "TIP_MARKER",
    "ExampleStudy",
    "GeneratorSettings",
    "MeasuredTrial",
    "TrialPlan",
    "clamp_cluster_positions",
    "default_tip",
    "degrade_stance",
    "extend_flight",
    "make_example_study",
    "measure_stance",
    "plan_trials",
    "read_ground_truth",
]
