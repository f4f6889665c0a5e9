"""Solve every design of the transtibial study again from the study's cheapest stride.

The settled study (`../transtibial-collocation-4mps`) has a cheap branch at its soft, long-toe
corners (CoT 3.77-3.91 J/(kg·m), the residual knee barely loaded) that its neighbour-to-
neighbour settling did not carry to the other designs. Does the branch exist there too (the
surfaces then describe starts, not blades), or only for those blades?

Works on a copy of the study (``--work``; the committed one is not changed): one solve per
design from ``--from`` (default the cheapest stride), kept in the copy when clean and cheaper,
as a settling pass does. Writes ``from_cheapest.json`` (per design: objective before and after,
the start's status, responses) beside this script, after every design, so an interrupted run
loses nothing; a rerun skips the designs already in it.

Usage (repository root): ``OMP_NUM_THREADS=1 .venv/bin/python
benchmarks/design/transtibial-branch-2026-12-04/from_cheapest.py --jobs 2``
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import shutil
from pathlib import Path

import pandas as pd

from bladelab._io import read_json, write_json
from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.design.settling import settle_strides
from bladelab.design.stride_files import point_file_stem

HERE = Path(__file__).resolve().parent
STUDY = HERE.parent / "transtibial-collocation-4mps"
RECORD = HERE / "from_cheapest.json"
FACTORS = ("stiffness_kN_per_m", "width_m", "height_m", "toe_length_m")


@dataclasses.dataclass(frozen=True)
class FromOne(CollocationEvaluator):
    """The study's evaluator whose only "neighbour" is one given stride."""

    from_stride: str = ""

    def _neighbours(self, point):
        return [Path(self.from_stride)]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", type=Path, default=Path("/tmp/transtibial-branch"))
    ap.add_argument("--from", dest="start", type=Path, default=None,
                    help="the stride every design starts from (default: the cheapest)")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    if not (args.work / "strides").is_dir():
        shutil.copytree(STUDY / "strides", args.work / "strides")
    results = pd.read_csv(STUDY / "results.csv")
    points = [{f: float(r[f]) for f in FACTORS} for _, r in results.iterrows()]
    cheapest = points[int(results["cost_of_transport_J_per_kg_m"].idxmin())]
    start = args.start or (args.work / "strides" / f"{point_file_stem(cheapest)}.json")
    options = read_json(STUDY / "evaluator.json", what="evaluator settings")
    options.pop("evaluator")
    options["start"] = None if str(options["start"]).startswith("built-in") else options["start"]
    options["solutions_dir"] = str(args.work / "strides")
    evaluator = FromOne(**options, from_stride=str(start))
    record = json.loads(RECORD.read_text()) if RECORD.is_file() else {
        "from": start.name, "designs": {}}
    done = {i for i, p in enumerate(points) if point_file_stem(p) in record["designs"]
            or p == cheapest}

    def on_design(i, row):
        record["designs"][point_file_stem(points[i])] = row
        write_json(RECORD, record)

    settle_strides(evaluator, points, neighbours=1, jobs=args.jobs, skip=done,
                   on_design=on_design)


if __name__ == "__main__":
    main()
