"""The maximum-speed problem of some designs of the transtibial study, from their strides.

Seed 002's responses are sprint responses, and a designer asks how fast a blade lets the
athlete run. Does the maximum speed separate the blades of the default box? One solve of the
maximum-speed problem (``max_speed_settings``: speed free, the stride time free of people's
band) per design, warm-started from the design's committed 4 m/s stride, the same runner,
mesh and constraints; the stride is judged by the gait checks and the criteria of people's
running as every predicted stride is.

Writes ``max_speed.json`` beside this script after every design (a rerun skips the designs in
it) and each stride to ``--work``.

Usage (repository root): ``OMP_NUM_THREADS=1 .venv/bin/python
benchmarks/design/transtibial-branch-2026-12-04/max_speed.py --runs 2,17,18,23,24,25 --jobs 2``
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd

from bladelab._io import write_json
from bladelab.design.stride_files import point_file_stem
from bladelab.executors import make_executor

HERE = Path(__file__).resolve().parent
STUDY = HERE.parent / "transtibial-collocation-4mps"
RECORD = HERE / "max_speed.json"
FACTORS = ("stiffness_kN_per_m", "width_m", "height_m", "toe_length_m")


def solve_max_speed(payload: dict) -> dict:
    """One design's maximum-speed stride from its 4 m/s stride (in a worker)."""
    from bladelab.predict.collocation.continuation import max_speed_settings
    from bladelab.predict.collocation.human_running import human_running_criteria
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.predict.collocation.solve import predict_stride
    from bladelab.predict.collocation.stored import runner_from_spec

    stride = CollocationSolution.read(payload["stride"])
    runner = runner_from_spec(stride.model_spec)
    settings = max_speed_settings(stride.settings)
    guess = stride.to_guess(f"collocation solution {Path(payload['stride']).name}")
    sol = predict_stride(runner, settings, guess, model_spec=stride.model_spec, track=False)
    sol.write(Path(payload["out"]))
    summary = sol.summary()
    criteria = human_running_criteria(sol) if sol.converged else []
    return {"run": payload["run"], "converged": bool(sol.converged),
            "status": str(sol.nlp.status), "speed_m_per_s": summary["mean_speed_mps"],
            "stride_time_s": summary["stride_time_s"],
            "contact_time_intact_s": summary["contact_time_intact_s"],
            "contact_time_prosthetic_s": summary["contact_time_prosthetic_s"],
            "peak_vertical_grf_intact_bw": summary["peak_vertical_grf_intact_bw"],
            "peak_vertical_grf_prosthetic_bw": summary["peak_vertical_grf_prosthetic_bw"],
            "step_phase": summary["step_phase"],
            "warnings": list(sol.gait_warnings()) if sol.converged else [],
            "criteria_missed": [c.line() for c in criteria if not c.met],
            "iterations": int(sol.nlp.iterations), "wall_s": float(sol.nlp.wall_s)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", default="2,17,18,23,24,25")
    ap.add_argument("--work", type=Path, default=Path("/tmp/transtibial-max-speed"))
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    results = pd.read_csv(STUDY / "results.csv").set_index("run")
    record = json.loads(RECORD.read_text()) if RECORD.is_file() else {"designs": {}}
    payloads = []
    for run in (int(r) for r in args.runs.split(",")):
        point = {f: float(results.loc[run, f]) for f in FACTORS}
        stem = point_file_stem(point)
        if stem not in record["designs"]:
            payloads.append({"run": run, "stride": str(STUDY / "strides" / f"{stem}.json"),
                             "out": str(args.work / f"{stem}.json"), "stem": stem})
    for k, status, value in make_executor("local", args.jobs).run(solve_max_speed, payloads):
        row = value if status == "ok" else {"run": payloads[k]["run"], "error": str(value)}
        record["designs"][payloads[k]["stem"]] = row
        write_json(RECORD, record)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
