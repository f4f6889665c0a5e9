"""The design box's centre blade on the amputee sprinter (strength 1.5, fibres 15
l_opt/s, prosthetic leg 4.5 cm longer), people's stride time, a speed chain on MESH intervals
from the built-in 4 m/s centre stride (or START); one JSON line per speed.

Usage: python chain.py OUT MESH SPEEDS [START], e.g. OUT 50 4,4.5,5 then OUT2 100 7,7.5,8
OUT/7/solution.json.
"""
import json
import sys
import time
from pathlib import Path

from bladelab.design.collocation_evaluator import DEFAULT_STARTS, CollocationEvaluator
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.stored import runner_from_spec

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "human_body"))
from criteria import stride_record  # noqa: E402

out, mesh = Path(sys.argv[1]), int(sys.argv[2])
speeds = [float(v) for v in sys.argv[3].split(",")]
start = Path(sys.argv[4]) if len(sys.argv) > 4 else DEFAULT_STARTS[("transtibial", "human")]
athlete = {"muscle_strength": 1.5, "max_shortening_velocity": 15.0,
           "prosthesis_extra_length_m": 0.045}
centre = {"stiffness_kN_per_m": 25.0, "width_m": 0.065, "height_m": 0.44, "toe_length_m": 0.22}
guess_file = start
for v in speeds:
    ev = CollocationEvaluator(amputation="transtibial", athlete=athlete, mesh_intervals=mesh,
                              speed_mps=v, stride_time_people=True)
    spec, settings = ev.problem(centre)
    guess = CollocationSolution.read(guess_file).to_guess(f"chain from {guess_file}")
    t0 = time.perf_counter()
    sol = predict_stride(runner_from_spec(spec), settings, guess, model_spec=spec, track=False)
    folder = out / f"{v:g}"
    folder.mkdir(parents=True, exist_ok=True)
    name = "solution.json" if sol.converged else "best_iterate.json"
    sol.write(folder / name)
    rec = {"speed_mps": v, "mesh": mesh, **stride_record(sol), "warnings": sol.gait_warnings(),
           "wall_s": time.perf_counter() - t0}
    print(json.dumps(rec), flush=True)
    if not sol.converged or sol.gait_warnings():
        break
    guess_file = folder / name
