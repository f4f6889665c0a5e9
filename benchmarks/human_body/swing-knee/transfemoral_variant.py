"""The transfemoral runner's stride with a body variant (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/swing-knee/transfemoral_variant.py OUT.json VARIANT \\
        from=benchmarks/design/transfemoral-gait-2026-12-01/alternating-passive-knee.json

``VARIANT`` (JSON): ``force_factor`` {muscle type: factor on its F_max} and ``muscle``
{muscle type: {field: value}}, applied to the human body's parameter set (both legs, the
residual limb included) before the runner is built; ``{}`` is the shipped body. The problem
and the measurement are ``homotopy.py``'s (4 m/s, mesh 50, the design box's centre blade,
the passive knee; run without its reserve patch: the library's own problem).
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

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
    homotopy.solve(out, "none", *sys.argv[3:])


if __name__ == "__main__":
    main()
