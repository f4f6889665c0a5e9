"""Fingerprints of bladelab's numerical results, for refactors that must not change them.

Prints one SHA-256 (first 16 hex digits) per result: the blade kernel's and MuJoCo engine's GRF,
an identification, the runner (open loop, multi-link blade, reflex-controlled shipped solution),
and a design study (blade evaluator) plus one transfemoral runner-evaluator run. Run it before and
after a change and compare (``python benchmarks/fingerprint.py > before.txt``); bit-identical
results print identical lines. Not a test: the hashes depend on the machine's floating point.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tempfile
from pathlib import Path

import numpy as np


def _h(*arrays) -> str:
    m = hashlib.sha256()
    for a in arrays:
        if isinstance(a, (dict, list, str)):
            m.update(json.dumps(a, sort_keys=True, default=float).encode())
        else:
            m.update(np.ascontiguousarray(np.asarray(a, dtype=float)).tobytes())
    return m.hexdigest()[:16]


def blade_and_identify() -> dict[str, str]:
    from bladelab.blade import load_blade
    from bladelab.identify import identify_stance
    from bladelab.sim import generate_stance, prepare, simulate, simulate_batch

    model = load_blade("xtreme-cat5").build()
    stance, truth = generate_stance(model, speed_mps=7.0, body_mass_kg=76.0)
    out = {"sim.generate_stance": _h(stance.time, stance.grf_z, stance.clamp_x, stance.clamp_pitch)}
    problem = prepare(model, stance)
    res = simulate(problem, stiffness=1031.3, damping=17.2)
    out["sim.kernel"] = _h(res.grf_x, res.grf_z, res.distance)
    batch = simulate_batch(problem, np.array([[900.0], [1100.0]]), np.array([[15.0], [20.0]]))
    out["sim.kernel_batch"] = _h(*[np.asarray(v) for v in _fields(batch)])
    mj = simulate(prepare(model, stance, engine="mujoco"), stiffness=1031.3, damping=17.2)
    out["sim.mujoco"] = _h(mj.grf_x, mj.grf_z, mj.distance)
    ident = identify_stance(stance, "xtreme-cat5", seed=0)
    out["identify.pso"] = _h(_untimed(ident.to_dict()))
    seed_f = identify_stance(stance, "xtreme-cat5", seed=0, formulation="seed", identifiability=False)
    out["identify.seed_formulation"] = _h(_untimed(seed_f.to_dict()))
    return out


def _untimed(d: dict) -> dict:
    return {k: v for k, v in d.items() if k != "wall_s"}


def _fields(obj):
    if isinstance(obj, dict):
        return [obj[k] for k in sorted(obj)]
    if hasattr(obj, "__dataclass_fields__"):
        return [getattr(obj, k) for k in sorted(obj.__dataclass_fields__)
                if isinstance(getattr(obj, k), np.ndarray)]
    return [obj]


def runner() -> dict[str, str]:
    from bladelab.blade import load_blade
    from bladelab.predict.reflex import (
        ObjectiveSettings,
        controller_layout,
        read_parameters,
        simulate_controlled,
    )
    from bladelab.runner import build_runner, simulate_runner

    out = {}
    m = build_runner("amputee", blade="Cat6")
    r = simulate_runner(m, excitations=0.05, duration=1.0)
    out["runner.open_loop"] = _h(r.qpos, r.contacts)
    wear = build_runner("amputee", blade_model=load_blade("xtreme-cat5").build())
    r = simulate_runner(wear, excitations=0.05, duration=0.5)
    out["runner.multilink"] = _h(r.qpos, r.contacts)
    import bladelab

    sol = Path(bladelab.__file__).parent / "data/runner/reflex-starts/amputee-Cat6-3.5.json"
    layout = controller_layout(m)
    x = read_parameters(sol, layout)
    data = json.loads(sol.read_text())
    settings = dict(data["settings"])
    for k in ("knee_load_range", "pelvis_tilt_range_deg"):
        settings[k] = tuple(settings[k])
    settings["duration"] = 3.0
    settings["robust_samples"] = 1
    ev, res = simulate_controlled(m, x, layout=layout, settings=ObjectiveSettings(**settings),
                                  record_every=4)
    out["reflex.solution"] = _h(ev.to_dict(), res.qpos)
    return out


def design() -> dict[str, str]:
    from bladelab.design import BladeEvaluator, DesignSpace, Factor, run_design
    from bladelab.design.transfemoral import RunnerEvaluator
    space = DesignSpace((Factor("stiffness_kN_per_m", 18.0, 32.0, "kN/m"),
                         Factor("toe_length_m", 0.19, 0.25, "m")))
    with tempfile.TemporaryDirectory() as tmp:
        res = run_design(space, runs="ccd", evaluator=BladeEvaluator(), out_dir=tmp, seed=0,
                         progress=False)
        table = Path(tmp, "results.csv").read_text()
    out = {"design.blade_ccd": _h(table), "design.optimum": _h(res.to_dict().get("optimum"))}
    ev = RunnerEvaluator()
    out["design.runner_evaluator"] = _h(ev({"stiffness_kN_per_m": 25.0, "width_m": 0.065,
                                            "height_m": 0.44, "toe_length_m": 0.22}))
    return out


def main() -> None:
    parts = sys.argv[1:] or ["blade", "runner", "design"]
    fns = {"blade": blade_and_identify, "runner": runner, "design": design}
    for p in parts:
        for k, v in fns[p]().items():
            print(f"{k:28s} {v}", flush=True)


if __name__ == "__main__":
    main()
