"""The runner of the predicted-stride design studies, by default.

Which runner model each amputation has (:data:`AMPUTATIONS`), the body and the built-in start
stride of each (:data:`DEFAULT_BODIES`, :data:`DEFAULT_STARTS`), the prescribed speed, the
blade soles' contact stiffness factor and the athlete's own coordinates that a technique
reference keeps: the defaults of
:class:`~bladelab.design.collocation_evaluator.CollocationEvaluator`.
"""

from __future__ import annotations

from pathlib import Path

from bladelab.design import defaults

__all__ = ["AMPUTATIONS", "DEFAULT_AMPUTATION", "DEFAULT_BODIES", "DEFAULT_BODY",
           "DEFAULT_DESIGN_SPEED_MPS", "DEFAULT_SOLE_STIFFNESS_SCALE", "DEFAULT_START",
           "DEFAULT_STARTS", "REFERENCE_DOFS", "REFERENCE_DOFS_TRANSTIBIAL"]

#: Prescribed speed of a design's stride [m/s] (our choice, docs/design.md "Predicted
#: transfemoral gaits"): the transfemoral runner's maximum speed on collocation is 5.6–5.8 m/s
#: (sphere blade), so seed 002's sprint speeds (about 7 m/s) are out of its reach; 4 m/s is
#: the speed of the clean multi-link stride the first design starts from (2026-11-26: the
#: continuations to 4.5 and 5 m/s were not finished).
DEFAULT_DESIGN_SPEED_MPS = defaults.COLLOCATION_SPEED_MPS
_STRIDES = Path(__file__).resolve().parents[1] / "data" / "runner" / "collocation"
#: The amputations a design's runner may have: the runner model of each
#: (:data:`bladelab.runner.model.KINDS`).
AMPUTATIONS = {"transfemoral": "transfemoral", "transtibial": "amputee"}
#: The amputation of a design study's runner: seed 002's athlete (a transfemoral amputation).
DEFAULT_AMPUTATION = "transfemoral"
#: The start of the first design by (amputation, runner body): a clean stride wearing the
#: default box's centre blade at :data:`DEFAULT_DESIGN_SPEED_MPS`, its joints by backward
#: Euler (how each was made: ``data/runner/collocation/README.md``). The transfemoral runner
#: on the human body has none: its converged strides gallop, or alternate only with a 10.8 BW
#: intact-leg impact (measured: benchmarks/design/README.md), so a study of it needs
#: ``start``.
DEFAULT_STARTS = {("transfemoral", "seed001"): _STRIDES / "transfemoral-design-centre-4.json",
                  ("transtibial", "human"): _STRIDES / "transtibial-design-centre-4-human.json"}
#: The runner body of the design studies by amputation: the one with a start stride
#: (:data:`DEFAULT_STARTS`), seed 001's for the transfemoral runner, predict's human body for
#: the transtibial one.
DEFAULT_BODIES = {"transfemoral": "seed001", "transtibial": "human"}
#: The runner body of the transfemoral design studies (:data:`DEFAULT_BODIES`).
DEFAULT_BODY = DEFAULT_BODIES[DEFAULT_AMPUTATION]
#: The start of the first design on :data:`DEFAULT_BODY`.
DEFAULT_START = DEFAULT_STARTS[(DEFAULT_AMPUTATION, DEFAULT_BODY)]
#: Factor on the generated blade's sole contact stiffness (its damping by the square root, the
#: damping ratio kept) in the design's runner, forward and collocation alike (our choice,
#: measured 2026-11-26, docs/design.md): with the generator's 10⁶ N/m soles the transfemoral
#: 4 m/s stride from the sphere's clean run converged to 12-BW intact-leg impacts (or, with a
#: tracking stage, to an infeasible point); with 10⁵ N/m it converged in 154 s to a stride
#: without gait warnings (a gallop, as every transfemoral stride found so far).
#: 10⁵ N/m (three soles: 3·10⁵ N/m against the blade's 18–32 kN/m) adds 6–10 % to the
#: blade's compression at a given load.
DEFAULT_SOLE_STIFFNESS_SCALE = 0.1
#: The athlete's own coordinates that the collocation evaluator's ``reference_weight``
#: (:class:`~bladelab.design.collocation_evaluator.CollocationEvaluator`) keeps near the start
#: stride: trunk, pelvis tilt, the intact leg and the residual hip. The prosthetic knee and the
#: blade's joints move as the blade makes them (our choice, docs/design.md).
REFERENCE_DOFS = ("pelvis_tilt", "lumbar_extension", "hip_flexion_l", "knee_angle_l",
                  "ankle_angle_l", "hip_flexion_r")
#: :data:`REFERENCE_DOFS` of the transtibial runner: with the residual knee, the athlete's own.
REFERENCE_DOFS_TRANSTIBIAL = (*REFERENCE_DOFS, "knee_angle_r")
