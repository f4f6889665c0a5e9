"""Where a stride's muscle fibres work on their force–length curve (a measuring probe).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/fibre_states.py STRIDE.json [MUSCLE,MUSCLE,...]

For each named muscle (default ``soleus_l,gastroc_l,vasti_l``) prints, at every mesh node of
the stride: its leg's vertical ground force [BW], activation [-], tendon force [F_max], fibre
length [l_opt] and fibre velocity [v_max l_opt/s, + lengthening], then the fibre length at
the node of peak activation in stance. A ``variant.json`` beside the stride (written by
``solve_variant.py`` or ``sprint_limit.py``) rebuilds that variant's body, so that its tendon
slack lengths, forces and fibre speeds are the ones the stride was solved with; otherwise the
stride's own model. People's
soleus in running: 0.88 l_opt at peak activation (Rubenson et al. 2012, J Exp Biol 215:3539),
0.90 ± 0.10 l_opt (Bohm et al. 2019, Proc R Soc B 286:20192560).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from solve_variant import stride_runner

from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.muscles import MP_LOPT, MP_VMAX
from bladelab.predict.collocation.nodes import evaluate_nodes
from bladelab.predict.collocation.solution import CONTACT_THRESHOLD_N, CollocationSolution


def fibre_table(path: Path, muscles: list[str]) -> tuple[dict[str, np.ndarray], float]:
    """({muscle: (nodes, 6) array of node, force [BW], a, F̃, l̃, ṽ}, the loaded threshold
    [BW]) of the stride in ``path``."""
    sol = CollocationSolution.read(path)
    runner = stride_runner(path, sol)
    cm, s, mp = build_collocation_model(runner), sol.nlp, runner.muscle_params
    names = list(runner.muscle_names)
    fz = sol.leg_vertical_force() / sol.body_weight_N
    fibres = evaluate_nodes(cm, s.q, s.qd, s.tendon_force, s.tendon_force_rate)
    nodes = np.arange(s.q.shape[0])
    out = {}
    for name in muscles:
        i, leg = names.index(name), 0 if name.endswith("_l") else 1
        out[name] = np.column_stack([nodes, fz[:, leg], s.activation[:, i], s.tendon_force[:, i],
                                     fibres["l_m"][:, i] / mp[i, MP_LOPT],
                                     fibres["v_m"][:, i] / (mp[i, MP_VMAX] * mp[i, MP_LOPT])])
    return out, CONTACT_THRESHOLD_N / sol.body_weight_N


def main() -> None:
    path = Path(sys.argv[1])
    muscles = sys.argv[2].split(",") if len(sys.argv) > 2 else ["soleus_l", "gastroc_l", "vasti_l"]
    table, loaded_bw = fibre_table(path, muscles)
    for name, rows in table.items():
        print(f"== {name}: node, vertical force [BW], activation, tendon force [Fmax], "
              f"fibre length [l_opt], fibre velocity [v_max]")
        for r in rows:
            print(f"  {r[0]:3.0f} {r[1]:5.2f} {r[2]:5.2f} {r[3]:5.2f} {r[4]:5.2f} {r[5]:6.2f}")
        k = int(np.argmax(np.where(rows[:, 1] > loaded_bw, rows[:, 2], -1.0)))
        print(f"  at peak activation in stance (node {k}): fibre {rows[k, 4]:.2f} l_opt, "
              f"tendon force {rows[k, 3]:.2f} Fmax")


if __name__ == "__main__":
    main()
