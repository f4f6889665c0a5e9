"""Predictive running by direct collocation: the CasADi side of the runner model.

The model layer ("same model on both sides"): :func:`build_collocation_model` derives,
from the very :class:`bladelab.runner.RunnerModel` that the forward simulation runs, CasADi
Functions of the planar multibody dynamics (implicit inverse dynamics, exact against MuJoCo's
``mj_inverse``), the muscle paths (lengths, velocities, moment arms, exact against
:func:`bladelab.runner.kernel.path_kinematics`), smooth Hunt–Crossley contact with smooth
friction, smooth ligaments and socket, and De Groote et al. (2016) muscle–tendon dynamics with
the forward Hill model's curves. Numeric code (:mod:`.planar`, reading the MuJoCo model) and
symbolic code (:mod:`.multibody`, :mod:`.paths`, :mod:`.contact`, :mod:`.muscles`) are kept
apart. What is exact and what is smoothed, by how much: ``docs/collocation.md``.
"""

import os

# One BLAS thread for IPOPT and MUMPS (CasADi loads its own OpenBLAS with the first solver, after
# this): measured, the iterates depend on the number of BLAS threads (the same 60 iterations
# from the same start ended at objectives 6.19 with two threads and 3.98 with one) and one
# thread is as fast at these sizes. Set OPENBLAS_NUM_THREADS before the import to override.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

from bladelab.predict.collocation.model import CollocationModel, build_collocation_model
from bladelab.predict.collocation.planar import PlanarJoint, PlanarTree, planar_tree
from bladelab.predict.collocation.smooth import Smoothing

__all__ = [
    "CollocationModel",
    "PlanarJoint",
    "PlanarTree",
    "Smoothing",
    "build_collocation_model",
    "planar_tree",
]
