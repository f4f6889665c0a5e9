"""The mesh-halving check of each category's kept stride at 4 or 5 m/s (``bladelab predict --mesh-check``).

Usage (from the repository root)::

    .venv/bin/python benchmarks/human_body/mesh_check_categories.py OUT [--speed 4|5] [--mu MU] \
        [--only Cat5,...]

For each category, OUT/<category>/solution.json is the kept stride of ``categories-people10``
(4 m/s) or ``categories-people10-5mps`` (5 m/s; their READMEs name the start kept) and
``bladelab predict --model amputee --blade <category> --speed V --out OUT/<category> --resume
--mesh-check`` solves the
same problem on 100 intervals from it (a finer solve already in OUT/<category>/mesh-check/ is
read back). ``--mu`` starts IPOPT's barrier of the finer solve at MU (set as the stride's
``warm_start_mu``; default: the check's own start, 1e-4; the bound push stays 1e-8 either
way, so 0.1 is not IPOPT's default start, which also pushes the start off its bounds). Writes OUT/mesh-check.csv: per
category the objective, cost of transport, stride time and peaks on both meshes and their
changes, and the verdict.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import shutil
import sys
from pathlib import Path

from bladelab.cli import main
from bladelab.predict.collocation.mesh_check import MESH_CHECK_DIR, read_mesh_check
from bladelab.predict.collocation.solution import CollocationSolution

HERE = Path(__file__).resolve().parent
#: Per speed [m/s]: the record's folder and each category's kept start.
KEPT = {4: ("categories-people10", {"Cat4": "neighbour", "Cat5": "shipped", "Cat6": "neighbour",
                                   "Cat6High": "neighbour", "Cat7": "best"}),
        5: ("categories-people10-5mps", {"Cat4": "best", "Cat5": "neighbour", "Cat6": "fast",
                                         "Cat6High": "neighbour", "Cat7": "fast"})}
COLUMNS = ("objective", "cost_of_transport_J_per_kg_m", "stride_time_s",
           "peak_vertical_grf_intact_bw", "peak_vertical_grf_prosthetic_bw",
           "contact_time_prosthetic_s")


def main_(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--speed", type=int, choices=sorted(KEPT), default=4)
    ap.add_argument("--mu", type=float, default=None)
    ap.add_argument("--only", default="Cat4,Cat5,Cat6,Cat6High,Cat7")
    args = ap.parse_args(argv)
    record, kept = KEPT[args.speed]
    rows = []
    for cat in args.only.split(","):
        folder = args.out / cat
        folder.mkdir(parents=True, exist_ok=True)
        stride = HERE / record / f"{cat}.{kept[cat]}.json"
        if args.mu is None:
            shutil.copyfile(stride, folder / "solution.json")
        else:
            sol = CollocationSolution.read(stride)
            sol = dataclasses.replace(sol, settings=dataclasses.replace(
                sol.settings, warm_start_mu=args.mu))
            sol.write(folder / "solution.json")
        status = main(["predict", "--method", "collocation", "--model", "amputee", "--blade",
                       cat, "--speed", str(args.speed), "--out", str(folder), "--resume",
                       "--mesh-check",
                       "--json"])
        check = read_mesh_check(folder / MESH_CHECK_DIR)
        if status != 0 or check is None:
            print(f"{cat}: no check (exit status {status})", file=sys.stderr)
            continue
        row = {"category": cat, "kept start": kept[cat], "converged": check.converged,
               "settled": check.settled}
        for key in COLUMNS:
            label, unit, coarse, fine = check.quantities[key]
            row[f"{key} mesh 50"] = coarse
            row[f"{key} mesh 100"] = fine
            row[f"{key} change %"] = check.change_pct(key)
        row["verdict"] = check.verdict()
        rows.append(row)
    if rows:
        with open(args.out / "mesh-check.csv", "w", newline="", encoding="utf-8") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main_())
