"""The whole collocation category study, from its stored files.

Six models (able, amputee Cat4, Cat5, Cat6, Cat6High, Cat7) × speed continuation (4, 5 m/s)
+ maximum speed, 2 workers: on the human body from the shipped strides with one start per
problem (the stride time free, and held at people's band, the latter with the settling pass
from the neighbouring categories' strides, before and after the vasti change); on seed 001's
body from the
measured trial's guess, once with one start per problem,
once with three (``--starts 3``: the warm start, the barrier start and the template). Target:
≤ 10 min on 2 cores with three starts. The studies take 20–50 min of both cores, so ``make bench`` does not run
them again: it reads the solve times each recorded (its ``collocation-sweep.csv``) and the wall
time from ``timing.json`` beside it. To measure anew, run the ``command`` of a study's
``timing.json`` and write the wall time, date and host into it (keys ``wall_s``, ``date``,
``host``, ``command``).
"""

from __future__ import annotations

import json
from pathlib import Path

HERE = Path(__file__).resolve().parent / "collocation"
#: (folder, what differs) of each timed study.
STUDIES = (("study-human-soleus-three-starts-2026-12-07", "the human body as shipped, with the "
            "soleus at its running length (tendon slack length 0.25 m), three starts for every "
            "problem as in the study below; the rows are the kept starts', the wall time both "
            "passes'"),
           ("study-human-three-starts-2026-12-06", "the human body with the soleus tendon at "
            "0.2655 m, three starts for every problem (the first pass from the shipped strides, then the settling pass: "
            "each amputee problem from the two nearest categories' strides, the able runner "
            "from its own other strides or its shipped one), the predictive stages' L-BFGS "
            "update inside IPOPT's augmented system (the library's since 2026-12-06); the "
            "rows are the kept starts', the wall time both passes'"),
           ("study-human-three-starts-2026-12-05", "the same three starts per problem, the "
            "L-BFGS update by IPOPT's default (Sherman-Morrison) route; the same study on "
            "2026-12-06, bit-identical iterations and answers, took 13.6 min on the same host "
            "(1,505 s of solver time against 1,206 s: the host's own spread)"),
           ("study-human-timed-2026-12-05", "the human body as shipped since 2026-12-03 (the "
            "toes' damper, people's swing knee held), at people's stride time, people's joint "
            "angles at weight 10 1/rad², one start per problem from the shipped strides, then "
            "the settling pass (`--settle`); the rows are the kept starts', the wall time both "
            "passes'"),
           ("study-human-vasti16-2026-12-01", "the human body with the vasti's series "
            "elasticity at 16 % (since 2026-12-01), at people's stride time, people's joint "
            "angles at weight 10 1/rad², one start per problem from the shipped strides, then "
            "the settling pass (`--settle`: the amputees from their neighbouring categories' "
            "strides, the able runner from its own faster ones); the rows are the kept "
            "starts', the wall time both passes'"),
           ("study-human-settled-2026-12-01", "the human body with the vasti tendon at 8 % "
            "(2026-12-01), at people's stride time, people's joint angles at weight "
            "10 1/rad², one start per problem from the shipped strides, then the settling pass "
            "(`--settle`); the rows are the kept starts', the wall time both passes'"),
           ("study-human-people-cadence-2026-11-30", "the human body at people's stride time "
            "(`--stride-time people`: every prescribed speed's stride time within measured "
            "runners' band at that speed; the maximum speed free), people's joint angles at "
            "weight 10 1/rad², one start per problem, from the shipped strides, the node "
            "function compiled, then the settling pass (`--settle`: each amputee problem "
            "solved again from the neighbouring categories' kept strides; the rows are the "
            "kept starts', the wall time both passes')"),
           ("study-human-people10-2026-11-29", "the human body with people's joint angles in "
            "the objective at weight 10 1/rad² (the default), one start per problem, from the "
            "shipped strides, each later speed from the previous solution's primal and dual "
            "values"),
           ("study-human-2026-11-29", "the human body, one start per problem, from the shipped "
            "free strides of the time (`--guess stored`), each later speed from the previous "
            "solution's primal and dual values, no people's angles (`--people-weight 0`)"),
           ("study-timed-2026-11-26", "seed 001's body, one start per problem, from the "
            "measured trial's guess"),
           ("study-starts3-timed-2026-11-26", "seed 001's body, three starts per problem "
            "(`--starts 3`), from the measured trial's guess"))


