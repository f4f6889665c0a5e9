"""Each muscle's metabolic energy per stride of two strides of the able runner, and what
changed (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/swing-knee/muscle_energy.py BASE.json OTHER.json...

Per stride file: each muscle's metabolic energy over the stride per body mass and distance
[J/(kg·m)] (the collocation twin's Uchida et al. 2016 rates, ``muscle_metabolic_rates``, at
the mesh nodes, trapezoidal rule), both on the shipped able body. Prints, for each OTHER, the
muscles' total against BASE's and the ten largest changes.
"""

from __future__ import annotations

import sys

import casadi as ca
import numpy as np

from bladelab.predict.collocation.metabolics import muscle_metabolic_rates
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.nodes import evaluate_nodes
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.runner import build_runner


def muscle_energy(runner, cm, path: str) -> np.ndarray:
    """Each muscle's metabolic energy [J/(kg·m)] over the stride in ``path``."""
    sol = CollocationSolution.read(path)
    s = sol.nlp
    fibres = evaluate_nodes(cm, s.q, s.qd, s.tendon_force, s.tendon_force_rate)
    rates = np.array([np.asarray(muscle_metabolic_rates(
        runner, ca.DM(s.excitation[k]), ca.DM(s.activation[k]), ca.DM(s.tendon_force[k]),
        ca.DM(s.tendon_force_rate[k]), ca.DM(fibres["l_mt"][k]), ca.DM(fibres["v_mt"][k]),
        cm.smoothing)).ravel() for k in range(s.q.shape[0])])
    time = np.linspace(0.0, sol.period_s, s.q.shape[0])
    return np.trapezoid(rates, time, axis=0) / sol.stride_length_m / sol.body_mass_kg


def main() -> None:
    runner = build_runner("able", body="human")
    cm = build_collocation_model(runner)
    names = list(runner.muscle_names)
    base = muscle_energy(runner, cm, sys.argv[1])
    for path in sys.argv[2:]:
        other = muscle_energy(runner, cm, path)
        change = other - base
        print(f"{path}: the muscles {base.sum():.3f} -> {other.sum():.3f} J/(kg·m)")
        for i in np.argsort(-np.abs(change))[:10]:
            print(f"  {names[i]:14s} {base[i]:.3f} -> {other[i]:.3f} ({change[i]:+.3f})")


if __name__ == "__main__":
    main()
