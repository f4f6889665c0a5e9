"""Solve every design's kept stride of a predicted-gait design study again from itself, with
IPOPT's stall stop off (its default acceptable-level test; tol unchanged): how far are the
kept strides from where their own solve would go on to?

A stride kept by the study ended at IPOPT's acceptable level (the objective changing by less
than 1e-5 of itself over five iterations, ``ipopt_options.STALL_STOP_OPTIONS``). Started again
from its own point (primal values; the stored strides hold no multipliers) without that stop,
the solve either goes on down (the stop came early) or lands a little above or below on a
neighbouring optimum (the restart's barrier moves the point off the bounds). The spread of
these changes is the share of the start spread (``bladelab.design.start_spread``) that a
stricter stop or a restart can remove; the rest is distinct local optima.

Solves nothing already solved: each design's outcome is kept in ``--work`` as
``<design>.result.json`` (and its stride as ``strides/<design>.json``), so an interrupted run
resumes. Writes ``restart-from-self.csv`` into ``--work`` and prints a summary.

Usage (repository root, about 4 min per design per worker at 100 intervals)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/design/restart_from_self.py \
        benchmarks/design/transtibial-sprinter-6mps-2026-12-07 --work /tmp/restart --jobs 2
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab.design.stride_files import point_from_stem


def restart_one(study: Path, stem: str, work: Path) -> dict:
    """Solve design ``stem``'s stride of ``study`` again from itself (stall stop off); cached."""
    result = work / f"{stem}.result.json"
    if result.is_file():
        return json.loads(result.read_text(encoding="utf-8"))
    import bladelab.predict.collocation.ipopt_options as ipopt_options
    from bladelab.design.collocation_evaluator import CollocationEvaluator
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.predict.collocation.solve import predict_stride
    from bladelab.predict.collocation.stored import runner_from_spec

    ipopt_options.STALL_STOP_OPTIONS.clear()  # this worker only: IPOPT's default stop
    setup = json.loads((study / "evaluator.json").read_text(encoding="utf-8"))
    setup.pop("evaluator")
    setup.update(solutions_dir=None, start_strides=None,
                 factor_ranges={k: tuple(v) for k, v in setup["factor_ranges"].items()})
    evaluator = CollocationEvaluator(**setup)
    point = point_from_stem(stem)
    spec, settings = evaluator.problem(point)
    runner = runner_from_spec(spec)
    kept = CollocationSolution.read(study / "strides" / f"{stem}.json")
    t0 = time.perf_counter()
    sol = predict_stride(runner, dataclasses.replace(settings, max_iter=3000),
                         kept.to_guess("the study's kept stride"), model_spec=spec, track=False,
                         speed_floor=evaluator.speed_floor(point, kept))
    warnings = sol.gait_warnings() if sol.converged else None
    clean = bool(sol.converged) and not warnings
    out = {"design": stem, "point": point, "kept_objective": float(kept.nlp.objective),
           "status": str(sol.nlp.status), "iterations": int(sol.nlp.iterations),
           "objective": float(sol.nlp.objective) if clean else None,
           "warnings": warnings,
           "wall_s": time.perf_counter() - t0,
           "responses_kept": evaluator.responses(kept, runner),
           "responses": evaluator.responses(sol, runner) if clean else None}
    if clean:
        (work / "strides").mkdir(parents=True, exist_ok=True)
        sol.write(work / "strides" / f"{stem}.json")
    result.write_text(json.dumps(out, indent=1), encoding="utf-8")
    print(f"{stem}: {out['status']}, objective {out['kept_objective']:.5g} -> "
          f"{out['objective']}, {out['wall_s']:.0f} s", flush=True)
    return out


def _restart(args: tuple[Path, str, Path]) -> dict:
    return restart_one(*args)


def summary(results: list[dict]) -> pd.DataFrame:
    """Per design: objective change [%] and cost-of-transport change [J/(kg·m)]."""
    rows = []
    for r in results:
        cot = "cost_of_transport_J_per_kg_m"
        rows.append({**r["point"], "status": r["status"], "iterations": r["iterations"],
                     "wall_s": round(r["wall_s"], 1),
                     "kept_objective": r["kept_objective"], "objective": r["objective"],
                     "objective_change_pct": (100 * (r["objective"] / r["kept_objective"] - 1)
                                              if r["objective"] is not None else None),
                     "cot_change_J_per_kg_m": (r["responses"][cot] - r["responses_kept"][cot]
                                               if r["responses"] else None)})
    return pd.DataFrame(rows).sort_values("objective_change_pct")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("study", type=Path)
    ap.add_argument("--work", type=Path, required=True, help="checkpoint and output folder")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    # a design's stride only: a replaced stride or a failed solve's iterate names no point
    stems = sorted(p.stem for p in (args.study / "strides").glob("*.json")
                   if point_from_stem(p.stem) is not None)
    todo = [(args.study, s, args.work) for s in stems]
    with ProcessPoolExecutor(args.jobs) as pool:
        results = list(pool.map(_restart, todo))
    table = summary(results)
    table.to_csv(args.work / "restart-from-self.csv", index=False)
    change = table["objective_change_pct"].to_numpy(float)
    cot = table["cot_change_J_per_kg_m"].to_numpy(float)
    print(f"{len(table)} designs, {int(np.sum(np.isfinite(change)))} clean; objective change "
          f"{np.nanmin(change):+.2f} … {np.nanmax(change):+.2f} % "
          f"(median {np.nanmedian(change):+.2f} %, lower in {int(np.sum(change < 0))}); "
          "cost of transport change SD "
          f"{np.nanstd(cot, ddof=1):.3f} J/(kg·m), mean {np.nanmean(cot):+.3f}; "
          f"{table['wall_s'].sum() / 60:.0f} min of solver time")


if __name__ == "__main__":
    main()
