"""Warm starts of the shipped strides with the predictive stages' L-BFGS history m = 3..7 (a
measuring probe; changes nothing in src).

Usage (repository root; one core)::

    .venv/bin/python benchmarks/collocation_speed/lbfgs_history.py [OTHER_CAT6_STRIDE.json]

Prints one JSON line per warm start: the case, m, converged, iterations, wall [s], objective.
The second case (another Cat6 stride at 4 m/s, mesh 50) runs only when its file is given.
"""

import dataclasses
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

from bladelab.predict.collocation import ipopt_options as io
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.runner import build_runner

SHIPPED = Path(__file__).resolve().parents[2] / "src" / "bladelab" / "data" / "runner" / "collocation"
cases = [("amputee shipped 4->4.2", "amputee", str(SHIPPED / "amputee-Cat6-4-human.json"), 4.0, 4.2),
         *([("amputee other 4->4.2", "amputee", sys.argv[1], 4.0, 4.2)] if len(sys.argv) > 1 else []),
         ("able 3.5->3.7", "able", str(SHIPPED / "able-3.5-human.json"), 3.5, 3.7)]
people = people_settings("human")
for label, kind, f, v0, v1 in cases:
    spec = {"model": kind, "body": "human"} | ({"blade": "Cat6"} if kind == "amputee" else {})
    runner = build_runner(kind, blade="Cat6", body="human") if kind == "amputee" else build_runner("able", body="human")
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=v0, **people)
    io.PREDICTIVE_LBFGS_OPTIONS["ipopt.limited_memory_max_history"] = 4
    stored = predict_stride(runner, settings, CollocationSolution.read(f).to_guess(), model_spec=spec)
    for hist in (3, 4, 5, 6, 7):
        io.PREDICTIVE_LBFGS_OPTIONS["ipopt.limited_memory_max_history"] = hist
        warm = predict_stride(runner, dataclasses.replace(settings, speed_m_per_s=v1), stored.to_guess(), model_spec=spec)
        print(json.dumps({"case": label, "m": hist, "conv": warm.converged, "it": warm.nlp.iterations, "wall": round(warm.nlp.wall_s, 1), "obj": round(warm.nlp.objective, 5)}), flush=True)
