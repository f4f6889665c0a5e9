"""Report sections of a collocation sweep folder (``bladelab report DIR`` on the output of
``bladelab sweep --method collocation``).

The folder holds :data:`~bladelab.predict.collocation.sweep.SWEEP_TABLE` (one row per solve:
each model's speed continuation and its maximum speed) and the solution files it names. The
report shows, before the predictive sections that every predictive report has:

- cost of transport, contact time and peak vertical ground force per leg against speed, one
  curve per model, the maximum-speed solve marked;
- every solve of the table, converged or not (a solve that did not converge is listed, never
  plotted or averaged; a converged solve that the gait checks flag, its ``warnings`` column not
  empty: a hop, a stride on its bound, a double contact, an impact peak; the checks are run
  again on each solution file, so an older table is judged by today's checks) is drawn as a
  cross off the curves and left out of the category table, and the text names it);
- for a folder whose problems were solved from several starts (``bladelab sweep --method
  collocation --starts K``, or paths merged by ``benchmarks/collocation/merge_starts.py``):
  per problem the kept start, every start's objective and their spread (:func:`starts_table`);
- per blade category the summary that the reflex sweep's report shows (maximum speed, cost at
  4 m/s, 200/400 m times, contact times at the maximum speed), beside seed 001's values
  (:func:`~bladelab.report.predictive_sections.add_predictive_sections`' category section).

The gait-cycle figures and seed 001's Tables 3.2, 3.3 and D.1 then come from the converged
maximum-speed solutions (the stride repeated, not re-simulated; seed 001 reports those tables
at the maximum speed).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab.errors import InputFileError
from bladelab.predict.collocation.alternating_steps import step_phase
from bladelab.predict.collocation.continuation_records import ON_FLOOR_TOL_MPS
from bladelab.predict.collocation.human_running import gallop_sentence
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.predict.collocation.sweep import SWEEP_TABLE
from bladelab.report.collocation import reference_term_text

__all__ = ["collocation_sweep_sections", "is_collocation_sweep", "starts_table",
           "sweep_summary"]

#: Speed [m/s] at which the category table reports the cost of transport (seed 001 Fig. 3.7a).
COST_SPEED_M_PER_S = 4.0


def is_collocation_sweep(path: str | Path) -> bool:
    """True if ``path`` is a folder with a collocation sweep's table."""
    p = Path(path)
    return p.is_dir() and (p / SWEEP_TABLE).is_file()


def read_sweep_table(folder: str | Path) -> pd.DataFrame:
    """The sweep's table, with ``converged`` as bool and ``flagged`` (bool) added: converged,
    but with gait warnings (a table written before the warnings existed flags nothing).

    Raises
    ------
    InputFileError
        The table cannot be read or lacks a column the report needs.
    """
    path = Path(folder) / SWEEP_TABLE
    try:
        table = pd.read_csv(path)
    except (OSError, ValueError) as err:
        raise InputFileError(f"cannot read the sweep table ({err})", file=path,
                             hint="run 'bladelab sweep --method collocation --resume' on the "
                                  "folder to rewrite it") from None
    need = {"model", "blade", "problem", "prescribed_speed_mps", "converged", "mean_speed_mps",
            "cost_of_transport_J_per_kg_m", "file"}
    missing = sorted(need - set(table.columns))
    if missing:
        raise InputFileError(f"the sweep table lacks the column(s) {', '.join(missing)}",
                             file=path, hint="rewrite it with 'bladelab sweep --method "
                                             "collocation --resume'")
    table["converged"] = table["converged"].astype(str).str.lower().isin(["true", "1"])
    table["warnings"] = (table["warnings"].astype(object).fillna("").astype(str)
                         if "warnings" in table else "")
    return _flag(table)


def _flag(table: pd.DataFrame) -> pd.DataFrame:
    """Set ``flagged``: converged, with a non-empty ``warnings`` (on a de-fragmented copy: a
    wide table read column by column would warn of fragmentation)."""
    table = table.copy()
    table["flagged"] = table.converged & table.warnings.str.strip().str.len().gt(0)
    return table


