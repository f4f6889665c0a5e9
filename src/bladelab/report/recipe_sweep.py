"""The report sections of a recipe sweep (``bladelab sweep --recipe``, :mod:`bladelab.predict.reflex.recipe_sweep`).

Every finished level of every task is re-simulated (:func:`~bladelab.predict.reflex.recipe.level_row`:
10 s nominal and, for a gait that runs, the stable-gait acceptance), and the category table is
recomputed from these re-simulations, not read from ``summary.csv``; ``levels.json``'s stored
rows are compared with them.
"""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from bladelab._io import read_json
from bladelab.errors import InputFileError
from bladelab.predict.reflex.recipe import (
    LEVELS_NAME,
    RECIPE_NAME,
    Recipe,
    level_row,
    maximum_speed,
    settled_speed,
)
from bladelab.predict.reflex.recipe_sweep import category_agreement, summarise_levels
from bladelab.report.predictive_sections import seed001_results

__all__ = ["is_recipe_sweep", "recipe_sweep_sections"]

_COMPARED = ("cost", "mean_speed_m_per_s", "fell", "accepted")


def is_recipe_sweep(path: Path) -> bool:
    """Whether ``path`` is a ``bladelab sweep --recipe`` folder."""
    return path.is_dir() and (path / "levels.csv").is_file() and any(
        path.glob(f"*/seed-*/{LEVELS_NAME}"))


def _tasks(folder: Path) -> list[tuple[Path, dict, list[dict]]]:
    out = []
    for levels in sorted(folder.glob(f"*/seed-*/{LEVELS_NAME}")):
        task = levels.parent
        recipe = read_json(task / RECIPE_NAME, what="recipe task")
        rows = read_json(levels, what="levels of a recipe task")
        if not isinstance(rows, list):
            raise InputFileError("not a list of levels", file=levels)
        out.append((task, recipe, rows))
    return out


