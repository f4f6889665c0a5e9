"""The 25-run design studies on predicted amputee strides, from their stored files: the
transfemoral runner's free gait and knee-safe one (the knee's extension moment kept at or
above 0), and the transtibial runner's on the human body.

The study takes about half an hour of both cores, so ``make bench`` does not run it again: it
reads the solve times and iterations of every design's stride in the committed study folder
(each stride file records its own), and the study's wall time from ``timing.json`` written
beside it (``bladelab design`` run as in docs/design.md). Run the study again to measure anew::

    bladelab design --evaluator collocation --jobs 2 --out benchmarks/design/transfemoral-collocation-4mps
    bladelab design --evaluator collocation --jobs 2 --knee-moment-min 0 \
        --start benchmarks/collocation/transfemoral-2026-11-26/knee-safe-centre-4.json \
        --out benchmarks/design/transfemoral-collocation-4mps-knee-safe
    bladelab design --evaluator collocation --amputation transtibial --runs ccd --jobs 2 \
        --settle 2 --skip-failed --objective cost_of_transport_J_per_kg_m --sense min \
        --out benchmarks/design/transtibial-collocation-4mps
    bladelab design --evaluator collocation --amputation transtibial --stride-time people \
        --runs ccd --jobs 2 --settle 2 --skip-failed \
        --objective cost_of_transport_J_per_kg_m --sense min \
        --out benchmarks/design/transtibial-collocation-4mps-people-stride
    (the same command, --settle 3, for transtibial-people-stride-soleus-2026-12-07)
    bladelab design --evaluator collocation --amputation transtibial --max-speed \
        --start-strides benchmarks/design/transtibial-collocation-4mps/strides \
        --runs ccd --jobs 2 --settle 6 --skip-failed \
        --objective max_speed_m_per_s --sense max \
        --out benchmarks/design/transtibial-collocation-max-speed
    bladelab design --evaluator collocation --amputation transtibial --max-speed \
        --stride-time people \
        --start-strides benchmarks/design/transtibial-collocation-4mps-people-stride/strides \
        --runs ccd --jobs 2 --settle 3 --skip-failed \
        --objective max_speed_m_per_s --sense max \
        --out benchmarks/design/transtibial-collocation-max-speed-people-stride
    (the same command from transtibial-people-stride-soleus-2026-12-07/strides for
    transtibial-max-speed-people-stride-soleus-2026-12-07)
    (transtibial-sprinter-6mps-2026-12-07: the command in its README)

Studies since the study timing record write their own ``timing.json`` (each sitting of each
stage, :mod:`bladelab.design.timing`); older ones hold their times written by hand.

Each study's designer responses are fitted twice from its ``results.csv``: the full quadratic
and the reduced one (:mod:`bladelab.design.reduction`), with the reduced surface's predicted R²
both as usual and with the term choice repeated in each leave-one-out fold.
"""

from __future__ import annotations

import json
from pathlib import Path

