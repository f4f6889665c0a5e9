"""Report sections of a collocation solution (``bladelab report DIR/solution.json``).

A collocation solution is one periodic stride at the mesh nodes. For the predictive report's
gait-cycle figures and tables (:func:`bladelab.report.predictive_sections.
add_predictive_sections`, the same as for a reflex solution) the stride is repeated
(:meth:`~bladelab.predict.collocation.solution.CollocationSolution.to_runner_result`: pelvis_tx
advanced by the stride length, :data:`REFINE` samples per mesh interval on the trapezoidal
rule's interpolant); nothing is re-simulated. :func:`collocation_sections` adds before them the
solve's own numbers: the summary of ``bladelab predict --method collocation --json``, IPOPT's
report of both stages, the dynamic consistency with the forward model, the vertical and horizontal
ground force per leg at the nodes over % of the stride, and how each foot lands (its slide at
touch-down).

A file is recognised by its ``"kind": "collocation-solution"`` field
(:func:`collocation_solution_file`); a best iterate (``"collocation-best-iterate"``) is not a
solution and is refused.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab.datasets import MEASURED_TRIAL_SPEED_M_PER_S
from bladelab.errors import BladelabError, InputFileError
from bladelab.predict.collocation.guess import measured_trial_guess
from bladelab.predict.collocation.human_running import (
    COMPARED_JOINTS,
    angle_agreement,
    human_running_criteria,
    stride_from_left_touchdown,
)
from bladelab.predict.collocation.mesh_check import MESH_CHECK_DIR, read_mesh_check
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.output_folder import SOLUTION_FILE
from bladelab.predict.collocation.settings import PEOPLE_REFERENCE
from bladelab.predict.collocation.solution import (
    BEST_ITERATE_KIND,
    SOLUTION_KIND,
    CollocationSolution,
)
from bladelab.predict.collocation.stored import athlete_label, runner_from_spec
from bladelab.predict.collocation.touchdown import touchdown_slides
from bladelab.report.collocation_loads import add_loads_section
from bladelab.report.stance_shape import stance_shape

__all__ = ["N_STRIDES", "REFINE", "collocation_sections", "collocation_solution_file",
           "reference_term_text"]

#: Strides in the trajectory handed to the gait-cycle analyses.
N_STRIDES = 3
#: Samples per mesh interval of that trajectory.
REFINE = 1


def _kind(path: Path) -> str | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data.get("kind") if isinstance(data, dict) else None


def collocation_solution_file(path: str | Path) -> Path | None:
    """The collocation solution file of ``path`` (the file itself, or ``solution.json`` in a
    ``bladelab predict --method collocation`` folder), or None if it is none.

    Raises
    ------
    InputFileError
        ``path`` is a best iterate (a solve that did not converge).
    """
    p = Path(path)
    if p.is_dir():
        p = p / SOLUTION_FILE
    if not p.is_file() or p.suffix.lower() != ".json":
        return None
    kind = _kind(p)
    if kind == BEST_ITERATE_KIND:
        raise InputFileError("the best iterate of a collocation solve that did not converge, "
                             "not a solution", file=p,
                             hint="resume the solve ('bladelab predict --method collocation "
                                  "--resume') until it writes solution.json")
    return p if kind == SOLUTION_KIND else None


def _label(sol) -> str:
    spec = sol.model_spec
    who = {"able": "able-bodied", "amputee": f"amputee {spec['blade']}",
           "transfemoral": f"transfemoral amputee {spec['blade']}"}[spec["model"]]
    speed = ("maximum speed" if sol.settings.speed_m_per_s is None
             else f"{sol.settings.speed_m_per_s:g} m/s")
    body = f", {spec['body']} body" if "body" in spec else ""
    athlete = f"; {athlete_label(spec)}" if "athlete" in spec else ""
    return f"{who} {speed} (collocation{body}{athlete})"


def _grf_figure(sol, trial=None):
    """Each leg's vertical (top) and horizontal (bottom) ground force over the stride from the
    left (intact) touch-down; with ``trial`` (the measured stride, a StrideGuess with its
    forces), the totals beside the measured totals in a second column."""
    import matplotlib.pyplot as plt

    rows = [(name, stride_from_left_touchdown(sol, values=force) / sol.body_weight_N, meas)
            for name, force, meas in (
                ("vertical", sol.leg_vertical_force(),
                 None if trial is None else trial.vertical_grf_bw),
                ("horizontal", sol.leg_horizontal_force(),
                 None if trial is None else trial.horizontal_grf_bw))]
    measured = any(m is not None for *_, m in rows)
    fig, axes = plt.subplots(2, 2 if measured else 1, figsize=(11 if measured else 7, 6.2),
                             squeeze=False)
    for r, (name, force, meas) in enumerate(rows):
        pct = np.linspace(0.0, 100.0, force.shape[0])
        ax = axes[r, 0]
        for j, leg in enumerate(sol.leg_names):
            ax.plot(pct, force[:, j], "o-", ms=3, label=leg)
        ax.set_xlabel("stride (% of the gait cycle, from the left/intact touch-down)")
        ax.set_ylabel(f"{name} GRF (body weights)")
        ax.set_title(f"each leg: {name}" + (" (forward positive)" if r else ""), fontsize=9)
        ax.legend(fontsize=7)
        if r:
            ax.axhline(0.0, color="0.8", lw=0.8, zorder=0)
        if not measured:
            continue
        ax = axes[r, 1]
        if meas is None:
            ax.text(0.5, 0.5, "not measured", ha="center", va="center", transform=ax.transAxes)
            continue
        total = force.sum(axis=1)
        ax.plot(pct, total, "o-", ms=3, color="k", label="this stride")
        ax.plot(np.linspace(0.0, 100.0, len(meas)), meas, "--", color="0.5",
                label="measured 3.5 m/s stride (RBDS001, mean)")
        ax.set_xlabel("stride (% of the gait cycle, from the left touch-down)")
        ax.set_ylabel(f"total {name} GRF (body weights)")
        ax.set_title("against the measured stride: " + ("the force's shape in stance" if not r
                     else "braking, then propulsion"), fontsize=9)
        lo = min(float(np.min(total)), float(np.min(meas)))
        hi = max(float(np.max(total)), float(np.max(meas)))
        ax.set_ylim(lo - 0.05 * (hi - lo) if r else None, hi + 0.3 * (hi - lo))
        if r:
            ax.axhline(0.0, color="0.8", lw=0.8, zorder=0)
        ax.legend(fontsize=7, loc="upper center", ncol=2)
    fig.tight_layout()
    return fig


#: Speeds [m/s] within which the measured 3.5 m/s trial is drawn beside a solution.
TRIAL_SPEED_WINDOW_M_PER_S = 0.51


def _trial_figure(sol, runner, trial):
    """Joint angles of the solution and of the measured trial over % of the stride from the
    left touch-down, per leg (``trial``: a StrideGuess of the measured stride)."""
    import matplotlib.pyplot as plt

    n = sol.nlp.q.shape[0] - 1
    q_sol = stride_from_left_touchdown(sol)
    pct_sol = np.linspace(0.0, 100.0, n + 1)
    pct_trial = np.linspace(0.0, 100.0, trial.q.shape[0])
    fig, axes = plt.subplots(2, 3, figsize=(10, 5.2), sharex=True)
    for row, (side, leg) in enumerate((("l", sol.leg_names[0]), ("r", sol.leg_names[1]))):
        for col, (base, label, sign) in enumerate(COMPARED_JOINTS):
            ax = axes[row, col]
            name = f"{base}_{side}"
            ax.set_title(f"{leg} leg: {label}", fontsize=9)
            if name not in runner.dof_names:
                ax.text(0.5, 0.5, "no such joint (prosthesis)", ha="center", va="center",
                        transform=ax.transAxes, fontsize=8)
                continue
            j = runner.dof(name)
            ax.plot(pct_sol, sign * np.degrees(q_sol[:, j]), label="collocation")
            ax.plot(pct_trial, sign * np.degrees(trial.q[:, j]), "k--", label="measured")
            ax.set_ylabel("angle (deg)", fontsize=8)
            if row == 1:
                ax.set_xlabel("% of the stride from the left touch-down", fontsize=8)
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def _measured_trial(runner, sol):
    """The measured 3.5 m/s trial's mean stride on ``runner``'s coordinates (a StrideGuess),
    or None where it does not apply (another speed, the trial file absent) or cannot be read."""
    speed = sol.mean_speed_mps
    if abs(speed - MEASURED_TRIAL_SPEED_M_PER_S) > TRIAL_SPEED_WINDOW_M_PER_S:
        return None
    try:
        return measured_trial_guess(runner, n=100)
    except BladelabError:  # the trial missing from the installation, or unreadable
        return None


def _imposed_stride_time_text(settings) -> str:
    """The sentence that says a stride time range was imposed (``--stride-time``), or ""."""
    imposed = settings.imposed_stride_time
    if imposed is None:
        return ""
    r = settings.stride_time_range_s
    what = f"{'at' if r is not None and r[0] == r[1] else 'within'} {imposed}"
    return (f" Stride time imposed {what} (bladelab predict --stride-time): the cadence is "
            "given, not predicted.")


def _objective_share_text(sol) -> str:
    """:func:`reference_term_text` of a solution, with the term's share of its objective."""
    value = sol.nlp.objective_terms.get("tracking")
    share = (f", {value:.3g} of the objective's {sol.nlp.objective:.4g}"
             if value is not None else "")
    return reference_term_text(sol.settings, share)