def sweep_summary(table: pd.DataFrame) -> pd.DataFrame:
    """One row per blade category (amputee models) in the reflex sweep summary's columns
    (:func:`bladelab.predict.reflex.sweep.summarise`): max_speed [m/s] (the converged
    maximum-speed solve), cot_4 [J/(kg·m)] (converged solve at 4 m/s), t200 and t400 [s]
    (200 m and 400 m at the maximum speed) and the contact times [s] of each leg at the maximum
    speed. NaN where the solve is missing, did not converge or is flagged by the gait checks
    (``flagged`` of :func:`read_sweep_table`). A sweep with mesh-halving checks (``bladelab
    sweep --mesh-check``) adds ``settled``: whether those two solves settled on twice the mesh
    intervals, e.g. "4 m/s: yes; maximum speed: not checked". ``max_speed_floor`` says whether
    the maximum speed is its problem's floor (:func:`on_speed_floor`), e.g. "on it (5 m/s)"."""
    checked = "mesh_check_settled" in table.columns
    rows = []
    amputee = table[table.model.astype(str).str.startswith("amputee")]
    for cat, df in amputee.groupby("blade", sort=False):
        ok = df[df.converged & ~df.flagged]
        top = ok[ok.problem == "max-speed"]
        at4 = ok[(ok.problem == "speed")
                 & np.isclose(ok.prescribed_speed_mps.astype(float), COST_SPEED_M_PER_S)]
        vmax = float(top.mean_speed_mps.iloc[0]) if len(top) else math.nan
        floor = on_speed_floor(df, top)
        row = {"category": cat, "max_speed": vmax,
               "max_speed_floor": "–" if floor is None else (
                   f"{'on it' if floor[0] else 'above it'} ({floor[1]:g} m/s)"),
               "cot_4": float(at4.cost_of_transport_J_per_kg_m.iloc[0]) if len(at4) else math.nan,
               "t200": 200.0 / vmax if vmax > 0 else math.nan,
               "t400": 400.0 / vmax if vmax > 0 else math.nan}
        for leg in ("intact", "prosthetic"):
            col = f"contact_time_{leg}_s"
            row[f"contact_time_{leg}"] = (float(top[col].iloc[0]) if len(top) and col in top
                                          else math.nan)
        if checked:
            row["settled"] = "; ".join(f"{name}: {_settled_word(solve)}" for name, solve in (
                (f"{COST_SPEED_M_PER_S:g} m/s", at4), ("maximum speed", top)))
        rows.append(row)
    return pd.DataFrame(rows, columns=["category", "max_speed", "max_speed_floor", "cot_4",
                                       "t200", "t400",
                                       "contact_time_intact", "contact_time_prosthetic"]
                        + (["settled"] if checked else []))


def on_speed_floor(model_rows: pd.DataFrame, top: pd.DataFrame) -> tuple[bool, float] | None:
    """(on its floor, the floor [m/s]) of a model's converged maximum-speed solve ``top`` (one
    row or none) among the model's rows: the floor its table records (``speed_floor_mps``),
    else, in a table written before it did, the model's fastest prescribed speed (the floor of
    the continuation's warm start); on it within ``ON_FLOOR_TOL_MPS``. None without a solve or
    a floor."""
    if not len(top):
        return None
    floor = (pd.to_numeric(top["speed_floor_mps"], errors="coerce").iloc[0]
             if "speed_floor_mps" in top.columns else math.nan)
    if not math.isfinite(floor):
        speeds = pd.to_numeric(model_rows.loc[model_rows.problem == "speed",
                                              "prescribed_speed_mps"], errors="coerce")
        floor = speeds.max() if speeds.notna().any() else math.nan
    if not math.isfinite(floor):
        return None
    speed = float(top.mean_speed_mps.iloc[0])
    return speed - floor <= ON_FLOOR_TOL_MPS, float(floor)


