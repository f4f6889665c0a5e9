"""The "Seed 002 trends" section of a design report: each trend's verdict on the study's own
surfaces (:func:`bladelab.design.trends.evaluate_trends`), the reasons numbered below the
table."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from bladelab.design.start_spread import NEAR_PCT
from bladelab.design.trends import (
    CEILING_MIN,
    NO_RUNNER,
    SEED002_TRENDS,
    SPEED_TRENDS,
    evaluate_trends,
    trends_frame,
)

__all__ = ["trend_ceilings", "trends_section"]


#: How the trends section names an evaluator whose key is not its plain name.
_EVALUATOR_LABELS = {"collocation-transtibial": "collocation on the transtibial runner"}


def trend_ceilings(spread: pd.DataFrame | None) -> dict[str, float]:
    """Response -> the start spread's R² ceiling that decides whether a trend on it can be
    judged: that of the strides competing to be kept (within 5 % of each design's best), else
    that of every clean stride; {} without a spread."""
    if spread is None:
        return {}
    near = spread.get("r2_ceiling_near", pd.Series(np.nan, index=spread.index))
    value = near.where(near.notna(), spread["r2_ceiling"])
    return {r: float(v) for r, v in zip(spread["response"], value, strict=True) if np.isfinite(v)}


def trends_section(surfaces, evaluator: dict | None = None,
                   ceilings: dict[str, float] | None = None) -> dict[str, Any]:
    """The "Seed 002 trends" section: each trend's verdict on the study's own surfaces
    (:func:`bladelab.design.trends.evaluate_trends`), with the test used and, for a trend that
    does not hold or is undecided, the reason. ``evaluator`` is the study's ``evaluator.json``
    (its kind selects the reasons; its generator ``roles`` map factors to stiffness/width/
    height/toe length); ``ceilings`` the start spread's R² ceilings (:func:`trend_ceilings`)."""
    evaluator = evaluator or {}
    kind = evaluator.get("evaluator")
    if kind == "collocation" and evaluator.get("amputation") == "transtibial":
        kind = "collocation-transtibial"  # its own runner, its own reasons
    roles = (evaluator.get("generator") or {}).get("roles")
    held = {}
    if evaluator.get("knee_moment_min_Nm") is not None:
        held["knee_moment_min_Nm"] = (f"held at or above {evaluator['knee_moment_min_Nm']:g} "
                                      "N·m on every loaded interval by the solve")
    trends = SEED002_TRENDS + (SPEED_TRENDS if "max_speed_m_per_s" in surfaces else ())
    verdicts = evaluate_trends(surfaces, evaluator=kind, roles=roles, held=held,
                               ceilings=ceilings, trends=trends)
    if kind in NO_RUNNER:  # every verdict "not tested": the section says why, once
        frame = trends_frame(verdicts).rename(columns={"mechanism": "the blade's mechanism"})
        return {"title": "Seed 002 trends", "text": (
                    f"{NO_RUNNER[kind]} The table gives, for each of seed 002's trends, the "
                    "blade's own coefficient or effect ranges on this study's surfaces (and the "
                    "mechanism behind them where one is known): a description of the blade, "
                    "not a verdict on the trend."),
                "tables": [("Seed 002 trends: not tested by this evaluator",
                            frame[["trend", "response", "evidence",
                                   "the blade's mechanism"]])]}
    counts = {v: sum(1 for x in verdicts if x.verdict == v)
              for v in ("holds", "does not hold", "undecided", "not estimable")}
    text = (f"The trends seed 002 reports, checked on this study's fitted surfaces "
            f"(evaluator: {_EVALUATOR_LABELS.get(kind, kind or 'unknown')}): "
            f"{counts['holds']} hold, {counts['does not hold']} do not hold, "
            + (f"{counts['undecided']} undecided, " if counts["undecided"] else "")
            + f"{counts['not estimable']} not estimable. "
            "Sign trends use a two-sided t-test of the linear coefficient per coded unit "
            "(α = 0.05); 'matter less' compares the ranges of the main-effect curves over the "
            "coded interval. "
            + (f"A trend is undecided where the solver's start moves its response about as "
               f"much as the designs do (the start spread's R² ceiling below {CEILING_MIN:g}, "
               f"from each design's strides within {NEAR_PCT:g} % of its best): the test's "
               "numbers are "
               "given, but the start, not the blade, decided them. " if counts["undecided"]
               else "")
            + "A trend that does not hold or is undecided gives the reason known for this "
            "evaluator (docs/design.md), or says it is not explained.")
    frame = trends_frame(verdicts).drop(columns="mechanism")
    tables = [("Seed 002 trends on this study", frame)]
    reasons = list(dict.fromkeys(r for r in frame["reason"] if r))
    if reasons:  # long paragraphs, often shared: numbered below the table, not in a cell
        number = {r: f"note {k}" for k, r in enumerate(reasons, start=1)}
        frame["reason"] = frame["reason"].map(lambda r: number.get(r, ""))
        tables.append(("Why a trend does not hold or is undecided", pd.DataFrame(
            {"note": list(number.values()), "reason": reasons})))
    return {"title": "Seed 002 trends", "text": text, "tables": tables}
