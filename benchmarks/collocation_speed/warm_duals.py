"""Warm starts with the multipliers: a measuring probe (changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/collocation_speed/warm_duals.py VARIANT [--kind amputee]
        [--blade Cat6] [--from 4.0] [--to 4.2] [--hessian limited-memory]

Solves the predictive stride NLP at ``--from`` from the shipped stride of the runner's kind
(recording the solution's primal and dual values), then at ``--to`` from that solution with
the start named by VARIANT:

- ``primal``: the primal point only, the library's options (a start without multipliers);
- ``duals-MU``: primal and multipliers (``StrideNLP.solve``'s primal-dual warm start,
  ``DUAL_WARM_START_OPTIONS``: the warm-start pushes at 1e-9) with ``mu_init`` MU;
- ``--ipopt NAME=VALUE`` (repeatable): another IPOPT option of a duals variant's second
  solve, e.g. ``mu_strategy=monotone``;
- ``scaled-`` before either: the start scaled to the new speed first (``StrideGuess.with_speed``,
  as ``predict_stride`` scales a start without multipliers), instead of the solution's own
  point.

Appends one JSON record per solve to ``benchmarks/collocation_speed/warm_records.jsonl``.
"""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path

import numpy as np

from bladelab.predict.collocation.dynamics import stride_dynamics
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.predict.collocation.transcription import StrideNLP
from bladelab.runner import build_runner
from bladelab.runner.params import default_runner_params

RECORDS = Path(__file__).with_name("warm_records.jsonl")


def solve(nlp, x0, speed, variant="primal", hessian="limited-memory", lam=None, extra=None):
    """``StrideNLP.solve`` as the variant says: ``primal`` with the library's options,
    ``duals-MU`` from ``lam`` (its primal-dual warm start) with the barrier starting at MU;
    returns (solution, its scaled NLP vector and multipliers)."""
    if variant == "primal":
        sol = nlp.solve(x0, speed=speed, hessian=hessian)
    else:
        mu = float(variant.split("-", 1)[1])
        sol = nlp.solve(x0, speed=speed, hessian=hessian, multipliers=lam,
                        options={"ipopt.mu_init": mu, **(extra or {})})
    return sol, (nlp.initial_vector(sol.to_guess()), *sol.multipliers)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("variant")
    ap.add_argument("--kind", default="amputee")
    ap.add_argument("--blade", default="Cat6")
    ap.add_argument("--from", dest="v0", type=float, default=4.0)
    ap.add_argument("--to", dest="v1", type=float, default=4.2)
    ap.add_argument("--hessian", default="limited-memory")
    ap.add_argument("--ipopt", action="append", default=[], metavar="NAME=VALUE",
                    help="another IPOPT option of the second solve (a duals variant)")
    a = ap.parse_args()
    extra = {}
    for item in a.ipopt:
        name, value = item.split("=", 1)
        try:
            extra[f"ipopt.{name}"] = float(value) if "." in value or "e" in value else int(value)
        except ValueError:
            extra[f"ipopt.{name}"] = value
    blade = a.blade if a.kind == "amputee" else None
    runner = build_runner(default_runner_params(a.kind, body="human", blade=blade))
    settings = CollocationSettings(speed_m_per_s=a.v0)
    dyn = stride_dynamics(build_collocation_model(runner))
    nlp = StrideNLP(dyn, n=settings.mesh_intervals, speed=a.v0, weights=settings.weights)
    guess = make_guess(runner, "stored", n=nlp.n, speed=a.v0)
    cache = Path(f"/tmp/warm_duals/{a.kind}-{blade}-{a.v0}.npz")
    if cache.is_file():  # the first solve of an earlier run (same body, speed, options)
        z = np.load(cache)
        point, first = (z["x"], z["lam_x"], z["lam_g"]), json.loads(str(z["first"]))
    else:
        sol0, point = solve(nlp, nlp.initial_vector(guess), a.v0)
        first = {"iterations": sol0.iterations, "wall_s": round(sol0.wall_s, 1),
                 "objective": sol0.objective, "status": sol0.status}
        cache.parent.mkdir(exist_ok=True)
        np.savez(cache, x=point[0], lam_x=point[1], lam_g=point[2], first=json.dumps(first))
    variant = a.variant.removeprefix("scaled-")
    x0 = point[0]
    if a.variant.startswith("scaled-"):  # as predict_stride does: the start scaled to the speed
        lbx, ubx, lbg, ubg = nlp.bounds()
        start = nlp.unpack(x0, {}, 0.0, 0.0, lbg, ubg, np.zeros(lbg.size)).to_guess()
        x0 = nlp.initial_vector(start.with_speed(a.v1))
    sol1, _ = solve(nlp, x0, a.v1, variant, a.hessian, lam=point[1:], extra=extra)
    rec = {"date": time.strftime("%Y-%m-%d %H:%M"), "kind": a.kind, "blade": blade,
           "from": a.v0, "to": a.v1, "variant": a.variant, "hessian": a.hessian,
           "ipopt": a.ipopt,
           "first": first,
           "second": {"iterations": sol1.iterations, "wall_s": round(sol1.wall_s, 1),
                      "build_s": round(sol1.timings["build_s"], 1),
                      "objective": sol1.objective, "status": sol1.status,
                      "speed": round(sol1.speed, 6), "period_s": round(sol1.period, 4),
                      "violation": sol1.max_violation},
           "maxrss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024}
    with RECORDS.open("a") as fh:
        fh.write(json.dumps(rec) + "\n")
    print(json.dumps(rec))


if __name__ == "__main__":
    main()
