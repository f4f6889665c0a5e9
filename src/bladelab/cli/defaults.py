"""Library defaults that the command line shows in its options, as literals.

Importing the library module that owns a default would load its whole wing (numba, MuJoCo, ...)
for every command, ``bladelab --help`` included; the values are copied here instead and
``tests/test_cli_startup.py`` checks that each still equals the library's.
"""

from __future__ import annotations

__all__ = ["COLLOCATION_MAX_ITER", "COLLOCATION_MESH", "RUNNER_DT", "TRACK_WEIGHT"]

# Time step of the runner's forward simulation [s]: bladelab.runner.model.DEFAULT_DT (also the
# reflex objective's default, bladelab.predict.reflex.objective.DEFAULT_PREDICT_DT).
RUNNER_DT = 2.5e-4

# Collocation (bladelab.predict.collocation.solve.CollocationSettings): mesh intervals of the
# stride and IPOPT's iteration limit per stage.
COLLOCATION_MESH = 50
COLLOCATION_MAX_ITER = 3000

# Weight of the reflex route's tracking term [1/rad²]:
# bladelab.predict.reflex.tracking.DEFAULT_WEIGHT.
TRACK_WEIGHT = 1000.0
