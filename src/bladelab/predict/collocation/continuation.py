"""Speed continuation and maximum speed of one model (issue 15).

Two drivers on top of :func:`~bladelab.predict.collocation.solve.predict_stride`:

- :func:`speed_continuation` solves the stride at a sequence of prescribed speeds [m/s], in the
  order given, each warm-started from the previous converged solution
  (``solution.to_guess().with_speed(v)``: same period and joint curves, pelvis_tx and its
  speed scaled to the new mean speed; a collocation guess skips the tracking stage). The
  first speed starts from ``first_guess`` (template, trial, reflex solution, or a collocation
  solution), through the tracking stage unless it is a collocation solution.
- :func:`max_speed` solves the maximum-speed problem (``CollocationSettings(speed_m_per_s=
  None)``: the mean speed maximised with an effort term), warm-started from the fastest
  converged solution of the continuation.

The category sweep that runs both for several models is
:func:`bladelab.predict.collocation.sweep.collocation_sweep`.

Files (JSON of :class:`~bladelab.predict.collocation.solution.CollocationSolution`, written
atomically as soon as a solve ends, so results already computed are never lost):
``speed-<v>.json`` (``<v>`` as ``f"{v:g}"``: ``speed-3.5.json``, ``speed-4.json``) for a
converged solve, ``speed-<v>.best_iterate.json`` for one that did not converge (never both: the
stale one is removed once the new file is in place); ``max-speed.json`` and
``max-speed.best_iterate.json`` likewise.

Failure: a speed that does not converge from the previous converged one is tried again after
an intermediate speed halfway between them (``speed-<mid>.json``, a record of its own), down
to steps of 1/2^``refinements`` of the first step towards that prescribed speed (default
:data:`DEFAULT_REFINEMENTS` = 2: quarter steps; measured on
2026-11-25: the amputee Cat4 stride warm-started from 4 to 5 m/s was still infeasible after
800 iterations). A speed that still does not converge is recorded (its best-iterate file,
IPOPT's status in the table) and the continuation stops there;
:attr:`ContinuationResult.last_converged_speed` reports the last speed that converged.

Resuming: running again with the same folder reads a converged file of the same problem (model,
mesh, speed, objective weights: :meth:`CollocationSettings.same_problem`) back instead of
solving it; a best iterate of the same problem warm-starts that speed's predictive stage (as
``bladelab predict --resume``). A file of another problem is an error naming it, unless
``force`` (start over: existing files are neither read nor trusted, and are replaced).

Table rows (:meth:`SolveRecord.row`, units in the names): ``model``, ``blade``, ``problem``
(``speed`` or ``max-speed``), ``prescribed_speed_mps`` (empty for the maximum speed),
``converged``, ``status``, ``mean_speed_mps``, ``cost_of_transport_J_per_kg_m``,
``stride_time_s``, ``contact_time_s`` (mean of the legs), ``contact_time_<leg>_s``,
``peak_vertical_grf_<leg>_bw`` [body weights], ``flight_fraction``, ``dynamics_residual_pct``,
``iterations``, ``wall_s`` (of the solve, both stages; the stored value for a file read back),
``mesh_intervals`` and ``file``. Legs are left/right (able) or intact/prosthetic (amputee).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.solve import (
    COLLOCATION_SOURCE,
    CollocationSettings,
    SolveProgress,
    predict_stride,
)
from bladelab.predict.collocation.stored import (
    check_model_spec,
    model_label,
    read_stored,
    runner_from_spec,
    write_solve,
)

__all__ = [
    "MAX_SPEED_BEST_ITERATE_FILE",
    "MAX_SPEED_FILE",
    "TABLE_COLUMNS",
    "DEFAULT_REFINEMENTS",
    "ContinuationProgress",
    "ContinuationResult",
    "LazyRunner",
    "SolveRecord",
    "check_speeds",
    "max_speed",
    "max_speed_settings",
    "model_folder",
    "speed_continuation",
    "speed_file",
    "table_columns",
]

#: File names of the maximum-speed solve in a model's folder.
MAX_SPEED_FILE = "max-speed.json"
MAX_SPEED_BEST_ITERATE_FILE = "max-speed.best_iterate.json"
#: Columns of a table row in order; the per-leg columns (``contact_time_<leg>_s``,
#: ``peak_vertical_grf_<leg>_bw``) follow ``contact_time_s`` in :data:`_LEGS` order.
TABLE_COLUMNS = (
    "model", "blade", "problem", "prescribed_speed_mps", "converged", "status",
    "mean_speed_mps", "cost_of_transport_J_per_kg_m", "stride_time_s", "contact_time_s",
    "flight_fraction", "dynamics_residual_pct", "iterations", "wall_s", "mesh_intervals", "file",
)
_LEGS = ("intact", "prosthetic", "left", "right")
_PER_LEG = ("contact_time_{}_s", "peak_vertical_grf_{}_bw")


def speed_file(speed: float, *, converged: bool = True) -> str:
    """The file name of the solve at ``speed`` [m/s]: ``speed-<v:g>.json``, or
    ``speed-<v:g>.best_iterate.json`` when it did not converge."""
    return f"speed-{float(speed):g}" + (".json" if converged else ".best_iterate.json")


def model_folder(spec: dict) -> str:
    """A model's subfolder in a sweep: ``able`` or ``amputee-<blade>``."""
    return model_label(spec).replace(" ", "-")


