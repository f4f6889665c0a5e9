"""A study's start stride carried to the study's speed and mesh before its first design.

A design study at a prescribed speed far from its start stride's (a sprinter's study at 6 m/s
from the built-in 4 m/s stride) would solve its first design in one jump. Measured on the
transtibial sprinter with the box's centre blade: from the 4 m/s stride straight to 5 m/s on 100
intervals the solve converged to a hop on the blade, while a chain of 0.5 m/s steps on the
start's 50 intervals up to 7 m/s, then 100 intervals at that speed, gave a clean stride at every
step (benchmarks/design/transtibial-sprinter-centre-2026-12-07). :func:`continue_stride` is that
chain: the first design's stride at the start's own speed (the study's athlete and blade may
differ from the start's), then at speeds :data:`CONTINUATION_STEP_MPS` apart up to the study's,
on the start's mesh, then once on the study's mesh. Each step's stride is written to a folder
(``strides/continuation/`` of a study) and read back when a stopped study resumes.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from pathlib import Path

from bladelab.design.stride_files import start_text
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import check_model_spec, same_model_spec

__all__ = ["CONTINUATION_STEP_MPS", "continuation_speeds", "continue_stride",
           "read_clean_stride"]

#: Largest speed step [m/s] of the chain (the step of the measured sprinter chain: every step
#: gave a clean stride); a study within one step of its start's speed is solved directly.
CONTINUATION_STEP_MPS = 0.5


def continuation_speeds(start_mps: float, speed_mps: float,
                        step_mps: float = CONTINUATION_STEP_MPS) -> list[float]:
    """The chain's speeds [m/s]: the start's, then equal steps of at most ``step_mps`` up (or
    down) to ``speed_mps``; [] when the two are within one step (no chain needed)."""
    gap = float(speed_mps) - float(start_mps)
    if not (step_mps > 0 and math.isfinite(gap)):
        raise ValueError(f"bad continuation: {start_mps} -> {speed_mps} m/s, step {step_mps}")
    if abs(gap) <= step_mps * (1 + 1e-9):
        return []
    n = math.ceil(abs(gap) / step_mps - 1e-9)
    return [float(start_mps) + gap * k / n for k in range(n + 1)]


def _clean(solution) -> bool:
    return bool(solution.converged) and not solution.gait_warnings()


def read_clean_stride(path: Path, spec: dict, settings):
    """The stride stored in ``path`` if it is a clean stride (converged, no gait warning) of
    this problem (model ``spec``: the same blade and athlete; ``settings``: the same speed,
    mesh, weights, constraints and transcription); else None, also for a missing file."""
    path = Path(path)
    if not path.is_file():
        return None
    sol = CollocationSolution.read(path)
    if (same_model_spec(sol.model_spec, check_model_spec(spec))
            and sol.settings.same_problem(settings) and _clean(sol)):
        return sol
    return None


def continue_stride(runner, spec: dict, settings, start: Path, folder: Path, name: str, *,
                    solve: Callable, say: Callable[[str], None] | None = None):
    """Solve the stride of ``runner`` (built from ``spec``) under ``settings`` (a prescribed
    speed) by continuation from the stride file ``start`` (module docstring). ``solve`` is
    :func:`~bladelab.predict.collocation.solve.predict_stride`; each step's stride is written
    to ``folder/<name>-<speed>mps-mesh<N>.json`` (a failed step's as ``.best_iterate.json``)
    and ``say(line)`` gets a line per step. Returns the clean stride at the study's speed and
    mesh, or None when no chain is needed (the start within one step of the speed) or a step
    gave no clean stride (the study then starts from ``start`` as it is)."""
    start = Path(start)
    first = CollocationSolution.read(start)
    speeds = continuation_speeds(first.mean_speed_mps, settings.speed_m_per_s)
    if not speeds:
        return None
    coarse = first.settings.mesh_intervals
    steps = [dataclasses.replace(settings, speed_m_per_s=v, mesh_intervals=coarse)
             for v in speeds]
    if coarse != settings.mesh_intervals:
        steps.append(settings)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    guess, guess_path = first, start
    for k, step in enumerate(steps, 1):
        path = folder / f"{name}-{step.speed_m_per_s:.3f}mps-mesh{step.mesh_intervals}.json"
        head = (f"start continued to {step.speed_m_per_s:.3g} m/s on {step.mesh_intervals} "
                f"intervals (step {k} of {len(steps)})")
        sol = read_clean_stride(path, spec, step)
        if sol is None:
            t0 = time.perf_counter()
            sol = solve(runner, step, guess.to_guess(start_text(guess_path, guess)),
                        model_spec=spec, track=False)
            if not _clean(sol):
                sol.write(path.with_name(path.stem + ".best_iterate.json"))
                if say is not None:
                    why = ("IPOPT " + str(sol.nlp.status) if not sol.converged
                           else "; ".join(sol.gait_warnings()))
                    say(f"{head}: {why}; the designs start from {start.name} as it is")
                return None
            sol.write(path)
            if say is not None:
                say(f"{head}: objective {sol.nlp.objective:.5g}, "
                    f"{time.perf_counter() - t0:.0f} s")
        elif say is not None:
            say(f"{head}: read back from {path.name}")
        guess, guess_path = sol, path
    return guess
