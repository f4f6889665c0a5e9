"""The transfemoral runner's stride with a body variant (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/swing-knee/transfemoral_variant.py OUT.json VARIANT \\
        from=benchmarks/design/transfemoral-gait-2026-12-01/alternating-passive-knee.json

``VARIANT`` (JSON): the fields of ``solve_variant.py``'s variants (``force_factor``,
``muscle``, ``set``, ``vmax``, ``active_tension``; :func:`solve_variant.apply_variant`),
applied to the human body's parameter set (both legs, the residual limb included) before the
runner is built; ``{}`` is the shipped body.
``knee_bound_deg`` {knee coordinate: flexion [deg]} holds that knee flexed at least so much
at the node where the ``from=`` stride's knee flexes most (as ``knee_bound.py``). The problem
and the measurement are ``homotopy.py``'s (4 m/s, mesh 50, the design box's centre blade,
the passive knee; run without its reserve patch: the library's own problem).
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

from knee_bound import deepest_flexion_nodes, hold_knees

from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.runner.params import runner_params_from_dict

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/human_body
from solve_variant import apply_variant  # noqa: E402

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
        return runner_params_from_dict(apply_variant(data, variant))

    stored.default_runner_params = with_variant
    held = variant.get("knee_bound_deg", {})
    if held:
        start = next(a.split("=", 1)[1] for a in sys.argv[3:] if a.startswith("from="))
        hold_knees(deepest_flexion_nodes(CollocationSolution.read(start), held), held)
    homotopy.solve(out, "none", *sys.argv[3:])


if __name__ == "__main__":
    main()
