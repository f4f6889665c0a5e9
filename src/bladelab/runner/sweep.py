"""Blade-category sweeps (seed 001 §2.2.2 B–C, Fig. 3.7, Table 3.1).

Each category is one independent task (run on an executor of :mod:`bladelab.study.executors`:
in-process, local process pool or Ray): the amputee with that blade is optimised at the first
prescribed speed, warm-started from ``init`` (or the controller's initial guess), then at each
higher speed warm-started from the previous speed's best, until the model falls (it "can no
longer run"). Per category:

- ``max_speed``: the highest mean speed [m/s] of a solution that ran the whole simulation;
- ``cot_4``: metabolic cost of transport [J/(kg·m)] of the 4 m/s solution (if it ran);
- ``t200``, ``t400``: 200 m and 400 m times [s] at the maximum speed (distance / speed).

Results: ``out/results.csv`` (tidy: category, speed, cost, fell, mean_speed, j_cot, ...) and
``out/summary.csv`` (one row per category), each task's optimisation under
``out/<category>/<speed>/``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from bladelab._io import atomic_open
from bladelab.errors import OptimizationError
from bladelab.runner.objective import ObjectiveSettings
from bladelab.runner.params import blade_category


def category_task(payload: dict) -> dict:
    """Run one category's speed chain (a top-level function for executors)."""
    from bladelab.runner.controller import read_parameters
    from bladelab.runner.predict import _model, optimize_controller

    cat = payload["category"]
    _, layout = _model("amputee", cat)
    x = read_parameters(payload["init"], layout, transfer=True) if payload.get("init") else None
    rows = []
    for speed in payload["speeds"]:
        res = optimize_controller(
            "amputee",
            blade=cat,
            speed=speed,
            x0=x,
            generations=payload["generations"],
            popsize=payload["popsize"],
            seed=payload["seed"],
            jobs=1,
            out=Path(payload["out"]) / cat / f"{speed:g}",
            settings=ObjectiveSettings(**payload["settings"]),
        )
        ev = res.best.to_dict()
        rows.append({"category": cat, "speed": speed, **ev, "generations": res.generations})
        if ev["fell"]:
            break
        x = res.x
    return {"category": cat, "rows": rows}


def _run_wave(ex, payloads: list[dict], bar) -> list[dict]:
    rows, failed = [], []
    for i, status, value in ex.run(category_task, payloads):
        if status != "ok":
            failed.append(f"{payloads[i]['category']}: {value}")
            continue
        bar.update(len(value["rows"]))
        rows.extend(value["rows"])
    if failed:
        raise OptimizationError("sweep task(s) failed: " + "; ".join(failed))
    return rows


def _chain(ex, base, categories, speeds, init, chain_from, bar) -> list[dict]:
    """Waves of first-speed optimisations outwards from ``chain_from``, then speed chains."""
    from bladelab.runner.params import blade_catalogue

    stiff = {name: c.stiffness_n_per_m for name, c in blade_catalogue().items()}
    ordered = sorted(categories, key=lambda c: stiff[blade_category(c).name])
    names = [blade_category(c).name for c in ordered]
    start = blade_category(chain_from).name
    if start not in names:
        raise OptimizationError(
            f"--chain-from {chain_from} is not among the categories", where="chain_from"
        )
    i0 = names.index(start)
    first = speeds[0]

    def best(cat: str) -> str:
        return str(Path(base["out"]) / cat / f"{first:g}" / "best.json")

    rows: list[dict] = []
    for dist in range(max(i0, len(ordered) - 1 - i0) + 1):
        wave = []
        for i in {i0 - dist, i0 + dist}:
            if 0 <= i < len(ordered):
                parent = None if dist == 0 else (i + 1 if i < i0 else i - 1)
                src = (str(init) if init else None) if parent is None else best(ordered[parent])
                wave.append({**base, "category": ordered[i], "speeds": [first], "init": src})
        rows.extend(_run_wave(ex, wave, bar))
    ran = {r["category"] for r in rows if not r["fell"]}
    rest = [
        {**base, "category": c, "speeds": speeds[1:], "init": best(c)}
        for c in ordered
        if c in ran and len(speeds) > 1
    ]
    if rest:
        rows.extend(_run_wave(ex, rest, bar))
    return rows


