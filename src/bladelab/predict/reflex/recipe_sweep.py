"""The reflex category sweep: a recipe (:mod:`bladelab.predict.reflex.recipe`) per blade
category and seed, and whether each category's seeds agree.

Tasks (category × seed) run on an executor of :mod:`bladelab.executors`, one core each. After
every finished task the tables are rebuilt from every task folder on disk (finished levels of
unfinished tasks included), atomically:

- ``OUT/levels.csv``: one row per finished level of every task (:func:`level_row`'s values,
  prescribed and initial speed [m/s], generations, wall time [s]);
- ``OUT/summary.csv``: one row per category (:func:`summarise_levels`).

A category has settled when at least three seeds agree at the recipe's speed (the
last stage's gait, re-simulated nominally for 10 s with the same settings, so on the same
"copy"): costs within 2 % of the best seed's and settled speeds within 0.05 m/s
(:func:`~bladelab.predict.reflex.agreement.seed_agreement`). Speeds here are settled speeds
(:func:`~bladelab.predict.reflex.recipe.settled_speed`: at a quarter of the time step), and a
level that falls at any of its steps is not compared. The maximum speed is reported per seed with its
spread; it is not part of the verdict, because seeds that reach different speeds are not
compared on the same cost.
"""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd
from tqdm import tqdm

from bladelab._io import atomic_open, read_json
from bladelab.errors import OptimizationError
from bladelab.executors import make_executor
from bladelab.predict.reflex.agreement import seed_agreement
from bladelab.predict.reflex.recipe import (
    LEVELS_NAME,
    STABLE_GAIT_RECIPE,
    Recipe,
    maximum_speed,
    model_of,
    recipe_task,
    settled_speed,
)

__all__ = ["category_agreement", "run_recipe_sweep", "summarise_levels"]


def _levels_on_disk(out: Path) -> list[dict]:
    rows = []
    for path in sorted(out.glob(f"*/seed-*/{LEVELS_NAME}")):
        rows.extend(read_json(path, what="levels of a recipe task"))
    return rows


def _settled_levels(levels: pd.DataFrame, last_stage: str) -> pd.DataFrame:
    """The ``last_stage`` levels that settle in the time step, with their
    ``settled_speed_m_per_s``."""
    speeds = [settled_speed(r) for r in levels.to_dict("records")]
    levels = levels.assign(settled_speed_m_per_s=pd.Series(speeds, index=levels.index,
                                                           dtype=float))
    return levels[(levels.stage == last_stage) & levels.settled_speed_m_per_s.notna()]


def _agreement(base: pd.DataFrame):
    if not len(base):
        return None
    return seed_agreement(base.cost.tolist(), base.settled_speed_m_per_s.tolist())


def category_agreement(levels: pd.DataFrame, last_stage: str):
    """How one category's seeds agree at the recipe's speed: the
    :class:`~bladelab.predict.reflex.agreement.SeedAgreement` of the ``last_stage`` levels that
    ran their 10 s at every time step, on their settled speeds (None: none did)."""
    return _agreement(_settled_levels(levels, last_stage))