def _speeds_figure(levels: pd.DataFrame, verdicts: dict[str, str]):
    import matplotlib.pyplot as plt

    cats = list(dict.fromkeys(levels.category))
    fig, axes = plt.subplots(1, len(cats), figsize=(4.2 * len(cats), 3.6), squeeze=False,
                             sharey=True)
    for ax, cat in zip(axes[0], cats, strict=True):
        mine = levels[levels.category == cat]
        names = list(dict.fromkeys(mine.level))
        for seed, g in mine.groupby("seed"):
            xs = [names.index(n) for n in g.level]
            line, = ax.plot(xs, g.mean_speed_m_per_s, "-o", ms=4, label=f"seed {seed}")
            settled = [settled_speed(r) for r in g.to_dict("records")]
            ax.plot(xs, [math.nan if v is None else v for v in settled], "o", ms=6, mfc="none",
                    color=line.get_color())
            fell = g.fell.astype(bool).to_numpy()
            ax.plot([x for x, f in zip(xs, fell, strict=True) if f],
                    g.mean_speed_m_per_s[fell], "x", ms=9, color=line.get_color())
            ok = g.accepted.astype(bool).to_numpy()
            ax.plot([x for x, a in zip(xs, ok, strict=True) if a],
                    g.mean_speed_m_per_s[ok], "*", ms=13, color=line.get_color())
        ax.plot(range(len(names)), [mine[mine.level == n].prescribed_speed_m_per_s.iloc[0]
                                    for n in names], "k--", lw=0.8, label="prescribed")
        ax.set_xticks(range(len(names)), names, rotation=35, ha="right", fontsize=8)
        ax.set_title(f"{cat}: {verdicts.get(cat, '')}", fontsize=10)
        ax.set_xlabel("level")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("mean speed of the 10 s re-simulation (m/s)")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def recipe_sweep_sections(report, folder: Path, bar) -> tuple[pd.DataFrame, dict[str, Path]]:
    """Add the sweep's sections; return the recomputed category table and the parameter files
    of the gaits to show (per category, the fastest level of any seed that runs)."""
    tasks = _tasks(folder)
    rows, same = [], []
    last_stage = None
    for task, recipe, stored in tasks:
        last_stage = Recipe.from_dict(recipe["recipe"]).stages[-1].name
        for r in stored:
            again = {**r, **level_row(task / r["level"] / "best.json")}
            bar.update()
            rows.append(again)
            same.append(all(_same(r.get(k), again[k]) for k in _COMPARED))
    levels = pd.DataFrame(rows)
    summary = _beside_seed001(summarise_levels(levels, last_stage))
    verdicts, sentences = {}, []
    for cat, df in levels.groupby("category", sort=False):
        a = category_agreement(df, last_stage)
        if a is not None:
            verdicts[cat] = "settled" if a.settled else "not settled"
            sentences.append(f"{cat} at the recipe's speed ({last_stage}): {a.describe()}")
        else:
            verdicts[cat] = "not settled"
            sentences.append(f"{cat}: no seed's {last_stage} level runs its 10 s yet.")
    shown = {}
    for cat, df in levels.groupby("category", sort=False):
        speed, top = maximum_speed(df.to_dict("records"))
        if top is not None:
            shown[f"{cat} seed {top['seed']} {top['level']} ({speed:.2f} m/s at a quarter "
                  "of the step, fastest that runs at every step)"] = (
                folder / cat / f"seed-{top['seed']}" / top["level"] / "best.json")
    table = levels[["category", "seed", "level", "prescribed_speed_m_per_s",
                    "initial_speed_m_per_s", "generations", "mean_speed_m_per_s", "cost",
                    "fell", "swing_contact_peak_bw", "pelvis_tilt_mean_deg",
                    "judged_at_m_per_s", "nominal_meets_acceptance", "accepted",
                    "runs_at_half_step", "half_step_speed_m_per_s", "runs_at_quarter_step",
                    "quarter_step_speed_m_per_s", "step_speed_change_m_per_s"]].assign(
        **{"as in levels.json (yes/no)": same},
        # None where a level falls at that step; all None would print as "None"
        **{k: levels[k].astype(float) for k in ("half_step_speed_m_per_s",
                                                "quarter_step_speed_m_per_s",
                                                "step_speed_change_m_per_s")})
    table = table.rename(columns={
        "prescribed_speed_m_per_s": "prescribed speed (m/s)",
        "initial_speed_m_per_s": "initial speed (m/s)",
        "generations": "generations (count)",
        "mean_speed_m_per_s": "mean speed (m/s)", "cost": "cost (–)", "fell": "fell (yes/no)",
        "swing_contact_peak_bw": "largest swing contact (BW)",
        "pelvis_tilt_mean_deg": "pelvis tilt mean (deg)",
        "judged_at_m_per_s": "judged at (m/s)",
        "nominal_meets_acceptance": "nominal run meets the acceptance (yes/no)",
        "accepted": "meets the stable-gait acceptance (yes/no)",
        "runs_at_half_step": "runs 10 s at half the time step (yes/no)",
        "half_step_speed_m_per_s": "mean speed at half the time step (m/s)",
        "runs_at_quarter_step": "runs 10 s at a quarter of the time step (yes/no)",
        "quarter_step_speed_m_per_s": "mean speed at a quarter of the time step (m/s)",
        "step_speed_change_m_per_s": "speed change from half to a quarter of the step (m/s)"})
    report.add_section(
        "Recipe sweep: categories and seeds",
        text=("Each category was optimised by a recipe of CMA-ES stages per seed, then its "
              "speed raised by continuation on the speed reached (docs/predictive.md, "
              "'Recipes'). Every finished level is simulated again here for 10 s with its own "
              "settings and, if it runs, judged by the stable-gait acceptance at the speed it reached "
              "(4 copies moved by 1e-3 and ±5 % initial speed, each within 0.1 m/s of that "
              "speed, swing contacts ≤ 0.2 BW, mean pelvis tilt in −16…−2°); the table of "
              "categories comes from these re-simulations. A category "
              "has settled when at least 3 seeds agree at the recipe's speed (cost within 2 %, "
              "speed within 0.05 m/s of the best seed's). Speeds compared between seeds and "
              "the maximum speeds are settled speeds: the 10 s re-simulation at a quarter of "
              "the level's time step (at Newmark's 1 ms the gaits run 0.09–0.25 m/s faster "
              "than at finer steps, which still differ by a few hundredths of a m/s: the "
              "levels table gives the change from half to a quarter of the step); a level "
              "that falls at any of these steps is not compared. The maximum speed is "
              "the fastest settled speed of a level that meets the acceptance (last column "
              "of the categories table; '–': none does yet), beside the fastest of all."
              "\n\n" + " ".join(sentences)),
        figures=[("Speed reached per level and seed at the level's time step (filled) and at "
                  "a quarter of it (open: the settled speed; none where it falls at a finer "
                  "step); × fell in its 10 s re-simulation, ★ meets the stable-gait acceptance; "
                  "dashed: the prescribed speed",
                  _speeds_figure(levels, verdicts))],
        tables=[("Categories", summary), ("Levels, re-simulated", table)],
    )
    return summary, shown


def _beside_seed001(summary: pd.DataFrame) -> pd.DataFrame:
    """The category table with seed 001's maximum speed [m/s] beside ours (Table 3.1)."""
    seed = seed001_results()
    seed = seed[seed.quantity == "max_speed"].set_index("category").value
    col = summary.columns.get_loc("maximum speed (m/s)") + 1
    summary = summary.copy()
    summary.insert(col, "seed 001 maximum speed (m/s)",
                   [float(seed.get(c, math.nan)) for c in summary.category])
    return summary


def _same(a, b) -> bool:
    if isinstance(b, bool):
        return bool(a) == b
    try:
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-12)
    except (TypeError, ValueError):
        return False
