"""Gather the category answer at people's-angle weights 0 and 20 beside the record's weight 10.

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/study-human-toes-2026-12-02/collect_people_weight.py RUNS [OUT]

RUNS holds ``wW/speed-S/CAT/`` folders of ``../../human_body/sprint_limit.py`` (one speed
each, ``people_weight`` W, started from ``speed-S/CAT-best.json``) and ``CAT-from-OTHER/``
(started from OTHER's stride of the same weight and speed). OUT (default ``people-weight/``
beside this file) gets ``records.jsonl`` (one line per solve: the weight, speed, category,
start, objective and its terms, the summary, every criterion's value), ``CAT-wW-S.json``, the
lowest stride per (weight, speed, category) (multipliers removed), and ``table.csv`` of the
same rows, the weight-10 rows read from ``speed-S/CAT-best.json``.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.solution import CollocationSolution

HERE = Path(__file__).parent
CATEGORIES = ("Cat4", "Cat5", "Cat6", "Cat6High", "Cat7")


def _row(path: Path, weight: float, speed: float, category: str) -> dict:
    raw = json.loads(path.read_text(encoding="utf-8"))
    sol = CollocationSolution.from_dict(raw, file=path)
    crit = human_running_criteria(sol)
    return {"people_weight": weight, "speed": speed, "category": category,
            "objective": raw["objective"], **{f"term_{k}": v for k, v in
                                              raw["objective_terms"].items()},
            **raw["summary"],
            "criteria_met": sum(c.met for c in crit), "criteria": len(crit),
            "criteria_missed": "; ".join(c.line() for c in crit if not c.met),
            "criteria_values": {c.name: round(c.value, 4) for c in crit}}


def main(runs: Path, out: Path = HERE / "people-weight") -> int:
    out.mkdir(parents=True, exist_ok=True)
    rows, best = [], {}
    for sdir in sorted(runs.glob("w*/speed-*")):
        weight, speed = float(sdir.parent.name[1:]), float(sdir.name.split("-")[1])
        for folder in sorted(p for p in sdir.iterdir() if p.is_dir()):
            category, _, start = folder.name.partition("-from-")
            path = folder / f"speed-{speed:g}.json"
            if not path.is_file():
                rows.append({"people_weight": weight, "speed": speed, "category": category,
                             "start": start or "own", "converged": False})
                continue
            row = {**_row(path, weight, speed, category), "start": start or "own"}
            rows.append(row)
            key = (weight, speed, category)
            if key not in best or row["objective"] < best[key][0]:
                best[key] = (row["objective"], path)
    for (weight, speed, category), (_, path) in best.items():
        raw = json.loads(path.read_text(encoding="utf-8"))
        raw.pop("multipliers", None)
        (out / f"{category}-w{weight:g}-{speed:g}.json").write_text(json.dumps(raw),
                                                                   encoding="utf-8")
    speeds = sorted({r["speed"] for r in rows})
    for speed in speeds:
        for category in CATEGORIES:
            record_best = HERE / f"speed-{speed:g}" / f"{category}-best.json"
            if record_best.is_file():
                rows.append({**_row(record_best, 10.0, speed, category),
                             "start": "the record's best"})
    rows.sort(key=lambda r: (r["speed"], r["people_weight"], CATEGORIES.index(r["category"])))
    with open(out / "records.jsonl", "w", encoding="utf-8") as f:
        for r in rows:
            f.write(json.dumps(r) + "\n")
    keys = [k for k in dict.fromkeys(k for r in rows for k in r) if k != "criteria_values"]
    with open(out / "table.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        if "objective" not in r:
            print(f"{r['speed']:g} m/s w {r['people_weight']:g} {r['category']:>8} "
                  f"{r['start']}: no stride")
            continue
        v = r["criteria_values"]
        knees = [f"{val:.0f}" for name, val in v.items() if "swing knee" in name]
        print(f"{r['speed']:g} m/s w {r['people_weight']:>4g} {r['category']:>8} "
              f"{r['start'][:8]:>8}: "
              f"obj {r['objective']:.4f} CoT {r['cost_of_transport_J_per_kg_m']:.3f} "
              f"T {r['stride_time_s']:.3f} tc {r['contact_time_intact_s']:.3f}/"
              f"{r['contact_time_prosthetic_s']:.3f} peaks "
              f"{r['peak_vertical_grf_intact_bw']:.2f}/{r['peak_vertical_grf_prosthetic_bw']:.2f} "
              f"knees {'/'.join(knees)} {r['criteria_met']}/{r['criteria']} "
              f"it {r['iterations']} {r['wall_s']:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(*(Path(a) for a in sys.argv[1:3])))
