"""How fast can the body run? Prescribed-speed continuation to the speed where no stride is
found (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/sprint_limit.py OUT '{"kind": "able", ...}'

Seed 001's definition of the maximum speed: the fastest prescribed speed at which the optimiser
finds a stride (its §2.2 C: 4, 4.5, 5 m/s, each from the previous). Here: from ``start`` (a
solution file, default the shipped stride of the kind) at ``speeds`` (default 4.5, 5.5, 6.0,
6.5, … in 0.5 m/s steps to 10), each solve from the previous solution's primal and dual values,
no people's term (``people_weight``, default 0); a speed that does not converge is tried once
more halfway from the last converged one, then the chain stops. The variant (JSON):
``active_tension`` [N/cm²] (the fibres' active specific tension; the body's is 30),
``vmax`` [optimal fibre lengths/s] (every muscle's maximum shortening velocity; the body's is
10), ``force_factor``, ``muscle`` and ``set`` as in solve_variant.py, ``symmetric`` (true: each leg does what the other
did half a stride earlier, ``CollocationSettings.symmetric``; able runner), ``mesh`` (mesh
intervals, default 50; a start on another mesh is resampled), ``stride_time`` (``"people"``:
people's band at each speed, ``CollocationSettings.stride_time_people``; default free),
``start_mu`` (the first solve's barrier start, ``CollocationSettings.warm_start_mu``, e.g.
1e-4 for a start file without multipliers, which IPOPT's default barrier lets leave its
basin; default IPOPT's), ``max_iter`` (IPOPT iterations per stage, default the settings'),
``swing_knee`` [deg] (people's swing knee held at least this flexed,
``CollocationSettings.swing_knee_min_deg``; default none).
Writes ``OUT/speed-<v>.json`` per converged speed and ``OUT/records.jsonl`` (one line per
solve: the summary, the largest activation of any muscle at any node, the human-running
criteria met and missed, the wall time), and prints each line.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np
from solve_variant import variant_runner

from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess


def main() -> None:
    out, variant = Path(sys.argv[1]), json.loads(sys.argv[2])
    kind, blade = variant.get("kind", "able"), variant.get("blade")
    runner = variant_runner(variant)
    spec = {"model": kind, "blade": blade, "body": "human"}
    speeds = variant.get("speeds", [4.5, 5.5] + [6.0 + 0.5 * k for k in range(9)])
    people = people_term(float(variant.get("people_weight", 0.0)))
    mesh = int(variant.get("mesh", 50))
    if variant.get("start"):
        guess = CollocationSolution.read(variant["start"]).to_guess()
    else:
        guess = make_guess(runner, "stored", n=mesh, speed=speeds[0])
    out.mkdir(parents=True, exist_ok=True)
    (out / "variant.json").write_text(json.dumps(variant))
    last, pending = None, list(speeds)
    mu = variant.get("start_mu")
    while pending:
        v = pending.pop(0)
        settings = CollocationSettings(
            mesh_intervals=mesh, speed_m_per_s=v, **people,
            symmetric=bool(variant.get("symmetric", False)),
            stride_time_people=variant.get("stride_time") == "people",
            swing_knee_min_deg=variant.get("swing_knee"),
            warm_start_mu=mu if last is None else None,
            **({"max_iter": int(variant["max_iter"])} if "max_iter" in variant else {}))
        t0 = time.perf_counter()
        sol = predict_stride(runner, settings, guess, model_spec=spec)
        crit = human_running_criteria(sol)
        rec = {"speed": v, **sol.summary(), "objective": float(sol.nlp.objective),
               "max_activation": float(np.max(sol.nlp.activation)),
               "criteria_met": sum(c.met for c in crit), "criteria": len(crit),
               "missed": [c.line() for c in crit if not c.met],
               "probe_wall_s": round(time.perf_counter() - t0, 1)}
        with (out / "records.jsonl").open("a") as fh:
            fh.write(json.dumps(rec) + "\n")
        print(json.dumps(rec), flush=True)
        if sol.converged:
            sol.write(out / f"speed-{v:g}.json")
            guess, last = sol.to_guess(), v
        elif last is not None and v - last > 0.2:
            pending = [round((last + v) / 2, 3)]
        else:
            break


if __name__ == "__main__":
    main()