def run() -> str:
    parts = [
        "## Collocation: the whole category study",
        "",
        "Six models × speed continuation (4, 5 m/s) + maximum speed, mesh 50, `--jobs 2`; the "
        "body and first guess per study below. Target: ≤ 10 min on 2 cores with three starts "
        "per problem. Times are those the "
        "studies recorded (`collocation-sweep.csv`, `timing.json`), not measured again by "
        "`make bench`; a solve that does not converge is tried again from an intermediate "
        "speed (its row counts). ✓ converged, ⚠ converged but flagged by the gait checks (a "
        "hop, a stride on its 0.4 s bound, a double contact, a peak above 8 BW: not a running "
        "gait), ✗ not converged.",
    ]
    for folder, what in STUDIES:
        parts += ["", _study(HERE / folder, what)]
    return "\n".join(parts)


def _study(study: Path, what: str) -> str:
    table = study / "collocation-sweep.csv"
    title = f"### {what[:1].upper()}{what[1:]}"
    if not table.is_file():
        return f"{title}\n\nNo study in {study.name}: run it first (docstring)."
    import pandas as pd

    df = pd.read_csv(table).copy()  # one block: the columns added below
    converged = df.converged.astype(bool)
    df["mark"] = "✓"
    df.loc[df.warnings.fillna("").astype(str).str.len().gt(0), "mark"] = "⚠"
    df.loc[~converged, "mark"] = "✗"
    info = json.loads((study / "timing.json").read_text(encoding="utf-8"))
    # every start's solve in the model folders (several starts or a settling pass)
    walls = [json.loads(f.read_text(encoding="utf-8")).get("wall_s") or 0.0
             for f in study.glob("*/*.json")]
    n_files, all_walls = len(walls), sum(walls)
    residual = pd.to_numeric(df.dynamics_residual_pct, errors="coerce")
    rows = []
    for model, part in df.groupby("model", sort=False):
        rows.append(f"| {model} | {int((part.mark != '✗').sum())} of {len(part)} | "
                    f"{part.wall_s.sum():.0f} s | {int(part.iterations.sum())} | "
                    f"{', '.join(_problem(r) for r in part.itertuples())} |")
    return "\n".join([
        title,
        "",
        "| quantity | value |",
        "|---|---|",
        f"| study wall time, 2 workers | **{info['wall_s'] / 60:.1f} min** ({info['date']}, "
        f"{info['host']}) |",
        f"| solver time of the kept solves, both workers together | "
        f"{df.wall_s.sum() / 60:.1f} min |",
        *([f"| solver time of every start's solve ({n_files} solves) | "
           f"{all_walls / 60:.1f} min |"] if n_files > len(df) else []),
        f"| problems converged | {int(converged.sum())} of {len(df)} |",
        f"| … of which flagged by the gait checks | {int((df.mark == '⚠').sum())} |",
        f"| kept solves with a dynamics residual above 1 % | {int((residual > 1).sum())} "
        f"(largest {residual.max():.2f} %) |",
        "",
        "| model | problems converged | solver time (kept solves) | IPOPT iterations | problems "
        "(converged ✓, flagged ⚠) |",
        "|---|---|---|---|---|",
        *rows,
        "",
        f"Command: `{info['command']}`.",
    ])


def _problem(row) -> str:
    name = ("max" if row.problem == "max-speed"
            else f"{row.prescribed_speed_mps:g} m/s")
    return f"{name} {row.mark}"