def reference_term_text(settings, share: str = "", *,
                        lead: str = "Not a free prediction: the objective held") -> str:
    """The sentence saying what an objective held besides the predictive terms (a
    :class:`~bladelab.predict.collocation.settings.CollocationSettings`): people's measured
    joint angles (a tracking term of measured running) or another solution's, opening with
    ``lead`` and with ``share`` (e.g. ", 0.35 of the objective's 5.1") after the weight; then
    the sentence saying that the swing knee was held at people's (``swing_knee_min_deg``);
    empty without either."""
    knee = settings.swing_knee_min_deg
    knee_text = ("" if knee is None else
                 f" Swing knee imposed: every knee that is a person's flexes at least {knee:g}° "
                 "at its peak (people's at 3.5 m/s; bladelab predict --swing-knee): the "
                 "swing's depth is given, not predicted.")
    if not settings.reference_weight:
        return knee_text
    if settings.reference == PEOPLE_REFERENCE:
        return (f" {lead} people's measured hip, knee and ankle angles at 3.5 m/s (Fukuchi et "
                f"al. 2017, subjects RBDS002 and RBDS003, not the trial that strides are "
                f"compared with), weight {settings.reference_weight:g} 1/rad²{share}."
                + knee_text)
    return (f" {lead} the joint angles and stride time of {Path(settings.reference).name}, "
            f"weight {settings.reference_weight:g} 1/rad²{share}." + knee_text)