def _floor_text(table: pd.DataFrame) -> str:
    """The sentence naming the models whose maximum speed is its problem's floor."""
    on = []
    for model, df in table.groupby("model", sort=False):
        top = df[df.converged & ~df.flagged & (df.problem == "max-speed")]
        floor = on_speed_floor(df, top)
        if floor is not None and floor[0]:
            on.append(f"{model} ({floor[1]:g} m/s)")
    if not on:
        return ""
    return (" On its floor (the speed of the stride its solve started from, which the "
            "problem holds it at or above): the maximum speed of " + ", ".join(on)
            + "; there the objective found no faster stride worth its effort, so that "
            "speed says only that the model runs at least that fast.")


def _settled_word(solve: pd.DataFrame) -> str:
    """'yes', 'no' or 'not checked' for the mesh-halving check of a (one-row) solve; '–'
    without a solve."""
    if not len(solve):
        return "–"
    value = solve["mesh_check_settled"].iloc[0]
    if pd.isna(value) or str(value).strip() == "":
        return "not checked"
    return "yes" if _truth(value) else "no"


def starts_table(table: pd.DataFrame) -> pd.DataFrame | None:
    """Per problem of a several-start table (a ``start`` column): model, problem, prescribed
    speed, converged, the kept start, how many starts converged (where recorded), the kept
    objective, every start's objective (``objective_<start>``) and ``spread_pct``
    (:func:`~bladelab.predict.collocation.starts.start_columns`); None for a one-start
    table."""
    if "start" not in table.columns:
        return None
    cols = ["model", "problem", "prescribed_speed_mps", "converged", "start", "starts",
            "objective", *[c for c in table.columns if c.startswith("objective_")],
            "spread_pct"]
    return table[[c for c in cols if c in table.columns]].reset_index(drop=True)


def _starts_shown(starts: pd.DataFrame) -> pd.DataFrame:
    """:func:`starts_table` as the report shows it: objectives to five significant digits
    (starts differ by tenths of a per cent), the count of starts as an integer."""
    shown = starts.copy()
    for c in [c for c in shown.columns if c == "objective" or c.startswith("objective_")]:
        shown[c] = [f"{v:.5g}" if pd.notna(v) else "–" for v in shown[c]]
    if "starts" in shown:
        shown["starts"] = [f"{v:.0f}" if pd.notna(v) else "–" for v in shown["starts"]]
    return shown


def _with_current_warnings(table: pd.DataFrame, folder: Path) -> tuple[pd.DataFrame, dict]:
    """(the table with ``warnings`` and ``flagged`` from today's gait checks, re-run on each
    converged solve's file (a table written before a check existed says nothing of it), {row
    index: the solution read}); a row whose file is missing keeps its recorded warnings."""
    table = table.copy()
    solutions = {}
    for i, row in table[table.converged].iterrows():
        path = folder / str(row["file"])
        if path.is_file():
            solutions[i] = CollocationSolution.read(path)
            table.loc[i, "warnings"] = "; ".join(solutions[i].gait_warnings())
    return _flag(table), solutions


#: The sweep table's columns shown with a solve's mesh-halving check
#: (:func:`~bladelab.predict.collocation.sweep.mesh_check_columns`) -> their headers.
_MESH_CHECK_SHOWN = {
    "mean_speed_mps": "speed (m/s)", "mesh_check_converged": "finer solve converged",
    "mesh_check_settled": "settled", "mesh_check_objective_change_pct": "objective (%)",
    "mesh_check_stride_time_change_pct": "stride time (%)",
    "mesh_check_cot_change_pct": "cost of transport (%)",
    "mesh_check_round_trip_objective_pct": "round trip: objective (%)",
    "mesh_check_own_objective_pct": "the mesh's own part: objective (%)",
    "mesh_check_own_stride_time_pct": "the mesh's own part: stride time (%)"}


def mesh_check_table(table: pd.DataFrame) -> pd.DataFrame | None:
    """The converged solves' mesh-halving checks (``bladelab sweep --mesh-check``): model,
    problem, speed and the check's columns; None for a sweep without them."""
    if "mesh_check_settled" not in table.columns:
        return None
    rows = table[table.converged]
    cols = ["model", "problem", *_MESH_CHECK_SHOWN]
    shown = rows[[c for c in cols if c in rows.columns]].reset_index(drop=True)
    return shown.rename(columns=_MESH_CHECK_SHOWN)


