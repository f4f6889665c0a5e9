"""``bladelab predict --method collocation``: one stride by direct collocation (issue 15).

The command parses its options, builds the model and the initial guess, and calls
:func:`bladelab.predict.collocation.solve.predict_stride_in_folder`, which owns the output
folder (``solution.json`` for a converged solve, ``best_iterate.json`` otherwise). Progress goes
to stderr, one line at each stage's start and end and every :data:`PROGRESS_EVERY_S` seconds
in between; stdout holds the summary (one JSON object with ``--json``). A solve that does not
converge exits with status 2 after naming IPOPT's status and the worst-violated constraints.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import typer

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.guess import (
    MEASURED_STATIC,
    MEASURED_TRIAL,
    MEASURED_TRIAL_SPEED_M_PER_S,
)

__all__ = ["FUKUCHI_STATIC", "FUKUCHI_TRIAL", "PROGRESS_EVERY_S", "StageProgress", "TRIAL_SPEED_M_PER_S",
           "make_guess", "run_collocation"]

#: The measured running trial of ``--guess trial``, its standing trial and its treadmill speed
#: [m/s] (one definition: :mod:`bladelab.predict.collocation.guess`).
FUKUCHI_TRIAL = MEASURED_TRIAL
FUKUCHI_STATIC = MEASURED_STATIC
TRIAL_SPEED_M_PER_S = MEASURED_TRIAL_SPEED_M_PER_S
#: Seconds between two progress lines while a stage iterates.
PROGRESS_EVERY_S = 5.0
#: Template speed [m/s] of a maximum-speed problem's guess.
MAX_SPEED_TEMPLATE_M_PER_S = 4.0


def make_guess(runner, guess: str, *, n: int, speed: float | None):
    """The initial guess named by ``--guess``: template (at ``speed`` [m/s], or
    :data:`MAX_SPEED_TEMPLATE_M_PER_S` when None), trial, or a file (a collocation solution or
    best iterate, or a reflex-controller parameter file), on ``n`` mesh intervals."""
    from bladelab.predict.collocation.guess import (
        guess_from_reflex,
        guess_from_trial,
        template_guess,
    )

    if guess == "template":
        return template_guess(runner, speed=speed or MAX_SPEED_TEMPLATE_M_PER_S, n=n)
    if guess == "trial":
        if not FUKUCHI_TRIAL.is_file():
            raise InputFileError("the measured running trial is not there", file=FUKUCHI_TRIAL,
                                 where="--guess trial",
                                 hint="it needs the shared data folder beside the project "
                                      "(../shared/data), or use --guess template")
        static = FUKUCHI_STATIC if FUKUCHI_STATIC.is_file() else None
        return guess_from_trial(runner, FUKUCHI_TRIAL, static=static, n=n,
                                speed=TRIAL_SPEED_M_PER_S)
    path = Path(guess)
    kind = _file_kind(path)
    if kind == "collocation":
        from bladelab.predict.collocation.solution import CollocationSolution

        sol = CollocationSolution.read(path)
        guess = sol.to_guess(f"collocation solution {path.name} ({sol.guess_source})")
        if sol.model_spec["model"] == runner.kind:  # another body of the same kind is mapped
            return guess
        from bladelab.runner.params import PROSTHETIC_KINDS

        if {sol.model_spec["model"], runner.kind} <= set(PROSTHETIC_KINDS):
            from bladelab.predict.collocation.guess import prosthetic_stride_on

            return prosthetic_stride_on(runner, guess)
        raise SpecError("the guess is a solution of another model", file=path,
                        where="--guess", hint=f"it is of {sol.model_spec}; an amputee runner's "
                                              "stride starts the other amputee kind")
    return guess_from_reflex(path, n=n)


def _file_kind(path: Path) -> str:
    """``"collocation"`` or ``"reflex"`` for a ``--guess`` file."""
    from bladelab._io import read_json

    if not path.is_file():
        raise SpecError(f"{str(path)!r} is neither template, trial nor a file", where="--guess",
                        hint="template, trial, or the path of a solution.json, "
                             "best_iterate.json or reflex parameter JSON file")
    data = read_json(path, what="--guess file")
    if isinstance(data, dict) and str(data.get("kind", "")).startswith("collocation-"):
        return "collocation"
    if isinstance(data, dict) and isinstance(data.get("parameters"), dict):
        return "reflex"
    raise InputFileError("not a collocation solution nor a reflex parameter file", file=path,
                         where="--guess", hint="a solution.json, best_iterate.json or a "
                                               "'bladelab predict' parameter JSON file")


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


def _text(summary: dict, path: Path, solved: bool) -> str:
    head = "solution" if summary["converged"] else "best iterate (not converged)"
    lines = [f"{head}: {path}" + ("" if solved else " (already solved: read back)")]
    for key, value in summary.items():
        if key == "warnings":
            continue
        lines.append(f"  {key}: {value:.4g}" if isinstance(value, float)
                     else f"  {key}: {value}")
    lines += [f"  warning: {w}" for w in (summary.get("warnings") or "").split("; ") if w]
    return "\n".join(lines)


def _tilt_range(text: str | None) -> tuple[float, float] | None:
    """``--tilt-range LO,HI`` [deg] as a pair of numbers (checked by CollocationSettings)."""
    if text is None:
        return None
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise SpecError(f"expected two numbers LO,HI [deg], got {text!r}", where="--tilt-range",
                        hint="e.g. --tilt-range=-16,-2 (seed 001's window)") from None
    return lo, hi


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
    body: str = "seed001",
    swing_clearance: float = 0.0,
    knee_moment_min: float | None = None,
    knee_flexion_max: float | None = None,
    tilt_range: str | None = None,
) -> int:
    """Run ``bladelab predict --method collocation``; returns the exit status (0 converged,
    2 not converged)."""
    from bladelab.predict.collocation.solve import CollocationSettings, predict_stride_in_folder
    from bladelab.predict.collocation.stored import check_model_spec, runner_from_spec
    from bladelab.runner.params import KINDS, default_runner_params

    if model not in KINDS:
        raise SpecError(f"unknown model {model!r}", where="--model", hint=" or ".join(KINDS))
    if blade is None and model != "able":
        blade = default_runner_params(model).blade
    if not max_speed and not (math.isfinite(speed) and speed > 0):
        raise SpecError("speed must be positive", where="--speed")
    if mesh < 4:
        raise SpecError(f"need at least 4 mesh intervals, got {mesh}", where="--mesh")
    if max_iter < 1:
        raise SpecError(f"need at least 1 iteration, got {max_iter}", where="--max-iter")
    if not (math.isfinite(swing_clearance) and 0.0 <= swing_clearance < 0.5):
        raise SpecError(f"swing clearance must be within [0, 0.5) m, got {swing_clearance}",
                        where="--swing-clearance")
    for name, given in (("--knee-moment-min", knee_moment_min),
                        ("--knee-flexion-max", knee_flexion_max)):
        if given is not None and model != "transfemoral":
            raise SpecError(f"the {model} model has no prosthetic knee", where=name,
                            hint="a setting of --model transfemoral")
    spec = check_model_spec({"model": model, "blade": blade, "body": body})
    try:
        settings = CollocationSettings(mesh_intervals=mesh,
                                       speed_m_per_s=None if max_speed else float(speed),
                                       max_iter=max_iter, swing_clearance_m=swing_clearance,
                                       knee_moment_min_nm=knee_moment_min,
                                       knee_flexion_max_loaded_deg=knee_flexion_max,
                                       pelvis_tilt_range_deg=_tilt_range(tilt_range))
    except SpecError as err:  # the only values not checked above: name their options
        option = {"knee_moment_min_nm": "--knee-moment-min",
                  "knee_flexion_max_loaded_deg": "--knee-flexion-max",
                  "pelvis_tilt_range_deg": "--tilt-range"}.get(err.where)
        if option is None:
            raise
        raise SpecError(err.message, where=option, hint=err.hint) from None
    runner = runner_from_spec(spec)
    result = predict_stride_in_folder(
        out, runner, settings,
        lambda: make_guess(runner, guess, n=mesh, speed=settings.speed_m_per_s),
        model_spec=spec, resume=resume, force=force, progress=StageProgress())
    sol = result.solution
    summary = sol.summary()
    typer.echo(json.dumps(summary) if as_json else _text(summary, result.path, result.solved))
    if sol.converged:
        return 0
    worst = "; ".join(f"{name} ({value:.3g})" for name, value in sol.nlp.worst_constraints)
    typer.echo(f"error: not converged: IPOPT status {sol.nlp.status} in the {sol.stage} stage "
               f"after {sol.nlp.iterations} iterations; worst-violated constraints: "
               f"{worst or 'none'}; best iterate saved to {result.path} (not a solution)",
               err=True)
    return 2