def _mesh_check_of(path: Path, sol):
    """The mesh-halving check kept beside the solution (its folder's ``mesh-check/``), or
    None if there is none or it was made of another stride."""
    check = read_mesh_check((path if path.is_dir() else path.parent) / MESH_CHECK_DIR)
    return check if check is not None and check.describes(sol) else None


def _mesh_check_text(check) -> str:
    if check is None:
        return (" Not checked on a finer mesh (bladelab predict --mesh-check solves it on "
                "twice the mesh intervals): until then, differences of a few per cent between "
                "strides may be the mesh's.")
    return f" {check.verdict()}."


def _touchdown_text(sol, runner, cm, trial) -> str:
    """How each leg lands (:func:`~bladelab.predict.collocation.touchdown.touchdown_slides`), in
    words, for the ground-force figure's caption."""
    slides, work = touchdown_slides(sol, runner, cm)
    if not slides:
        return ""
    parts = [(f"the {s.leg} leg's loaded contact meets the ground at {s.speed_mps:+.2f} m/s and "
              f"slides {s.slide_mm:.0f} mm in {s.slide_ms:.0f} ms, braking at up to "
              f"{s.braking_bw:+.2f} BW")
             if s.slide_ms > 0 else
             f"the {s.leg} leg lands sticking (loaded contact at {s.speed_mps:+.2f} m/s)"
             for s in slides]
    sliding = any(s.slide_ms > 0 for s in slides)
    return ("At touch-down " + "; ".join(parts)
            + (" (a sliding contact brakes at its friction limit, μ times its normal force)"
               if sliding else "") + "; friction takes "
            + " and ".join(f"{w:.1f} J" for w in work.values())
            + f" per stride from the {' and '.join(work)} leg. A rigid contact sphere takes the "
            "foot's forward speed by sliding, where a shoe's sole and a heel pad take it in "
            "shear (docs/collocation.md, 'How a foot lands')"
            + ("; people land with a braking transient too (the measured stride, lower right)."
               if trial is not None and trial.horizontal_grf_bw is not None else "."))