def _truth(v) -> bool:
    return str(v).strip().lower() in ("true", "1", "1.0")


def _mesh_check_text(checks: pd.DataFrame | None) -> str:
    if checks is None:
        return (" No mesh-halving check ('bladelab sweep --mesh-check' solves every problem "
                "again on twice the mesh intervals): differences of a few per cent between "
                "solves may be the mesh's.")
    done = checks[checks["settled"].notna()]
    settled = int(sum(_truth(v) for v in done["settled"]))
    change = pd.to_numeric(done["objective (%)"], errors="coerce").abs()
    text = (f" Mesh-halving check: {settled} of {len(done)} converged solves settled "
            "(objective and stride time within 1 % on twice the mesh intervals)")
    if change.notna().any():
        text += f"; objectives moved by {change.min():.2g}–{change.max():.2g} %"
    return text + " (table 'Mesh-halving check per solve')."


def _problem_name(row) -> str:
    """'amputee Cat4 speed 5.0' or 'able max-speed' for the text."""
    return (f"{row.model} {row.problem} "
            f"{row.prescribed_speed_mps if row.problem == 'speed' else ''}").strip()


def _speed_figure(table: pd.DataFrame):
    """Cost of transport, contact time and peak vertical GRF per leg against speed: curves
    through the clean converged solves, a cross for each flagged one."""
    import matplotlib.pyplot as plt

    flagged = table.flagged
    ok = table[table.converged]
    # per-leg columns contact_time_<leg>_s (not the legs' mean, contact_time_s)
    legs = [m.group(1) for c in table.columns if (m := re.fullmatch(r"contact_time_(.+)_s", c))]
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    quantities = [("cost_of_transport_J_per_kg_m", "cost of transport (J/(kg·m))", [""]),
                  ("contact_time_{}_s", "contact time (s)", legs),
                  ("peak_vertical_grf_{}_bw", "peak vertical GRF (body weights)", legs)]
    for ax, (col, label, which) in zip(axes, quantities, strict=True):
        for k, (model, df) in enumerate(ok.groupby("model", sort=False)):
            df = df.sort_values("mean_speed_mps")
            color = f"C{k}"
            for j, leg in enumerate(which):
                c = col.format(leg) if leg else col
                if c not in df or df[c].isna().all():
                    continue
                style = "-" if j == 0 else "--"
                name = f"{model} {leg}".strip()
                bad = flagged.loc[df.index].to_numpy(bool)
                clean = df[~bad]
                ax.plot(clean.mean_speed_mps, clean[c], style, color=color, marker="o", ms=3,
                        label=name)
                top = clean[clean.problem == "max-speed"]
                ax.plot(top.mean_speed_mps, top[c], "*", color=color, ms=10)
                ax.plot(df.mean_speed_mps[bad], df[c][bad], "x", color=color, ms=7, mew=1.5)
        if flagged.any():
            ax.plot([], [], "x", color="0.3", label="flagged (gait warnings)")
        ax.set_xlabel("mean speed (m/s)")
        ax.set_ylabel(label)
    axes[0].legend(fontsize=7)
    axes[1].legend(fontsize=6, ncol=1)
    fig.tight_layout()
    return fig


