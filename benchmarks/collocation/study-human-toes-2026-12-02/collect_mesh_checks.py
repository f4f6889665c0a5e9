"""Gather the mesh-halving checks of this record's best strides.

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/study-human-toes-2026-12-02/collect_mesh_checks.py RUNS OUT

RUNS holds one ``bladelab predict --mesh-check`` output folder per category (``RUNS/CAT``).
Writes ``OUT/mesh-checks.jsonl`` (each category's ``mesh-check.json``) and the finer stride as
``OUT/CAT-mesh200.json`` (multipliers removed), and prints the changes.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def main(runs: Path, out: Path) -> int:
    lines = []
    for folder in sorted(p for p in runs.iterdir() if (p / "mesh-check" / "mesh-check.json").is_file()):
        check = json.loads((folder / "mesh-check" / "mesh-check.json").read_text(encoding="utf-8"))
        check["category"] = folder.name
        lines.append(json.dumps(check))
        fine = folder / "mesh-check" / "solution.json"
        if fine.is_file():
            raw = json.loads(fine.read_text(encoding="utf-8"))
            raw.pop("multipliers", None)
            (out / f"{folder.name}-mesh200.json").write_text(json.dumps(raw), encoding="utf-8")
        q = check["quantities"]
        print(folder.name, "settled" if check["settled"] else "NOT settled",
              ", ".join(f"{v['label']} {v['coarse']:.4g} → {v['fine']:.4g} ({v['change_pct']:+.2f} %)"
                        for v in q.values()))
    (out / "mesh-checks.jsonl").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1]), Path(sys.argv[2])))