def _add_human_running_section(report, sol, trial, check=None, shape=None) -> None:
    """The stride against measured human running, criterion by criterion (the report's first
    words about a gait), the shape of its stances beside the measured runner's (``shape``, a
    :class:`~bladelab.report.stance_shape.StanceShape`, or None) and its mesh-halving check
    (``check``, or None)."""
    crit = human_running_criteria(sol)
    if trial is not None:
        crit += angle_agreement(sol, trial.q)
    outside = [c for c in crit if not c.met]
    verdict = (f"This stride is outside measured human running on {len(outside)} of "
               f"{len(crit)} criteria: " + "; ".join(
                   f"{c.name} {c.value_text()} (people: {c.band_text()})" for c in outside)
               + "."
               if outside else f"This stride is within measured human running on all "
               f"{len(crit)} criteria.")
    table = pd.DataFrame([{"criterion": c.name, "value": c.value, "unit": c.unit,
                           "people": c.band_text(), "met": "yes" if c.met else "NO",
                           "note": c.note} for c in crit])
    report.add_section(
        "Against measured human running",
        text=(verdict + _objective_share_text(sol)
              + (" Symmetric by constraint: each leg does what the other did half a stride "
                 "earlier (bladelab predict --symmetric), so the step phase of 50 % and the "
                 "two legs' equal numbers are imposed, not predicted."
                 if sol.settings.symmetric else "")
              + _imposed_stride_time_text(sol.settings)
              + " Bands: people at this speed (bladelab.predict.collocation.human_running: "
              "the Fukuchi et al. 2017 trial at 3.5 m/s, Weyand et al. 2000 and "
              "Nummela et al. 2007 at 9 m/s, interpolated in speed between them)"
              + ("; joint angles against the measured 3.5 m/s stride." if trial is not None
                 else ".")
              + f" Contact times here interpolate the force between the nodes; the gait-cycle "
              f"and leg-stiffness tables below count whole mesh intervals "
              f"({1e3 * sol.period_s / sol.settings.mesh_intervals:.1f} ms each), so the two "
              f"may differ by up to one interval."
              + (shape.summary_text() if shape is not None else "") + _mesh_check_text(check)),
        tables=[("The stride against people running at its speed", table)]
        + ([] if shape is None else [(
            "The shape of each stance beside the measured runner's (Fukuchi et al. 2017, "
            "RBDS001 at 3.5 m/s, its mean stride; a second runner of that dataset, RBDS004 at "
            "2.5 m/s, peaks at 37–44 % of 78 stances; no criterion checks it)", shape.table())])
        + ([] if check is None else [(
            f"Mesh-halving check: the same problem on {check.fine_intervals} mesh intervals "
            f"against this stride's {check.coarse_intervals}"
            + ("" if check.converged else " (the finer solve did not converge: a best "
               "iterate's numbers)"),
            pd.DataFrame([{"quantity": q, f"{check.coarse_intervals} intervals": a,
                           f"{check.fine_intervals} intervals": b, "change": c}
                          for q, a, b, c in check.table()]))]
             + ([] if check.returned is None else [(
                 f"Round trip: the {check.coarse_intervals}-interval problem solved again from "
                 f"the {check.fine_intervals}-interval stride (against this stride: a lower "
                 "optimum of its own mesh; the finer against it: the mesh's own part)"
                 + ("" if check.returned_converged else " (did not converge: a best "
                    "iterate's numbers)"),
                 pd.DataFrame([{"quantity": q, "this stride": a, "round trip": b,
                                "round trip against this stride": c,
                                f"{check.fine_intervals} intervals": d,
                                "finer against the round trip": e}
                               for q, a, b, c, d, e in check.round_trip_table()]))])),
    )


