"""Write one line per solve folder: the swing-knee brackets at 4 m/s and the 5 m/s solves.

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/study-human-swing-knee-2026-12-03/collect_records.py RUNS OUT.jsonl

RUNS holds ``bladelab predict`` output folders; each line of ``OUT.jsonl`` has the folder's
name, the category, speed [m/s] and swing-knee minimum [deg] of its settings, the objective,
the criteria met and missed and the summary (a folder without ``solution.json``: not
converged). Prints them.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.solution import CollocationSolution


def solve_record(path: Path) -> tuple[dict, dict]:
    """(the solution file's raw mapping, its record: objective, criteria met of how many, the
    criteria missed as lines, the summary)."""
    raw = json.loads(path.read_text(encoding="utf-8"))
    crit = human_running_criteria(CollocationSolution.read(path))
    return raw, {"objective": raw["objective"], "criteria_met": sum(c.met for c in crit),
                 "criteria": len(crit),
                 "criteria_missed": [c.line() for c in crit if not c.met], **raw["summary"]}


def main(runs: Path, out: Path) -> int:
    records = []
    for folder in sorted(p for p in runs.iterdir() if p.is_dir()):
        path = folder / "solution.json"
        if not path.is_file():
            records.append({"run": folder.name, "converged": False})
            continue
        raw, rec = solve_record(path)
        records.append({"run": folder.name, "category": raw["model"].get("blade"),
                        "speed_mps": raw["settings"]["speed_m_per_s"],
                        "swing_knee_min_deg": raw["settings"]["swing_knee_min_deg"], **rec})
    with open(out, "w", encoding="utf-8") as f:
        for rec in records:
            f.write(json.dumps(rec) + "\n")
    for rec in records:
        if "objective" not in rec:
            print(f"{rec['run']:>16}: not converged")
            continue
        print(f"{rec['run']:>16}: objective {rec['objective']:.4f}, CoT "
              f"{rec['cost_of_transport_J_per_kg_m']:.3f}, {rec['criteria_met']} of "
              f"{rec['criteria']}; " + "; ".join(m.split(" (people")[0]
                                                    for m in rec["criteria_missed"]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1]), Path(sys.argv[2])))
