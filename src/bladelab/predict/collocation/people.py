"""People's joint angles as a reference of the predictive objective (``reference="people"``).

A predicted stride of the human body is, by itself, the body's cheapest: on the able runner
at 3.5 m/s a stride with a shallow swing (knee 73–75°), a high cadence and a landing on a
flexed knee, while people's measured stride costs the same body 4 % more
(benchmarks/human_body/README.md). With ``CollocationSettings(reference="people",
reference_weight=w)`` the predictive stage adds ``w`` [1/rad²] × the time-averaged mean
squared deviation of the hip, knee and ankle angles from people's, the mean of two subjects of
Fukuchi et al. (2017) at 3.5 m/s (:func:`bladelab.datasets.people_joint_angles_table`:
RBDS002 and RBDS003, never RBDS001, the trial every predicted stride is checked against).
There is no stride-time term: the cadence stays predicted. The same curves serve every speed
and both legs, the right leg half a stride after the left; the reference is shifted to the
start's phase (:func:`people_reference`), so that the term does not ask the stride to move
its touch-downs.

This is a tracking term of measured running, and the answers say so (the report's first
section, docs/predictive.md); the weight is a setting, and answers are compared at 0, w and
2w.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from bladelab.datasets import people_joint_angles_table
from bladelab.errors import InputFileError, SpecError

__all__ = ["PEOPLE_JOINTS", "PEOPLE_SUBJECTS", "PROSTHETIC_JOINTS", "people_joint_angles",
           "people_reference", "subject_joint_angles"]

#: Subjects of the dataset whose mean pattern is people's reference.
PEOPLE_SUBJECTS = ("RBDS002", "RBDS003")
#: (model coordinate base name, the table's column, sign: model angle = sign × column) [rad].
PEOPLE_JOINTS = (("hip_flexion", "hip_flexion_deg", 1.0),
                 ("knee_angle", "knee_flexion_deg", -1.0),
                 ("ankle_angle", "ankle_dorsiflexion_deg", 1.0))
#: Per runner kind, the coordinates that bear a joint's name but are a prosthesis's: the
#: transfemoral runner's knee on the prosthetic (right) side is the prosthetic knee.
PROSTHETIC_JOINTS = {"transfemoral": ("knee_angle_r",)}
#: Candidate phases tried when aligning the reference with a start, per stride.
_PHASE_STEPS = 400


@cache
def people_joint_angles() -> dict[str, np.ndarray]:
    """People's mean joint angles over the stride from the heel strike, per model coordinate
    base name (``hip_flexion``, ``knee_angle``, ``ankle_angle``) [rad, model signs: knee
    flexion negative], 100 samples at 0, 1, ..., 99 % of the stride."""
    return {base: curves.mean(axis=1) for base, curves in subject_joint_angles().items()}


@cache
def subject_joint_angles() -> dict[str, np.ndarray]:
    """Each of :data:`PEOPLE_SUBJECTS`' joint angles, per model coordinate base name: (100,
    subjects) [rad, model signs], samples as in :func:`people_joint_angles`."""
    path = people_joint_angles_table()
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    out = {}
    for base, column, sign in PEOPLE_JOINTS:
        names = [f"{s}_{column}" for s in PEOPLE_SUBJECTS]
        missing = [n for n in names if n not in header]
        if missing or data.shape[0] != 100:
            raise InputFileError(f"expected 100 rows and the columns {', '.join(names)}",
                                 file=path, hint="reinstall bladelab; the packaged file is "
                                                 "written by benchmarks/human_body/people_angles.py")
        cols = [header.index(n) for n in names]
        out[base] = sign * np.radians(data[:, cols])
    return out


def _curve_at(curve: np.ndarray, frac: np.ndarray) -> np.ndarray:
    """A periodic 100-sample curve at stride fractions ``frac`` (any real numbers)."""
    return np.interp(np.mod(frac, 1.0), np.arange(100) / 100.0, curve, period=1.0)


def people_reference(dof_names, q_start: np.ndarray, dofs=None, *, exclude=(),
                     phase: float | None = None) -> tuple[np.ndarray, tuple[str, ...], float]:
    """People's angles on a stride's nodes, in phase with a start.

    Parameters
    ----------
    dof_names
        The model's coordinate names (``RunnerModel.dof_names``).
    q_start
        The start's coordinates on the mesh nodes, (n + 1, n_dof) [rad, m], node n the
        periodic repeat of node 0.
    dofs
        Coordinates to track, a subset of those people's table has on this model
        (``hip_flexion_l``, ``knee_angle_l``, ``ankle_angle_l`` and the right leg's); None: all
        of them (a prosthetic leg's missing joints are left out).
    exclude
        Coordinates that are no person's joint although they bear a joint's name (a prosthetic
        knee: :data:`PROSTHETIC_JOINTS`), never tracked.
    phase
        The phase [fraction of the stride] of the left heel strike at node 0, or None: the
        phase that fits the start best (least squares over the tracked angles, in steps of
        1/400 of the stride). A stride solved against the reference moves towards it, so its
        best fit moves too; a solve from such a stride passes the phase it was solved with.

    Returns
    -------
    (q_ref, dofs, phase)
        ``q_ref`` (n + 1, n_dof): people's angles in the tracked columns, the start's values in
        the others; the tracked names; the phase [fraction of the stride, in 0–1) of the left
        heel strike at node 0: ``phase`` if given, else the best fit.
    """
    names = list(dof_names)
    q_start = np.asarray(q_start, float)
    if q_start.ndim != 2 or q_start.shape[1] != len(names) or q_start.shape[0] < 5:
        raise SpecError(f"expected the start's coordinates as (nodes, {len(names)}), got "
                        f"{q_start.shape}", where="reference")
    curves = people_joint_angles()
    available = [f"{base}_{side}" for side in ("l", "r") for base, _, _ in PEOPLE_JOINTS
                 if f"{base}_{side}" in names and f"{base}_{side}" not in exclude]
    if dofs is None:
        dofs = tuple(available)
    unknown = [d for d in dofs if d not in available]
    if unknown or not dofs:
        raise SpecError(f"people's reference has no {', '.join(unknown) or 'coordinates'} on "
                        f"this model", where="reference_dofs",
                        hint=f"choose among {', '.join(available)}")
    frac = np.linspace(0.0, 1.0, q_start.shape[0])
    cols = [names.index(d) for d in dofs]

    def reference(phase: float) -> np.ndarray:
        q = q_start.copy()
        for d, j in zip(dofs, cols, strict=True):
            base, side = d.rsplit("_", 1)
            q[:, j] = _curve_at(curves[base], frac - phase - (0.5 if side == "r" else 0.0))
        return q

    if not np.all(np.isfinite(q_start[:, cols])):
        raise SpecError("the start's joint angles are not finite", where="reference")
    if phase is None:
        phases = np.arange(_PHASE_STEPS) / _PHASE_STEPS
        misfit = [float(np.sum((reference(p)[:-1, cols] - q_start[:-1, cols]) ** 2))
                  for p in phases]
        phase = float(phases[int(np.argmin(misfit))])
    elif not math.isfinite(phase):
        raise SpecError(f"the reference phase must be finite, got {phase}",
                        where="reference_phase")
    phase = float(phase) % 1.0
    return reference(phase), tuple(dofs), phase
