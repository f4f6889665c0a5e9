"""``bladelab predict --method collocation``: one stride by direct collocation.

The command parses its options into
:class:`~bladelab.predict.collocation.settings.CollocationSettings` and calls
:func:`bladelab.predict.collocation.named_runs.solve_named_stride`, which builds the runner and
the initial guess and owns the output folder (``solution.json`` for a converged solve,
``best_iterate.json`` otherwise). Progress goes to stderr, one line at each stage's start and
end and every :data:`PROGRESS_EVERY_S` seconds in between; stdout holds the summary (one JSON
object with ``--json``). A solve that does not converge exits with status 2 after naming
IPOPT's status and the worst-violated constraints.
"""

from __future__ import annotations

import json
import math
import shutil
import time
from pathlib import Path

import typer

from bladelab.cli.panels import renamed
from bladelab.errors import BladelabError, SpecError
from bladelab.predict import defaults
from bladelab.predict.collocation.mesh_check import (
    MESH_CHECK_DIR,
    MeshCheck,
    mesh_check_in_folder,
)
from bladelab.predict.collocation.named_runs import solve_named_stride
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.stored import runner_from_spec

__all__ = ["OPTIONS", "PEOPLE_STRIDE_TIME", "PROGRESS_EVERY_S", "StageProgress",
           "is_people_stride_time", "run_collocation", "stride_time_settings"]

#: Seconds between two progress lines while a stage iterates.
PROGRESS_EVERY_S = 5.0
#: Library argument or ``CollocationSettings`` field -> the option that sets it.
OPTIONS = {
    "model": "--model", "blade": "--blade", "body": "--body", "guess": "--guess",
    "mesh_intervals": "--mesh", "speed_m_per_s": "--speed", "max_iter": "--max-iter",
    "swing_clearance_m": "--swing-clearance", "knee_moment_min_nm": "--knee-moment-min",
    "knee_flexion_max_loaded_deg": "--knee-flexion-max",
    "pelvis_tilt_range_deg": "--tilt-range", "stride_time_range_s": "--stride-time",
    "stride_time_people": "--stride-time",
    "reference_weight": "--people-weight", "swing_knee_min_deg": "--swing-knee",
    "step_phase_tolerance": "--alternating-steps", "symmetric": "--symmetric",
    "prosthetic_load_max_bw": "--prosthetic-load-max",
    "athlete.body_mass_kg": "--body-mass", "athlete.height_m": "--height",
    "athlete.muscle_strength": "--muscle-strength",
    "athlete.max_shortening_velocity": "--max-shortening-velocity",
    "athlete.residual_limb_length_m": "--residual-limb",
    "athlete.thigh_length_m": "--thigh-length", "athlete.shank_length_m": "--shank-length",
    "athlete.prosthesis_extra_length_m": "--prosthesis-extra-length",
    "starts": "--starts", "mesh check": "--mesh-check",
}


class StageProgress:
    """Progress lines on stderr for one solve's stage reports (``SolveProgress``): a stage's
    start and end, and an iteration line at most every ``every_s`` seconds [s] (default
    :data:`PROGRESS_EVERY_S`), each after ``prefix``. Picklable (the sweep's workers use it)."""

    def __init__(self, prefix: str = "", every_s: float | None = None) -> None:
        self.prefix = prefix
        self.every_s = PROGRESS_EVERY_S if every_s is None else float(every_s)
        self.last = -math.inf

    def __call__(self, p) -> None:
        head = f"{self.prefix}{p.stage} stage"
        if p.event == "start":
            typer.echo(f"{head}: started ({p.message})", err=True)
            self.last = time.perf_counter()
        elif p.event == "iteration":
            now = time.perf_counter()
            if now - self.last >= self.every_s:
                self.last = now
                typer.echo(f"{head}: iteration {p.iteration}, objective {p.objective:.5g}, "
                           f"constraint violation {p.violation:.2g}, {p.elapsed_s:.0f} s",
                           err=True)
        else:
            typer.echo(f"{head}: {p.message} after {p.iteration} iterations, "
                       f"{p.elapsed_s:.1f} s", err=True)


