"""The sections of a design report that describe a collocation study's predicted strides.

:func:`strides_section` (the stride problem posed, each run's stride checked again),
:func:`settling_text` (whether the strides have settled, and the study's wall time),
:func:`collocation_start_spread` and :func:`spread_section` (what the solver's start decides:
the responses' spread between strides of one design against their spread across designs),
:func:`settling_effects_section` (each factor's effect after the runs and after each settling
pass), :func:`gallop_text` and :func:`people_text` (the strides against people's running).
:mod:`bladelab.report.design` assembles them into the report.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from bladelab.design.plots import effects_by_stage_plot
from bladelab.design.responses import MAX_SPEED_RESPONSE_UNITS, PREDICTED_RESPONSE_UNITS
from bladelab.design.settling import (
    RECORD_NAME,
    is_settled,
    objective_drop,
    read_settling_record,
)
from bladelab.design.settling_effects import (
    RESOLVED_P,
    effects_by_stage,
    effects_summary,
    last_stage_moves,
    settling_stages,
)
from bladelab.design.start_spread import NEAR_PCT, start_spread
from bladelab.design.timing import stage_walls
from bladelab.predict.collocation.human_running import gallop_sentence
from bladelab.predict.collocation.solution import RESIDUAL_WARNING_PCT

__all__ = ["COLLOCATION_UNITS", "ROUGH_SPREAD_DESIGNS", "collocation_start_spread",
           "gallop_text", "people_text", "problem_posed", "settling_effects_section",
           "settling_text", "spread_section", "strides_section", "timing_text"]

#: The units of the collocation evaluator's responses (either problem).
COLLOCATION_UNITS = {**PREDICTED_RESPONSE_UNITS, **MAX_SPEED_RESPONSE_UNITS}


def problem_posed(evaluator: dict) -> str:
    """One sentence on the stride problem every design was solved with."""
    speed = evaluator.get("speed_mps")
    text = (f"Every design's stride is a periodic stride at {speed:g} m/s "
            if isinstance(speed, int | float) else "Every design's stride is a periodic stride ")
    weight = evaluator.get("reference_weight") or 0.0
    if evaluator.get("max_speed"):
        text = ("Every design's stride is the periodic stride of the maximum-speed problem "
                "(its mean speed, max_speed_m_per_s, is the design's maximum speed): the "
                "negative mean speed plus activation and acceleration effort minimised, the "
                "stride time free")
        if evaluator.get("people_weight"):
            text += (f", people's measured hip, knee and ankle angles at "
                     f"{evaluator['people_weight']:g} /rad² × their mean squared deviation in "
                     "the objective")
    elif weight > 0:
        text += ("of least metabolic cost and effort, with the athlete's own joints (trunk, "
                 "intact leg, residual hip) kept near the start stride's: "
                 f"{weight:g} /rad² × their mean squared deviation added to the objective "
                 "(the same technique on every blade; the prosthetic knee and the blade move "
                 "freely)")
    elif evaluator.get("people_weight"):
        text += ("of least metabolic cost and effort, with people's measured hip, knee and "
                 f"ankle angles at {evaluator['people_weight']:g} /rad² × their mean squared "
                 "deviation in the objective (a small tracking term of measured running)")
    else:
        text += "of least metabolic cost and effort, the gait predicted freely"
    if evaluator.get("knee_moment_min_Nm") is not None:
        text += (f"; the prosthetic knee's extension moment held at or above "
                 f"{evaluator['knee_moment_min_Nm']:g} N·m")
    if evaluator.get("stride_time_people"):
        text += ("; the stride time held within measured runners' band at the speed (an "
                 "athlete's cadence imposed, not predicted)")
    elif evaluator.get("stride_time_range_s"):
        lo, hi = evaluator["stride_time_range_s"]
        text += (f"; the stride time held within {lo:g}–{hi:g} s (imposed, not predicted)"
                 if lo != hi else f"; the stride time fixed at {lo:g} s (imposed, not "
                                  "predicted)")
    return text + ". "


def strides_section(checks: pd.DataFrame, evaluator: dict) -> dict[str, Any]:
    """The predicted strides of a collocation study: the problem posed, and each run's stride
    as checked now."""
    flagged = checks[checks["excluded"]]
    missing = int(checks["stride"].isna().sum())
    text = (problem_posed(evaluator)
            + "Each run's stride file checked again by today's gait checks (no swinging foot "
            "striking the ground, flight in each step, peak vertical force, dynamics residual "
            f"against the forward model at most {RESIDUAL_WARNING_PCT:g} %). "
            f"{len(checks) - len(flagged) - missing} of {len(checks)} strides are clean; "
            + (f"{len(flagged)} carry warnings and are left out of the surfaces"
               if len(flagged) else "none carries warnings")
            + (f"; {missing} stride files were not found (their runs are kept, unchecked)"
               if missing else "") + ".")
    gallops = gallop_text(checks)
    if gallops:
        text += " " + gallops
    people = people_text(checks)
    if people:
        text += " " + people
    shown = checks.assign(stride=checks["stride"].notna(),
                          step_phase=100.0 * checks["step_phase"])
    if "criteria" in shown:
        shown = shown.assign(criteria_met=[
            f"{m:.0f} of {n:.0f}" if pd.notna(n) else "–"
            for m, n in zip(shown["criteria_met"], shown["criteria"], strict=True)]).drop(
            columns=["criteria"])
    shown = shown.drop(columns=["excluded"]).rename(
        columns={"stride": "file found", "dynamics_residual_pct": "dynamics residual (%)",
                 "step_phase": "step phase (% of the stride)",
                 "criteria_met": "criteria of people's running met",
                 "outside_people": "outside people's running"})
    tables = [("Strides (files in the study's strides folder, named by the design point)",
               shown)]
    if len(flagged):
        tables.insert(0, ("Runs left out", flagged[["run", "warnings"]]))
    return {"title": "Design study: predicted strides", "text": text, "tables": tables}


def settling_text(design_dir: Path) -> str:
    """Whether a collocation study's strides have settled, from its settling record
    (:mod:`bladelab.design.settling`): the passes, the last one's largest drop, an unfinished
    pass."""
    if not (design_dir / RECORD_NAME).is_file():
        return ("Not settled: no settling pass was run (--settle); each stride is one local "
                "optimum.")
    passes = read_settling_record(design_dir)
    done = [p for p in passes if p.get("complete")]
    text = f"Settling: {len(done)} complete pass{'es' if len(done) != 1 else ''}"
    cheapest = [str(p["pass"]) for p in passes if p.get("from_cheapest")]
    if cheapest:
        text += (f" (pass{'es' if len(cheapest) > 1 else ''} {', '.join(cheapest)} also from "
                 "the study's cheapest stride, besides each design's two nearest)")
    if done:
        last = done[-1]
        n_lowered = last.get("improved", 0)
        text += (f"; the last lowered {n_lowered} objective{'s' if n_lowered != 1 else ''}, "
                 f"the largest by {100 * last['largest_objective_drop']:.2f} %" if n_lowered
                 else "; the last lowered no objective")
    open_pass = next((p for p in passes if not p.get("complete")), None)
    if open_pass is not None:
        drops = [objective_drop(r) for r in open_pass["designs"]
                 if r.get("before") and r.get("after") is not None]
        text += (f"; pass {open_pass['pass']} stopped after {len(open_pass['designs'])} designs"
                 + (f" (largest drop {100 * max(drops):.2f} %)" if drops else ""))
    text += (": settled (below 1 %)." if is_settled(passes) else
             ": not settled, the responses may still move (resume with --settle).")
    return text + timing_text(design_dir)


def timing_text(design_dir: Path) -> str:
    """" The study took …": its recorded wall time by stage (:mod:`bladelab.design.timing`);
    "" when it recorded none."""
    stages = stage_walls(design_dir)
    if not stages:
        return ""
    total = sum(w["wall_s"] for w in stages.values())
    parts = "; ".join(f"{stage} {w['wall_s'] / 60:.0f} min" for stage, w in stages.items())
    jobs = max(w["jobs"] for w in stages.values())
    return (f" The study took {total / 60:.0f} min of wall time with {jobs} worker"
            f"{'s' if jobs > 1 else ''} ({parts}).")


def people_text(checks: pd.DataFrame) -> str:
    """How the study's strides compare with people's running: how many meet every criterion
    (:func:`~bladelab.predict.collocation.human_running.human_running_criteria`) and which
    criteria are missed by how many strides; "" when no stride was checked."""
    if "criteria" not in checks or checks["criteria"].isna().all():
        return ""
    done = checks[checks["criteria"].notna()]
    every = int((done["criteria_met"] == done["criteria"]).sum())
    missed: dict[str, int] = {}
    for names in done["outside_people"]:
        for name in filter(None, str(names).split("; ")):
            missed[name] = missed.get(name, 0) + 1
    text = (f"Against people's running (the criteria of a predicted stride's own report): "
            f"{every} of {len(done)} strides meet every criterion")
    if missed:
        text += ". Missed: " + "; ".join(
            f"{name} by {n}" for name, n in sorted(missed.items(), key=lambda kv: -kv[1]))
    return text + "."


def gallop_text(checks: pd.DataFrame | None) -> str:
    """How many of a collocation study's strides gallop (:func:`~bladelab.predict.
    collocation.human_running.gallop_sentence`); "" when none does or there are no strides.
    A gallop is a converged stride, not a gait warning: it stays in the surfaces, and the
    report says what they then describe."""
    if checks is None or "step_phase" not in checks:
        return ""
    return gallop_sentence(100.0 * checks["step_phase"].astype(float))


def collocation_start_spread(design_dir: Path, meta: dict, table: pd.DataFrame,
                  checks: pd.DataFrame | None) -> pd.DataFrame | None:
    """The start spread of a collocation study's responses
    (:func:`~bladelab.design.start_spread.start_spread`) over its fitted runs; None when it
    has no design solved to two clean strides."""
    if (meta.get("_evaluator") or {}).get("evaluator") != "collocation":
        return None
    runs = table["run"] if checks is None else table.loc[~checks["excluded"].to_numpy(bool),
                                                         "run"]
    spread = start_spread(design_dir, units=COLLOCATION_UNITS,
                          fitted_runs=[int(r) for r in runs])
    spread = spread[spread["across_sd"] > 0]  # a prescribed response (the speed) has none
    return None if spread.empty else spread.reset_index(drop=True)


#: Fewer designs with two clean strides than this: the report calls the start spread rough.
ROUGH_SPREAD_DESIGNS = 5


def spread_section(spread: pd.DataFrame, unmeasured: Sequence[str] = ()) -> dict[str, Any]:
    """What the solver's start decides: the responses' spread between clean strides of the
    same design against their spread across the designs; ``unmeasured``: fitted responses the
    settling record has no values of (added to the library after its passes)."""
    low = spread[spread["r2_ceiling"] < 0.8]
    n_designs = int(spread["designs"].max())
    text = ("Each design's stride is a local optimum. The settling passes solve each design "
            "again from its neighbours' strides; "
            f"{n_designs} designs have two or more distinct clean strides "
            "in the settling record (settling.json). within_sd is the pooled standard "
            "deviation of a response between clean strides of the same design (the start's "
            "error), within_sd_near the same for strides within "
            f"{NEAR_PCT:g} % of the design's lowest objective (from designs_near designs), "
            "across_sd its spread across the study's fitted runs. R² ceiling = "
            "1 − within_sd²/across_sd²: the share of the responses' variance a perfect surface "
            "could explain if each run carried this start error (an estimate, not a bound: "
            "the kept stride is the best found, not a random one); r2_ceiling_near the same "
            "from within_sd_near, the ceiling if every design were solved that close to its "
            "best.")
    if "stride_objective" in set(spread["response"]):
        text += (" stride_objective is the value each solve minimised: the kept stride is a "
                 "design's lowest, so its own start error is the gap to a lower optimum not "
                 "found yet (what a settling pass measures), smaller than within_sd, which "
                 "also pools the dearer optima. Every other response is a feature of "
                 "whichever optimum was kept, and near-equal optima can differ in it by more "
                 "than the designs do.")
    if n_designs < ROUGH_SPREAD_DESIGNS:
        text += (f" With {n_designs} designs the spread is a rough estimate: settle more "
                 "designs (--settle) before reading the ceilings.")
    if len(low):
        text += (f" {len(low)} of {len(spread)} responses have a ceiling below 0.8 "
                 f"({', '.join(low['response'])}): were each run any of its clean strides, "
                 "no surface could predict them to R² 0.8. The kept strides are each design's "
                 "best found, which carry less of that error the more the study has settled: "
                 "the surfaces' R²pred (the fits above) says how much less.")
    if unmeasured:
        text += (f" No spread of {', '.join(unmeasured)}: the settling record's strides were "
                 "evaluated before these responses existed, and only each design's kept stride "
                 "is stored (a new settling pass records them).")
    return {"title": "Design study: what the solver's start decides",
            "text": text, "tables": [("Start spread of the responses", spread)]}


def settling_effects_section(design_dir: Path, fitted: pd.DataFrame, space,
                             units: dict[str, str]) -> dict[str, Any] | None:
    """How each factor's first-order effect on each response of ``units`` ({response:
    unit}: the objective and the constraints) moved from the runs through the settling passes
    (:mod:`bladelab.design.settling_effects`), on the ``fitted`` runs (``results.csv``'s
    rows the surfaces are fitted to); None without a settling pass."""
    passes = read_settling_record(design_dir)
    if not any(p.get("designs") for p in passes):
        return None
    responses = [r for r in units if r in fitted]
    stages = settling_stages(fitted, passes, responses)
    coded = fitted.set_index("run")[[f"{n}_coded" for n in space.names]]
    coded.columns = list(space.names)
    effects = {r: effects_by_stage(stages, coded, r, units[r]) for r in responses}
    effects = {r: e for r, e in effects.items() if len(e)}
    if not effects:
        return None
    first = next(iter(effects))
    summary = effects_summary(effects[first])
    moves = last_stage_moves(effects[first])
    last_text = "" if moves is None else (
        f" The last stage ({stages[-1].label}) moved no effect on {first} by more than "
        f"{moves[0]:.2g} of its standard errors, and "
        + ("left the resolved effects and their signs as they were." if moves[1] else
           "changed which effects are resolved: read the answer after a further pass."))
    text = (f"Each factor's effect on {first} as the study stood after its runs and after each "
            "settling pass (a pass stopped midway is a stage of its own), from a first-order "
            "surface (an intercept and one slope per factor, the change from a factor's centre "
            "to its high level) fitted to the same runs at every stage: the record of each "
            "pass (settling.json) keeps every changed design's responses before it. Where the "
            "passes do not settle, the answer to read is an effect that keeps its sign and "
            "size from stage to stage; an effect resolved at p < "
            f"{RESOLVED_P:g} at one stage and not at the next, or one whose sign turns, is "
            "the solver's start, not the blade." + last_text + "\n\n"
            + "\n\n".join(f"{name}: {line}." for name, line in summary.items()))
    if len(stages) < len(passes) + 1:
        text += (" The stages before "
                 f"{stages[0].label} cannot be rebuilt: a design changed then was recorded "
                 "without its earlier responses.")
    table = pd.concat([e.assign(response=r) for r, e in effects.items()], ignore_index=True)
    table = table[["response", *[c for c in table.columns if c != "response"]]]
    return {"title": "Design study: the effects through the settling passes", "text": text,
            "figures": [("First-order effects by stage", effects_by_stage_plot(effects, space))],
            "tables": [("First-order effects by stage", table)]}
