"""The transfemoral runner's stride with a body variant (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/swing-knee/transfemoral_variant.py OUT.json VARIANT \\
        from=benchmarks/design/transfemoral-gait-2026-12-01/alternating-passive-knee.json

``VARIANT`` (JSON): ``force_factor`` {muscle type: factor on its F_max} and ``muscle``
{muscle type: {field: value}}, applied to the human body's parameter set (both legs, the
residual limb included) before the runner is built; ``{}`` is the shipped body.
``knee_bound_deg`` {knee coordinate: flexion [deg]} holds that knee flexed at least so much
at the node where the ``from=`` stride's knee flexes most (as ``knee_bound.py``). The problem
and the measurement are ``homotopy.py``'s (4 m/s, mesh 50, the design box's centre blade,
the passive knee; run without its reserve patch: the library's own problem).
"""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np

from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.transcription import StrideNLP
from bladelab.runner.params import runner_params_from_dict

HOMOTOPY = (Path(__file__).resolve().parents[2] / "design" / "transfemoral-gait-2026-12-01"
            / "homotopy.py")


def main() -> None:
    out, variant = sys.argv[1], json.loads(sys.argv[2])
    spec = importlib.util.spec_from_file_location("homotopy", HOMOTOPY)
    homotopy = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(homotopy)
    stored = homotopy.ft.stored
    original = stored.default_runner_params

    def with_variant(kind, **kw):
        data = json.loads(original(kind, **kw).model_dump_json())
        for name, factor in variant.get("force_factor", {}).items():
            data["muscle_types"][name]["max_isometric_force_N"] *= factor
        for name, row in variant.get("muscle", {}).items():
            data["muscle_types"][name].update(row)
        return runner_params_from_dict(data)

    stored.default_runner_params = with_variant
    held = variant.get("knee_bound_deg", {})
    if held:
        start = next(a.split("=", 1)[1] for a in sys.argv[3:] if a.startswith("from="))
        sol0 = CollocationSolution.read(start)
        names = list(sol0.dof_names)
        rows = {names.index(k): (int(np.argmin(sol0.nlp.q[:-1, names.index(k)])), deg)
                for k, deg in held.items()}
        bounds = StrideNLP.bounds

        def with_knees(self):
            lbx, ubx, lbg, ubg = bounds(self)
            nx = len(self.sx)
            for j, (k, deg) in rows.items():
                ubx[k * nx + j] = min(ubx[k * nx + j], -math.radians(deg) / self.sx[j])
            return lbx, ubx, lbg, ubg

        StrideNLP.bounds = with_knees
    homotopy.solve(out, "none", *sys.argv[3:])


if __name__ == "__main__":
    main()
