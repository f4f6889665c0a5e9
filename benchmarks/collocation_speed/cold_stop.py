"""Solves without a dual warm start, with and without IPOPT's stop at an acceptable level (a
measuring probe; changes nothing in src: it empties ``STALL_STOP_OPTIONS`` in this process for
the "full" solves).

Usage (repository root, one core)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/cold_stop.py [CASE ...]

Cases: ``able-template`` (the able runner at 3.5 m/s from the template guess: the tracking
stage, then the predictive one) and ``amputee-primal`` (the shipped amputee Cat6 stride's
primal values at 4.2 m/s, its multipliers dropped), both mesh 50, people's angles at the
default weight, as ``make bench`` solves them. Prints and appends to
``cold_stop_records.jsonl`` one JSON line per case, with the fields of ``warm_stop.py``.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

from warm_stop import append_record, full_and_stopped, solve_row

from bladelab.predict import defaults
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.settings import CollocationSettings, people_term
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.runner import build_runner

HERE = Path(__file__).parent


def _problem(name: str):
    people = people_term(defaults.people_weight_for("human"))
    if name == "able-template":
        runner = build_runner("able", body="human")
        settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=3.5, **people)
        return runner, settings, template_guess(runner, speed=3.5, n=50), {"model": "able",
                                                                           "body": "human"}
    runner = build_runner("amputee", blade="Cat6", body="human")
    spec = {"model": "amputee", "blade": "Cat6", "body": "human"}
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=4.0, **people)
    stored = predict_stride(runner, settings, make_guess(runner, "stored", n=50, speed=4.0),
                            model_spec=spec)
    guess = dataclasses.replace(stored.to_guess(), multipliers=None)
    return runner, dataclasses.replace(settings, speed_m_per_s=4.2), guess, spec


def run(name: str) -> dict:
    runner, settings, guess, spec = _problem(name)
    full, stopped, diff = full_and_stopped(
        lambda: predict_stride(runner, settings, guess, model_spec=spec))
    rec = {"case": name,
           "full": {**solve_row(full),
                    "tracking_iterations": (full.tracking or {}).get("iterations")},
           "stopped": {**solve_row(stopped),
                       "tracking_iterations": (stopped.tracking or {}).get("iterations")},
           **diff}
    append_record(HERE / "cold_stop_records.jsonl", rec)
    return rec


if __name__ == "__main__":
    for case in sys.argv[1:] or ["able-template", "amputee-primal"]:
        print(json.dumps(run(case)), flush=True)
