"""Defaults of the design wing's settings, in a module that imports nothing.

The evaluators (:class:`~bladelab.design.evaluators.BladeEvaluator`,
:class:`~bladelab.design.transfemoral.RunnerEvaluator`,
:class:`~bladelab.design.collocation_evaluator.CollocationEvaluator`), :func:`run_design`,
the blade generator and the virtual compression test take their defaults from here, and the
command line shows the same values in ``bladelab design --help`` and ``bladelab blade test
--help`` without loading pandas or scipy.
"""

from __future__ import annotations

__all__ = [
    "BASE_BLADE",
    "BLADE_SPEED_MPS",
    "BODY_MASS_KG",
    "COLLOCATION_SPEED_MPS",
    "COMPRESSION_ALIGNMENTS_DEG",
    "COMPRESSION_MAX_DISPLACEMENT_M",
    "COMPRESSION_STEPS",
    "DESIGN_FACTORS",
    "OBJECTIVE",
    "RUNNER_SPEED_MPS",
    "RUNS",
    "SEED",
    "SENSE",
    "SETTLED_REL",
    "SETTLE_FROM_CHEAPEST",
    "SURFACE_MODEL",
]

#: Body mass of the runner [kg] (blade and runner evaluators; the compression test's load is
#: this mass times standard gravity).
BODY_MASS_KG = 76.0
#: Touch-down speed of the blade evaluator's stance [m/s].
BLADE_SPEED_MPS = 8.0
#: Running speed of the runner evaluator's gait cycle [m/s].
RUNNER_SPEED_MPS = 7.0
#: Prescribed mean speed of the collocation evaluator's predicted stride [m/s].
COLLOCATION_SPEED_MPS = 4.0
#: Built-in blade that the blade generator reshapes to each design point.
BASE_BLADE = "xtreme"

#: The factors of the default design space (seed 002's four, with illustrative ranges around
#: :data:`BASE_BLADE`): (name, low, high, unit, label). Vertical stiffness target 18-32 kN/m
#: (seed 000 §3.5: peak K_c of category 2-5 blades), width 0.05-0.08 m, build height
#: 0.40-0.48 m, toe length 0.19-0.25 m.
DESIGN_FACTORS = (
    ("stiffness_kN_per_m", 18.0, 32.0, "kN/m", "vertical stiffness"),
    ("width_m", 0.05, 0.08, "m", "width"),
    ("height_m", 0.40, 0.48, "m", "height"),
    ("toe_length_m", 0.19, 0.25, "m", "toe length"),
)

#: Runs of a design study: the face-centred central composite design.
RUNS = "ccd"
#: Model of the response surfaces: the full quadratic.
SURFACE_MODEL = "quadratic"
#: Seed of a D-optimal design and of the optimiser's starts.
SEED = 0
#: Response whose optimum a study looks for: the forward speed gained over the stance [m/s].
OBJECTIVE = "delta_vx_m_per_s"
#: The optimum maximises the objective.
SENSE = "max"

#: A settling pass of a collocation study that lowers no design's objective by more than this
#: fraction [-] has settled (:mod:`bladelab.design.settling`).
SETTLED_REL = 0.01
#: A settling pass also starts each design from the study's cheapest stride of another design
#: (besides its two nearest neighbours'): neighbours alone left a cheaper branch uncarried.
SETTLE_FROM_CHEAPEST = True

#: Alignment angles of the virtual compression test [deg].
COMPRESSION_ALIGNMENTS_DEG = (0.0, -8.0, 8.0)
#: Largest clamp displacement of the virtual compression test [m].
COMPRESSION_MAX_DISPLACEMENT_M = 0.08
#: Load steps of the virtual compression test up to its largest displacement.
COMPRESSION_STEPS = 40
