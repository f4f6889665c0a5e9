"""How a predicted-gait design study's answer moved with its settling passes.

A settling pass (:mod:`bladelab.design.settling`) solves each design's stride again from
other starts and keeps a lower optimum where it finds one. Where the solver's start limits
the surfaces (docs/design.md, "What the solver's start decides") the passes may not settle
below 1 % at all, and what such a study can still answer is each factor's effect: whether it
keeps its sign and size from pass to pass. This module reads that from a study's files alone
(``results.csv`` and ``settling.json``; nothing is solved):

- :func:`settling_stages` rebuilds every run's responses as they stood after the runs and
  after each pass (a pass stopped midway is a stage of its own), walking back from today's
  responses through each pass's record of the responses before it;
- :func:`effects_by_stage` fits a first-order surface (intercept and one slope per factor,
  :func:`~bladelab.design.surfaces.fit_surface` with ``model="linear"``) to a response at
  every stage: each factor's effect per coded unit with its 95 % confidence interval and
  p-value;
- :func:`effects_summary` says per factor whether its effect held, and
  :func:`last_stage_moves` what the last pass did to the answer (how many standard errors it
  moved an effect, and whether it changed which effects are resolved).

Every stage is read on the same runs (those given, e.g. the report's clean runs), so a
change from stage to stage is the passes' alone.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from bladelab.design.settling import objective_drop
from bladelab.design.surfaces import fit_surface

__all__ = ["RESOLVED_P", "SettlingStage", "effects_by_stage", "effects_summary",
           "last_stage_moves", "settling_stages"]

#: An effect with a p-value below this is resolved (its sign read from the data) [-].
RESOLVED_P = 0.05


@dataclass(frozen=True)
class SettlingStage:
    """One stage of a study: after its runs, or after a (possibly unfinished) settling pass.

    Attributes
    ----------
    label
        ``"runs"``, ``"pass 1"``, ``"pass 2 (stopped after 10 designs)"``.
    changed
        Runs whose stride this stage changed (none for ``"runs"``).
    largest_drop
        The stage's largest relative objective drop [-]; NaN for the runs.
    values
        The responses of every run at this stage (index: run number; NaN where the record
        lacks a value).
    """

    label: str
    changed: int
    largest_drop: float
    values: pd.DataFrame


def _responses_before(row: Mapping) -> dict | None:
    """A settled design's responses before its pass, the objective among them (records
    written before it was a response lack it); None where the record has none."""
    before = row.get("responses_before")
    if not before:
        return None
    return {"stride_objective": row.get("before"), **before}


def settling_stages(table: pd.DataFrame, passes: Sequence[Mapping],
                    responses: Sequence[str]) -> list[SettlingStage]:
    """The study's ``responses`` per run after its runs and after each settling pass, first
    to last.

    ``table`` is today's responses (``results.csv``'s rows: a ``run`` column and one column
    per response), ``passes`` the settling record's passes
    (:func:`~bladelab.design.settling.read_settling_record`). Walking back from today, each
    pass's changed designs take the responses recorded before it (``responses_before``);
    designs not in ``table`` (e.g. runs left out) are skipped. A stage before a changed design
    whose record lacks its earlier responses cannot be rebuilt: the stages returned then start
    after it.
    """
    values = table.set_index("run")[list(responses)].astype(float).copy()
    stages: list[SettlingStage] = []
    for rec in reversed(passes):
        rows = [r for r in rec.get("designs", []) if r.get("after") is not None]
        drops = [objective_drop(r) for r in rows if r.get("before")]
        changed = [r for r in rows if r.get("from") is not None and r["run"] in values.index]
        label = f"pass {rec['pass']}"
        if not rec.get("complete"):
            label += f" (stopped after {len(rows)} designs)"
        stages.append(SettlingStage(label, len(changed), max(drops, default=0.0),
                                    values.copy()))
        for r in changed:
            before = _responses_before(r)
            if before is None:
                return stages[::-1]
            values.loc[r["run"]] = [float(before.get(c, np.nan)) for c in values.columns]
    stages.append(SettlingStage("runs", 0, float("nan"), values))
    return stages[::-1]


def effects_by_stage(stages: Sequence[SettlingStage], coded: pd.DataFrame, response: str,
                     unit: str = "", *, level: float = 0.95) -> pd.DataFrame:
    """Each factor's first-order effect on ``response`` at every stage, one row per stage and
    factor: ``stage``, ``designs_changed``, ``largest_objective_drop_pct`` [%],
    ``factor``, ``effect`` [the response's unit per coded unit: the change from the
    factor's centre to its high level], ``ci_lower``/``ci_upper`` (``level`` confidence),
    ``p_value``, ``std_error``, ``moved_se`` (how far the stage moved the effect from the
    stage before, in this stage's standard errors; NaN for the first), ``unit``, ``R2_pred``
    (the first-order surface's, the same for a stage's factors). ``coded`` holds each run's
    coded factor levels (index: run number; one column per factor, named after it). A stage
    where a run lacks the response is left out.
    """
    rows = []
    names = list(coded.columns)
    previous: dict[str, float] = {}
    for stage in stages:
        y = stage.values[response].reindex(coded.index).to_numpy(float)
        if not np.all(np.isfinite(y)):
            continue
        surface = fit_surface(coded.to_numpy(float), y, factor_names=names, model="linear",
                              response=response, unit=unit)
        coef = surface.coefficients(level=level).set_index("term")
        for name in names:
            effect, se = float(coef.loc[name, "estimate"]), float(coef.loc[name, "std_error"])
            rows.append({"stage": stage.label, "designs_changed": stage.changed,
                         "largest_objective_drop_pct": 100.0 * stage.largest_drop,
                         "factor": name, "effect": effect,
                         "ci_lower": coef.loc[name, "ci_lower"],
                         "ci_upper": coef.loc[name, "ci_upper"],
                         "p_value": coef.loc[name, "p_value"], "std_error": se,
                         "moved_se": (abs(effect - previous[name]) / se
                                      if name in previous and se > 0 else float("nan")),
                         "unit": f"{unit} per coded unit".strip(),
                         "R2_pred": surface.r2_pred})
            previous[name] = effect
    return pd.DataFrame(rows, columns=[
        "stage", "designs_changed", "largest_objective_drop_pct", "factor", "effect",
        "ci_lower", "ci_upper", "p_value", "std_error", "moved_se", "unit", "R2_pred"])


def last_stage_moves(effects: pd.DataFrame) -> tuple[float, bool] | None:
    """What the last stage of :func:`effects_by_stage` did to the answer: (the largest
    ``moved_se`` over the factors, whether the factors resolved at p < :data:`RESOLVED_P`
    and their signs are the stage before's); None with a single stage."""
    labels = list(dict.fromkeys(effects["stage"]))
    if len(labels) < 2:
        return None
    last = effects[effects["stage"] == labels[-1]]
    before = effects[effects["stage"] == labels[-2]]

    def resolved(rows: pd.DataFrame) -> set[tuple[str, float]]:
        hit = rows[rows["p_value"] < RESOLVED_P]
        return set(zip(hit["factor"], np.sign(hit["effect"]), strict=True))

    return float(last["moved_se"].max()), resolved(last) == resolved(before)


def effects_summary(effects: pd.DataFrame) -> dict[str, str]:
    """Per factor, one sentence on its effect over the stages of :func:`effects_by_stage`:
    its value at the last stage; if resolved there (p < :data:`RESOLVED_P`), since which
    stage it has been resolved with that sign and how far its size moved since, relative to
    the last stage's; any earlier stage that resolved the opposite sign; and the effect by
    stage."""
    out = {}
    for name, rows in effects.groupby("factor", sort=False):
        eff = rows["effect"].to_numpy(float)
        p = rows["p_value"].to_numpy(float)
        stages = rows["stage"].tolist()
        unit = rows["unit"].iloc[0]
        text = f"{eff[-1]:+.3g} {unit} (p {p[-1]:.2g})"
        resolved = p < RESOLVED_P
        sign = np.sign(eff[-1])
        if not resolved[-1]:
            text += ", not resolved at the last stage"
        else:
            since = len(eff) - 1
            while since > 0 and resolved[since - 1] and np.sign(eff[since - 1]) == sign:
                since -= 1
            moved = float(np.max(np.abs(eff[since:] - eff[-1]))) / abs(eff[-1])
            text += (", resolved with this sign at every stage" if since == 0 else
                     f", resolved with this sign from {stages[since]} on")
            where = "throughout" if since == 0 else "there"
            if since < len(eff) - 1:
                text += (f", its size unchanged {where}" if moved < 0.005 else
                         f", its size within {100 * moved:.0f} % of the last stage's {where}")
        opposite = [s for s, r, e in zip(stages, resolved, eff, strict=True)
                    if r and np.sign(e) == -sign]
        if opposite:
            text += f"; the opposite sign was resolved at {', '.join(opposite)}"
        out[name] = text + " (by stage: " + " → ".join(f"{e:+.3g}" for e in eff) + ")"
    return out
