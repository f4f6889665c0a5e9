"""CMA-ES on the human body with a tracking term that scores strides from the first touch-down.

The earlier runs' tracking term skipped the first second (``track_skip`` 1 s), so every
candidate that fell before it scored the same and the search had no slope. Here the term
(``ObjectiveSettings.track``, ``w_track``) scores every stride of leg 0 from the start (the
shipped human stride's touch-down, ``start_stride``, with the run-up), against that same
stride, so a candidate that takes more steps like it scores lower from the first step on. With
``inhibition`` the hamstrings' inhibition of the swinging hip flexor is held at SCONE's values.
A second call with the same OUT continues the run up to GENERATIONS.

    .venv/bin/python benchmarks/runs/reflex-human/track_from_start.py OUT GENERATIONS W_TRACK \
        [inhibition] [JOBS]
"""

from __future__ import annotations

import sys

from fixed_placement import STRIDE, search

from bladelab.predict.reflex.named_runs import held_parameters
from bladelab.predict.reflex.objective import ObjectiveSettings
from bladelab.predict.reflex.optimize import runner_and_layout

HELD = ("S11100.iliopsoas_?-hamstrings.*",)


def main(out: str, generations: int, w_track: float, inhibition: bool = False,
         jobs: int = 1) -> None:
    _, layout = runner_and_layout("able", None, "human")
    fixed = held_parameters(layout.names, HELD) if inhibition else ()
    settings = ObjectiveSettings(speed=3.5, duration=4.0, integrator="newmark", dt=1e-3,
                                 run_up=True, start_stride=STRIDE, track=STRIDE,
                                 w_track=w_track, track_skip=0.0)
    search(out, generations, settings, fixed, jobs)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), "inhibition" in sys.argv[4:],
         int(sys.argv[5]) if len(sys.argv) > 5 else 1)