_DESIGN = Path(__file__).resolve().parent / "design"
#: (folder, runner, what distinguishes it)
STUDIES = (
    (_DESIGN / "transfemoral-collocation-4mps", "transfemoral", "free gait"),
    (_DESIGN / "transfemoral-collocation-4mps-knee-safe", "transfemoral",
     "knee-safe: knee moment ≥ 0 N·m on every mesh interval (`--knee-moment-min 0`)"),
    (_DESIGN / "transtibial-collocation-4mps", "transtibial",
     "human body, people's joint angles and swing knee (`--amputation transtibial`)"),
    (_DESIGN / "transtibial-collocation-4mps-people-stride", "transtibial",
     "human body, people's joint angles, swing knee and stride time (`--amputation "
     "transtibial --stride-time people`)"),
    (_DESIGN / "transtibial-people-stride-soleus-2026-12-07", "transtibial",
     "the human body as shipped (the soleus at its running length), people's joint angles, "
     "swing knee and stride time (`--amputation transtibial --stride-time people`)"),
    (_DESIGN / "transtibial-collocation-max-speed", "transtibial",
     "human body, each design's maximum speed (`--amputation transtibial --max-speed`)"),
    (_DESIGN / "transtibial-collocation-max-speed-people-stride", "transtibial",
     "human body, each design's maximum speed at people's stride time (`--amputation "
     "transtibial --max-speed --stride-time people`)"),
    (_DESIGN / "transtibial-max-speed-people-stride-soleus-2026-12-07", "transtibial",
     "the human body as shipped (the soleus at its running length), each design's maximum "
     "speed at people's stride time (`--amputation transtibial --max-speed --stride-time "
     "people`)"),
    (_DESIGN / "transtibial-sprinter-6mps-2026-12-07", "transtibial",
     "an amputee sprinter at 6 m/s, the body as shipped, people's joint angles, swing knee "
     "and stride time (`--amputation transtibial --speed 6 --mesh 100 --stride-time people "
     "--muscle-strength 1.5 --max-shortening-velocity 15 --prosthesis-extra-length 0.045`)"),
)
#: The responses a designer asks for, fitted in each study that has them.
DESIGNER_RESPONSES = ("cost_of_transport_J_per_kg_m", "max_speed_m_per_s", "stride_objective",
                      "socket_moment_max_Nm", "blade_moment_max_Nm")


def run() -> str:
    return "\n\n".join(_study(*study) for study in STUDIES)


def _study(study: Path, runner: str, what: str) -> str:
    strides = sorted((study / "strides").glob("*.json"))
    strides = [p for p in strides
               if not p.name.endswith((".best_iterate.json", ".previous.json"))]
    if not strides:
        return (f"## Design study on predicted {runner} strides: {what}\n\n"
                f"No study in {study.relative_to(study.parents[2])}: run it first (docstring).")
    from bladelab.design.settling import is_settled, read_settling_record
    from bladelab.predict.collocation.solution import CollocationSolution

    rows, flagged = [], 0
    for p in strides:  # each file read once: its solve's record and today's gait checks
        sol = CollocationSolution.read(p)
        flagged += bool(sol.gait_warnings())
        rows.append((p.stem, float(sol.nlp.wall_s), int(sol.nlp.iterations), sol.guess_source))
    from bladelab.design.timing import RUNS_STAGE, stage_walls

    timing = study / "timing.json"
    info = json.loads(timing.read_text(encoding="utf-8")) if timing.is_file() else {}
    stages = stage_walls(study)  # recorded by the study itself (older studies: by hand)
    if RUNS_STAGE in stages:
        info = {"wall_s": stages[RUNS_STAGE]["wall_s"],
                "date": f"recorded by the study, {stages[RUNS_STAGE]['sittings']} sitting(s), "
                        f"{stages[RUNS_STAGE]['jobs']} workers"}
    walls = sorted(r[1] for r in rows)
    lines = [
        f"## Design study on predicted {runner} strides: {what}",
        "",
        "25-run face-centred CCD over seed 002's four factors, `--evaluator collocation` "
        f"({runner} runner wearing each generated 6-link blade, {_speed(study)}, backward "
        "Euler for the blade's joints), `--jobs 2`. Target: the study ≤ 30 min on 2 cores. "
        "Times are those the study recorded (its stride files and `timing.json`), not measured "
        "again by `make bench`.",
        "",
        "| quantity | value |",
        "|---|---|",
        f"| study wall time, 2 workers | {info.get('wall_s', float('nan')) / 60:.1f} min "
        f"({info.get('date', 'date not recorded')}) |",
        f"| designs solved (strides stored; a design whose problem is the built-in start's "
        f"reads it back) | "
        f"{len(rows)} |",
        f"| … of which flagged by today's gait checks (left out of the report's surfaces) | "
        f"{flagged} |",
        f"| designs with no clean stride (`--skip-failed`: runs/*.failed.json, failed.csv) | "
        f"{len(list((study / 'runs').glob('*.failed.json')))} |",
        f"| time per design point, one core: median | {walls[len(walls) // 2]:.0f} s |",
        f"| time per design point: min … max | {walls[0]:.0f} … {walls[-1]:.0f} s |",
        f"| IPOPT iterations per design: median | "
        f"{sorted(r[2] for r in rows)[len(rows) // 2]} |",
    ]
    for rec in read_settling_record(study):
        if rec["complete"]:
            starts = ("the 2 nearest strides and the cheapest" if rec.get("from_cheapest")
                      else "the 2 nearest strides")
            lines.append(f"| settling pass {rec['pass']} (`--settle`, from {starts}) | "
                         f"{rec['improved']} of {len(rec['designs'])} designs improved, largest "
                         f"objective drop {100 * rec['largest_objective_drop']:.1f} % ("
                         + ("settled: at most 1 %" if is_settled([rec])
                            else "not settled: above 1 %") + ") |")
        else:
            lines.append(f"| settling pass {rec['pass']} | stopped after "
                         f"{len(rec['designs'])} designs (resumes with `--settle`) |")
    settle = {k: v for k, v in stages.items() if k != RUNS_STAGE}
    for stage, w in settle.items():
        lines.append(f"| {stage} wall time, {w['jobs']} workers (recorded) | "
                     f"{w['wall_s'] / 60:.1f} min for {w['designs']} designs |")
    if settle or RUNS_STAGE in stages:
        total = sum(w["wall_s"] for w in stages.values())
        lines.append(f"| **whole study** (runs and settling passes, recorded) | "
                     f"**{total / 60:.1f} min** |")
    elif info.get("settle_wall_s"):
        lines.append(f"| settling pass wall time, 2 workers | {info['settle_wall_s'] / 60:.0f} "
                     f"min ({info.get('settle_note', '')}) |")
    lines += ["", "Per-design times are those of the kept strides: after settling, a stride's "
              "solve may have run on a machine shared with other work.", "",
              *_surfaces(study)]
    return "\n".join(lines)


