"""Transfemoral 4 m/s from the transtibial Cat6 4 m/s stride (an alternating run): the common
coordinates copied by name, the prosthetic knee from the transtibial's residual knee, the
pelvis lowered until a contact is 1 cm deep at every node, the template's force pattern.

    python benchmarks/collocation/transfemoral-2026-11-26/from_transtibial.py \\
        benchmarks/collocation/study-2026-11-25-cat6-starts/amputee-Cat6/speed-4.warm-mu-1e-4.json \\
        track|notrack OUT.json

``speed-4.from-transtibial-tracked.json`` (track) and
``speed-4.from-transtibial.json`` (notrack) were written this way on 2026-11-26
(docs/design.md, "Predicted transfemoral gaits"); the maximum-speed files came from
``bladelab predict --method collocation --model transfemoral --max-speed --swing-clearance 0.02
--guess <that file>``.
"""

from __future__ import annotations

import json
import sys

from bladelab.design.predicted import stride_responses
from bladelab.predict.collocation.guess import prosthetic_stride_on
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.stride_guess import StrideGuess
from bladelab.runner import build_runner


def main(source: str, mode: str, out: str) -> None:
    src = CollocationSolution.read(source)
    runner = build_runner("transfemoral")
    # coordinates only (no muscle states), and not marked a collocation solution: a cold start
    guess = prosthetic_stride_on(runner, StrideGuess(
        "transtibial stride on the transfemoral runner", src.period_s, src.nlp.q, src.nlp.qd,
        dof_names=src.dof_names))
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=4.0, swing_clearance_m=0.02)
    sol = predict_stride(runner, settings, guess,
                         model_spec={"model": "transfemoral", "blade": "Cat4"},
                         track=mode == "track")
    print(json.dumps(sol.summary()))
    if sol.converged:
        print(json.dumps(stride_responses(sol, runner)))
    sol.write(out)


if __name__ == "__main__":
    main(*sys.argv[1:4])
