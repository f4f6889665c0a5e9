"""The maximum-speed problem of the centre blade on the amputee sprinter, from a chain stride.

Usage: python max_speed.py START FLOOR_M_PER_S (writes centre-max-speed.json here).
"""
import json
import sys
import time
from pathlib import Path

from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.stored import runner_from_spec

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "human_body"))
from criteria import stride_record  # noqa: E402

start, floor = sys.argv[1], float(sys.argv[2])
ev = CollocationEvaluator(amputation="transtibial", max_speed=True, mesh_intervals=100,
                          stride_time_people=True,
                          athlete={"muscle_strength": 1.5, "max_shortening_velocity": 15.0,
                                   "prosthesis_extra_length_m": 0.045})
spec, settings = ev.problem({"stiffness_kN_per_m": 25.0, "width_m": 0.065, "height_m": 0.44,
                              "toe_length_m": 0.22})
t0 = time.perf_counter()
sol = predict_stride(runner_from_spec(spec), settings, CollocationSolution.read(start).to_guess(str(start)),
                     model_spec=spec, track=False, speed_floor=floor)
sol.write(Path(__file__).with_name("centre-max-speed.json"))
print(json.dumps({**stride_record(sol), "speed": sol.mean_speed_mps, "warnings": sol.gait_warnings(),
                  "wall_s": time.perf_counter() - t0}))
