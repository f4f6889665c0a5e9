"""Collocation speed: one stride of the human body at a prescribed speed, from the default
guess, warm-started and from the template, on one core.

Targets: the amputee Cat6 stride at 4 m/s from the default guess ≤ 60 s; warm-started at
4.2 m/s ≤ 10 s; the able runner at 3.5 m/s from the template ≤ 60 s. Reported per
solve: wall time, IPOPT iterations per stage, and the time per evaluation of the objective,
constraints, objective gradient and constraint Jacobian (IPOPT's own counters, CasADi
``stats()``), the time inside IPOPT's own algebra, the process's peak resident memory (a
high-water mark over the solves so far), and the compiled-library cache's size on disk. The
plausibility of the gait is a separate matter (docs/collocation.md).
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
    compile_s = nlp.timings.get("compile_s", 0.0)
    own = (trk.get("ipopt_own_s", 0.0) if trk else 0.0) + nlp.timings.get("ipopt_own_s", 0.0)
    memory = nlp.timings.get("peak_memory_MB")
    return (f"| {label} | {'yes' if sol.converged else 'no: ' + sol.nlp.status} | {iters} | "
            f"{wall:.1f} s | {own:.1f} s | {build:.1f} s | {compile_s:.1f} s | "
            + " | ".join(evals)
            + f" | {'–' if memory is None else f'{memory:.0f} MB'} |")


def _cache_line() -> str:
    """The compiled-library cache's size on disk [MB] and its number of libraries."""
    from bladelab.predict.collocation.compiled import cache_dir

    folder = cache_dir()
    files = [f for f in folder.iterdir() if f.is_file() and not f.name.startswith(".")]
    size = sum(f.stat().st_size for f in files) / 1e6
    return (f"The compiled-library cache ({folder}) holds {len(files)} files, {size:.1f} MB on "
            "disk, after these solves.")


def run() -> str:
    import dataclasses

    from bladelab.predict import defaults
    from bladelab.predict.collocation.guess import template_guess
    from bladelab.predict.collocation.settings import CollocationSettings, people_settings
    from bladelab.predict.collocation.solve import predict_stride
    from bladelab.predict.collocation.starting_guess import make_guess
    from bladelab.runner import build_runner

    spec = {"model": "amputee", "blade": "Cat6", "body": "human"}
    runner = build_runner("amputee", blade="Cat6", body="human")
    people = people_settings("human")  # as the command line solves the able and amputee runners
    settings = CollocationSettings(mesh_intervals=MESH, speed_m_per_s=SPEED_MPS, **people)
    stored = predict_stride(runner, settings,
                            make_guess(runner, "stored", n=MESH, speed=SPEED_MPS),
                            model_spec=spec)
    rows = [_row(f"amputee Cat6, the default guess (the shipped stride) → {SPEED_MPS:g} m/s",
                 stored)]
    if stored.converged:
        warm_settings = dataclasses.replace(settings, speed_m_per_s=WARM_SPEED_MPS)
        start = stored.to_guess()  # predict_stride keeps its point or scales it
        warm = predict_stride(runner, warm_settings, start, model_spec=spec)
        rows.append(_row(f"warm start from {SPEED_MPS:g} → {WARM_SPEED_MPS:g} m/s (primal and "
                         f"dual values): objective {warm.nlp.objective:.4f}", warm))
        primal = predict_stride(runner, warm_settings,
                                dataclasses.replace(start, multipliers=None), model_spec=spec)
        rows.append(_row(f"the same from the primal values alone: objective "
                         f"{primal.nlp.objective:.4f}", primal))
    able = build_runner("able", body="human")
    cold = predict_stride(able, CollocationSettings(mesh_intervals=MESH, speed_m_per_s=3.5,
                                                    **people),
                          template_guess(able, speed=3.5, n=MESH),
                          model_spec={"model": "able", "body": "human"})
    warnings = cold.gait_warnings()
    rows.append(_row("able, the template guess → 3.5 m/s (tracking, then predictive): "
                     f"objective {cold.nlp.objective:.4f}, "
                     + ("no gait warning" if not warnings else "; ".join(warnings)), cold))
    return "\n".join([
        "## Collocation: one stride",
        "",
        f"The human body with people's joint angles in the objective (the default weight) "
        f"and people's swing knee (at least {defaults.SWING_KNEE_MIN_DEG:g}°), "
        f"mesh {MESH} intervals, one core (`OMP_NUM_THREADS=1`), L-BFGS (the predictive "
        "stages' update inside IPOPT's augmented system, the tracking stage's by IPOPT's "
        "default, every swinging foot held 1 cm above the ground), tol 1e-4. Targets: the amputee from the default guess ≤ 60 s, "
        "warm-started at 4.2 m/s "
        "≤ 10 s, the able runner from the template ≤ 60 s. A warm start from a solution "
        "restores its controls and multipliers (IPOPT's primal-dual warm start, its own "
        "solver options, so its solver is built once); the primal-only row drops the "
        "multipliers. Time per evaluation (the predictive stage): objective f, constraints g, "
        "∇f, Jacobian of g. The node function is compiled to C (the library's default, "
        "docs/collocation.md \"Compiled node functions\"): its compile (or its load from the "
        "cache) is reported in its own column, outside the solve's wall time.",
        "",
        "| solve | converged | iterations | wall | of it, IPOPT's own | of it, building the "
        "predictive solver | compiling the node function (before the solve) | f | g | ∇f | ∂g | "
        "peak memory of the process so far |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        _cache_line(),
    ])
