"""One stride of the library's default problem on the human body changed by a variant (a
measuring probe; changes nothing in src).

Usage (repository root; one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/human_body/soleus-length/probe.py \
        START.json VARIANT OUT.json

The problem: people's joint angles at the body's weight, people's swing knee and, unless the
variant says ``"stride_time_people": false``, people's stride time; at START's speed and mesh
(or the variant's ``speed`` and ``mesh``), from START's primal and dual values, no tracking
stage. VARIANT is ``../solve_variant.py``'s JSON (``muscle``, ``force_factor``, ``set``; ``kind``
and ``blade`` for the amputee; ``people_weight``). Writes the stride to OUT.json and prints one
JSON line: converged, iterations, objective, cost of transport [J/(kg·m)], stride time [s],
the criteria of people's running met and missed, wall time [s].
"""
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from solve_variant import variant_runner  # noqa: E402

from bladelab.predict.collocation.human_running import human_running_criteria  # noqa: E402
from bladelab.predict.collocation.settings import CollocationSettings, people_settings  # noqa: E402
from bladelab.predict.collocation.solution import CollocationSolution  # noqa: E402
from bladelab.predict.collocation.solve import predict_stride  # noqa: E402

start, variant, out = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3]
first = CollocationSolution.read(start)
kind = variant.get("kind", "able")
settings = CollocationSettings(mesh_intervals=int(variant.get("mesh", first.settings.mesh_intervals)),
                               speed_m_per_s=float(variant.get("speed", first.settings.speed_m_per_s)),
                               stride_time_people=bool(variant.get("stride_time_people", True)),
                               **people_settings("human", variant.get("people_weight"), kind=kind))
t = time.time()
spec = {"model": kind, "body": "human"} | ({"blade": variant["blade"]} if "blade" in variant else {})
sol = predict_stride(variant_runner(variant), settings, first.to_guess(), track=False, model_spec=spec)
Path(out).parent.mkdir(parents=True, exist_ok=True)
sol.write(out)
crit = human_running_criteria(sol)
print(json.dumps({"variant": variant, "start": start, "speed": settings.speed_m_per_s, "converged": sol.converged,
                  "iterations": sol.nlp.iterations, "objective": sol.nlp.objective,
                  "cot": sol.cost_of_transport_J_per_kg_m, "stride_s": sol.period_s,
                  "criteria_met": f"{sum(c.met for c in crit)} of {len(crit)}",
                  "missed": [c.line() for c in crit if not c.met], "wall_s": time.time() - t}))
