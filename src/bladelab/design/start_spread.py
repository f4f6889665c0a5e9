"""How much a predicted-gait design study's responses depend on the solver's start.

A design's predicted stride is a local optimum: solved again from another start (a settling
pass starts each design from its solved neighbours), the same design can give another clean
stride, of a slightly different objective and different responses. Computer experiments are
called deterministic, but these are not, in this sense: the start plays the part of the
replicate error of a physical experiment. :func:`start_spread` measures it from the settling
record (``settling.json``, :mod:`bladelab.design.settling`), where every settled design keeps
the responses of its stored stride and of each start's clean stride.

Per response (``results.csv``'s columns; values in their units):

- ``within_sd``: pooled standard deviation of a design's clean strides about their mean,
  sqrt(Σ_d Σ_i (y_di − ȳ_d)² / Σ_d (n_d − 1)) over designs with at least two distinct strides
  (a stride is identified by its objective: the stored stride of one pass is the kept try of
  the pass before);
- ``within_sd_near``: the same over the strides within ``near_pct`` of their design's lowest
  objective (are near-optimal strides alike?), from ``designs_near`` designs with two such;
- ``across_sd``: standard deviation of the study's responses across its designs (the runs
  fitted: ``results.csv`` less the runs the report leaves out);
- ``r2_ceiling``: 1 − within_sd² / across_sd² (at least 0): the share of the responses'
  variance across the box that a perfect surface could explain if each design's response
  carried this start error. A response whose ceiling is below a target R² cannot reach it
  by any surface model; only solving each design to its global optimum would help. The
  kept stride is the best of those found, not a random one, so its error can be smaller:
  the ceiling is an estimate, not a bound. ``r2_ceiling_near`` is the same from
  ``within_sd_near``: the ceiling if every design were solved to within ``near_pct`` of its
  best objective.

Predicted R² (from PRESS) has a lower ceiling than R², because each left-out run is
predicted from the others with the start error of all of them: :func:`r2_pred_ceiling`
gives it for a fitted surface from its runs' leverages.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab._io import read_json
from bladelab.design.settling import RECORD_NAME
from bladelab.design.surfaces import EXACT_FIT_LEVERAGE

__all__ = ["NEAR_PCT", "design_strides", "r2_pred_ceiling", "start_spread"]

#: Objective window of ``within_sd_near`` [%] (the report's).
NEAR_PCT = 5.0
#: Strides of one design whose objectives agree to this relative tolerance are the same stride.
SAME_STRIDE_REL = 1e-9


def design_strides(record: Mapping) -> dict[int, list[tuple[float, dict]]]:
    """Run number -> distinct clean strides of that design, as (objective, responses), from
    a settling record (``settling.json``'s contents), lowest objective first; the responses
    include the objective as ``stride_objective`` (older records lack it)."""
    found: dict[int, list[tuple[float, dict]]] = {}
    for rec in record.get("passes", []):
        for row in rec.get("designs", []):
            strides = found.setdefault(int(row["run"]), [])
            cand = []
            if row.get("responses_before") is not None:
                cand.append((float(row["before"]), row["responses_before"]))
            for t in row.get("tries", []):
                if t.get("responses") is not None and t.get("objective") is not None:
                    cand.append((float(t["objective"]), t["responses"]))
            for obj, resp in cand:
                resp = {**resp, "stride_objective": obj}  # records before it was a response
                if not any(abs(obj - o) <= SAME_STRIDE_REL * max(abs(o), 1.0)
                           for o, _ in strides):
                    strides.append((obj, dict(resp)))
    return {run: sorted(s, key=lambda x: x[0]) for run, s in found.items() if s}


def _pooled_sd(groups: Sequence[np.ndarray]) -> tuple[float, int]:
    """Pooled SD about each group's mean over the groups of two or more values, and how many
    such groups there are."""
    used = [g for g in groups if len(g) >= 2]
    ss = sum(float(((g - g.mean()) ** 2).sum()) for g in used)
    dof = sum(len(g) - 1 for g in used)
    return (float(np.sqrt(ss / dof)) if dof else float("nan")), len(used)


def start_spread(design_dir: str | Path, *, responses: Sequence[str] | None = None,
                 units: Mapping[str, str] | None = None, fitted_runs: Sequence[int] | None = None,
                 near_pct: float = NEAR_PCT) -> pd.DataFrame:
    """Per response: the start's spread within designs against the spread across designs
    (module docstring). ``fitted_runs``: the runs of ``results.csv`` the surfaces are fitted
    to (default all); ``near_pct`` [%]: the objective window of ``within_sd_near``.

    Returns an empty frame when the study has no settling record or no design with two
    distinct clean strides."""
    design_dir = Path(design_dir)
    path = design_dir / RECORD_NAME
    cols = ["response", "unit", "designs", "strides", "within_sd", "designs_near",
            "within_sd_near", "across_sd", "r2_ceiling", "r2_ceiling_near"]
    if not path.is_file():
        return pd.DataFrame(columns=cols)
    strides = design_strides(read_json(path, what="settling record"))
    multi = {run: s for run, s in strides.items() if len(s) >= 2}
    if not multi:
        return pd.DataFrame(columns=cols)
    table = pd.read_csv(design_dir / "results.csv")
    if fitted_runs is not None:
        table = table[table["run"].isin(list(fitted_runs))]
    names = list(responses) if responses is not None else sorted(
        {k for s in multi.values() for _, r in s for k in r})
    rows = []
    for name in names:
        groups, near = [], []
        for s in multi.values():
            best = s[0][0]
            vals = [(o, r[name]) for o, r in s if r.get(name) is not None
                    and np.isfinite(r[name])]
            groups.append(np.array([v for _, v in vals], float))
            near.append(np.array([v for o, v in vals
                                  if o <= best + abs(best) * near_pct / 100.0], float))
        within, n_designs = _pooled_sd(groups)
        within_near, n_near = _pooled_sd(near)
        across = float(table[name].std(ddof=1)) if name in table and len(table) > 1 else np.nan
        ceiling, ceiling_near = (
            max(0.0, 1.0 - sd ** 2 / across ** 2) if np.isfinite(sd) and across > 0 else np.nan
            for sd in (within, within_near))
        rows.append({"response": name, "unit": (units or {}).get(name, ""),
                     "designs": n_designs,
                     "strides": int(sum(len(g) for g in groups if len(g) >= 2)),
                     "within_sd": within, "designs_near": n_near,
                     "within_sd_near": within_near,
                     "across_sd": across, "r2_ceiling": ceiling,
                     "r2_ceiling_near": ceiling_near})
    return pd.DataFrame(rows, columns=cols)


def r2_pred_ceiling(within_sd: float, across_sd: float, leverage: Sequence[float]) -> float:
    """The predicted R² (PRESS) a surface of the right form would reach on average if each
    run's response carried a start error of standard deviation ``within_sd``, when the runs
    vary by ``across_sd`` (sample SD, both in the response's unit) and have the surface's
    ``leverage`` (hat-matrix diagonal, one per fitted run).

    A left-out run's PRESS residual e_i / (1 − h_i) has variance σ² / (1 − h_i) when the
    model is right, so E[PRESS] = σ² Σ 1 / (1 − h_i) and the ceiling is
    1 − (within_sd / across_sd)² Σ 1 / (1 − h_i) / (n − 1). A quadratic in four factors on
    a 25-run face-centred design has mean leverage 0.6, so its ceiling sits 2.7 times as far
    below 1 as :func:`start_spread`'s R² ceiling. Like that one it is an estimate (the start
    error is not independent between neighbouring designs). At least 0, as that one: 0 says
    the start's error alone leaves the surface predicting no better than the runs' mean. NaN
    when a run has leverage 1 (no leave-one-out prediction) or the spreads are not finite."""
    h = np.asarray(leverage, dtype=float)
    n = len(h)
    if (n < 2 or not (np.isfinite(within_sd) and np.isfinite(across_sd)) or across_sd <= 0
            or (h >= EXACT_FIT_LEVERAGE).any()):
        return float("nan")
    share = (within_sd / across_sd) ** 2 * float(np.sum(1.0 / (1.0 - h))) / (n - 1)
    return max(0.0, 1.0 - share)
