"""Solve one stride of a modified human body (a measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/solve_variant.py OUT '{"kind": "able", ...}'
    .venv/bin/python benchmarks/human_body/solve_variant.py OUT VARIANT --from START.json

The JSON variant says what differs from the built-in human parameter set of ``kind``
(``able``/``amputee``, default able; ``blade``; ``speed`` [m/s], default 3.5):
``force_factor`` ({muscle type or "all": factor} on the table's maximum isometric forces; the
tendon and passive curves follow them), ``volume_factor`` ({muscle type: factor} on its volume
fraction; its maximum isometric force follows), ``muscle`` ({muscle type: {field: value}}),
``lumbar`` ([stiffness N·m/rad, damping N·m·s/rad] of the lumbar spring–damper in place of
``bladelab.runner.joints.LIGAMENTS``' 500 and 5), ``set`` (top-level parameter fields), ``weights`` (``StrideWeights`` fields), ``guess`` (a word or a
solution file; default the measured trial), ``track`` (true: a tracking stage of the guess
first, as for a guess that is no collocation solution), ``mesh`` (mesh intervals, default 50)
``stride_time`` ([lo, hi] s, ``CollocationSettings.stride_time_range_s``, or ``"people"``:
their band at the speed) and
``people_weight`` (people's joint angles in the objective, the command line's
``--people-weight``; default 0). Writes
``OUT/solution.json`` (or ``best_iterate.json``) and ``OUT/variant.json``, and prints the summary and the wall time [s].
With ``--from START.json``: the library's default problem of the human body instead (people's
joint angles at the body's weight, or the variant's ``people_weight``; people's swing knee;
people's stride time unless ``"stride_time_people": false``), at START's speed and mesh (or the
variant's ``speed`` and ``mesh``), from START's primal and dual values, no tracking stage; it
prints one JSON line with the criteria of people's running met and missed.
The rows of README.md made with it: every force doubled (``{"force_factor": {"all": 2.0}}``),
the acceleration weight 0.01, the vasti tendon slack length 0.146 m.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from criteria import stride_record

from bladelab.predict.collocation.settings import (
    CollocationSettings,
    people_settings,
    people_term,
)
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import predict_stride
from bladelab.predict.collocation.starting_guess import make_guess
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.predict.collocation.stride_problem import StrideWeights
from bladelab.runner import build_runner
from bladelab.runner.params import default_runner_params, runner_params_from_dict


def apply_variant(data: dict, variant: dict) -> dict:
    """``data`` (a parameter set as a dict) with the variant's ``force_factor``, ``muscle`` and
    ``set``, and ``sprint_limit.py``'s shorthands ``vmax`` [l_opt/s] and ``active_tension``
    [N/cm²], applied in place; returns it."""
    if "vmax" in variant:
        data["max_shortening_velocity_lopt_per_s"] = float(variant["vmax"])
    if "active_tension" in variant:
        data["active_specific_tension_N_per_cm2"] = float(variant["active_tension"])
    for name, factor in variant.get("force_factor", {}).items():
        for muscle, row in data["muscle_types"].items():
            if name in ("all", muscle) and row.get("max_isometric_force_N"):
                row["max_isometric_force_N"] *= factor
    for muscle, factor in variant.get("volume_factor", {}).items():
        data["muscle_types"][muscle]["volume_fraction"] *= float(factor)
    for muscle, row in variant.get("muscle", {}).items():
        data["muscle_types"][muscle].update(row)
    data.update(variant.get("set", {}))
    return data


def variant_runner(variant: dict):
    """The human runner of ``kind`` (and ``blade``) with the variant applied
    (:func:`apply_variant`)."""
    kind, blade = variant.get("kind", "able"), variant.get("blade")
    data = json.loads(default_runner_params(kind, body="human", blade=blade).model_dump_json())
    if "lumbar" in variant:  # the ligament table is read when the runner is built
        from bladelab.runner import joints

        joints.LIGAMENTS["lumbar_extension"] = (0.0, 0.0, *map(float, variant["lumbar"]))
    return build_runner(runner_params_from_dict(apply_variant(data, variant)))


def stride_runner(path: Path, sol: CollocationSolution):
    """The runner the stride ``sol`` (read from ``path``) was solved on: the variant of a
    ``variant.json`` beside it (written by this script or ``sprint_limit.py``), else the
    stride's own model."""
    variant_file = path.parent / "variant.json"
    return (variant_runner(json.loads(variant_file.read_text())) if variant_file.is_file()
            else runner_from_spec(sol.model_spec))


def solve_from_stride(start: str, variant: dict, out: Path) -> dict:
    """The library's default problem on the body changed by ``variant``, from the stride
    ``start`` (see the module's ``--from``); writes ``out/solution.json`` and returns one
    record (:func:`criteria.stride_record`) with the variant, the start and the wall time [s]."""
    first = CollocationSolution.read(start)
    kind = variant.get("kind", "able")
    settings = CollocationSettings(
        mesh_intervals=int(variant.get("mesh", first.settings.mesh_intervals)),
        speed_m_per_s=float(variant.get("speed", first.settings.speed_m_per_s)),
        stride_time_people=bool(variant.get("stride_time_people", True)),
        **people_settings("human", variant.get("people_weight"), kind=kind))
    t0 = time.perf_counter()
    spec = {"model": kind, "body": "human"} | ({"blade": variant["blade"]} if "blade" in variant
                                               else {})
    sol = predict_stride(variant_runner(variant), settings, first.to_guess(), track=False,
                         model_spec=spec)
    out.mkdir(parents=True, exist_ok=True)
    sol.write(out / "solution.json")
    (out / "variant.json").write_text(json.dumps(variant))
    return {"variant": variant, "start": start, **stride_record(sol),
            "wall_s": time.perf_counter() - t0}


def main() -> None:
    out, variant = Path(sys.argv[1]), json.loads(sys.argv[2])
    if len(sys.argv) == 5 and sys.argv[3] == "--from":
        print(json.dumps(solve_from_stride(sys.argv[4], variant, out)))
        return
    kind, blade = variant.get("kind", "able"), variant.get("blade")
    speed = variant.get("speed", 3.5)
    runner = variant_runner(variant)
    weights = variant.get("weights")
    stride_time = variant.get("stride_time")
    period = ({"stride_time_people": True} if stride_time == "people"
              else {"stride_time_range_s": stride_time})
    settings = CollocationSettings(speed_m_per_s=speed,
                                   weights=StrideWeights(**weights) if weights else None,
                                   mesh_intervals=variant.get("mesh", 50), **period,
                                   **people_term(variant.get("people_weight", 0)))
    guess = make_guess(runner, variant.get("guess", "trial"), n=settings.mesh_intervals,
                       speed=speed)
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, guess,
                         model_spec={"model": kind, "blade": blade, "body": "human"},
                         track=variant.get("track"))
    out.mkdir(parents=True, exist_ok=True)
    sol.write(out / ("solution.json" if sol.converged else "best_iterate.json"))
    (out / "variant.json").write_text(json.dumps(variant))
    print(json.dumps(sol.summary()), f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