def summarise_levels(levels: pd.DataFrame, last_stage: str) -> pd.DataFrame:
    """Per category: the seeds whose ``last_stage`` level finished, their agreement at the
    recipe's speed (costs and settled speeds of that level; beside the seeds' speed spread,
    the largest change of those levels' speed from half to a quarter of the time step, which
    bounds what a spread below it means), and each seed's maximum speed
    [m/s] (fastest settled speed of a level that settles) with its spread and how many of
    them meet the stable-gait acceptance; and the fastest settled speed of a level that meets
    it (the maximum speed meeting the acceptance)."""
    cols = ["category", "seeds (count)", "agreeing seeds (count)", "settled (yes/no)",
            "cost spread (%)", "speed spread (m/s)",
            "largest speed change from half to a quarter of the step (m/s)",
            "best cost (–)", "speed of the best (m/s)",
            "maximum speed (m/s)", "maximum speed spread (m/s)",
            "maximum-speed gaits meeting the acceptance (count)",
            "maximum speed meeting the acceptance (m/s)"]
    out = []
    for cat, df in levels.groupby("category", sort=False):
        base = _settled_levels(df, last_stage)
        agreement = _agreement(base)
        tops = [maximum_speed(g.to_dict("records")) for _, g in df.groupby("seed")]
        speeds = [v for v, _ in tops if math.isfinite(v)]
        best = base.loc[base.cost.idxmin()] if len(base) else None
        out.append({
            "category": cat,
            "seeds (count)": int(df.seed.nunique()),
            "agreeing seeds (count)": sum(agreement.agreeing) if agreement else 0,
            "settled (yes/no)": bool(agreement and agreement.settled),
            "cost spread (%)": agreement.cost_spread_pct if agreement else math.nan,
            "speed spread (m/s)": agreement.speed_spread_m_per_s if agreement else math.nan,
            "largest speed change from half to a quarter of the step (m/s)": (
                float(base.step_speed_change_m_per_s.astype(float).max())
                if "step_speed_change_m_per_s" in base and len(base) else math.nan),
            "best cost (–)": float(best.cost) if best is not None else math.nan,
            "speed of the best (m/s)": (float(best.settled_speed_m_per_s) if best is not None
                                        else math.nan),
            "maximum speed (m/s)": max(speeds) if speeds else math.nan,
            "maximum speed spread (m/s)": (max(speeds) - min(speeds)) if speeds else math.nan,
            "maximum-speed gaits meeting the acceptance (count)":
                sum(bool(r and r["accepted"]) for _, r in tops),
            "maximum speed meeting the acceptance (m/s)":
                maximum_speed(df.to_dict("records"), accepted=True)[0],
        })
    return pd.DataFrame(out, columns=cols)


def _write_tables(out: Path, recipe: Recipe) -> pd.DataFrame:
    levels = pd.DataFrame(_levels_on_disk(out))
    summary = (summarise_levels(levels, recipe.stages[-1].name) if len(levels)
               else summarise_levels(pd.DataFrame(columns=["category", "stage", "fell", "seed"]),
                                     recipe.stages[-1].name))
    with atomic_open(out / "levels.csv") as fh:
        levels.to_csv(fh, index=False)
    with atomic_open(out / "summary.csv") as fh:
        summary.to_csv(fh, index=False)
    return summary


def run_recipe_sweep(
    categories: list[str],
    seeds: list[int],
    *,
    out: str | Path,
    recipe: Recipe = STABLE_GAIT_RECIPE,
    init: str | Path | None = None,
    track_study: str | Path | None = None,
    jobs: int = 1,
    executor: str = "local",
    checkpoint_every: int = 5,
    progress: bool = True,
) -> pd.DataFrame:
    """Run (or continue) ``recipe`` for every category × seed in ``out`` (module docstring;
    ``"able"`` among the categories: the able-bodied runner);
    returns the per-category summary. ``jobs`` tasks run at once on ``executor``; a task that
    fails is named in the error raised after the others finished (their results are kept)."""
    for c in categories:
        model_of(c)
    if not seeds:
        raise OptimizationError("no seeds", where="--seeds")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    payloads = [{"category": c, "seed": int(s), "out": str(out.resolve()),
                 "recipe": recipe.to_dict(), "init": str(Path(init).resolve()) if init else None,
                 "track_study": str(Path(track_study).resolve()) if track_study else None,
                 "checkpoint_every": int(checkpoint_every), "announce": bool(progress)}
                for c in categories for s in seeds]
    ex = make_executor(executor, jobs)
    failed = []
    with tqdm(total=len(payloads), desc="recipe tasks (category × seed)", unit="task",
              disable=not progress) as bar:
        for i, status, value in ex.run(recipe_task, payloads):
            if status != "ok":
                failed.append(f"{payloads[i]['category']} seed {payloads[i]['seed']}: {value}")
            _write_tables(out, recipe)
            bar.update(1)
    summary = _write_tables(out, recipe)
    if failed:
        raise OptimizationError("recipe task(s) failed: " + "; ".join(failed))
    return summary
