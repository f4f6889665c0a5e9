"""The round trip of each category's mesh-halving check at 4 m/s: the 50-interval problem
solved again from the 100-interval stride (``bladelab.predict.collocation.mesh_check.round_trip``).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/round_trip_categories.py OUT [--only Cat4,...]

For each category, the kept stride and its 100-interval stride are those of
``categories-people10/mesh-100/<category>/`` (``solution.json``, ``mesh-check/solution.json``);
the round trip is written to ``OUT/<category>/solution.json`` (read back if there) and one
line per category to ``OUT/round-trip.csv``: objective, cost of transport, stride time and
peaks of the kept stride, the round trip and the 100-interval stride.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import pandas as pd

os.environ.setdefault("OMP_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
RECORD = HERE / "categories-people10" / "mesh-100"
KEYS = ("objective", "cost_of_transport_J_per_kg_m", "stride_time_s",
        "peak_vertical_grf_intact_bw", "peak_vertical_grf_prosthetic_bw")


def _values(sol) -> dict:
    s = sol.summary()
    return {"objective": float(sol.nlp.objective), **{k: s[k] for k in KEYS[1:]}}


def main(argv=None) -> int:
    from bladelab.predict.collocation.mesh_check import round_trip
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.predict.collocation.stored import runner_from_spec

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--only", default="Cat4,Cat5,Cat6,Cat6High,Cat7")
    args = ap.parse_args(argv)
    rows = []
    for cat in args.only.split(","):
        stride = CollocationSolution.read(RECORD / cat / "solution.json")
        fine = CollocationSolution.read(RECORD / cat / "mesh-check" / "solution.json")
        target = args.out / cat / "solution.json"
        if target.is_file():
            back = CollocationSolution.read(target)
        else:
            back = round_trip(runner_from_spec(stride.model_spec), stride, fine)
            back.write(target)
        row = {"category": cat, "round trip converged": back.converged,
               "round trip iterations": back.nlp.iterations,
               "round trip wall (s)": round(back.nlp.wall_s, 1)}
        for name, sol in (("stride", stride), ("round trip", back), ("mesh 100", fine)):
            row |= {f"{k} ({name})": v for k, v in _values(sol).items()}
        rows.append(row)
        print(row, flush=True)
    pd.DataFrame(rows).to_csv(args.out / "round-trip.csv", index=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
