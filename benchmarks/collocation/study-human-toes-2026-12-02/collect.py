"""Gather the 5 m/s solves of this record into ``records.jsonl`` and each category's best.

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/study-human-toes-2026-12-02/collect.py RUNS_DIR [OUT]

RUNS_DIR holds one ``bladelab predict`` output folder per solve, named ``CAT-START`` (e.g.
``Cat4-A``; ``-m200`` in the name: a mesh-200 solve). Appends nothing twice: a run already in
OUT's ``records.jsonl`` is replaced by its folder, the others are kept. Each category's lowest
objective on 100 intervals (among the folders and the ``CAT-best.json`` already in OUT) is
``CAT-best.json`` (multipliers removed), its lowest on 200 intervals ``CAT-mesh200.json``.
``categories.csv`` has one row per category's best: its summary, criteria and stride analyses
(K_leg, joint powers, leg and blade energies; ``bladelab.predict.collocation.analyses``).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.solution import CollocationSolution

HERE = Path(__file__).parent


def _acceleration_term(s: dict) -> float:
    qdd = np.asarray(s["qdd"], float)[:-1, 3:]
    return float(s["settings"]["weights"]["acceleration"] * np.mean(qdd**2) / 1e4)


def _earlier(out: Path, runs: set[str]) -> tuple[list[dict], dict]:
    """OUT's records of runs not in ``runs``, and its ``CAT-best.json`` strides keyed (category, 100)."""
    path = out / "records.jsonl"
    kept = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()
            if line.strip()] if path.is_file() else []
    best = {}
    for f in out.glob("*-best.json"):
        raw = json.loads(f.read_text(encoding="utf-8"))
        best[(f.name.split("-")[0], 100)] = (raw["objective"], raw)
    return [r for r in kept if r["run"] not in runs], best


def _category_table(out: Path) -> None:
    import csv

    from bladelab.predict.collocation.analyses import stride_analyses

    rows = []
    for f in sorted(out.glob("*-best.json")):
        sol = CollocationSolution.read(f)
        crit = human_running_criteria(sol)
        rows.append({"category": f.name.split("-")[0], "objective": sol.nlp.objective,
                     **sol.summary(), "criteria_met": f"{sum(c.met for c in crit)}/{len(crit)}",
                     "criteria_missed": "; ".join(f"{c.name} {c.value_text()}" for c in crit
                                                  if not c.met),
                     **stride_analyses(sol)})
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(out / "categories.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


def main(runs: Path, out: Path = HERE) -> int:
    folders = sorted(p for p in runs.iterdir() if p.is_dir())
    records, best = _earlier(out, {p.name for p in folders})
    for folder in folders:
        path = folder / "solution.json"
        if not path.is_file():
            records.append({"run": folder.name, "converged": False})
            continue
        raw = json.loads(path.read_text(encoding="utf-8"))
        sol = CollocationSolution.read(path)
        crit = human_running_criteria(sol)
        category, start = folder.name.split("-", 1)
        rec = {"run": folder.name, "category": category, "start": start,
               "mesh_intervals": raw["settings"]["mesh_intervals"], "objective": raw["objective"],
               "objective_terms": raw["objective_terms"],
               "acceleration_term": _acceleration_term(raw),
               "criteria_met": sum(c.met for c in crit), "criteria": len(crit),
               "criteria_missed": [c.name for c in crit if not c.met],
               "criteria_values": {c.name: c.value for c in crit}, **raw["summary"]}
        records.append(rec)
        key = (category, rec["mesh_intervals"])
        if rec["converged"] and (key not in best or rec["objective"] < best[key][0]):
            best[key] = (rec["objective"], raw)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "records.jsonl", "w", encoding="utf-8") as f:
        for rec in records:
            f.write(json.dumps(rec) + "\n")
    for (category, mesh), (_, raw) in best.items():
        raw.pop("multipliers", None)
        name = f"{category}-best.json" if mesh == 100 else f"{category}-mesh{mesh}.json"
        (out / name).write_text(json.dumps(raw), encoding="utf-8")
    _category_table(out)
    for rec in records:
        if "objective" in rec:
            print(f"{rec['run']:>22} mesh {rec['mesh_intervals']:>3} obj {rec['objective']:.4f} "
                  f"CoT {rec['cost_of_transport_J_per_kg_m']:.3f} acc {rec['acceleration_term']:.3f} "
                  f"T {rec['stride_time_s']:.3f} {rec['criteria_met']}/{rec['criteria']} "
                  f"{rec['criteria_missed']} it {rec['iterations']}")
        else:
            print(f"{rec['run']:>22} not converged")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(*(Path(a) for a in sys.argv[1:3])))
