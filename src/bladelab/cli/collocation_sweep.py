"""``bladelab sweep --method collocation``: speed continuation and maximum speed per model.

The command parses its options and calls
:func:`bladelab.predict.collocation.named_runs.sweep_named_models`, which owns the output
folder (one subfolder per model, ``collocation-sweep.csv``). Progress goes to stderr, one line
per solve's start and end (and every :data:`~bladelab.cli.collocation.PROGRESS_EVERY_S`
seconds while IPOPT iterates), each line led by the model and the problem; stdout holds the
table (one JSON object with ``--json``). Any model that did not converge everywhere makes the
exit status 2, after all models ran, with one ``error:`` line naming each failure.
``--starts K`` solves each problem from up to K starts and keeps the best
(:mod:`bladelab.predict.collocation.starts`); the table then names the kept start and the
spread of the objectives.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from bladelab.cli.collocation import StageProgress, is_people_stride_time
from bladelab.cli.panels import renamed
from bladelab.cli.values import parse_list
from bladelab.errors import BladelabError, SpecError
from bladelab.predict.collocation.named_runs import sweep_named_models

__all__ = ["OPTIONS", "SweepProgress", "run_collocation_sweep"]

#: Library argument or ``CollocationSettings`` field -> the option that sets it (an unknown
#: blade is an unknown category).
OPTIONS = {
    "categories": "--categories", "blade": "--categories", "model": "--categories",
    "body": "--body", "speeds": "--speeds", "guess": "--guess", "mesh_intervals": "--mesh",
    "max_iter": "--max-iter", "starts": "--starts", "jobs": "--jobs",
    "people_weight": "--people-weight", "reference_weight": "--people-weight",
    "step_phase_tolerance": "--alternating-steps",
    "athlete.body_mass_kg": "--body-mass", "athlete.height_m": "--height",
    "athlete.muscle_strength": "--muscle-strength",
    "athlete.max_shortening_velocity": "--max-shortening-velocity",
    "athlete.residual_limb_length_m": "--residual-limb",
    "athlete.thigh_length_m": "--thigh-length", "athlete.shank_length_m": "--shank-length",
    "athlete.prosthesis_extra_length_m": "--prosthesis-extra-length",
    "mesh check": "--mesh-check", "settle": "--settle",
}


class SweepProgress:
    """Progress lines on stderr for :class:`ContinuationProgress` reports: each solve's start,
    its stages' start and end, an iteration line at most every ``every_s`` seconds [s], and
    its result. Picklable (it runs in the worker processes of ``--jobs``)."""

    def __init__(self, every_s: float | None = None) -> None:
        self.every_s = every_s
        self.stages: dict[str, object] = {}

    def __call__(self, r) -> None:
        head = f"{r.model}, {r.problem}:"
        if r.event == "solve":
            if head not in self.stages:
                self.stages[head] = StageProgress(f"{head} ", self.every_s)
            self.stages[head](r.solve)
        elif r.event == "read":
            typer.echo(f"{head} read back {r.path}", err=True)
        else:
            typer.echo(f"{head} {r.event}: {r.message}", err=True)


def _speeds(text: str) -> list[float]:
    speeds = parse_list(text, "--speeds", float,
                        hint="comma-separated speeds in m/s, e.g. 3,3.5,4")
    bad = [v for v in speeds if not (math.isfinite(v) and v > 0)]
    if bad:
        raise SpecError(f"speeds must be > 0 m/s, got {bad[0]:g}", where="--speeds")
    return speeds


def _text(result) -> str:
    if not result.rows:
        return f"no result; table: {result.table_path}"
    keep = ["model", "problem", "prescribed_speed_mps", "converged", "mean_speed_mps",
            "cost_of_transport_J_per_kg_m", "stride_time_s", "contact_time_s",
            "iterations", "wall_s"]
    if any("start" in row for row in result.rows):
        keep += ["start", "starts", "spread_pct"]
    if any("mesh_check_settled" in row for row in result.rows):
        keep += ["mesh_check_objective_change_pct", "mesh_check_stride_time_change_pct",
                 "mesh_check_settled"]
    lines = ["  ".join(keep)]
    for row in result.rows:
        cells = []
        for k in keep:
            v = row.get(k)
            missing = v is None or (isinstance(v, float) and not math.isfinite(v))
            cells.append("-" if missing else f"{v:.4g}" if isinstance(v, float) else str(v))
        lines.append("  ".join(cells))
    lines.append(f"table: {result.table_path}")
    return "\n".join(lines)


def run_collocation_sweep(
    *,
    out: Path,
    categories: str,
    able: bool,
    speeds: str,
    mesh: int,
    guess: str,
    max_iter: int,
    jobs: int,
    executor: str,
    resume: bool,
    force: bool,
    as_json: bool,
    starts: int,
    body: str,
    people_weight: float | None = None,
    swing_knee: float | None = None,
    alternating_steps: float | None = None,
    athlete: dict | None = None,
    mesh_check: bool = False,
    stride_time: str | None = None,
    settle: bool = False,
) -> int:
    """Run ``bladelab sweep --method collocation``; returns the exit status (0 every solve
    converged, 2 some model failed). ``alternating_steps``:
    ``CollocationSettings.step_phase_tolerance``; ``athlete``: every model scaled to this
    athlete (None: the body's own); ``swing_knee`` [deg]: people's swing knee
    (``CollocationSettings.swing_knee_min_deg``; 0: none; None: the body's default);
    ``mesh_check``: every converged solve checked on twice
    the mesh intervals; ``stride_time``: ``people`` (people's band at each prescribed speed,
    ``CollocationSettings.stride_time_people``) or None (free); ``settle``: a settling pass
    from the neighbouring categories' strides (the able runner's: its own faster ones)."""
    if stride_time is not None and not is_people_stride_time(stride_time):
        raise SpecError(f"a sweep imposes people's band at each speed, got {stride_time!r}",
                        where="--stride-time",
                        hint="--stride-time people; one range fits one speed: bladelab "
                             "predict --stride-time LO,HI")
    speed_list = _speeds(speeds)
    # --able --categories "": the able model alone
    cats = parse_list(categories, "--categories") if categories.strip() or not able else []
    try:
        result = sweep_named_models(
            out, categories=cats, speeds=speed_list, able=able, body=body, guess=guess,
            mesh_intervals=mesh, max_iter=max_iter, people_weight=people_weight,
            swing_knee_deg=swing_knee,
            step_phase_tolerance=alternating_steps, stride_time_people=stride_time is not None,
            athlete=athlete, starts=starts, jobs=jobs,
            executor=executor, resume=resume, force=force, progress=SweepProgress(),
            mesh_check=mesh_check, settle=settle)
    except BladelabError as err:
        raise renamed(err, OPTIONS) from None
    if as_json:
        typer.echo(json.dumps({"table": str(result.table_path), "rows": result.rows,
                               "failures": result.failures}))
    else:
        typer.echo(_text(result))
    if not result.failures:
        return 0
    n = len(result.failures)
    n_models = len(cats) + int(able)  # the sweep refuses a repeated category
    typer.echo(f"error: {n} of {n_models} model(s) failed:", err=True)
    for label, what in result.failures.items():
        typer.echo(f"error: {label}: " + "; ".join(what), err=True)
    return 2
