"""The whole collocation category study (issue 15), from its stored files.

Six models (able, amputee Cat4, Cat5, Cat6, Cat6High, Cat7) × speed continuation (4, 5 m/s)
+ maximum speed, from the measured trial's guess, one start per problem, 2 workers. Target:
≤ 30 min on 2 cores. The study takes a quarter of an hour of both cores, so ``make bench``
does not run it again: it reads the solve times the study recorded (its
``collocation-sweep.csv``) and the wall time from ``timing.json`` beside it. To measure anew::

    bladelab sweep --method collocation --categories Cat4,Cat5,Cat6,Cat6High,Cat7 --able \\
        --speeds 4,5 --guess trial --jobs 2 --out benchmarks/collocation/study-timed-2026-11-26

and write the wall time, date and host into ``timing.json`` (keys ``wall_s``, ``date``,
``host``, ``command``).
"""

from __future__ import annotations

import json
from pathlib import Path

STUDY = Path(__file__).resolve().parent / "collocation" / "study-timed-2026-11-26"


def run() -> str:
    table = STUDY / "collocation-sweep.csv"
    title = "## Collocation: the whole category study (issue 15)"
    if not table.is_file():
        return f"{title}\n\nNo study in {STUDY.name}: run it first (docstring)."
    import pandas as pd

    df = pd.read_csv(table)
    # ✓ converged, ⚠ converged but flagged by the gait checks (not a running gait: one start
    # per problem is the timed study, the best of several the answer), ✗ not converged
    converged = df.converged.astype(bool)
    df["mark"] = "✓"
    df.loc[df.warnings.fillna("").astype(str).str.len().gt(0), "mark"] = "⚠"
    df.loc[~converged, "mark"] = "✗"
    info = json.loads((STUDY / "timing.json").read_text(encoding="utf-8"))
    rows = []
    for model, part in df.groupby("model", sort=False):
        rows.append(f"| {model} | {int((part.mark != '✗').sum())} of {len(part)} | {part.wall_s.sum():.0f} s | "
                    f"{int(part.iterations.sum())} | "
                    f"{', '.join(_problem(r) for r in part.itertuples())} |")
    return "\n".join([
        title,
        "",
        "Six models × speed continuation (4, 5 m/s) + maximum speed, mesh 50, from the "
        "Fukuchi trial's guess, one start per problem, `--jobs 2`. Target: ≤ 30 min on 2 "
        "cores. Times are those the study recorded (`collocation-sweep.csv`, `timing.json`), "
        "not measured again by `make bench`; a solve that does not converge is tried again "
        "from an intermediate speed (its row counts).",
        "",
        "| quantity | value |",
        "|---|---|",
        f"| study wall time, 2 workers | **{info['wall_s'] / 60:.1f} min** ({info['date']}, "
        f"{info['host']}) |",
        f"| solver time, both workers together | {df.wall_s.sum() / 60:.1f} min |",
        f"| solves converged | {int(converged.sum())} of {len(df)} |",
        f"| … of which flagged by the gait checks (a hop, a stride on its 0.4 s bound, a "
        f"double contact, a peak above 8 BW) | {int((df.mark == '⚠').sum())} |",
        "",
        "| model | solves converged | solver time | IPOPT iterations | problems (converged ✓, "
        "flagged ⚠) |",
        "|---|---|---|---|---|",
        *rows,
        "",
        f"Command: `{info['command']}`.",
    ])


def _problem(row) -> str:
    name = ("max" if row.problem == "max-speed"
            else f"{row.prescribed_speed_mps:g} m/s")
    return f"{name} {row.mark}"