@dataclass(frozen=True)
class ContinuationProgress:
    """One progress report of the drivers.

    Attributes
    ----------
    model
        :func:`model_label` of the model.
    problem
        ``"<v> m/s"`` or ``"maximum speed"``.
    event
        ``"read"`` (a converged file read back, ``path``), ``"start"`` (a solve starts;
        ``message`` names its warm start), ``"solve"`` (a :class:`SolveProgress` of the solve in
        ``solve``), ``"converged"`` or ``"failed"`` (``path``: the file written; ``message``:
        the result), ``"refine"`` (a failed speed is tried again after an intermediate one,
        named in ``message``).
    path
        The file concerned, if any.
    message
        Text for the event.
    solve
        The solver's own report (event ``"solve"``).
    """

    model: str
    problem: str
    event: str
    path: Path | None = None
    message: str = ""
    solve: SolveProgress | None = None


@dataclass(frozen=True)
class SolveRecord:
    """One solve of a driver (solved now or read back).

    Attributes
    ----------
    problem
        ``"speed"`` (prescribed) or ``"max-speed"``.
    speed_mps
        The prescribed speed [m/s]; None for the maximum speed.
    solution
        The :class:`CollocationSolution` (a best iterate when not converged).
    path
        The file it is in.
    solved
        False when it was read back from ``path`` (nothing solved).
    """

    problem: str
    speed_mps: float | None
    solution: object
    path: Path
    solved: bool

    @property
    def converged(self) -> bool:
        return bool(self.solution.converged)

    def row(self, relative_to: str | Path | None = None) -> dict:
        """The table row (module docstring); ``file`` relative to ``relative_to`` if given."""
        sol = self.solution
        summary = sol.summary()
        path = self.path
        if relative_to is not None:
            try:
                path = self.path.relative_to(relative_to)
            except ValueError:
                pass
        row = {
            "model": model_label(sol.model_spec),
            "blade": sol.model_spec["blade"] or "",
            "problem": self.problem,
            "prescribed_speed_mps": self.speed_mps,
            "converged": summary["converged"],
            "status": summary["status"],
        }
        skip = {"converged", "status", "iterations", "wall_s"}
        row.update({k: v for k, v in summary.items() if k not in skip})
        row.update({"iterations": summary["iterations"], "wall_s": summary["wall_s"],
                    "mesh_intervals": sol.settings.mesh_intervals, "file": str(path)})
        return row


@dataclass(frozen=True)
class ContinuationResult:
    """What :func:`speed_continuation` did: one record per speed reached, in order (the last one
    did not converge when the continuation stopped early).

    Attributes
    ----------
    speeds
        The prescribed speeds asked for [m/s], in order.
    records
        :class:`SolveRecord` of each speed reached, intermediate speeds of a refined step
        included, in the order solved.
    """

    speeds: tuple[float, ...]
    records: tuple[SolveRecord, ...]

    @property
    def complete(self) -> bool:
        """True if every prescribed speed converged."""
        done = {f"{r.speed_mps:g}" for r in self.records if r.converged}
        return all(f"{v:g}" in done for v in self.speeds)

    @property
    def failed(self) -> SolveRecord | None:
        """The speed that did not converge (where the continuation stopped), or None."""
        return next((r for r in self.records if not r.converged), None)

    @property
    def last_converged_speed(self) -> float | None:
        """The last prescribed speed [m/s] that converged (in the order solved), or None."""
        done = [r.speed_mps for r in self.records if r.converged]
        return done[-1] if done else None

    @property
    def fastest(self) -> SolveRecord | None:
        """The converged record of the highest prescribed speed, or None."""
        done = [r for r in self.records if r.converged]
        return max(done, key=lambda r: r.speed_mps) if done else None

    def rows(self, relative_to: str | Path | None = None) -> list[dict]:
        """Table rows (:meth:`SolveRecord.row`), one per speed reached."""
        return [r.row(relative_to) for r in self.records]

    def table(self):
        """The rows as a pandas DataFrame, columns in :func:`table_columns` order."""
        import pandas as pd

        rows = self.rows()
        return pd.DataFrame(rows, columns=table_columns(rows))


