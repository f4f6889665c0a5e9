"""CMA-ES on the human body with the pelvis-speed (placement) reflexes held at SCONE's values.

Every parameter of the rows fed by ``pelvis_tx`` (both legs, stance and swing: 24 parameters)
is fixed through ``optimize_controller(..., fixed=...)``; with ``inhibition`` also the
hamstrings' inhibition of iliopsoas in the swing (4 more). The run starts from SCONE's
parameters at the shipped human stride's touch-down with the run-up (the mean-speed reflexes
act from the start). A second call with the same OUT continues the run up to GENERATIONS.

    .venv/bin/python benchmarks/runs/reflex-human/fixed_placement.py OUT GENERATIONS \
        [inhibition] [JOBS]
"""

from __future__ import annotations

import sys
from pathlib import Path

from bladelab.predict.reflex.named_runs import held_parameters
from bladelab.predict.reflex.objective import ObjectiveSettings
from bladelab.predict.reflex.optimize import optimize_controller, runner_and_layout

STRIDE = "src/bladelab/data/runner/collocation/able-3.5-human.json"
#: The placement rows, then the hamstrings' inhibition of the swinging hip flexor (``--hold``).
HELD = ("*-pelvis_tx.*", "S11100.iliopsoas_?-hamstrings.*")


def main(out: str, generations: int, inhibition: bool = False, jobs: int = 1) -> None:
    _, layout = runner_and_layout("able", None, "human")
    fixed = held_parameters(layout.names, HELD[:2 if inhibition else 1])
    settings = ObjectiveSettings(speed=3.5, duration=4.0, integrator="newmark", dt=1e-3,
                                 run_up=True, start_stride=STRIDE)
    search(out, generations, settings, fixed, jobs)


def search(out: str, generations: int, settings: ObjectiveSettings, fixed, jobs: int) -> None:
    """CMA-ES of the able runner on the human body from SCONE's parameters (σ 0.5, popsize 32,
    seed 1) with ``fixed`` parameters held; a second call with the same ``out`` continues."""
    print(f"fixed at SCONE's values: {len(fixed)} parameters")

    def progress(generation, best, median):
        if generation % 50 == 0:
            print(generation, best, median, flush=True)

    result = optimize_controller("able", body="human", speed=3.5, generations=generations,
                                 popsize=32, sigma=0.5, seed=1, jobs=jobs, out=out,
                                 settings=settings, fixed=fixed, progress=progress,
                                 resume=(Path(out) / "checkpoint.pkl").exists())
    print(result)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), "inhibition" in sys.argv[3:],
         int(sys.argv[4]) if len(sys.argv) > 4 else 1)
