"""Report sections of a collocation solution (``bladelab report DIR/solution.json``).

A collocation solution is one periodic stride at the mesh nodes. For the predictive report's
gait-cycle figures and tables (:func:`bladelab.report.predictive_sections.
add_predictive_sections`, the same as for a reflex solution) the stride is repeated
(:meth:`~bladelab.predict.collocation.solution.CollocationSolution.to_runner_result`: pelvis_tx
advanced by the stride length, :data:`REFINE` samples per mesh interval on the trapezoidal
rule's interpolant); nothing is re-simulated. :func:`collocation_sections` adds before them the
solve's own numbers: the summary of ``bladelab predict --method collocation --json``, IPOPT's
report of both stages, the dynamic consistency with the forward model, and the vertical ground
force per leg at the nodes over % of the stride.

A file is recognised by its ``"kind": "collocation-solution"`` field
(:func:`collocation_solution_file`); a best iterate (``"collocation-best-iterate"``) is not a
solution and is refused.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab.errors import InputFileError

__all__ = ["N_STRIDES", "REFINE", "collocation_sections", "collocation_solution_file"]

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
    from bladelab.predict.collocation.solution import BEST_ITERATE_KIND, SOLUTION_KIND
    from bladelab.predict.collocation.solve import SOLUTION_FILE

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
    who = "able-bodied" if spec["model"] == "able" else f"amputee {spec['blade']}"
    speed = ("maximum speed" if sol.settings.speed_m_per_s is None
             else f"{sol.settings.speed_m_per_s:g} m/s")
    body = f", {spec['body']} body" if "body" in spec else ""
    return f"{who} {speed} (collocation{body})"


def _grf_figure(sol):
    import matplotlib.pyplot as plt

    fz = sol.leg_vertical_force() / sol.body_weight_N
    pct = np.linspace(0.0, 100.0, fz.shape[0])
    fig, ax = plt.subplots(figsize=(7, 3.2))
    for j, leg in enumerate(sol.leg_names):
        ax.plot(pct, fz[:, j], "o-", ms=3, label=leg)
    ax.set_xlabel("stride (% of the gait cycle, from the left/intact touch-down)")
    ax.set_ylabel("vertical GRF (body weights)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def collocation_sections(report, path: str | Path) -> tuple[dict, object]:
    """Add the collocation solution's own sections to ``report``; return ({label:
    RunnerResult} for :func:`~bladelab.report.predictive_sections.add_predictive_sections`,
    the :class:`~bladelab.predict.collocation.solution.CollocationSolution`)."""
    from bladelab.predict.collocation.model import build_collocation_model
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.predict.collocation.stored import runner_from_spec

    sol = CollocationSolution.read(collocation_solution_file(path) or path)  # file or folder
    runner = runner_from_spec(sol.model_spec)
    result = sol.to_runner_result(N_STRIDES, refine=REFINE, runner=runner,
                                  cm=build_collocation_model(runner))
    s = sol.nlp
    summary = pd.DataFrame([{"quantity": k, "value": v} for k, v in sol.summary().items()])
    stages = []
    if sol.tracking is not None:
        t = sol.tracking
        stages.append({"stage": "tracking", "status": t.get("status"),
                       "iterations (count)": t.get("iterations"), "wall time (s)": t.get("wall_s"),
                       "objective (–)": t.get("objective"),
                       "largest constraint violation (–)": t.get("max_violation")})
    stages.append({"stage": sol.stage, "status": s.status, "iterations (count)": s.iterations,
                   "wall time (s)": s.wall_s, "objective (–)": s.objective,
                   "largest constraint violation (–)": s.max_violation})
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

    fig = _grf_figure(sol)
    report.add_section(
        "Collocation solution",
        text=("One periodic stride solved by direct collocation (CasADi + IPOPT), "
              f"{sol.settings.mesh_intervals} mesh intervals. The figures and tables below "
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
              "the anchor along the stride. The component rows show where a difference comes "
              "from."),
        figures=[("Vertical ground reaction force per leg at the mesh nodes over % of the "
                  "stride", fig)],
        tables=[("Summary (as 'bladelab predict --method collocation --json')", summary),
                ("IPOPT per stage", pd.DataFrame(stages)),
                ("Objective terms of the final stage", terms),
                ("Dynamic consistency with the forward model", consistency),
                ("Settings", settings)],
    )
    plt.close(fig)
    return {_label(sol): result}, sol
