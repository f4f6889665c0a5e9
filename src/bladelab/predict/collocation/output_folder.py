"""The output folder of one stride's solve (``bladelab predict --method collocation``).

:func:`predict_stride_in_folder` runs :func:`~bladelab.predict.collocation.solve.predict_stride`
into a folder: ``solution.json`` only for a converged solve, ``best_iterate.json`` otherwise
(never both: the stale one is removed once the new file is in place); files are written
atomically, so an interruption leaves the previous state of the folder. :func:`read_stored` and
:func:`write_solve` are the same rules for any pair of such files (the speed continuation's
``speed-<v>.json``), :func:`check_output_folder` the checks of an output folder before a run.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import SolveProgress, predict_stride
from bladelab.predict.collocation.stored import check_model_spec, describe_problem, same_model_spec

__all__ = [
    "BEST_ITERATE_FILE",
    "SOLUTION_FILE",
    "STARTS_DIR",
    "FolderResult",
    "check_output_folder",
    "predict_stride_in_folder",
    "read_stored",
    "write_solve",
]

#: File names in a ``bladelab predict --method collocation`` folder.
SOLUTION_FILE = "solution.json"
BEST_ITERATE_FILE = "best_iterate.json"
#: The folder of each start's solve when a folder's stride is solved from several starts.
STARTS_DIR = "starts"


def read_stored(ok: Path, best: Path, spec: dict, settings: CollocationSettings):
    """(converged solution, best iterate) of one problem stored as ``ok`` / ``best`` (a
    solution file and a best-iterate file), each None if absent; the solution is preferred.

    Raises
    ------
    InputFileError
        A file holds another problem (model, mesh, speed or weights).
    """
    for path in (Path(ok), Path(best)):
        if not path.is_file():
            continue
        sol = CollocationSolution.read(path)
        if (not same_model_spec(sol.model_spec, check_model_spec(spec))
                or not sol.settings.same_problem(settings)):
            there, asked = describe_problem(sol.model_spec, sol.settings), describe_problem(
                spec, settings)
            if there == asked:
                there, asked = (f"{there}, weights {sol.settings.weights.to_dict()}",
                                f"weights {settings.weights.to_dict()}")
            raise InputFileError(
                f"holds another problem ({there}; asked: {asked})", file=path,
                hint="resume with the same model, blade, speed and mesh, --force to start "
                     "over, or choose another --out")
        if path == Path(ok) and sol.converged:
            return sol, None
        return None, sol
    return None, None


def write_solve(sol: CollocationSolution, ok: Path, best: Path) -> Path:
    """Write a solve as ``ok`` (converged) or ``best`` (best iterate), then remove the other,
    now stale, file; returns the path written."""
    target, stale = (Path(ok), Path(best)) if sol.converged else (Path(best), Path(ok))
    sol.write(target)
    stale.unlink(missing_ok=True)
    return target


@dataclass(frozen=True)
class FolderResult:
    """What :func:`predict_stride_in_folder` did.

    Attributes
    ----------
    solution
        The solution (or best iterate) found or read back.
    path
        The file it is in (``solution.json`` or ``best_iterate.json``).
    solved
        False when a converged solution was already in the folder (``resume``) and nothing was
        solved.
    """

    solution: object
    path: Path
    solved: bool


def _held(out: Path) -> list[str]:
    return [n for n in (SOLUTION_FILE, BEST_ITERATE_FILE, STARTS_DIR) if (out / n).exists()]


def check_output_folder(out: Path, *, resume: bool, force: bool,
                        held: Callable[[Path], list[str]] | None = None,
                        what: str = "collocation solve") -> list[str]:
    """The result files that the output folder ``out`` holds (``held(out)``, default a
    stride's: ``solution.json``, ``best_iterate.json``, ``starts``; empty if none or no
    folder); ``what`` names its kind in the errors.

    Raises
    ------
    InputFileError
        ``out`` is a file, or holds results and neither ``resume`` nor ``force`` is given, or
        ``resume`` is given and it holds none.
    SpecError
        Both ``resume`` and ``force``.
    """
    if resume and force:
        raise SpecError("give --resume or --force, not both", where="--resume/--force")
    if out.exists() and not out.is_dir():
        raise InputFileError("is a file, not a folder", file=out, hint="give a folder for --out")
    found = (held or _held)(out) if out.is_dir() else []
    if found and not (resume or force):
        shown = ", ".join(found[:3]) + (f" and {len(found) - 3} more" if len(found) > 3 else "")
        raise InputFileError(
            f"the output folder holds a {what} ({shown})", file=out,
            hint="--resume continues it, --force starts over in it, or choose another --out")
    if resume and not found:
        raise InputFileError(f"no {what} to resume from", file=out,
                             hint="run without --resume first, with the same --out")
    return found


def predict_stride_in_folder(
    out: str | Path,
    runner,
    settings: CollocationSettings,
    make_guess: Callable[[], object],
    *,
    model_spec: dict,
    resume: bool = False,
    force: bool = False,
    progress: Callable[[SolveProgress], None] | None = None,
) -> FolderResult:
    """:func:`predict_stride` writing its result into the folder ``out`` (module docstring).

    Parameters
    ----------
    out
        Output folder (created if needed).
    runner, settings, model_spec, progress
        As :func:`predict_stride`.
    make_guess
        Returns the initial guess; not called when resuming.
    resume
        Continue from the folder: a converged ``solution.json`` of the same problem (model,
        mesh, speed, weights) is returned as it is; a ``best_iterate.json`` of it is the warm
        start of the predictive stage.
    force
        Start over in a folder that holds a solve (its files are replaced once the new result
        is written).

    Raises
    ------
    InputFileError
        ``out`` holds a solve and neither ``resume`` nor ``force`` is given; ``resume`` without
        a solve in the folder, or with one of another problem.
    """
    out = Path(out)
    spec = check_model_spec(model_spec)
    check_output_folder(out, resume=resume, force=force)
    guess = None
    ok, best = out / SOLUTION_FILE, out / BEST_ITERATE_FILE
    if resume:
        done, iterate = read_stored(ok, best, spec, settings)
        if done is not None:
            return FolderResult(done, ok, False)
        guess = iterate.to_guess()
    if guess is None:
        guess = make_guess()
    sol = predict_stride(runner, settings, guess, model_spec=spec, progress=progress)
    target = write_solve(sol, ok, best)
    return FolderResult(sol, target, True)
