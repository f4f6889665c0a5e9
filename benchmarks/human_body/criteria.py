"""Print a stored stride against measured human running, criterion by criterion.

Usage (repository root): ``.venv/bin/python benchmarks/human_body/criteria.py PATH...``; each
PATH is a solution file or a folder holding a ``solution.json`` (or ``best_iterate.json``) of
``bladelab predict --method collocation``. One block per path, or one JSON line each
(``--json``). :func:`stride_record` is the one record line of a stride that the folders'
``collect.py`` scripts append to their ``records.jsonl``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.solution import CollocationSolution

#: The summary fields of a stride record (``CollocationSolution.summary``'s names and units).
RECORD_FIELDS = ("cost_of_transport_J_per_kg_m", "stride_time_s", "contact_time_s",
                 "contact_time_left_s", "contact_time_right_s", "contact_time_intact_s",
                 "contact_time_prosthetic_s", "peak_vertical_grf_left_bw",
                 "peak_vertical_grf_right_bw", "peak_vertical_grf_intact_bw",
                 "peak_vertical_grf_prosthetic_bw", "dynamics_residual_pct", "iterations",
                 "wall_s")


def stride_record(sol: CollocationSolution) -> dict:
    """One record of the stride ``sol``: speed [m/s], mesh, converged, objective, the
    :data:`RECORD_FIELDS` it has, and the criteria of people's running met and missed."""
    summary = sol.summary()
    crit = human_running_criteria(sol)
    return {"speed_mps": sol.settings.speed_m_per_s, "mesh": sol.settings.mesh_intervals,
            "converged": sol.converged, "objective": sol.nlp.objective,
            **{k: summary[k] for k in RECORD_FIELDS if k in summary},
            "criteria_met": sum(c.met for c in crit), "criteria": len(crit),
            "criteria_missed": [c.line() for c in crit if not c.met]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("paths", nargs="+", type=Path)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    for folder in args.paths:
        path = folder if folder.is_file() else folder / "solution.json"
        if not path.is_file():
            path = folder / "best_iterate.json"
        sol = CollocationSolution.read(path)
        crit = human_running_criteria(sol)
        s = sol.summary()
        if args.json:
            print(json.dumps({"folder": str(folder), "summary": s,
                              "criteria": [c.to_dict() for c in crit]}))
            continue
        print(f"== {folder} ({path.name}): converged {s['converged']}, "
              f"{s['mean_speed_mps']:.2f} m/s, residual {s['dynamics_residual_pct']:.2f} %, "
              f"{s['iterations']} iterations, {s['wall_s']:.0f} s, "
              f"{sum(c.met for c in crit)}/{len(crit)} criteria met")
        for c in crit:
            print("  " + c.line())
        if s["warnings"]:
            print("  warnings: " + s["warnings"])


if __name__ == "__main__":
    main()
