"""The design-study section of the HTML report (a folder written by ``run_design``).

:func:`design_report_sections` reads a design folder (``study.json``, ``results.csv``,
``anova.csv``) and returns the keyword arguments of :meth:`Report.add_section` for: the fitted
surfaces (R², adjusted and predicted R², leave-one-out error), main effects, contours with the
constraint boundaries and the optimum, the ANOVA of the objective, seed 002's trends checked on
the study's surfaces (:func:`trends_section`) and the optimum with its prediction interval. :func:`build_design_report` writes them as ``<out_dir>/index.html``.
The surfaces are refitted from ``results.csv`` (same model), the optimum recomputed with the
study's seed (deterministic: the same as ``optimum.json``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from bladelab._io import read_json
from bladelab.design.confirmation import CONFIRMATION_FILE, same_point
from bladelab.design.optimum import constrained_optimum, surface_constraints
from bladelab.design.plots import contour_plot, figure_pairs, main_effects_plot
from bladelab.design.reduction import REDUCED_MODEL, fit_response
from bladelab.design.responses import (
    BLADE_RESPONSE_UNITS,
    PREDICTED_RESPONSE_UNITS,
    RUNNER_RESPONSE_UNITS,
)
from bladelab.design.space import DesignSpace
from bladelab.design.start_spread import r2_pred_ceiling
from bladelab.design.stride_checks import stride_checks
from bladelab.design.surfaces import EXACT_FIT_LEVERAGE
from bladelab.design.terms import parse_terms
from bladelab.errors import InputFileError, OptimizationError
from bladelab.predict.collocation.stored import athlete_text
from bladelab.report.builder import Report
from bladelab.report.design_strides import (
    COLLOCATION_UNITS,
    collocation_start_spread,
    gallop_text,
    settling_effects_section,
    settling_text,
    spread_section,
    strides_section,
)
from bladelab.report.design_trends import trend_ceilings, trends_section

__all__ = ["build_design_report", "design_report_sections", "is_design_folder", "trends_section"]



def is_design_folder(path: str | Path) -> bool:
    """True when ``path`` holds a design study (``study.json`` and ``results.csv``)."""
    p = Path(path)
    return (p / "study.json").is_file() and (p / "results.csv").is_file()


def _load(design_dir: Path):
    if not is_design_folder(design_dir):
        raise InputFileError("not a design-study folder (no study.json / results.csv)",
                             file=design_dir, hint="run 'bladelab design --out DIR' first")
    meta = read_json(design_dir / "study.json", what="design study file")
    try:
        space = DesignSpace.from_dict(meta["space"])
        table = pd.read_csv(design_dir / "results.csv")
    except (OSError, ValueError, KeyError) as err:
        raise InputFileError(f"cannot read the design study: {err}", file=design_dir) from None
    units = {}
    ev = design_dir / "evaluator.json"
    evaluator: dict = {}
    if ev.is_file():
        evaluator = read_json(ev, what="evaluator settings")
        kind = evaluator.get("evaluator")
        units = {"runner": RUNNER_RESPONSE_UNITS, "collocation": COLLOCATION_UNITS
                 }.get(kind, BLADE_RESPONSE_UNITS)
    meta = {**meta, "_evaluator": evaluator}
    coded_cols = [f"{n}_coded" for n in space.names]
    skip = {"run", *space.names, *coded_cols}
    responses = [c for c in table.columns if c not in skip]
    checks = _stride_checks(design_dir, evaluator, space, table)
    meta["_strides"] = checks
    failed_csv = design_dir / "failed.csv"
    meta["_failed"] = pd.read_csv(failed_csv) if failed_csv.is_file() else None
    fitted = table if checks is None else table[~checks["excluded"].to_numpy(bool)]
    terms = parse_terms(meta.get("model", "quadratic"), space.names)
    if len(fitted) < len(terms):
        raise InputFileError(
            f"only {len(fitted)} of {len(table)} runs have clean strides, fewer than the "
            f"{len(terms)} terms of the {meta.get('model', 'quadratic')} surface",
            file=design_dir, hint="re-solve the flagged runs: delete their runs/*.json and "
            "run the same 'bladelab design' command again")
    coded = fitted[coded_cols].to_numpy(float)
    surfaces = {r: fit_response(coded, fitted[r].to_numpy(float), factor_names=space.names,
                                model=meta.get("model", "quadratic"), response=r,
                                unit=units.get(r, ""))
                for r in responses}
    return meta, space, table, surfaces


def _stride_checks(design_dir: Path, evaluator: dict, space, table: pd.DataFrame
                   ) -> pd.DataFrame | None:
    """A collocation study's strides checked again (:func:`~bladelab.design.
    stride_checks.stride_checks`), one row per run, with ``excluded`` True for a run
    whose stride carries gait warnings (a missing stride file cannot be checked: kept, and
    said); None for other evaluators."""
    if evaluator.get("evaluator") != "collocation":
        return None
    points = [{n: float(row[n]) for n in space.names} for _, row in table.iterrows()]
    checks = pd.DataFrame(stride_checks(design_dir, evaluator, points))
    checks.insert(0, "run", table["run"].to_numpy())
    checks["excluded"] = [bool(w) and pd.notna(s)
                          for w, s in zip(checks["warnings"], checks["stride"], strict=True)]
    return checks


def _constant_responses(table: pd.DataFrame, surfaces: dict) -> dict[str, float]:
    """{response: value} of the responses that every run of ``table`` has the same to
    round-off (e.g. the prescribed mean speed of a predicted stride): nothing to fit."""
    out = {}
    for r in surfaces:
        if r not in table:
            continue
        v = pd.to_numeric(table[r], errors="coerce").to_numpy(float)
        v = v[np.isfinite(v)]
        if v.size > 1 and np.ptp(v) <= 1e-9 * max(1.0, float(np.abs(v).max())):
            out[r] = float(v.mean())
    return out


def _r2_pred_ceilings(responses: pd.Series, spread: pd.DataFrame,
                      surfaces: dict) -> list[float]:
    """Per fitted response, the predicted R² its surface would reach on average with the
    start spread's error in every run (:func:`~bladelab.design.start_spread.r2_pred_ceiling`
    from its own surface's leverages); NaN where the spread has no value."""
    by_name = spread.set_index("response")
    return [r2_pred_ceiling(float(by_name.loc[r, "within_sd"]),
                            float(by_name.loc[r, "across_sd"]), surfaces[r].leverage)
            if r in by_name.index else float("nan") for r in responses]


def design_report_sections(design_dir: str | Path) -> list[dict[str, Any]]:
    """Keyword arguments of :meth:`bladelab.report.Report.add_section`, one dict per section."""
    import matplotlib

    matplotlib.use("Agg")
    design_dir = Path(design_dir)
    meta, space, table, surfaces = _load(design_dir)
    objective = meta.get("objective") or next(iter(surfaces))
    constraints = {k: v for k, v in (meta.get("constraints") or {}).items() if k in surfaces}
    fit = pd.DataFrame([
        {"response": r, "unit": s.unit, "R2": s.r2, "R2_adj": s.r2_adj, "R2_pred": s.r2_pred,
         "loo_rmse": s.loo_rmse} for r, s in surfaces.items()])
    failed = meta.get("_failed")
    n_failed = 0 if failed is None else len(failed)
    design_text = (f"{len(table) + n_failed} runs ({meta.get('design', {}).get('kind', '?')} "
                   "design"
                   + (f"; {n_failed} failed and have no result: see 'runs without a result'"
                      if n_failed else "") + "), "
                   f"model {meta.get('model')}, factors: "
                   + ", ".join(f"{f.name} {f.low:g}–{f.high:g} {f.unit}".strip()
                               for f in space.factors) + ".")
    checks = meta.get("_strides")
    spread = collocation_start_spread(design_dir, meta, table, checks)
    if spread is not None:
        fit = fit.merge(spread[["response", "r2_ceiling"]].rename(
            columns={"r2_ceiling": "R2 ceiling (start spread)"}), on="response", how="left")
        fit["R2_pred ceiling (start spread)"] = _r2_pred_ceilings(fit["response"], spread,
                                                                  surfaces)
    r2_columns = [c for c in fit.columns if c.startswith("R2")]
    fit[r2_columns] = fit[r2_columns].astype(float).round(3)  # R² to three decimals
    fit_text = "Predicted R² comes from PRESS (leave-one-out)."
    if spread is not None:
        fit_text += (" The ceilings say how far the solver's start lets a surface go: 'R2 "
                     "ceiling' is the share of the runs' variance a perfect surface could "
                     "explain if each run carried the start's error; 'R2_pred ceiling' is the "
                     "predicted R² that a surface of the right form would reach on average "
                     "with that error, lower because each left-out run is predicted from "
                     "the others' errors, more so the more terms the surface has "
                     "(1 − (within_sd/across_sd)² Σ 1/(1 − leverage) / (runs − 1)). Both are "
                     "estimates: the kept stride is the best found, not a random one, and "
                     "settling carries strides between neighbouring designs, so their start "
                     "errors are alike and a smooth surface can fit part of them (an R2_pred "
                     "above its ceiling is that).")
    constant = _constant_responses(table, surfaces)
    if constant:
        fit = fit[~fit["response"].isin(constant)]
        fit_text += (" Not fitted, the same in every run (a prescribed quantity): "
                     + ", ".join(f"{r} = {v:.4g} {surfaces[r].unit}".rstrip()
                                 for r, v in constant.items()) + ".")
    if meta.get("model") == REDUCED_MODEL:
        fit["terms"] = fit["response"].map(lambda r: len(surfaces[r].terms))
        fit["R2_pred (selection in each fold)"] = fit["response"].map(
            lambda r: round(float(surfaces[r].r2_pred_selected), 3))
        fit_text += (" Each response's surface is reduced from the full quadratic ("
                     + next(iter(surfaces.values())).selection + "; 'terms' counts the "
                     "intercept). Its R2_pred is computed on the terms chosen from every run, so "
                     "it flatters; 'R2_pred (selection in each fold)' repeats the choice "
                     "without each run and is the one to compare with a full quadratic's.")
    if checks is not None and checks["excluded"].any():
        fit_text += (f" The surfaces, contours and optimum below are fitted to the "
                     f"{int((~checks['excluded']).sum())} runs with clean strides: "
                     f"{int(checks['excluded'].sum())} runs (marked in the table of runs, "
                     "listed under 'predicted strides') are left out, so the optimum can "
                     "differ from the study's optimum.json.")
    gallops = gallop_text(checks)
    if gallops:
        fit_text = gallops + " " + fit_text
    settling = settling_text(design_dir) if checks is not None else ""
    if settling:
        fit_text = settling + " " + fit_text
    lev = next(iter(surfaces.values())).leverage
    n_one = int((lev >= EXACT_FIT_LEVERAGE).sum())
    if n_one:
        fit_text += (f" Predicted R² and the leave-one-out error are blank: {n_one} of the "
                     f"{len(lev)} runs fitted {'has' if n_one == 1 else 'have'} leverage 1 "
                     "(the surface passes exactly through such a run whatever its value, as "
                     "when runs of the design are missing), so no leave-one-out prediction "
                     "exists and the surfaces' predictive power is unknown.")
    runs = table if checks is None else table.assign(stride=[
        "left out (warnings)" if x else ("clean" if not w else w)
        for w, x in zip(checks["warnings"], checks["excluded"], strict=True)])
    evaluated = _evaluator_sentence(meta.get("_evaluator") or {})
    sections: list[dict[str, Any]] = [{
        "title": "Design study: response surfaces",
        "text": (evaluated + " " if evaluated else "") + design_text + "\n\n" + fit_text,
        "tables": [("Surface fits", fit), ("Runs", runs)],
    }]
    if n_failed:
        sections.append({
            "title": "Design study: runs without a result",
            "text": (f"{n_failed} runs failed (the evaluator found no result; recorded in "
                     "runs/run_NNNN.failed.json). They are not in the surfaces, which are "
                     f"fitted to the {len(table)} runs that finished: the surfaces describe "
                     "the region where the evaluator succeeds, and a failed region is a "
                     "finding in itself (e.g. blades with no knee-safe gait)."),
            "tables": [("Failed runs", failed.drop(columns=[c for c in failed.columns
                                                            if c.endswith("_coded")])),
                       ("Failed runs per factor level", _failures_by_level(space, table,
                                                                           failed))]})
    if checks is not None:
        sections.append(strides_section(checks, meta.get("_evaluator") or {}))
    if spread is not None:
        unmeasured = [r for r in surfaces if r not in set(spread["response"])
                      and r in PREDICTED_RESPONSE_UNITS and table[r].std() > 0]
        sections.append(spread_section(spread, unmeasured))
    shown = [objective, *[c for c in constraints if c != objective]]
    if checks is not None:
        fitted = table[~checks["excluded"].to_numpy(bool)]
        passes = settling_effects_section(design_dir, fitted, space,
                                          {r: surfaces[r].unit for r in shown})
        if passes is not None:
            sections.append(passes)
    sections.append({
        "title": "Design study: main effects",
        "figures": [("Main effects (others at the centre; band: 95 % CI of the mean)",
                     main_effects_plot([surfaces[r] for r in shown], space))],
    })
    cons = surface_constraints(surfaces, constraints)
    optimum, why = None, ""
    try:
        optimum = constrained_optimum(surfaces[objective], sense=meta.get("sense", "max"),
                                      constraints=cons, space=space, seed=int(meta.get("seed", 0)),
                                      conservative=bool(meta.get("conservative", False)))
    except OptimizationError as err:
        why = str(err)
    coded_cols = [f"{n}_coded" for n in space.names]
    marks, labels = [], []  # runs not in the surfaces, crossed out on the contours
    if n_failed:
        marks.append(failed[coded_cols].to_numpy(float))
        labels.append("failed runs")
    if checks is not None and checks["excluded"].any():
        marks.append(table.loc[checks["excluded"].to_numpy(bool), coded_cols].to_numpy(float))
        labels.append("runs left out")
    figs = [(f"{objective} over {x} and {y}; constraints hatched on their infeasible side",
             contour_plot(surfaces[objective], space, x=x, y=y, constraints=cons,
                          optimum=optimum, missing=np.vstack(marks) if marks else None,
                          missing_label=" and ".join(labels) + " (projected)"))
            for x, y in figure_pairs(space.names)]
    sections.append({"title": "Design study: contours and constraints", "figures": figs})
    anova = surfaces[objective].anova
    sections.append({"title": f"Design study: ANOVA of {objective}",
                     "tables": [(f"ANOVA of {objective}", anova),
                                (f"Coefficients of {objective}",
                                 surfaces[objective].coefficients())]})
    motion = _motion_section(design_dir, meta)
    if motion is not None:
        sections.append(motion)
    sections.append(trends_section(surfaces, meta.get("_evaluator") or {},
                                   ceilings=trend_ceilings(spread)))
    if optimum is None:
        sections.append({"title": "Design study: optimum",
                         "text": f"No feasible optimum: {why}"})
    else:
        rows = [{"factor": k, "value": optimum.point[k], "unit": space.factor(k).unit,
                 "coded": optimum.coded[k]} for k in space.names]
        cons_rows = [{"constraint": k, **v} for k, v in optimum.constraints.items()]
        text = _optimum_text(optimum, objective, surfaces[objective], table, checks)
        tabs = [("Optimum design", pd.DataFrame(rows))]
        if cons_rows:
            tabs.append(("Constraints at the optimum", pd.DataFrame(cons_rows)))
        sections.append({"title": "Design study: optimum", "text": text, "tables": tabs})
    confirmed = _confirmation_section(design_dir, optimum, {r: s.unit for r, s in
                                                            surfaces.items()})
    if confirmed is not None:
        sections.append(confirmed)
    return sections


#: Below this predicted R² the report says that the optimum is the fit's, not the runs'.
_PREDICTIVE_R2 = 0.5


def _optimum_text(optimum, objective: str, surface, table: pd.DataFrame,
                  checks: pd.DataFrame | None) -> str:
    """The optimum's sentence: the surface's prediction with its interval, the best run the
    study measured beside it, and a caution where the surface predicts poorly."""
    verb = "Maximising" if optimum.sense == "max" else "Minimising"
    unit = f" {optimum.unit}" if optimum.unit else ""
    text = (f"{verb} {objective}: the surface predicts {optimum.predicted:.4g}{unit} at the "
            f"design below, 95 % prediction interval {optimum.pi[0]:.4g} to "
            f"{optimum.pi[1]:.4g}{unit}.")
    runs = table if checks is None else table[~checks["excluded"].to_numpy(bool)]
    if objective in runs and runs[objective].notna().any():
        best = runs.loc[runs[objective].idxmax() if optimum.sense == "max"
                        else runs[objective].idxmin()]
        label = f"run {int(best['run'])}" if "run" in best else "the best run"
        notes = [n for n, on in (
            ("the optimum's own design", all(
                abs(optimum.coded[k] - best.get(f"{k}_coded", np.nan)) < 1e-6
                for k in optimum.coded)),
            ("its constraints not checked", bool(optimum.constraints))) if on]
        text += (f" The best run measured: {label}, {best[objective]:.4g}{unit}"
                 + (f" ({'; '.join(notes)})" if notes else "") + ".")
    r2 = surface.r2_pred
    if not (r2 >= _PREDICTIVE_R2):
        shown = "unknown" if not np.isfinite(r2) else f"{r2:.2f}"
        text += (f" Caution: the surface predicts {objective} poorly (R²pred {shown}, "
                 f"below {_PREDICTIVE_R2:g}; the surface fits table gives its ceilings from "
                 "the start spread): this optimum is where the fitted quadratic is "
                 f"{'highest' if optimum.sense == 'max' else 'lowest'}, not a design the runs "
                 "have shown to be best.")
    return text


def _confirmation_section(design_dir: Path, optimum, units: dict[str, str]) -> dict | None:
    """The optimum solved as a design (``--confirm``, :mod:`bladelab.design.confirmation`)
    beside the surfaces' prediction; None without a confirmation run."""
    path = design_dir / CONFIRMATION_FILE
    if not path.is_file():
        return None
    rec = read_json(path, what="confirmation run")
    rows = [{"response": name, "unit": units.get(name, ""), "predicted": r["predicted"],
             "PI lower": r["pi"][0], "PI upper": r["pi"][1], "solved": r["solved"],
             "inside the PI": "yes" if r["inside"] else "no"}
            for name, r in rec["responses"].items()]
    inside = sum(r["inside"] for r in rec["responses"].values())
    point = ", ".join(f"{k} {v:.4g}" for k, v in rec["point"].items())
    text = (f"The optimum's blade ({point}) solved as one more design: from its nearest "
            "designs' strides (its own first, when it is a design of the study), then settled "
            "from its two nearest and the study's cheapest, a start already solved from "
            f"skipped ({1 + len(rec['starts'])} solves, {rec['wall_s']:.0f} s; the stride: "
            f"{rec['stride']}). {inside} of {len(rows)} responses lie inside their 95 % "
            "prediction interval. A surface's optimum is a prediction; where the designs' "
            "strides lie on two branches, a quadratic interpolates the kink between them, "
            "and the solved stride says which branch the blade runs on.")
    if optimum is not None and not same_point(optimum.point, rec["point"]):
        text += (" The optimum above (fitted to the clean strides only) differs from the one "
                 "confirmed (the study's optimum.json).")
    missed = [k for k, c in rec.get("constraints", {}).items() if not c["met"]]
    if missed:
        text += f" The solved stride violates {', '.join(missed)}."
    tables = [("Predicted and solved at the optimum", pd.DataFrame(rows))]
    if rec.get("constraints"):
        tables.append(("Constraints, solved", pd.DataFrame(
            [{"constraint": k, "relation": "≤" if c["upper"] else "≥", "bound": c["bound"],
              "solved": c["solved"], "met": "yes" if c["met"] else "no"}
             for k, c in rec["constraints"].items()])))
    return {"title": "Design study: the optimum, solved", "text": text, "tables": tables}


def _failures_by_level(space, table: pd.DataFrame, failed: pd.DataFrame) -> pd.DataFrame:
    """Per factor and coded level: runs of the design, how many failed, and the fraction
    (where the evaluator fails, e.g. one end of a factor's range)."""
    rows = []
    for f in space.factors:
        col = f"{f.name}_coded"
        done, bad = table[col].round(6), failed[col].round(6)
        for level in sorted(set(done) | set(bad)):
            n_bad = int((bad == level).sum())
            n = n_bad + int((done == level).sum())
            rows.append({"factor": f.name, "coded level": level,
                         "value": f.mid + level * f.half_range, "unit": f.unit, "runs": n,
                         "failed": n_bad, "failed (%)": 100.0 * n_bad / n})
    return pd.DataFrame(rows)


def _evaluator_sentence(evaluator: dict) -> str:
    """What each run of the study is, from its ``evaluator.json`` ("" when it has none): the
    first words of the report, so that no response is read as something it is not."""
    kind = evaluator.get("evaluator")
    speed = evaluator.get("speed_mps")
    at = f" at {speed:g} m/s" if isinstance(speed, int | float) else ""
    if evaluator.get("max_speed"):
        at = " at its maximum speed"
    if kind == "blade":
        mass = evaluator.get("body_mass_kg")
        mass = f"a {mass:g} kg point mass" if isinstance(mass, int | float) else "a point mass"
        return (f"Each run is the generated blade alone (the blade evaluator): {mass} on a "
                f"rigid pylon lands on it{at}, one prescribed passive stance, no runner. Its "
                "responses describe the blade under that stance; what an athlete would run on "
                "it is not computed, so seed 002's conclusions about running are not tested "
                "here.")
    if kind == "runner":
        return (f"Each run is one transfemoral gait cycle{at} with the generated blade, its "
                "motion prescribed (seed 002's motion-driven evaluator: the measured or "
                "adapted motion is imposed and the blade makes the forces, seed 002's own "
                "definition of its responses).")
    if kind == "collocation":
        body = evaluator.get("body")
        amputation = evaluator.get("amputation") or "transfemoral"
        notes = [f"{body} body"] if body else []
        athlete = evaluator.get("athlete")
        if isinstance(athlete, dict) and athlete:
            notes.append("the athlete: " + athlete_text(athlete))
        mesh = evaluator.get("mesh_intervals")
        if isinstance(mesh, int):
            notes.append(f"{mesh} mesh intervals")
        return (f"Each run is a predicted {amputation} stride{at} wearing the generated blade "
                "(the collocation evaluator" + "".join(f", {n}" for n in notes) + "): the "
                "gait is the optimum of the stride problem for that blade.")
    return ""


def _motion_section(design_dir: Path, meta: dict) -> dict[str, Any] | None:
    """The motion model of a study whose runner adapted its motion to each design (seed 002):
    model, terms, and the leave-one-blade-out errors of the period and the joint angles."""
    name = meta.get("motion")
    if not name:
        return None
    path = design_dir / name
    motion = read_json(path, what="motion model")
    loo = motion.get("loo_angles_deg") or {}
    errors = pd.DataFrame(
        [{"quantity": "period", "leave-one-blade-out error": motion.get("loo_period_s"),
          "unit": "s"}]
        + [{"quantity": f"{k} angle", "leave-one-blade-out error": v, "unit": "deg"}
           for k, v in loo.items()])
    coef = pd.DataFrame([{"term": k, "period coefficient (s)": v}
                         for k, v in (motion.get("period_coefficients_s") or {}).items()])
    text = (f"Each design run follows the gait cycle predicted for its blade by a "
            f"{motion.get('model')} motion model in the coded factors "
            f"({', '.join(motion.get('factors', []))}), fitted to {motion.get('n_cycles')} "
            f"cycles of {motion.get('n_blades')} blades (period and joint angles at "
            f"{motion.get('n_phase_nodes')} normalised times; seed 002's motion adaptation). "
            "Leave-one-blade-out errors: RMS error of a blade's cycles predicted from the "
            "other blades (blank where the others cannot fit the model).")
    return {"title": "Design study: motion adaptation", "text": text,
            "tables": [("Motion model errors", errors), ("Period model", coef),
                       ("Cycles used", pd.DataFrame({"source": motion.get("sources", [])}))]}


def build_design_report(design_dir: str | Path, out_dir: str | Path | None = None) -> Path:
    """Write the design report to ``out_dir`` (default ``design_dir/report``); returns index."""
    design_dir = Path(design_dir)
    meta = {}
    if (design_dir / "study.json").is_file():
        meta = read_json(design_dir / "study.json", what="design study file")
    if (design_dir / "evaluator.json").is_file():  # e.g. the knee bound every stride was held to
        meta["evaluator"] = read_json(design_dir / "evaluator.json", what="evaluator settings")
    sections = design_report_sections(design_dir)
    rep = Report("Blade design study", subtitle=str(design_dir),
                 settings={k: v for k, v in meta.items() if k != "seed"},  # its own row
                 seed=meta.get("seed"))
    for s in sections:
        rep.add_section(**s)
    return Path(rep.write(Path(out_dir) if out_dir else design_dir / "report"))
