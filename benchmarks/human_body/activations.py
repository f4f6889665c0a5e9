"""A stride's left-leg joint angles and muscle activations, node by node (a measuring probe).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/activations.py STRIDE.json [EVERY]

Prints every ``EVERY``-th mesh node (default 2): the left leg's vertical ground force [BW],
hip flexion, knee angle (flexion negative) and ankle dorsiflexion [deg], and the activation
[-] of each left-leg muscle. A ``variant.json`` beside the stride (written by
``solve_variant.py`` or ``sprint_limit.py``) names the body it was solved on; otherwise the
stride's own model. Shows which muscles saturate where, e.g. the rectus femoris braking the
knee's flexion in early swing while it flexes the hip.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from solve_variant import stride_runner

from bladelab.predict.collocation.solution import CollocationSolution


def main() -> None:
    path = Path(sys.argv[1])
    every = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    sol = CollocationSolution.read(path)
    runner = stride_runner(path, sol)
    names = list(runner.muscle_names)
    leg = [i for i, n in enumerate(names) if n.endswith("_l")
           and n[:-2] not in ("rect_abd", "int_obl", "erect_sp")]
    dofs = list(runner.dof_names)
    hip, knee, ankle = (dofs.index(f"{d}_l") for d in ("hip_flexion", "knee_angle", "ankle_angle"))
    q = np.degrees(sol.nlp.q)
    fz = sol.leg_vertical_force()[:, 0] / sol.body_weight_N
    print("node  Fz[BW]   hip  knee ankle [deg] | "
          + " ".join(f"{names[i][:-2][:8]:>8}" for i in leg))
    for n in range(0, q.shape[0], every):
        print(f"{n:4d} {fz[n]:6.2f} {q[n, hip]:6.1f}{q[n, knee]:6.1f}{q[n, ankle]:6.1f}       | "
              + " ".join(f"{sol.nlp.activation[n, i]:8.2f}" for i in leg))


if __name__ == "__main__":
    main()