def summarise(results: pd.DataFrame) -> pd.DataFrame:
    """One row per category: max_speed [m/s], cot_4 [J/(kg·m)], t200 and t400 [s]."""
    out = []
    for cat, df in results.groupby("category", sort=False):
        ran = df[~df.fell.astype(bool)]
        vmax = float(ran.mean_speed.max()) if len(ran) else math.nan
        at4 = ran[np.isclose(ran.speed, 4.0)]
        out.append(
            {
                "category": cat,
                "max_speed": vmax,
                "cot_4": float(at4.j_cot.iloc[0]) if len(at4) else math.nan,
                "t200": 200.0 / vmax if vmax > 0 else math.nan,
                "t400": 400.0 / vmax if vmax > 0 else math.nan,
            }
        )
    return pd.DataFrame(out)


def run_sweep(
    categories: list[str],
    speeds: list[float],
    *,
    out: str | Path,
    init: str | Path | None = None,
    generations: int = 100,
    popsize: int = 16,
    seed: int = 1,
    jobs: int = 1,
    executor: str = "local",
    duration: float = 10.0,
    chain_from: str | None = None,
    progress: bool = True,
) -> pd.DataFrame:
    """Run the category × speed sweep; returns the per-category summary (see module docstring).

    Parameters
    ----------
    categories
        Blade categories (``Cat4`` ... ``Cat7``).
    speeds
        Prescribed speeds [m/s], raised in this order.
    out
        Output folder.
    init
        Warm start for the first speed of every category (parameters JSON).
    generations, popsize, seed
        CMA-ES settings of every task.
    jobs, executor
        Categories run in parallel on ``executor`` (``local``/``ray``) with ``jobs`` workers.
    duration
        Simulated time [s] of each evaluation.
    chain_from
        Warm-start categories from each other at the first speed, as seed 001 §2.2.2 B does:
        this category starts from ``init``, its softer and stiffer neighbours (catalogue order)
        from its solution, and so on outwards (each wave in parallel); then every category
        raises its speed independently. None: every category starts from ``init``.
    """
    from bladelab.study.executors import make_executor

    for c in categories:
        blade_category(c)
    if not speeds or any(not (s > 0) for s in speeds):
        raise OptimizationError("speeds must be positive", where="speeds")
    out = Path(out)
    speeds = sorted(float(s) for s in speeds)
    base = {
        "generations": generations,
        "popsize": popsize,
        "seed": seed,
        "out": str(out),
        "settings": ObjectiveSettings(duration=duration).to_dict(),
    }
    ex = make_executor(executor, jobs)
    bar = tqdm(total=len(categories) * len(speeds), desc="optimisations", disable=not progress)
    rows: list[dict] = []
    if chain_from is None:
        payloads = [
            {**base, "category": c, "speeds": speeds, "init": str(init) if init else None}
            for c in categories
        ]
        rows.extend(_run_wave(ex, payloads, bar))
    else:
        rows.extend(_chain(ex, base, categories, speeds, init, chain_from, bar))
    bar.close()
    order = {c: i for i, c in enumerate(categories)}
    results = pd.DataFrame(rows)
    results = results.sort_values(
        ["category", "speed"], key=lambda s: s.map(order) if s.name == "category" else s
    ).reset_index(drop=True)
    summary = summarise(results)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_open(out / "results.csv", "w", newline="") as fh:
        results.to_csv(fh, index=False)
    with atomic_open(out / "summary.csv", "w", newline="") as fh:
        summary.to_csv(fh, index=False)
    return summary


__all__ = ["category_task", "run_sweep", "summarise"]
