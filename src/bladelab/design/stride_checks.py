"""Each run's stride of a predicted-gait design study, checked again as it is on disk.

A study's results may hold strides written before a check existed; :func:`stride_checks`
applies today's gait checks and the criteria of people's running to every stored stride, so
that the report marks the runs it leaves out of its surfaces (never averaged in silently).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bladelab.design.stride_files import point_file_stem
from bladelab.predict.collocation.alternating_steps import step_phase
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.solution import CollocationSolution

__all__ = ["stride_checks"]


def _solutions_folder(design_dir: Path, solutions_dir: str | None) -> Path | None:
    """A study's strides folder: ``solutions_dir`` as recorded (absolute, or relative to the
    folder the study was run from), else a folder of that name inside ``design_dir`` (a study
    moved or cloned elsewhere)."""
    if not solutions_dir:
        return None
    recorded = Path(solutions_dir)
    for path in (recorded, design_dir / recorded.name):
        if path.is_dir():
            return path
    return None


def stride_checks(design_dir: str | Path, evaluator: Mapping[str, Any],
                  points: list[Mapping[str, float]]) -> list[dict]:
    """Each run's stride of a collocation design study, checked again as it is now on disk:
    one row per point with ``stride`` (file name, or None when not found), ``converged``,
    ``dynamics_residual_pct`` [%], ``step_phase`` [fraction of the stride: 0.5 alternating,
    near 0 or 1 a gallop; :func:`~bladelab.predict.collocation.alternating_steps.step_phase`],
    ``iterations``, ``warnings`` (its
    :meth:`~bladelab.predict.collocation.solution.CollocationSolution.gait_warnings`, "; "
    -joined; "" when clean), ``criteria_met`` / ``criteria`` (how many of the criteria of
    people's running it meets, :func:`~bladelab.predict.collocation.human_running.
    human_running_criteria`) and ``outside_people`` (the names of those it misses, "; "
    -joined). A study's results may hold strides written before a check existed
    (the 5 % residual gate came after the free-gait study): the report marks those runs and
    leaves them out of its surfaces rather than average them in silently."""
    folder = _solutions_folder(Path(design_dir), evaluator.get("solutions_dir"))
    rows = []
    for point in points:
        row = {"stride": None, "converged": None, "dynamics_residual_pct": math.nan,
               "step_phase": math.nan, "iterations": None, "warnings": "stride file not found",
               "criteria_met": None, "criteria": None, "outside_people": ""}
        path = folder / f"{point_file_stem(point)}.json" if folder is not None else None
        if path is not None and path.is_file():
            sol = CollocationSolution.read(path)
            warnings = sol.gait_warnings() if sol.converged else [f"IPOPT {sol.nlp.status}"]
            criteria = human_running_criteria(sol)
            row = {"stride": path.name, "converged": bool(sol.converged),
                   "dynamics_residual_pct": sol.dynamics_residual_pct,
                   "step_phase": step_phase(sol.leg_vertical_force()[:-1]),
                   "iterations": int(sol.nlp.iterations), "warnings": "; ".join(warnings),
                   "criteria_met": sum(c.met for c in criteria), "criteria": len(criteria),
                   "outside_people": "; ".join(c.name for c in criteria if not c.met)}
        rows.append(row)
    return rows