def collocation_sections(report, path: str | Path) -> tuple[dict, object]:
    """Add the collocation solution's own sections to ``report``; return ({label:
    RunnerResult} for :func:`~bladelab.report.predictive_sections.add_predictive_sections`,
    the :class:`~bladelab.predict.collocation.solution.CollocationSolution`)."""
    sol = CollocationSolution.read(collocation_solution_file(path) or path)  # file or folder
    runner = runner_from_spec(sol.model_spec)
    cm = build_collocation_model(runner)
    result = sol.to_runner_result(N_STRIDES, refine=REFINE, runner=runner, cm=cm)
    s = sol.nlp
    summary = pd.DataFrame([{"quantity": k, "value": "none" if k == "warnings" and not v else v}
                            for k, v in sol.summary().items()])
    stages = []
    if sol.tracking is not None:
        t = sol.tracking
        stages.append({"stage": "tracking", "status": t.get("status"),
                       "iterations (count)": t.get("iterations"), "wall time (s)": t.get("wall_s"),
                       "objective (–)": t.get("objective"),
                       "largest constraint violation (–)": t.get("max_violation")})
    t = s.timings
    stages.append({"stage": sol.stage, "status": s.status, "iterations (count)": s.iterations,
                   "wall time (s)": s.wall_s, "objective (–)": s.objective,
                   "largest constraint violation (–)": s.max_violation,
                   "of it, building the solver (s)": t.get("build_s"),
                   "of it, our functions (s)": t.get("functions_s"),
                   "of it, IPOPT's own (s)": t.get("ipopt_own_s"),
                   "process peak memory (MB)": t.get("peak_memory_MB")})
    terms = pd.DataFrame([{"term": k, "value (–)": v} for k, v in s.objective_terms.items()])
    settings = pd.DataFrame([{"setting": k, "value": json.dumps(v) if isinstance(v, dict) else v}
                             for k, v in sol.settings.to_dict().items()]
                            + [{"setting": "initial guess", "value": sol.guess_source}])
    res = sol.residual
    consistency = pd.DataFrame([
        {"quantity": "dynamics residual, forward model (% of peak)",
         "value": res.get("dynamics_residual_pct")},
        {"quantity": "dynamics residual, forward bristle state reconstructed (% of peak)",
         "value": res.get("bristle_residual_pct")},
        {"quantity": "dynamics residual, collocation model (% of peak)",
         "value": res.get("collocation_residual_pct")},
        *({"quantity": f"largest forward − collocation {k} force of a contact (N)", "value": v}
          for k, v in (res.get("contact_force_diff_N") or {}).items()),
        *({"quantity": f"forward − collocation {k} force (% of peak)", "value": v}
          for k, v in (res.get("component_pct") or {}).items()),
        {"quantity": "worst coordinate", "value": res.get("worst_dof")},
        {"quantity": "worst node", "value": res.get("worst_node")},
        {"quantity": "peak generalised force, translations (N)", "value": res.get("peak_force_N")},
        {"quantity": "peak generalised force, rotations (N·m)", "value": res.get("peak_moment_Nm")},
    ])
    import matplotlib.pyplot as plt

    trial = _measured_trial(runner, sol)
    shape = stance_shape(sol, trial)
    _add_human_running_section(report, sol, trial, _mesh_check_of(Path(path), sol), shape)
    fig = _grf_figure(sol, trial)
    report.add_section(
        "Collocation solution",
        text=("One periodic stride solved by direct collocation (CasADi + IPOPT), "
              f"{sol.settings.mesh_intervals} mesh intervals"
              + (" (the multi-link blade's joints by backward Euler, the rest trapezoidal)"
                 if sol.settings.blade_backward_euler and sol.model_spec.get("blade_spec")
                 else "")
              + ". The figures and tables below "
              f"repeat that stride {N_STRIDES} times (pelvis advanced by the stride length, "
              f"{REFINE} sample{'s' if REFINE != 1 else ''} per mesh interval on the trapezoidal "
              "interpolant); nothing is "
              "re-simulated. Dynamics residual: MuJoCo's inverse dynamics at the nodes against "
              "the forward model's muscle + passive + contact generalised forces, largest "
              "difference in % of their peak (translations and rotations each against their "
              "own peak). The forward friction has a state (the bristle's anchor) that a "
              "collocation solution does not carry: the first row takes what the forward "
              "bristle can do at each node (sliding: −μ·Fn·sign(v); sticking, below 0.1 m/s: "
              "any force within ±μ·Fn, here the collocation's own), the second reconstructs "
              "the anchor along the stride. That second row is near 100 % in every solve so "
              "far: the smooth friction carries a standing foot's force by letting it slip a "
              "few mm/s, and a reconstructed bristle, stuck, stretches by that slip over the "
              "whole stance (docs/collocation.md, 'Dynamic consistency'); the first row is the "
              "check. The component rows show where a difference comes from."),
        figures=[("Vertical (top) and horizontal (bottom) ground reaction force per leg at the "
                  "mesh nodes over % of the stride, from the left (intact) touch-down"
                  + ("; right: the totals against the measured 3.5 m/s stride's (its force "
                     "platform, the mean of its strides), which show where in stance the "
                     "force peaks and how braking turns into propulsion"
                     if trial is not None and trial.vertical_grf_bw is not None else "")
                  + ". " + _touchdown_text(sol, runner, cm, trial)
                  + (shape.caption_text() if shape is not None else ""), fig)],
        tables=[("Summary (as 'bladelab predict --method collocation --json')", summary),
                ("IPOPT per stage", pd.DataFrame(stages)),
                ("Objective terms of the final stage", terms),
                ("Dynamic consistency with the forward model", consistency),
                ("Settings", settings)],
    )
    plt.close(fig)
    if trial is not None:
        fig = _trial_figure(sol, runner, trial)
        report.add_section(
            "Joint angles against the measured trial",
            text=("The solution's joint angles (solid) beside the measured running trial's "
                  f"mean stride (dashed: Fukuchi et al. 2017, subject RBDS001 at "
                  "3.5 m/s, the model's inverse kinematics of its markers, standing as zero), "
                  "both from the left leg's touch-down. Drawn for solutions within "
                  f"{TRIAL_SPEED_WINDOW_M_PER_S:g} m/s of the trial's speed."),
            figures=[("Joint angles of the solution and of the measured trial over % of the "
                      "stride", fig)],
        )
        plt.close(fig)
    add_loads_section(report, sol, runner, cm)
    return {_label(sol): result}, sol
