"""Append one line per solve to ``constraint_records.jsonl``: the solves of the library's
swing-knee constraint (``bladelab predict --swing-knee``).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/swing-knee/record.py LABEL=FOLDER ...

Each FOLDER is a ``bladelab predict`` output folder (its ``solution.json`` or
``best_iterate.json``); the line holds the label, the settings' swing knee, the objective and
its terms, the iterations and wall time, the summary, both knees' peak flexion [deg] and the
criteria missed (people's running and, for the able runner, the joint angles against the
measured trial).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from bladelab.predict.collocation.guess import measured_trial_guess
from bladelab.predict.collocation.human_running import angle_agreement, human_running_criteria
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec

OUT = Path(__file__).parent / "constraint_records.jsonl"


def record(label: str, folder: Path) -> dict:
    path = folder / "solution.json"
    path = path if path.is_file() else folder / "best_iterate.json"
    sol = CollocationSolution.read(path)
    crit = human_running_criteria(sol)
    if sol.model_spec["model"] == "able":
        crit += angle_agreement(sol, measured_trial_guess(runner_from_spec(sol.model_spec),
                                                          n=100).q)
    q, names = np.asarray(sol.nlp.q), list(sol.dof_names)
    knees = {k: float(-np.degrees(q[:, names.index(k)].min()))
             for k in ("knee_angle_l", "knee_angle_r") if k in names}
    return {"label": label, "model": sol.model_spec, "file": path.name,
            "mesh": sol.settings.mesh_intervals,
            "swing_knee_min_deg": sol.settings.swing_knee_min_deg,
            "objective": sol.nlp.objective, "terms": sol.nlp.objective_terms,
            "iterations": sol.nlp.iterations, "wall_s": sol.nlp.wall_s,
            "knee_peaks_deg": knees, "criteria_met": sum(c.met for c in crit),
            "criteria": len(crit), "missed": [c.line() for c in crit if not c.met],
            **sol.summary()}


def main() -> None:
    with open(OUT, "a", encoding="utf-8") as f:
        for arg in sys.argv[1:]:
            label, folder = arg.split("=", 1)
            f.write(json.dumps(record(label, Path(folder)), default=str) + "\n")


if __name__ == "__main__":
    main()