def collocation_sweep_sections(report, folder: str | Path) -> tuple[dict, pd.DataFrame]:
    """Add the sweep's own sections to ``report``; return ({label: RunnerResult} of the
    converged maximum-speed solutions, for the predictive sections; the category summary
    :func:`sweep_summary`)."""
    import matplotlib.pyplot as plt

    folder = Path(folder)
    table, solutions = _with_current_warnings(read_sweep_table(folder), folder)
    failed = table[~table.converged]
    fig = _speed_figure(table)
    text = f"{len(table)} solves, {int(table.converged.sum())} converged. "
    starts = starts_table(table)
    if starts is not None:  # --starts K, or a merge of paths (merge_starts.py)
        spread = pd.to_numeric(table.get("spread_pct"), errors="coerce")
        largest = spread.max()
        text += ("Each problem was solved from several starts (the paths of a merged folder, "
                 "or the starts of 'bladelab sweep --starts', which continues each model from "
                 "the kept solution, and of its settling pass '--settle', labelled "
                 "from-<category>: the two nearest categories' kept strides; from-speed-<v>, "
                 "from-max-speed, from-stored: the able runner's own other strides and its "
                 "shipped stride; at the maximum speed every start held at the model's own "
                 "speed floor) and "
                 "the best converged solve kept: the lowest objective, "
                 "one without gait warnings preferred (column 'start' names it, "
                 "'objective_<start>' every start's, empty where it did not converge or did not "
                 "run; 'spread_pct' the largest minus the lowest objective in % of the lowest, "
                 "among the converged starts without gait warnings; the table 'Starts per "
                 "problem' shows them)"
                 + (f"; the largest spread between starts is "
                    f"{largest:.2f}".rstrip("0").rstrip(".") + " % of the lowest objective."
                    if spread.notna().any() else "."))
    else:
        text += ("Each model's speeds were solved in the order given, each warm-started from "
                 "the previous converged speed; the maximum speed (star) from the fastest.")
    text += (" Curves and the category table use converged solves without gait warnings "
             "only. The maximum speed is the optimum of the maximum-speed problem (speed "
             "traded against effort, at least the fastest prescribed speed solved), not the "
             "fastest stride the body can run, which a speed continuation to its end finds "
             "(docs/collocation.md, 'How fast the body can run').")
    text += _floor_text(table)
    text += "".join(sorted({reference_term_text(
        sol.settings, lead="Not free predictions: every objective held")
        for sol in solutions.values()}))
    banded = [sol.settings for sol in solutions.values() if sol.settings.stride_time_people]
    if banded:
        text += (" The stride time of every prescribed speed is imposed within people's band "
                 "at that speed (bladelab sweep --stride-time people; e.g. "
                 f"{banded[0].imposed_stride_time}): the cadence is given, not predicted; the "
                 "maximum speed's is free.")
    gallops = gallop_sentence([100.0 * step_phase(sol.leg_vertical_force()[:-1])
                               for sol in solutions.values()])
    if gallops:
        text += " Converged solves: " + gallops
    flagged = table[table.flagged]
    if len(flagged):
        text += (" Converged but flagged by the gait checks (drawn as crosses, left out of the "
                 "curves and the category table; the table's 'warnings' column says why): "
                 + ", ".join(_problem_name(r) for r in flagged.itertuples()) + ".")
    if len(failed):
        text += (" Not converged (listed in the table, left out of the figures and the "
                 "category table): " + ", ".join(_problem_name(r) for r in failed.itertuples())
                 + ".")
    checks = mesh_check_table(table)
    text += _mesh_check_text(checks)
    shown = table.rename(columns={"file": "solution file"})
    report.add_section(
        "Collocation sweep: speed continuation and maximum speed",
        text=text,
        figures=[("Cost of transport, contact time and peak vertical GRF per leg against mean "
                  "speed (solid: left/intact leg, dashed: right/prosthetic; star: maximum "
                  "speed)", fig)],
        tables=[("Every solve (collocation-sweep.csv)", shown)] + (
            [] if starts is None else [
                ("Starts per problem: objectives and spread", _starts_shown(starts))]) + (
            [] if checks is None else [
                ("Mesh-halving check per solve: the change [%] from the sweep's mesh to twice "
                 "its intervals", checks)]),
    )
    plt.close(fig)
    results = {}
    for r in table[table.converged & (table.problem == "max-speed")].itertuples():
        if r.Index not in solutions:
            raise InputFileError("a solution named in the sweep table is missing",
                                 file=folder / str(r.file),
                                 hint="re-run 'bladelab sweep --method collocation --resume'")
        sol = solutions[r.Index]
        runner = runner_from_spec(sol.model_spec)
        label = (f"{r.model} max {sol.mean_speed_mps:.2f} m/s (collocation"
                 + (", flagged)" if r.flagged else ")"))
        results[label] = sol.to_runner_result(3, runner=runner,
                                              cm=build_collocation_model(runner))
    return results, sweep_summary(table)
