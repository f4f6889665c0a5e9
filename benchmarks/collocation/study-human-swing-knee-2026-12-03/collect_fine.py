"""Gather this record's settling solves on 200 intervals (each category's 4 m/s problem on
the finer mesh from a neighbouring category's 200-interval stride).

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/study-human-swing-knee-2026-12-03/collect_fine.py RUNS

RUNS holds one ``bladelab predict --mesh 200`` output folder per solve, named
``CAT-from-OTHER``. Writes ``speed-4/fine-records.jsonl`` (objective, cost of transport,
criteria, summary per solve) and replaces ``speed-4/CAT-mesh200.json`` by a solve that is
lower (multipliers removed); prints each category's lowest 200-interval objective against its
100-interval best.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from collect_records import solve_record

OUT = Path(__file__).parent / "speed-4"


def main(runs: Path) -> int:
    records = []
    for folder in sorted(p for p in runs.iterdir() if (p / "solution.json").is_file()):
        raw, rec = solve_record(folder / "solution.json")
        category, start = folder.name.split("-from-")
        records.append({"run": folder.name, "category": category, "start": start, **rec})
        target = OUT / f"{category}-mesh200.json"
        current = json.loads(target.read_text(encoding="utf-8"))["objective"] \
            if target.is_file() else float("inf")
        if raw["objective"] < current:
            raw.pop("multipliers", None)
            target.write_text(json.dumps(raw), encoding="utf-8")
    with open(OUT / "fine-records.jsonl", "w", encoding="utf-8") as f:
        for rec in records:
            f.write(json.dumps(rec) + "\n")
    for f in sorted(OUT.glob("*-mesh200.json")):
        category = f.name.split("-")[0]
        fine = json.loads(f.read_text(encoding="utf-8"))["objective"]
        coarse = json.loads((OUT / f"{category}-best.json").read_text(encoding="utf-8"))[
            "objective"]
        print(f"{category:>9}: 100 intervals {coarse:.4f}, 200 intervals {fine:.4f} "
              f"({100 * (fine / coarse - 1):+.2f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1])))
