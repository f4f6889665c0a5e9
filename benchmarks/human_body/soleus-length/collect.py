"""Gather strides of this record into ``records.jsonl`` (a measuring probe; changes nothing in
src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/soleus-length/collect.py LABEL STRIDE.json [...]

Appends one line per stride: LABEL, its speed [m/s], mesh, converged, objective, cost of
transport [J/(kg·m)], stride time [s], contacts [s] and peak vertical forces [BW] per leg,
dynamics residual [%] and the criteria of people's running met and missed. The strides are read
on the library's body as it is (the soleus at 0.25 m); a stride of another body gets the
numbers it stores, but its criteria are those of its own motion and forces either way.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.solution import CollocationSolution

HERE = Path(__file__).parent


def main() -> None:
    label, paths = sys.argv[1], sys.argv[2:]
    with (HERE / "records.jsonl").open("a", encoding="utf-8") as out:
        for path in paths:
            sol = CollocationSolution.read(path)
            summary = sol.summary()
            crit = human_running_criteria(sol)
            row = {"label": label, "speed_mps": sol.settings.speed_m_per_s,
                   "mesh": sol.settings.mesh_intervals, "converged": sol.converged,
                   "objective": sol.nlp.objective,
                   **{k: v for k, v in summary.items()
                      if k.startswith(("cost_of", "stride_time", "contact_time_", "peak_vertical",
                                       "dynamics_residual"))},
                   "criteria_met": sum(c.met for c in crit), "criteria": len(crit),
                   "criteria_missed": [c.line() for c in crit if not c.met]}
            out.write(json.dumps(row) + "\n")
            print(json.dumps(row))


if __name__ == "__main__":
    main()
