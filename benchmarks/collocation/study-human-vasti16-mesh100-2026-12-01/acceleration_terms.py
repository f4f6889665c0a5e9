"""Where the effort's joint-acceleration term of a stride comes from, per coordinate.

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/study-human-vasti16-mesh100-2026-12-01/acceleration_terms.py FILE...

FILE: a collocation ``solution.json``. Prints one line per file: mesh intervals, objective and
its terms, the acceleration term's share per joint coordinate (the objective's own form: weight
× mean over the nodes of the squared accelerations [rad²/s⁴] over the joint coordinates / 1e4)
and the largest joint acceleration [rad/s²] with its coordinate and node.
"""

from __future__ import annotations

import json
import sys

import numpy as np


def main(paths: list[str]) -> int:
    for path in paths:
        with open(path, encoding="utf-8") as f:
            s = json.load(f)
        qdd = np.asarray(s["qdd"], float)[:-1, 3:]  # the nodes of one stride; joints only
        names = s["dof_names"][3:]
        weight = s["settings"]["weights"]["acceleration"]
        share = weight * np.mean(qdd**2, axis=0) / qdd.shape[1] / 1e4
        k, j = np.unravel_index(np.argmax(np.abs(qdd)), qdd.shape)
        terms = {t: round(v, 4) for t, v in s["objective_terms"].items()}
        parts = ", ".join(f"{n} {v:.3f}" for n, v in zip(names, share, strict=True))
        print(f"{path}: mesh {s['settings']['mesh_intervals']}, objective {s['objective']:.4f} "
              f"{terms}; acceleration term {share.sum():.3f} = {parts}; largest "
              f"{abs(qdd[k, j]):.0f} rad/s² ({names[j]}, node {k})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
