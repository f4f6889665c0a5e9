"""The warm start of the shipped amputee Cat6 stride (4 m/s, its primal and dual values) at
another speed, with IPOPT options over the library's dual warm start (a measuring probe;
changes nothing in src: it updates ``DUAL_WARM_START_OPTIONS`` in this process only).

Usage (repository root, one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/warm_barrier.py \
        '{"ipopt.mu_strategy": "monotone", "ipopt.mu_init": 1e-6}' 4.2

Prints one JSON line: the options, convergence, iterations, wall [s], objective.
"""
import dataclasses
import json
import sys

from bladelab.predict import defaults
from bladelab.predict.collocation import ipopt_options
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.runner import build_runner


def main() -> None:
    extra = json.loads(sys.argv[1]) if len(sys.argv) > 1 else {}
    target = float(sys.argv[2]) if len(sys.argv) > 2 else 4.2
    spec = {"model": "amputee", "blade": "Cat6", "body": "human"}
    runner = build_runner("amputee", blade="Cat6", body="human")
    people = people_term(defaults.people_weight_for("human"))
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=4.0, **people)
    stored = predict_stride(runner, settings, make_guess(runner, "stored", n=50, speed=4.0),
                            model_spec=spec)
    ipopt_options.DUAL_WARM_START_OPTIONS.update(extra)
    warm = predict_stride(runner, dataclasses.replace(settings, speed_m_per_s=target),
                          stored.to_guess(), model_spec=spec)
    s = warm.summary()
    print(json.dumps({"extra": extra, "converged": s["converged"], "iterations": s["iterations"],
                      "wall_s": round(s["wall_s"], 1), "objective": round(warm.nlp.objective, 5)}))


if __name__ == "__main__":
    main()