def _speed(study: Path) -> str:
    """The study's speed and mesh in words, from its ``evaluator.json``."""
    path = study / "evaluator.json"
    ev = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}
    speed = ("each design's maximum speed" if ev.get("max_speed")
             else f"{ev.get('speed_mps') or 4:g} m/s")
    athlete = ", the athlete " + ", ".join(f"{k} {v:g}" for k, v in ev["athlete"].items()) \
        if ev.get("athlete") else ""
    return f"{speed}{athlete}, mesh {ev.get('mesh_intervals', 50)}"


def _surfaces(study: Path) -> list[str]:
    """The designer responses' fits: full quadratic and reduced (module docstring)."""
    import pandas as pd

    from bladelab.design.reduction import fit_reduced
    from bladelab.design.space import DesignSpace
    from bladelab.design.surfaces import fit_surface

    results = study / "results.csv"
    if not results.is_file():
        return []
    table = pd.read_csv(results)
    space = DesignSpace.from_dict(json.loads((study / "study.json").read_text())["space"])
    coded = table[[f"{n}_coded" for n in space.names]].to_numpy(float)
    lines = ["| response | R²pred, full quadratic (15 terms) | reduced: terms | R²pred | "
             "R²pred, the choice repeated in each fold |", "|---|---|---|---|---|"]
    for name in (r for r in DESIGNER_RESPONSES if r in table):
        y = table[name].to_numpy(float)
        full = fit_surface(coded, y, factor_names=space.names)
        reduced = fit_reduced(coded, y, factor_names=space.names)
        lines.append(f"| {name} | {full.r2_pred:.2f} | {len(reduced.terms)} | "
                     f"{reduced.r2_pred:.2f} | {reduced.r2_pred_selected:.2f} |")
    return lines
