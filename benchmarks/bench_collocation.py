"""Collocation speed: one amputee stride at a prescribed speed, from the template
guess and warm-started, on one core.

Targets: ≤ 10 min from the template guess, ≤ 2 min from a warm start. Reported per
solve: wall time, IPOPT iterations per stage, and the time per evaluation of the objective,
constraints, objective gradient and constraint Jacobian (IPOPT's own counters, CasADi
``stats()``). The plausibility of the gait is a separate matter (docs/collocation.md).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: MUMPS/BLAS single-threaded

SPEED_MPS = 4.0
WARM_SPEED_MPS = 4.2
MESH = 50


def _row(label: str, sol) -> str:
    nlp, trk = sol.nlp, sol.tracking
    iters = f"{trk['iterations']} + {nlp.iterations}" if trk else f"{nlp.iterations}"
    wall = (trk["wall_s"] if trk else 0.0) + nlp.wall_s
    evals = []
    for key in ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g"):  # the final (predictive) stage
        calls, secs = nlp.timings.get(f"calls_{key}", 0.0), nlp.timings.get(f"{key}_s", 0.0)
        evals.append(f"{1e3 * secs / calls:.2f} ms" if calls else "–")
    build = nlp.timings.get("build_s", 0.0)
    return (f"| {label} | {'yes' if sol.converged else 'no: ' + sol.status} | {iters} | "
            f"{wall:.0f} s | {build:.1f} s | " + " | ".join(evals) + " |")


def run() -> str:
    from bladelab.predict.collocation.guess import template_guess
    from bladelab.predict.collocation.settings import CollocationSettings
    from bladelab.predict.collocation.solve import predict_stride
    from bladelab.runner import build_runner

    spec = {"model": "amputee", "blade": "Cat6"}
    runner = build_runner("amputee", blade="Cat6")
    cold = predict_stride(runner, CollocationSettings(mesh_intervals=MESH, speed_m_per_s=SPEED_MPS),
                          template_guess(runner, speed=SPEED_MPS, n=MESH), model_spec=spec)
    rows = [_row(f"template guess → {SPEED_MPS:g} m/s (tracking, then predictive)", cold)]
    if cold.converged:
        warm = predict_stride(
            runner, CollocationSettings(mesh_intervals=MESH, speed_m_per_s=WARM_SPEED_MPS),
            cold.to_guess().with_speed(WARM_SPEED_MPS), model_spec=spec)
        rows.append(_row(f"warm start from {SPEED_MPS:g} → {WARM_SPEED_MPS:g} m/s", warm))
        warm_mu = predict_stride(
            runner, CollocationSettings(mesh_intervals=MESH, speed_m_per_s=WARM_SPEED_MPS,
                                        warm_start_mu=1e-4),
            cold.to_guess().with_speed(WARM_SPEED_MPS), model_spec=spec)
        rows.append(_row(f"the same, barrier start 1e-4 (`warm_start_mu`): objective "
                         f"{warm_mu.nlp.objective:.4f} against {warm.nlp.objective:.4f}",
                         warm_mu))
    return "\n".join([
        "## Collocation: one amputee stride",
        "",
        f"Amputee with the Cat6 blade sphere, mesh {MESH} intervals, one core "
        "(`OMP_NUM_THREADS=1`), L-BFGS, tol 1e-4. Targets: ≤ 10 min from the template guess, "
        "≤ 2 min warm-started. The warm start reuses the predictive solver built by the first "
        "solve (the speed is a parameter of the NLP), as a speed continuation does; the barrier "
        "start has other IPOPT options, so its solver is built. Time per evaluation (the "
        "predictive stage): objective f, constraints g, ∇f, Jacobian of g.",
        "",
        "| solve | converged | iterations | wall | of it, building the predictive solver | f | g | ∇f | ∂g |",
        "|---|---|---|---|---|---|---|---|---|",
        *rows,
    ])
