"""Probe: IPOPT's L-BFGS update routes on the human body's strides (measuring only).

``warm OPTIONS`` solves the amputee Cat6 stride (mesh 50, people's angles and swing knee) at
4.2, 4.5 and 3.8 m/s from the shipped 4 m/s stride's primal and dual values (the warm row of
``make bench``), ``template TRACKING PREDICTIVE`` the able runner at 3.5 m/s from the template
(tracking, then predictive stage). OPTIONS are JSON objects of IPOPT options without the
``ipopt.`` prefix; they replace the library's ``PREDICTIVE_LBFGS_OPTIONS`` in the stage named
(``{}``: IPOPT's defaults, the Sherman-Morrison route). One JSON line per solve is printed
and appended to ``lowrank_records.jsonl``.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/lowrank_update.py warm \\
        '{"limited_memory_aug_solver": "extended", "limited_memory_max_history": 4}'
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/lowrank_update.py template \\
        '{}' '{"limited_memory_aug_solver": "extended", "limited_memory_max_history": 4}'
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from pathlib import Path

from bladelab.predict.collocation import solve as solve_module
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.ipopt_options import PREDICTIVE_LBFGS_OPTIONS
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.predict.collocation.transcription import StrideNLP
from bladelab.runner import build_runner

RECORDS = Path(__file__).with_name("lowrank_records.jsonl")


def per_stage(options_by_stage: dict[str, dict]) -> None:
    """Make every L-BFGS stage named in ``options_by_stage`` (``"tracking"``: a tracking NLP,
    ``"predictive"``: any other) solve with those options (IPOPT's, without the ``ipopt.``
    prefix) in place of the library's ``PREDICTIVE_LBFGS_OPTIONS``; a stage not named keeps
    the library's."""
    solve = StrideNLP.solve

    def staged(self, x0, *args, options=None, hessian="limited-memory", **kw):
        name = "predictive" if self.tracking is None else "tracking"
        if hessian == "limited-memory" and name in options_by_stage:
            options = {k: v for k, v in (options or {}).items()
                       if k not in PREDICTIVE_LBFGS_OPTIONS}
            options.update({f"ipopt.{k}": v for k, v in options_by_stage[name].items()})
        return solve(self, x0, *args, options=options, hessian=hessian, **kw)

    StrideNLP.solve = staged


def record(row: dict, records: Path = RECORDS) -> None:
    """Print ``row`` as one JSON line and append it to ``records`` (:data:`RECORDS`)."""
    line = json.dumps(row)
    print(line, flush=True)
    with records.open("a", encoding="utf-8") as f:
        f.write(line + "\n")


def warm(options: dict) -> None:
    per_stage({"predictive": options})
    spec = {"model": "amputee", "blade": "Cat6", "body": "human"}
    runner = build_runner("amputee", blade="Cat6", body="human")
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=4.0,
                                   **people_settings("human"))
    stored = solve_module.predict_stride(runner, settings,
                                         make_guess(runner, "stored", n=50, speed=4.0),
                                         model_spec=spec)
    for speed in (4.2, 4.5, 3.8):
        t0 = time.perf_counter()
        sol = solve_module.predict_stride(
            runner, dataclasses.replace(settings, speed_m_per_s=speed), stored.to_guess(),
            model_spec=spec)
        record({"case": "warm", "options": options, "speed_mps": speed,
                 "converged": sol.converged, "iterations": sol.nlp.iterations,
                 "wall_s": round(time.perf_counter() - t0, 2),
                 "ipopt_own_s": round(sol.nlp.timings.get("ipopt_own_s", 0.0), 2),
                 "objective": sol.nlp.objective})


def template(tracking: dict, predictive: dict) -> None:
    per_stage({"tracking": tracking, "predictive": predictive})
    runner = build_runner("able", body="human")
    t0 = time.perf_counter()
    sol = solve_module.predict_stride(
        runner, CollocationSettings(mesh_intervals=50, speed_m_per_s=3.5,
                                    **people_settings("human")),
        template_guess(runner, speed=3.5, n=50), model_spec={"model": "able", "body": "human"})
    trk = sol.tracking or {}
    record({"case": "template", "tracking_options": tracking, "options": predictive,
             "converged": sol.converged, "tracking_iterations": trk.get("iterations"),
             "tracking_s": trk.get("wall_s"), "iterations": sol.nlp.iterations,
             "predictive_s": round(sol.nlp.wall_s, 1),
             "wall_s": round(time.perf_counter() - t0, 1), "objective": sol.nlp.objective})


if __name__ == "__main__":
    if sys.argv[1:2] == ["warm"]:
        warm(json.loads(sys.argv[2]))
    elif sys.argv[1:2] == ["template"]:
        template(json.loads(sys.argv[2]), json.loads(sys.argv[3]))
    else:
        sys.exit(__doc__)