def table_columns(rows: Sequence[dict]) -> list[str]:
    """Column order of table rows: :data:`TABLE_COLUMNS` with the per-leg columns of the legs
    present after ``contact_time_s``, then any other key."""
    keys: list[str] = []
    for row in rows:
        keys.extend(k for k in row if k not in keys)
    legs = [fmt.format(leg) for fmt in _PER_LEG for leg in _LEGS
            if fmt.format(leg) in keys]
    head = list(TABLE_COLUMNS)
    i = head.index("contact_time_s") + 1
    cols = head[:i] + legs + head[i:]
    return cols + [k for k in keys if k not in cols]


# -- helpers ------------------------------------------------------------------------------
class LazyRunner:
    """The runner of a model specification, built on the first call unless given.

    ``LazyRunner(runner, spec)()`` returns ``runner``; if it is None, the runner built from
    ``spec`` (:func:`~bladelab.predict.collocation.stored.runner_from_spec`), once; if it is a
    callable that is not a runner (e.g. another :class:`LazyRunner`), what it returns."""

    def __init__(self, runner, spec: dict) -> None:
        self._runner, self._spec = runner, spec

    def __call__(self):
        if self._runner is None:
            self._runner = runner_from_spec(self._spec)
        elif callable(self._runner) and not hasattr(self._runner, "dof_names"):
            self._runner = self._runner()
        return self._runner


def _stored(ok: Path, best: Path, spec: dict, settings: CollocationSettings, force: bool):
    """(converged solution, best iterate) in ``ok`` / ``best``
    (:func:`~bladelab.predict.collocation.stored.read_stored`); ``force`` ignores both."""
    return (None, None) if force else read_stored(ok, best, spec, settings)


def _solve_and_write(runner, settings: CollocationSettings, guess, *, spec: dict, ok: Path,
                     best: Path, report: Callable[..., None], watched: bool):
    """Solve, write the solution (or best iterate) and remove the stale other file; the
    solver's progress goes to ``report`` when ``watched``."""
    sol = predict_stride(runner, settings, guess, model_spec=spec,
                         progress=(lambda p: report("solve", solve=p)) if watched else None)
    target = write_solve(sol, ok, best)
    s = sol.summary()
    if sol.converged:
        report("converged", path=target,
               message=f"mean speed {sol.mean_speed_mps:.4g} m/s, cost of transport "
                       f"{sol.cost_of_transport_J_per_kg_m:.4g} J/(kg·m), "
                       f"{s['iterations']} iterations, {s['wall_s']:.1f} s")
    else:
        report("failed", path=target,
               message=f"not converged: IPOPT status {sol.nlp.status} in the {sol.stage} stage "
                       f"after {sol.nlp.iterations} iterations; best iterate in {target.name}")
    return sol, target