def _text(summary: dict, path: Path, solved: bool, check: MeshCheck | None = None,
          start: str | None = None) -> str:
    head = "solution" if summary["converged"] else "best iterate (not converged)"
    lines = [f"{head}: {path}" + ("" if solved else " (already solved: read back)")]
    if start:
        lines.append(f"  started from: {start}")
    for key, value in summary.items():
        if key == "warnings":
            continue
        lines.append(f"  {key}: {value:.4g}" if isinstance(value, float)
                     else f"  {key}: {value}")
    lines += [f"  warning: {w}" for w in (summary.get("warnings") or "").split("; ") if w]
    if check is not None:
        lines.append(f"  {check.verdict()}")
        lines += [f"    {q}: {a} → {b} ({c})" for q, a, b, c in check.table()]
        if check.returned is not None:
            lines.append(f"  round trip ({check.coarse_intervals} intervals again, from the "
                         f"finer stride): this stride → round trip (change) → finer (change)")
            lines += [f"    {q}: {a} → {b} ({c}) → {d} ({e})"
                      for q, a, b, c, d, e in check.round_trip_table()]
    return "\n".join(lines)


def _mesh_check(out: Path, sol, *, asked: bool, solved: bool, resume: bool, max_iter: int):
    """The mesh-halving check of a converged stride in ``out`` (None if not asked or the
    stride did not converge); a check in the folder from an earlier stride is removed when
    the stride was solved anew, so that the report never shows a stale one."""
    folder = Path(out) / MESH_CHECK_DIR
    if solved and folder.exists() and not asked:
        shutil.rmtree(folder)
    if not asked or not sol.converged:
        return None
    runner = runner_from_spec(sol.model_spec)
    check = mesh_check_in_folder(folder, runner, sol, resume=resume and not solved,
                                 max_iter=max_iter, progress=StageProgress(prefix="mesh check: "))
    typer.echo(check.verdict(), err=True)
    return check


def _pair(text: str | None, option: str, expected: str, hint: str, *,
          single_ok: bool = False) -> tuple[float, float] | None:
    """``LO,HI`` (or, with ``single_ok``, one number T read as T,T) as a pair of numbers,
    checked by CollocationSettings; None for None."""
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) not in ((1, 2) if single_ok else (2,)):
        raise SpecError(f"expected {expected}, got {text!r}", where=option, hint=hint)
    return values[0], values[-1]


def _tilt_range(text: str | None) -> tuple[float, float] | None:
    """``--tilt-range LO,HI`` [deg]."""
    return _pair(text, "--tilt-range", "two numbers LO,HI [deg]",
                 "e.g. --tilt-range=-16,-2 (seed 001's window)")


#: ``--stride-time people``: people's band at each prescribed speed
#: (``CollocationSettings.stride_time_people``).
PEOPLE_STRIDE_TIME = "people"


def is_people_stride_time(text: str | None) -> bool:
    """True when ``--stride-time`` says ``people`` (any case, spaces around it allowed)."""
    return text is not None and text.strip().lower() == PEOPLE_STRIDE_TIME


def stride_time_settings(text: str | None) -> dict:
    """The ``CollocationSettings`` fields of ``--stride-time``: ``LO,HI`` or ``T`` [s] (T fixes
    the stride time) as ``stride_time_range_s``, ``people`` as ``stride_time_people``."""
    if is_people_stride_time(text):
        return {"stride_time_people": True}
    return {"stride_time_range_s": _pair(
        text, "--stride-time", "LO,HI or T [s], or people",
        "e.g. --stride-time 0.64,0.78 (people at 3.5 m/s), 0.70, or people (their band at "
        "the speed)", single_ok=True)}


