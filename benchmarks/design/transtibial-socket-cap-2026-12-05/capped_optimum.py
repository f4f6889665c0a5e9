"""The cheapest blade whose socket moment stays under a cap, predicted and then solved.

On the people's-stride transtibial study (`../transtibial-collocation-4mps-people-stride`) the
cheapest blades (soft, long toe) spare the residual knee but carry 207-211 N·m at the socket,
against 56-105 N·m elsewhere. Its surfaces give the cheapest design with the peak socket moment
at most ``--cap`` N·m (`constrained_optimum`, the cap on the fitted mean). That point lies
between the two branches of the study, where a quadratic interpolates a kink: is it a blade a
runner would run on as predicted? This solves it, as the study solves a design (its evaluator
and settings from ``evaluator.json``), from its nearest strides and the study's cheapest, on a
copy of the study's strides (``--work``; the committed study is not changed), the lowest clean
objective kept, and compares every response with the surfaces' prediction and 95 % interval.

Writes ``capped_optimum.json`` (the optimum, the solves, the comparison) and the kept stride
(multipliers removed) beside this script.

Usage (repository root): ``OMP_NUM_THREADS=1 .venv/bin/python
benchmarks/design/transtibial-socket-cap-2026-12-05/capped_optimum.py --cap 150``
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
import time
from pathlib import Path

import pandas as pd

from bladelab._io import read_json, write_json
from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.design.optimum import constrained_optimum, surface_constraints
from bladelab.design.space import DesignSpace
from bladelab.design.stride_files import point_file_stem
from bladelab.design.surfaces import fit_surface
from bladelab.predict.collocation.solution import CollocationSolution

HERE = Path(__file__).resolve().parent
STUDY = HERE.parent / "transtibial-collocation-4mps-people-stride"
FACTORS = ("stiffness_kN_per_m", "width_m", "height_m", "toe_length_m")
COMPARED = ("cost_of_transport_J_per_kg_m", "stride_objective", "socket_moment_max_Nm",
            "socket_force_max_N", "blade_moment_max_Nm", "knee_moment_min_Nm",
            "swing_clearance_m", "contact_time_prosthetic_s")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cap", type=float, default=150.0, help="socket moment cap [N·m]")
    ap.add_argument("--work", type=Path, default=Path("/tmp/transtibial-socket-cap"))
    args = ap.parse_args()
    results = pd.read_csv(STUDY / "results.csv")
    coded = results[[f"{f}_coded" for f in FACTORS]].to_numpy()
    surfaces = {r: fit_surface(coded, results[r].to_numpy(), factor_names=FACTORS, response=r)
                for r in COMPARED}
    space = DesignSpace.from_dict(read_json(STUDY / "study.json", what="study")["space"])
    cap = {"socket_moment_max_Nm": {"max": args.cap}}
    optimum = constrained_optimum(surfaces["cost_of_transport_J_per_kg_m"], sense="min",
                                  space=space, constraints=surface_constraints(surfaces, cap))
    point = {f: round(optimum.point[f], 4) for f in FACTORS}
    print(f"capped optimum {point}: CoT {optimum.predicted:.3f} J/(kg·m) predicted", flush=True)

    if not (args.work / "strides").is_dir():
        shutil.copytree(STUDY / "strides", args.work / "strides")
    options = read_json(STUDY / "evaluator.json", what="evaluator settings")
    options.pop("evaluator")
    options["start"] = None if str(options["start"]).startswith("built-in") else options["start"]
    options["solutions_dir"] = str(args.work / "strides")
    evaluator = CollocationEvaluator(**options)
    t0 = time.perf_counter()
    first = evaluator(point)  # from its nearest stride, as a study's run
    settled = evaluator.settle(point, neighbours=2, cheapest=True, say=print)
    wall = time.perf_counter() - t0
    stride = args.work / "strides" / f"{point_file_stem(point)}.json"
    sol = CollocationSolution.read(stride)
    kept = HERE / stride.name
    dataclasses.replace(sol, nlp=dataclasses.replace(sol.nlp, multipliers=None)).write(kept)
    best = next((t["responses"] for t in settled["tries"]
                 if t["objective"] == settled["after"] and t["responses"]), first)
    comparison = {}
    for r in COMPARED:
        pred = surfaces[r].predict([[optimum.coded[f] for f in FACTORS]])
        comparison[r] = {"predicted": float(pred.mean[0]),
                         "pi": [float(pred.pi_lower[0]), float(pred.pi_upper[0])],
                         "solved": float(best[r])}
    write_json(HERE / "capped_optimum.json", {
        "cap_Nm": args.cap, "optimum": optimum.to_dict(), "point": point,
        "first_solve": first, "settling": settled, "wall_s": wall,
        "stride": kept.name, "summary": sol.summary(), "comparison": comparison})
    for r, row in comparison.items():
        print(f"{r}: predicted {row['predicted']:.4g} (PI {row['pi'][0]:.4g} .. "
              f"{row['pi'][1]:.4g}), solved {row['solved']:.4g}")


if __name__ == "__main__":
    main()
