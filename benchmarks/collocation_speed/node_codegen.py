"""One mesh node's functions compiled to C, against the interpreted SX (a measuring probe).

Usage (repository root)::

    .venv/bin/python benchmarks/collocation_speed/node_codegen.py [MODEL BLADE SPEED] [OPT]

Builds the predictive stride NLP of the human body (default: amputee, Cat6, 4 m/s, mesh 50),
generates C for its node function (``StrideNLP.node``: state derivatives, path residuals,
effort, metabolic rate, inequalities, vertical force, ...) and the node function's Jacobian
(``jac_node``, what CasADi calls for an external's derivatives), compiles them with gcc at
``OPT`` (default -O1), and prints the C size, the compile time, the largest relative
difference from the interpreted functions on random inputs and the time per call of each.
Nothing under ``src`` is changed by it.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np


def _per_call(f, args, min_s: float = 1.0) -> float:
    """Median time per call [ms] of ``f(*args)``."""
    times = []
    t_end = time.perf_counter() + min_s
    while time.perf_counter() < t_end or len(times) < 20:
        t0 = time.perf_counter()
        f(*args)
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def main() -> None:
    from bladelab.predict.collocation import build_collocation_model
    from bladelab.predict.collocation.dynamics import stride_dynamics
    from bladelab.predict.collocation.settings import CollocationSettings
    from bladelab.predict.collocation.stored import check_model_spec, runner_from_spec
    from bladelab.predict.collocation.transcription import StrideNLP

    model = sys.argv[1] if len(sys.argv) > 1 else "amputee"
    blade = (sys.argv[2] if len(sys.argv) > 2 else "Cat6") if model != "able" else None
    speed = float(sys.argv[3]) if len(sys.argv) > 3 else 4.0
    opt = sys.argv[4] if len(sys.argv) > 4 else "-O1"
    runner = runner_from_spec(check_model_spec({"model": model, "blade": blade,
                                                "body": "human"}))
    settings = CollocationSettings(speed_m_per_s=speed)
    dyn = stride_dynamics(build_collocation_model(runner))
    nlp = StrideNLP(dyn, n=settings.mesh_intervals, speed=speed, weights=settings.weights,
                    compiled=False)
    node = nlp.node
    jac = node.jacobian()
    rec = {"model": model, "blade": blade, "opt": opt, "node_instructions": node.n_instructions(),
           "jac_instructions": jac.n_instructions()}
    work = Path(tempfile.mkdtemp(prefix="node-codegen-"))
    cg = ca.CodeGenerator("node_kernel.c", {"with_header": False})
    cg.add(node)
    cg.add(jac)
    src = Path(cg.generate(str(work) + "/"))
    rec["c_MB"] = src.stat().st_size / 1e6
    lib = work / "node_kernel.so"
    t0 = time.perf_counter()
    subprocess.run(["gcc", opt, "-shared", "-fPIC", str(src), "-o", str(lib), "-lm"],
                   check=True)
    rec["compile_s"] = time.perf_counter() - t0
    ext = ca.external("node", str(lib))
    ext_jac = ca.external(jac.name(), str(lib))
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(5):
        args = [rng.uniform(0.1, 1.0, node.size1_in(i)) for i in range(node.n_in())]
        for f, g in ((node, ext), (jac, ext_jac)):
            a = f(*args, *([] if f is node else [np.zeros(node.size1_out(j)) for j in range(node.n_out())]))
            b = g(*args, *([] if f is node else [np.zeros(node.size1_out(j)) for j in range(node.n_out())]))
            for x, y in zip(a if isinstance(a, (list, tuple)) else [a],
                            b if isinstance(b, (list, tuple)) else [b], strict=True):
                x, y = np.asarray(ca.DM(x).full()), np.asarray(ca.DM(y).full())
                scale = np.maximum(np.abs(x), 1e-300)
                ok = np.isfinite(x) & (np.abs(x) > 1e-12)
                if ok.any():
                    worst = max(worst, float(np.max(np.abs(x - y)[ok] / scale[ok])))
    rec["max_rel_diff"] = worst
    args = [rng.uniform(0.1, 1.0, node.size1_in(i)) for i in range(node.n_in())]
    outs = [np.zeros(node.size1_out(j)) for j in range(node.n_out())]
    rec["node_interpreted_ms"] = _per_call(node, args)
    rec["node_compiled_ms"] = _per_call(ext, args)
    rec["jac_interpreted_ms"] = _per_call(jac, args + outs)
    rec["jac_compiled_ms"] = _per_call(ext_jac, args + outs)
    m = settings.mesh_intervals + 1
    mapped = ext_jac.map(m)
    margs = [ca.DM(np.tile(np.reshape(a, (-1, 1)), (1, m))) for a in args + outs]
    rec["jac_compiled_mapped_ms"] = _per_call(mapped, margs)
    rec["jac_interpreted_mapped_ms"] = _per_call(jac.map(m), margs)
    print(json.dumps(rec, indent=1))




def solve_main(compiled: bool, speed: float = 4.2) -> None:
    """The amputee Cat6 stride at ``speed`` from the shipped 4 m/s stride (primal and dual
    values), with the node function compiled (the library's default: an ``external`` mapped
    over the mesh, the solver not expanded) or interpreted (``BLADELAB_COMPILE=0``: the
    expanded SX); prints the solve's numbers as JSON (``compile_s``: the compile, 0 when the
    library was in the cache already)."""
    import os

    os.environ["BLADELAB_COMPILE"] = "1" if compiled else "0"
    from bladelab.predict.collocation.settings import CollocationSettings, people_term
    from bladelab.predict.collocation.solve import predict_stride
    from bladelab.predict.collocation.starting_guess import make_guess
    from bladelab.predict.collocation.stored import check_model_spec, runner_from_spec

    spec = check_model_spec({"model": "amputee", "blade": "Cat6", "body": "human"})
    runner = runner_from_spec(spec)
    settings = CollocationSettings(speed_m_per_s=speed, **people_term(10.0))
    guess = make_guess(runner, "stored", n=settings.mesh_intervals, speed=speed)
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings, guess, model_spec=spec)
    rec = {"compiled": compiled, "speed": speed, "converged": sol.converged,
           "iterations": sol.nlp.iterations, "objective": sol.nlp.objective,
           "wall_s": time.perf_counter() - t0, **dict(sol.nlp.timings)}
    print(json.dumps(rec))

if __name__ == "__main__":
    if sys.argv[1:2] == ["solve"]:
        solve_main(sys.argv[2] == "compiled", float(sys.argv[3]) if len(sys.argv) > 3 else 4.2)
    else:
        main()
