"""Seed 001's shipped reflex gaits on the toes body with a stiffer toe joint and seed 001's
Achilles tendon: how far is the first step of a body continuation? (a measuring probe; it
changes the model's MTP stiffness and the toes body's tendon strains in this process only).

    .venv/bin/python benchmarks/runs/reflex-human/toes_stiffness.py
"""

from __future__ import annotations

import json

import bladelab.predict.reflex.objective as objective
import bladelab.predict.reflex.optimize as optimize
import bladelab.runner.model as runner_model
import bladelab.runner.params as runner_params
from bladelab.predict.reflex.controller import controller_layout, read_parameters
from bladelab.runner.params import REFLEX_STARTS_DIR

GAITS = (("amputee", "Cat6", "amputee-Cat6-3.5.json"), ("able", None, "able-3.5.json"))
#: Toe-joint spring stiffnesses [N·m/rad] (the model's: 25; 1e4 and above blow up at 1 ms).
STIFFNESSES = (25.0, 100.0, 300.0, 1000.0, 3000.0)
#: The toes body's Achilles (8 % strain at Fmax) and seed 001's (4 %, every tendon).
ACHILLES = ({"soleus": 0.08, "gastroc": 0.08}, {})


def main() -> None:
    for kind, blade, name in GAITS:
        path = REFLEX_STARTS_DIR / name
        settings = optimize.stored_settings(json.loads(path.read_text()), speed=3.5,
                                            duration=10.0, nominal=True)
        for achilles in ACHILLES:
            for k in STIFFNESSES:
                runner_model.MTP_STIFFNESS = k
                runner_params.TOES_BODY_TENDON_STRAIN.clear()
                runner_params.TOES_BODY_TENDON_STRAIN.update(achilles)
                model = runner_model.build_runner(kind, blade=blade, body="toes")
                layout = controller_layout(model)
                ev, _ = objective.simulate_controlled(model, read_parameters(path, layout),
                                                      layout=layout, settings=settings)
                strain = "8 %" if achilles else "4 %"
                print(f"{name}, toe spring {k:g} N·m/rad, Achilles {strain}: "
                      f"{'falls at' if ev.fell else 'runs'} {ev.duration:.2f} s, "
                      f"{ev.n_steps} steps", flush=True)


if __name__ == "__main__":
    main()