def check_speeds(speeds) -> tuple[float, ...]:
    """The prescribed speeds [m/s] as a tuple of floats: each > 0, none twice (as
    ``f"{v:g}"``); a single number is one speed. Raises SpecError naming ``speeds``."""
    if isinstance(speeds, int | float):
        speeds = [speeds]
    out = []
    for v in speeds:
        if isinstance(v, bool) or not isinstance(v, int | float) or not (
                math.isfinite(v) and v > 0):
            raise SpecError(f"speeds must be > 0 m/s, got {v!r}", where="speeds")
        out.append(float(v))
    if not out:
        raise SpecError("no speed given", where="speeds")
    names = [f"{v:g}" for v in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise SpecError(f"speed(s) {', '.join(dup)} m/s given twice", where="speeds")
    return tuple(out)


#: Halvings of the speed step allowed (:func:`speed_continuation`): steps down to a quarter.
DEFAULT_REFINEMENTS = 2


# -- drivers ------------------------------------------------------------------------------
def speed_continuation(runner, speeds: Sequence[float], settings: CollocationSettings,
                       first_guess, *, model_spec: dict, out_dir: str | Path,
                       progress: Callable[[ContinuationProgress], None] | None = None,
                       force: bool = False,
                       refinements: int = DEFAULT_REFINEMENTS) -> ContinuationResult:
    """Solve the stride at each prescribed speed in order, each warm-started from the previous
    converged solution (module docstring); files ``out_dir/speed-<v>.json``.

    Parameters
    ----------
    runner
        The forward model (:func:`bladelab.runner.build_runner`); None (or a callable returning
        it): built from ``model_spec`` when a solve is needed (a rerun that only reads files
        back builds nothing).
    speeds
        Prescribed mean speeds [m/s], solved in this order.
    settings
        :class:`CollocationSettings` of a prescribed-speed problem (mesh, weights, solver
        options); each speed replaces its ``speed_m_per_s``.
    first_guess
        Initial guess of the first speed (:class:`StrideGuess`), or a callable
        ``first_guess(runner) -> StrideGuess``, called only when it is needed.
    model_spec
        ``{"model": "able" | "amputee", "blade": name | None}``: how ``runner`` is built.
    out_dir
        Folder of the files (created if needed).
    progress
        Called with :class:`ContinuationProgress` reports.
    force
        Solve every speed, ignoring (and then replacing) files already in ``out_dir``; files of
        speeds not reached stay (:func:`sweep_model_task` removes them).
    refinements
        Halvings of the speed step allowed when a solve does not converge from the previous
        speed: the smallest step is the first step towards a prescribed speed / 2^refinements
        (0: stop at the first failure).

    Returns
    -------
    ContinuationResult
        One record per speed reached; the continuation stops at the first speed that does not
        converge.

    Raises
    ------
    SpecError
        No speed, a speed that is not > 0, a speed given twice, or maximum-speed settings.
    InputFileError
        A file in ``out_dir`` holds another problem (without ``force``).
    """
    spec = check_model_spec(model_spec)
    speeds = check_speeds(speeds)
    if not isinstance(settings, CollocationSettings):
        raise SpecError(f"expected CollocationSettings, got {type(settings).__name__}",
                        where="settings")
    if settings.max_speed:
        raise SpecError("the speed continuation needs the settings of a prescribed-speed "
                        "problem", where="settings",
                        hint="give speed_m_per_s (each speed of the continuation replaces it)")
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputFileError("is a file, not a folder", file=out_dir, hint="give a folder")
    get_runner = LazyRunner(runner, spec)
    label = model_label(spec)
    records: list[SolveRecord] = []
    prev = None  # the previous converged solution
    pending = list(speeds)  # speeds still to solve, intermediate ones inserted in front
    prescribed = {f"{v:g}" for v in speeds}
    min_step = None  # smallest step [m/s] allowed towards the current prescribed speed
    restart: set[str] = set()  # speeds whose stored best iterate is stale (a step was refined)
    while pending:
        v = pending[0]
        problem = f"{v:g} m/s"

        def report(event: str, *, path=None, message: str = "", solve=None,
                   _problem=problem) -> None:
            if progress is not None:
                progress(ContinuationProgress(label, _problem, event, path, message, solve))

        s_v = dataclasses.replace(settings, speed_m_per_s=v)
        ok, best = out_dir / speed_file(v), out_dir / speed_file(v, converged=False)
        done, iterate = _stored(ok, best, spec, s_v, force)
        if done is not None:
            report("read", path=ok, message="read back")
            records.append(SolveRecord("speed", v, done, ok, False))
            prev = done
            pending.pop(0)
            continue
        if iterate is not None and f"{v:g}" not in restart:
            guess = iterate.to_guess()
            report("start", message=f"warm start from the best iterate {best.name}")
        elif prev is not None:
            guess = prev.to_guess(f"{COLLOCATION_SOURCE} at "
                                  f"{prev.settings.speed_m_per_s:g} m/s").with_speed(v)
            report("start", message=f"warm start from the {prev.settings.speed_m_per_s:g} m/s "
                                    "solution")
        else:
            guess = first_guess(get_runner()) if callable(first_guess) else first_guess
            report("start", message=f"from {guess.source}")
        sol, path = _solve_and_write(get_runner(), s_v, guess, spec=spec, ok=ok, best=best,
                                     report=report, watched=progress is not None)
        if sol.converged:
            records.append(SolveRecord("speed", v, sol, path, True))
            prev = sol
            pending.pop(0)
            if f"{v:g}" in prescribed:
                min_step = None
            continue
        mid = None
        if prev is not None:
            v_prev = float(prev.settings.speed_m_per_s)
            if min_step is None:
                min_step = abs(v - v_prev) / 2**refinements
            mid = round(0.5 * (v_prev + v), 4)
            if (abs(v - v_prev) / 2 < min_step - 1e-9
                    or f"{mid:g}" in (f"{v_prev:g}", f"{v:g}")):
                mid = None
        if mid is None:
            records.append(SolveRecord("speed", v, sol, path, True))
            break
        restart.add(f"{v:g}")
        report("refine", path=path, message=f"not converged from {v_prev:g} m/s; "
                                            f"{mid:g} m/s first, then {v:g} m/s again")
        pending.insert(0, mid)
    return ContinuationResult(speeds, tuple(records))


def max_speed_settings(settings: CollocationSettings) -> CollocationSettings:
    """The maximum-speed problem with the mesh and solver options of ``settings``: speed None,
    the default maximum-speed weights (speed 1, activation 1, acceleration 0.1)."""
    return dataclasses.replace(settings, speed_m_per_s=None, weights=None)


def max_speed(runner, settings: CollocationSettings, guess, *, model_spec: dict,
              out_dir: str | Path,
              progress: Callable[[ContinuationProgress], None] | None = None,
              force: bool = False) -> SolveRecord:
    """Solve the maximum-speed problem warm-started from ``guess`` (the fastest converged
    solution of :func:`speed_continuation`, a :class:`CollocationSolution` or its
    ``to_guess()``); file ``out_dir/max-speed.json`` (``max-speed.best_iterate.json`` if it
    does not converge). A converged file of the same problem is read back; a best iterate of
    it is the warm start instead of ``guess`` (module docstring).

    ``settings`` must pose the maximum-speed problem (``speed_m_per_s=None``;
    :func:`max_speed_settings`). ``runner``, ``model_spec``, ``progress`` and ``force`` as
    :func:`speed_continuation`.
    """
    from bladelab.predict.collocation.solution import CollocationSolution

    spec = check_model_spec(model_spec)
    if not isinstance(settings, CollocationSettings):
        raise SpecError(f"expected CollocationSettings, got {type(settings).__name__}",
                        where="settings")
    if not settings.max_speed:
        raise SpecError(f"the maximum-speed problem needs speed_m_per_s None, got "
                        f"{settings.speed_m_per_s:g} m/s", where="settings",
                        hint="max_speed_settings(settings) gives it")
    out_dir = Path(out_dir)
    label = model_label(spec)

    def report(event: str, *, path=None, message: str = "", solve=None) -> None:
        if progress is not None:
            progress(ContinuationProgress(label, "maximum speed", event, path, message, solve))

    ok, best = out_dir / MAX_SPEED_FILE, out_dir / MAX_SPEED_BEST_ITERATE_FILE
    done, iterate = _stored(ok, best, spec, settings, force)
    if done is not None:
        report("read", path=ok, message="read back")
        return SolveRecord("max-speed", None, done, ok, False)
    if iterate is not None:
        start = iterate.to_guess()
        report("start", message=f"warm start from the best iterate {best.name}")
    else:
        if isinstance(guess, CollocationSolution):
            if guess.model_spec != spec:
                raise SpecError(f"the warm start is a solution of {model_label(guess.model_spec)}"
                                f", not {label}", where="guess")
            speed = guess.settings.speed_m_per_s
            start = guess.to_guess(f"{COLLOCATION_SOURCE} at "
                                   + (f"{speed:g} m/s" if speed else "maximum speed"))
        else:
            start = guess
        report("start", message=f"from {start.source}")
    sol, path = _solve_and_write(LazyRunner(runner, spec)(), settings, start, spec=spec, ok=ok,
                                 best=best, report=report, watched=progress is not None)
    return SolveRecord("max-speed", None, sol, path, True)
