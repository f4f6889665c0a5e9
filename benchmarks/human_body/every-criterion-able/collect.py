"""Tabulate speed chains of the able runner against the criteria of people's running.

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/every-criterion-able/collect.py NAME=RUNS [...]

Each RUNS folder holds one ``bladelab predict`` output folder per solve, named ``able-SPEED``
(e.g. ``able-4.5``). Appends to ``records.jsonl`` beside this file, per solve: the chain's NAME
and ``../criteria.py``'s :func:`stride_record` (speed [m/s], converged, criteria met and missed,
cost of transport [J/(kg·m)], stride time [s], per-leg peak vertical force [BW] and contact
time [s], dynamics residual [%], iterations and wall time [s]); and prints one line per solve.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from criteria import stride_record  # noqa: E402

from bladelab.predict.collocation.solution import CollocationSolution  # noqa: E402

RECORDS = Path(__file__).parent / "records.jsonl"


def main(args: list[str]) -> int:
    with open(RECORDS, "a", encoding="utf-8") as out:
        for arg in args:
            name, runs = arg.split("=", 1)
            folders = sorted((p for p in Path(runs).iterdir() if (p / "solution.json").is_file()),
                             key=lambda p: float(p.name.rsplit("-", 1)[1]))
            for folder in folders:
                rec = {"chain": name,
                       **stride_record(CollocationSolution.read(folder / "solution.json"))}
                out.write(json.dumps(rec) + "\n")
                print(f"{name} {rec['speed_mps']:g} m/s: {rec['criteria_met']} of "
                      f"{rec['criteria']}, CoT {rec['cost_of_transport_J_per_kg_m']:.2f}, peaks "
                      f"{rec['peak_vertical_grf_left_bw']:.2f} / "
                      f"{rec['peak_vertical_grf_right_bw']:.2f} BW; "
                      + "; ".join(rec["criteria_missed"]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