def run_collocation(
    *,
    out: Path,
    model: str,
    blade: str | None,
    speed: float,
    max_speed: bool,
    mesh: int,
    guess: str,
    max_iter: int,
    resume: bool,
    force: bool,
    as_json: bool,
    body: str,
    swing_clearance: float,
    knee_moment_min: float | None,
    knee_flexion_max: float | None,
    tilt_range: str | None,
    stride_time: str | None = None,
    alternating_steps: float | None = None,
    prosthetic_load_max: float | None = None,
    people_weight: float | None = None,
    swing_knee: float | None = None,
    athlete: dict | None = None,
    starts: int | None = None,
    mesh_check: bool = False,
    symmetric: bool = False,
) -> int:
    """Run ``bladelab predict --method collocation``; returns the exit status (0 converged,
    2 not converged). ``alternating_steps``: ``CollocationSettings.step_phase_tolerance``;
    ``stride_time``: ``LO,HI`` or ``T`` [s], ``CollocationSettings.stride_time_range_s``, or
    ``people``, ``CollocationSettings.stride_time_people``;
    ``symmetric``: ``CollocationSettings.symmetric``;
    ``prosthetic_load_max``: ``CollocationSettings.prosthetic_load_max_bw``;
    ``swing_knee`` [deg]: ``CollocationSettings.swing_knee_min_deg`` (0: none; None: the
    body's default).
    ``athlete``: the runner scaled to this athlete (``body_mass_kg``, ``height_m``,
    ``muscle_strength``, ``max_shortening_velocity``, ``residual_limb_length_m``,
    ``thigh_length_m``, ``shank_length_m``, ``prosthesis_extra_length_m``; None: the body's
    own). ``starts``:
    starts of the stride, the best kept (None: :data:`~bladelab.predict.defaults.ATHLETE_STARTS` for a
    scaled athlete, else :data:`~bladelab.predict.defaults.STARTS`). ``mesh_check``: the
    converged stride solved again on twice the mesh intervals and compared
    (:mod:`~bladelab.predict.collocation.mesh_check`); a check left from an earlier solve in
    the folder is removed when the stride is solved anew."""
    if starts is None:
        starts = defaults.ATHLETE_STARTS if athlete else defaults.STARTS
    tilt = _tilt_range(tilt_range)
    period = stride_time_settings(stride_time)
    try:
        settings = CollocationSettings(
            mesh_intervals=mesh, speed_m_per_s=None if max_speed else float(speed),
            max_iter=max_iter, swing_clearance_m=swing_clearance,
            knee_moment_min_nm=knee_moment_min, knee_flexion_max_loaded_deg=knee_flexion_max,
            pelvis_tilt_range_deg=tilt, step_phase_tolerance=alternating_steps,
            **period,
            prosthetic_load_max_bw=prosthetic_load_max, symmetric=symmetric,
            **people_settings(body, people_weight, swing_knee, kind=model))
        result = solve_named_stride(out, model=model, blade=blade, body=body,
                                    settings=settings, guess=guess, athlete=athlete,
                                    starts=starts, resume=resume, force=force,
                                    progress=StageProgress(),
                                    say=lambda line: typer.echo(line, err=True))
        sol = result.solution
        check = _mesh_check(out, sol, asked=mesh_check, solved=result.solved, resume=resume,
                            max_iter=max_iter)
    except BladelabError as err:
        raise renamed(err, OPTIONS) from None
    summary = sol.summary()
    if as_json:
        typer.echo(json.dumps(summary | ({} if check is None
                                         else {"mesh_check": check.to_dict()})))
    else:
        typer.echo(_text(summary, result.path, result.solved, check, start=sol.guess_source))
    if sol.converged:
        return 0
    worst = "; ".join(f"{name} ({value:.3g})" for name, value in sol.nlp.worst_constraints)
    typer.echo(f"error: not converged: IPOPT status {sol.nlp.status} in the {sol.stage} stage "
               f"after {sol.nlp.iterations} iterations; worst-violated constraints: "
               f"{worst or 'none'}; best iterate saved to {result.path} (not a solution)",
               err=True)
    return 2
