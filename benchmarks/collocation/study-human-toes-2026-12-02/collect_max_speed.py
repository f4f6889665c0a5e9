"""Collect the prescribed-speed continuations (``benchmarks/human_body/sprint_limit.py``, one
folder per runner) into ``max-speed/``: every solve in ``records.jsonl`` (with its runner),
each runner's fastest converged stride as ``RUNNER-fastest.json`` (multipliers removed;
``bladelab report`` rebuilds it) and ``max-speed.csv``, one row per runner: the fastest
prescribed speed with a converged stride [m/s], the first one without [m/s], the fastest
converged stride without a gait warning [m/s], the fastest one that meets every criterion of
people's running [m/s] (written as ``RUNNER-every-criterion.json`` where it is not the fastest),
and the fastest stride's cost of transport [J/(kg·m)], contacts [s], peaks [BW] and criteria (a
chain whose first speed failed: its speed alone). ``OUT`` (default ``max-speed/``) is the
folder written.

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/study-human-toes-2026-12-02/collect_max_speed.py RUNS [OUT]
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

HERE = Path(__file__).parent / "max-speed"


def _stride_file(folder: Path, speed: float, out: Path) -> None:
    """Copy the chain's converged stride at ``speed`` [m/s] to ``out``, multipliers removed."""
    raw = json.loads((folder / f"speed-{speed:g}.json").read_text())
    raw.pop("multipliers", None)
    out.write_text(json.dumps(raw))


def _row(runner: str, recs: list[dict]) -> dict:
    ok = [r for r in recs if r["converged"]]
    failed = [r["speed"] for r in recs if not r["converged"]]
    fastest = max(ok, key=lambda r: r["speed"])
    clean = [r["speed"] for r in ok if not r["warnings"]]
    every = [r["speed"] for r in ok if not r["warnings"] and r["criteria_met"] == r["criteria"]]
    first, second = (("intact", "prosthetic") if "contact_time_prosthetic_s" in fastest
                     else ("left", "right"))
    return {
        "runner": runner,
        "fastest_converged_mps": fastest["speed"],
        "first_not_converged_mps": min(failed) if failed else "",
        "fastest_without_gait_warning_mps": max(clean) if clean else "",
        "fastest_meeting_every_criterion_mps": max(every) if every else "",
        "cot_at_fastest_J_per_kg_m": round(fastest["cost_of_transport_J_per_kg_m"], 3),
        "stride_time_at_fastest_s": round(fastest["stride_time_s"], 3),
        **{f"contact_{leg}_s": round(fastest[f"contact_time_{leg}_s"], 3)
           for leg in (first, second)},
        **{f"peak_{leg}_bw": round(fastest[f"peak_vertical_grf_{leg}_bw"], 2)
           for leg in (first, second)},
        "criteria_met_at_fastest": f"{fastest['criteria_met']} of {fastest['criteria']}",
        "warnings_at_fastest": fastest["warnings"],
    }


def main(runs: Path, out: Path = HERE) -> int:
    out.mkdir(exist_ok=True)
    rows, lines = [], []
    for folder in sorted(p for p in runs.iterdir() if (p / "records.jsonl").is_file()):
        recs = [json.loads(s) for s in (folder / "records.jsonl").read_text().splitlines()]
        lines += [json.dumps({"runner": folder.name, **r}) for r in recs]
        if not any(r["converged"] for r in recs):  # the chain's first speed failed
            rows.append({"runner": folder.name,
                         "first_not_converged_mps": min(r["speed"] for r in recs)})
            continue
        row = _row(folder.name, recs)
        _stride_file(folder, row["fastest_converged_mps"], out / f"{folder.name}-fastest.json")
        every = row["fastest_meeting_every_criterion_mps"]
        if every not in ("", row["fastest_converged_mps"]):
            _stride_file(folder, every, out / f"{folder.name}-every-criterion.json")
        rows.append(row)
    (out / "records.jsonl").write_text("\n".join(lines) + "\n")
    keys = list(dict.fromkeys(k for row in rows for k in row))
    with open(out / "max-speed.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=keys)
        writer.writeheader()
        writer.writerows(rows)
    for row in rows:
        print(row)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(*(Path(a) for a in sys.argv[1:3])))
