"""Which gait state each leg is in, and which reflex rows drive the left hip's muscles, along a
reflex run on the human body: a measuring probe.

Simulates a parameter file from a collocation stride's state (``--start-stride``) for 1.2 s,
recorded at every 1 ms step, and replays the controller's compiled steps on the recording
(:func:`fit_to_stride.replay`): the replayed excitations must equal the simulation's (checked).
Every 20 ms it prints both legs' gait states, the pelvis tilt, both hips [deg], the right leg's
lowest contact [cm], and each active reflex row's own term (the row alone, unclipped: found
from the row alone with its gain at ±ε) for glut_max_l and iliopsoas_l, where larger than 0.05.

    .venv/bin/python benchmarks/runs/reflex-human/gait_states.py PARAMS.json STRIDE.json
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from bladelab.predict.reflex import controller as ctl
from bladelab.predict.reflex.objective import ObjectiveSettings, simulate_controlled
from bladelab.predict.reflex.optimize import runner_and_layout
from bladelab.runner.layout import CP_LEG
from bladelab.runner.model import contact_heights

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fit_to_stride import replay, replay_inputs  # noqa: E402

EPS = 1e-3
MUSCLES = ("glut_max_l", "iliopsoas_l")


def main(params: str, stride: str) -> None:
    model, layout = runner_and_layout("able", None, "human")
    x = ctl.read_parameters(params, layout, body="human")
    settings = ObjectiveSettings(speed=3.5, duration=1.2, integrator="newmark", dt=1e-3,
                                 start_stride=stride)
    ev, rec = simulate_controlled(model, x, layout=layout, settings=settings, record_every=1)
    print(f"falls {ev.fell} at {ev.duration:.3f} s")
    table = layout.table_for(settings.dt)
    # the controller of step k reads the muscle and contact states of step k − 1's forces
    # (recorded at k − 1) and the coordinates at the start of step k (recorded at k)
    muscles = np.concatenate([rec.muscles[:1], rec.muscles[:-1]])
    contacts = np.concatenate([np.zeros_like(rec.contacts[:1]), rec.contacts[:-1]])
    args = replay_inputs(model, layout, x, settings.dt, muscles, rec.qpos, rec.qvel, contacts,
                         settings.run_up)
    u, states = replay(table, x, *args)
    print(f"replay against the simulation's excitations after the first step: largest "
          f"difference {np.abs(u[1:] - rec.excitation[1:]).max():.2e}")
    names = list(model.muscle_names)
    terms = {}
    for muscle in MUSCLES:
        for r in np.flatnonzero(table[:, ctl.R_TARGET] == names.index(muscle)):
            if table[r, ctl.R_KIND] == ctl.T_CONST:
                continue
            one = table[r:r + 1]
            gi = int(table[r, ctl.R_GAIN])
            up, down = x.copy(), x.copy()
            up[gi], down[gi] = EPS, -EPS
            t_up = replay(one, up, *args)[0][:, names.index(muscle)]
            t_down = replay(one, down, *args)[0][:, names.index(muscle)]
            # u is clipped at 0: one of the two is 0 and their difference is ε·(the row's term)
            terms[(muscle, layout.names[gi])] = x[gi] * (t_up - t_down) / EPS
    right = model.contact_params[:, CP_LEG] == 1
    dof = {n: model.dof(n) for n in ("pelvis_tilt", "hip_flexion_l", "hip_flexion_r")}
    for k in range(0, len(rec.time), 20):
        q = np.degrees(rec.qpos[k])
        low = 100 * contact_heights(model, rec.qpos[k])[right].min()
        line = (f"t {rec.time[k]:.2f} s  states {ctl.STATE_NAMES[int(states[k, 0])]:>11s} / "
                f"{ctl.STATE_NAMES[int(states[k, 1])]:<11s} tilt {q[dof['pelvis_tilt']]:+4.0f}  "
                f"hips {q[dof['hip_flexion_l']]:+4.0f} / {q[dof['hip_flexion_r']]:+4.0f}  "
                f"right foot {low:+5.1f} cm")
        for muscle in MUSCLES:
            active = [f"{name.split('.', 1)[1]} {v[k]:+.2f}" for (m, name), v in terms.items()
                      if m == muscle and abs(v[k]) > 0.05]
            line += f"\n    {muscle} u {rec.excitation[k, names.index(muscle)]:.2f}: " + \
                ", ".join(active)
        print(line)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
