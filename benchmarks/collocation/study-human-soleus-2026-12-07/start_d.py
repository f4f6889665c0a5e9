"""The category study's start D: start A again with the predictive stages' L-BFGS history m
(a measuring probe; changes nothing in src).

Usage (repository root; one core)::

    .venv/bin/python benchmarks/collocation/study-human-soleus-2026-12-07/start_d.py M RUNS CAT [CAT ...]

Solves each category's problem of this study (4 m/s, 100 intervals, people's stride time, the
library's defaults otherwise) from the earlier body's best stride with
``PREDICTIVE_LBFGS_OPTIONS["ipopt.limited_memory_max_history"] = M`` and writes
``RUNS/CAT-D/solution.json``; prints one JSON line per category.
"""
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
from bladelab.predict.collocation import ipopt_options as io
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.runner import build_runner

m = int(sys.argv[1])
io.PREDICTIVE_LBFGS_OPTIONS["ipopt.limited_memory_max_history"] = m
OLD = Path(__file__).resolve().parent.parent / "study-human-swing-knee-2026-12-03" / "speed-4"
RUNS = Path(sys.argv[2])
for cat in sys.argv[3:]:
    runner = build_runner("amputee", blade=cat, body="human")
    settings = CollocationSettings(mesh_intervals=100, speed_m_per_s=4.0, stride_time_people=True, **people_settings("human"))
    t = time.time()
    sol = predict_stride(runner, settings, CollocationSolution.read(f"{OLD}/{cat}-best.json").to_guess(), model_spec={"model": "amputee", "blade": cat, "body": "human"})
    (RUNS / f"{cat}-D").mkdir(parents=True, exist_ok=True)
    sol.write(RUNS / f"{cat}-D" / "solution.json")
    print(json.dumps({"m": m, "cat": cat, "conv": sol.converged, "it": sol.nlp.iterations, "wall": round(time.time() - t, 1), "obj": round(sol.nlp.objective, 5)}), flush=True)
