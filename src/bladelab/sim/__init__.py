"""Blade simulation: a blade chain driven by a stance's clamp motion, pressing on the ground.

- :func:`prepare` / :func:`simulate` / :func:`simulate_batch`: the default numba planar-chain
  kernel (``engine="kernel"``) or the MuJoCo reference (``engine="mujoco"``).
- :func:`generate_stance`: a physically consistent synthetic stance (a point-mass runner whose
  leg carries the blade), with the true K, D.

Method notes: ``docs/blade-model.md``.
"""

from bladelab.sim.api import (
    DEFAULT_DT,
    Drive,
    SimProblem,
    prepare,
    simulate,
    simulate_batch,
    utilised_friction_ratio,
)
from bladelab.sim.chain import Chain, build_chain
from bladelab.sim.kernel import ENERGY_TERMS
from bladelab.sim.motion import ClampMotion
from bladelab.sim.result import BatchResult, SimResult, write_simulation_csv
from bladelab.sim.synthetic import generate_stance

__all__ = [
    "DEFAULT_DT",
    "ENERGY_TERMS",
    "BatchResult",
    "Chain",
    "ClampMotion",
    "Drive",
    "SimProblem",
    "SimResult",
    "build_chain",
    "generate_stance",
    "prepare",
    "simulate",
    "simulate_batch",
    "utilised_friction_ratio",
    "write_simulation_csv",
]
