"""Gather the speed chains of this record (each category's 4 m/s best, and the able runner's
shipped 3.5 m/s stride, continued by ``bladelab predict --guess PREVIOUS`` at rising speeds on
the category problem, a chain stopping at the first speed that misses a criterion).

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/study-human-swing-knee-2026-12-03/collect_chains.py RUNS

RUNS holds one output folder per solve, named ``RUNNER-SPEED`` (e.g. ``Cat7-4.75``,
``able-3.75``). Writes ``every-criterion/records.jsonl`` (per solve: runner, speed, objective,
cost of transport, criteria met and missed, the summary) and each runner's fastest stride
that meets every criterion as ``every-criterion/RUNNER-every-criterion.json`` (multipliers
removed), and prints the table.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from collect_records import solve_record

OUT = Path(__file__).parent / "every-criterion"


def main(runs: Path) -> int:
    OUT.mkdir(exist_ok=True)
    records, fastest = [], {}
    for folder in sorted(p for p in runs.iterdir() if p.is_dir()):
        runner, speed = folder.name.rsplit("-", 1)
        path = folder / "solution.json"
        if not path.is_file():
            records.append({"runner": runner, "speed_mps": float(speed), "converged": False})
            continue
        raw, rec = solve_record(path)
        records.append({"runner": runner, "speed_mps": float(speed), **rec})
        if not rec["criteria_missed"] and float(speed) > fastest.get(runner, (0.0, None))[0]:
            fastest[runner] = (float(speed), raw)
    with open(OUT / "records.jsonl", "w", encoding="utf-8") as f:
        for rec in records:
            f.write(json.dumps(rec) + "\n")
    for runner, (_, raw) in fastest.items():
        raw.pop("multipliers", None)
        (OUT / f"{runner}-every-criterion.json").write_text(json.dumps(raw), encoding="utf-8")
    for rec in sorted(records, key=lambda r: (r["runner"], r["speed_mps"])):
        if "objective" not in rec:
            print(f"{rec['runner']:>9} {rec['speed_mps']:5.2f} m/s: not converged")
            continue
        print(f"{rec['runner']:>9} {rec['speed_mps']:5.2f} m/s: CoT "
              f"{rec['cost_of_transport_J_per_kg_m']:.3f}, {rec['criteria_met']} of "
              f"{rec['criteria']}; " + "; ".join(rec["criteria_missed"]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1])))
