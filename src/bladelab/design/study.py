"""A design study: evaluate the runs of a design, fit response surfaces, find the optimum.

:func:`run_design` takes an *evaluator*, any callable ``{factor: value} -> {response: value}``
(the blade or runner simulation; a cheap analytic function in tests), evaluates every run of the
design with a progress bar and writes each run's result atomically to
``out_dir/runs/run_NNNN.json`` as soon as it is known, so an interrupted study resumes where it
stopped. It then writes, atomically:

- ``study.json``: the design space, design kind, model, seed and options;
- ``results.csv``: one row per run: ``run``, the factors in their units, ``<factor>_coded``, the
  responses;
- ``surfaces.json``, ``coefficients.csv``, ``anova.csv``: the fitted surfaces;
- ``estimability.json``: the rank/conditioning report of the design for the model;
- ``optimum.json``: the constrained optimum (if an objective is given);
- ``failed.csv``: with ``skip_failed``, the runs that have no result (run, factors, coded,
  ``error``), each also in ``runs/run_NNNN.failed.json``; ``results.csv`` and the surfaces then
  hold the other runs only (a design point a simulation cannot solve is a finding, e.g. a
  blade with no knee-safe gait, and is never a NaN in the table);
- ``motion.json``: with an evaluator that adapts the motion to the design (its ``motion``
  attribute, a :class:`~bladelab.design.motion_model.MotionModel`): the motion model, its terms,
  coding and leave-one-blade-out errors. Its factors must be the design's (checked before any
  run).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from bladelab._io import atomic_path, read_json, write_json
from bladelab.design import defaults
from bladelab.design.doe import Design, EstimabilityReport, make_design, require_estimable
from bladelab.design.motion import check_motion_factors
from bladelab.design.optimum import (
    OptimumResult,
    constrained_optimum,
    read_bound,
    surface_constraints,
)
from bladelab.design.reduction import fit_response
from bladelab.design.space import DesignSpace
from bladelab.design.surfaces import ResponseSurface
from bladelab.design.terms import parse_terms
from bladelab.design.timing import RUNS_STAGE, timed_stage
from bladelab.errors import BladelabError, DataError, OptimizationError, SpecError
from bladelab.executors import make_executor

__all__ = ["DesignStudyResult", "run_design"]

Evaluator = Callable[[dict[str, float]], Mapping[str, float]]


@dataclass(frozen=True, eq=False)
class DesignStudyResult:
    """The outcome of :func:`run_design`.

    Attributes
    ----------
    space, design
        The design space and the design evaluated.
    table
        One row per run: ``run``, factors (their units), ``<factor>_coded``, responses.
    responses
        Response names, in the evaluator's order.
    surfaces
        Response name -> fitted :class:`ResponseSurface`.
    estimability
        The design's report for the model.
    optimum
        The constrained optimum, or ``None`` (no objective, or no feasible design: see
        ``optimum_error``).
    optimum_error
        Why there is no optimum, if one was asked for.
    out_dir
        Where the files were written.
    n_evaluated, n_resumed
        Runs evaluated now and runs read back from an earlier, interrupted study.
    failed
        Run number (1-based) -> why it has no result (``skip_failed``; empty otherwise).
    """

    space: DesignSpace
    design: Design
    table: pd.DataFrame = field(repr=False)
    responses: tuple[str, ...]
    surfaces: dict[str, ResponseSurface] = field(repr=False)
    estimability: EstimabilityReport
    optimum: OptimumResult | None
    optimum_error: str | None
    out_dir: Path
    n_evaluated: int
    n_resumed: int
    failed: dict[int, str] = field(default_factory=dict)

    def coefficients(self) -> pd.DataFrame:
        """Tidy coefficient table of all surfaces."""
        return pd.concat([s.coefficients() for s in self.surfaces.values()], ignore_index=True)

    def anova(self) -> pd.DataFrame:
        """Tidy ANOVA table of all surfaces."""
        return pd.concat([s.anova for s in self.surfaces.values()], ignore_index=True)

    def to_dict(self) -> dict:
        return {
            "space": self.space.to_dict(),
            "design": {"kind": self.design.kind, "n_runs": self.design.n_runs},
            "responses": list(self.responses),
            "estimability": self.estimability.to_dict(),
            "surfaces": {k: s.to_dict() for k, s in self.surfaces.items()},
            "optimum": None if self.optimum is None else self.optimum.to_dict(),
            "optimum_error": self.optimum_error,
            "out_dir": str(self.out_dir),
            "n_evaluated": self.n_evaluated,
            "n_resumed": self.n_resumed,
        }


def run_file(out_dir: Path, i: int) -> Path:
    """The file of run ``i`` (0-based) of a study in ``out_dir``."""
    return out_dir / "runs" / f"run_{i + 1:04d}.json"


def failed_run_file(out_dir: Path, i: int) -> Path:
    """The record of run ``i`` (0-based) when its evaluation failed."""
    return out_dir / "runs" / f"run_{i + 1:04d}.failed.json"


def _read_failure(path: Path, coded: np.ndarray) -> str | None:
    """The recorded reason of a failed run of this design, or None."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        same = np.allclose(np.asarray(data["coded"], float), coded, atol=1e-9)
        return str(data["error"]) if same else None
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _read_run(path: Path, coded: np.ndarray) -> dict[str, float] | None:
    """Responses of a finished run, or None if absent; error if it belongs to another study."""
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        stored = np.asarray(data["coded"], dtype=float)
        responses = {str(k): float(v) for k, v in data["responses"].items()}
    except (OSError, ValueError, KeyError, TypeError):
        return None  # unreadable: evaluate again (it is rewritten atomically)
    if stored.shape != coded.shape or not np.allclose(stored, coded, atol=1e-9):
        raise SpecError(
            "the output folder holds a run of a different design",
            file=path,
            hint="use a new output folder, or delete its runs/ folder to start over",
        )
    return responses


#: Evaluator settings that say where results are kept or where solves start, not what they
#: are: a resumed study may change them.
_WHERE_NOT_WHAT = ("solutions_dir", "start_strides")


def _check_same_evaluator(out: Path, evaluator) -> None:
    """Refuse to resume a folder whose finished runs came from another evaluator (its
    ``evaluator.json`` differs in a setting that changes the responses). A setting the file
    predates counts as the evaluator's ``LEGACY_SETTINGS`` value (e.g. seed 001's body)."""
    path = out / "evaluator.json"
    if not (hasattr(evaluator, "to_dict") and path.is_file()
            and any((out / "runs").glob("run_*.json"))):
        return
    old = read_json(path, what="evaluator settings")
    new = json.loads(json.dumps(evaluator.to_dict()))
    legacy = getattr(evaluator, "LEGACY_SETTINGS", {})
    differ = sorted(k for k, v in new.items() if k not in _WHERE_NOT_WHAT
                    and (old[k] if k in old else legacy.get(k, v)) != v)
    if differ:
        shown = "; ".join(f"{k}: {old.get(k, legacy.get(k))!r} -> {new[k]!r}" for k in differ)
        raise SpecError(f"the output folder holds runs of another evaluator ({shown})",
                        file=path, hint="resume with the same settings, or use a new output "
                                        "folder")


def evaluate_design_run(payload: dict) -> dict:
    """One run in a worker process: ``payload`` = {"evaluator", "point"} -> responses."""
    return dict(payload["evaluator"](dict(payload["point"])))


def _evaluate_runs(evaluator, space: DesignSpace, design: Design, todo: list[int], *, jobs: int,
                   executor: str, progress: bool
                   ) -> Iterator[tuple[int, object, BladelabError | str | None]]:
    """Yield (run index, raw responses, None) or (run index, None, the error) for the runs
    ``todo`` as they finish: in this process (``jobs`` 1; the error is the evaluator's
    :class:`BladelabError`, others propagate) or on an executor (the error in words). An
    evaluator with a ``prepare(point, progress=)`` method is first given the first run's point,
    in this process (the collocation evaluator carries its start to the study's speed there)."""
    prepare = getattr(evaluator, "prepare", None)
    if todo and callable(prepare):
        prepare(dict(space.point(design.coded[todo[0]])), progress=progress)
    bar = tqdm(total=len(todo), desc="design runs", unit="run", disable=not progress)
    if jobs <= 1:
        for i in todo:
            try:
                raw, err = evaluator(dict(space.point(design.coded[i]))), None
            except BladelabError as exc:
                raw, err = None, exc
            bar.update()
            yield i, raw, err
        bar.close()
        return
    payloads = [{"evaluator": evaluator, "point": space.point(design.coded[i])} for i in todo]
    for k, status, value in make_executor(executor, jobs).run(evaluate_design_run, payloads):
        bar.update()
        yield (todo[k], value, None) if status == "ok" else (todo[k], None, str(value))
    bar.close()


def _point_text(point: Mapping[str, float]) -> str:
    return ", ".join(f"{k}={v:g}" for k, v in point.items())


def _check_responses(
    raw: object, run: int, expected: Sequence[str] | None
) -> dict[str, float]:
    if not isinstance(raw, Mapping) or not raw:
        raise DataError(
            f"the evaluator returned {type(raw).__name__}, not a non-empty mapping",
            where=f"run {run}",
            hint="an evaluator returns {response_name: value}",
        )
    out = {}
    for k, v in raw.items():
        try:
            fv = float(v)
        except (TypeError, ValueError):
            raise DataError(f"response {k!r} = {v!r} is not a number", where=f"run {run}") from None
        if not math.isfinite(fv):
            raise DataError(
                f"response {k!r} is not finite ({fv})", where=f"run {run}",
                hint="the simulation of this design point failed; check the evaluator",
            )
        out[str(k)] = fv
    if expected is not None and list(out) != list(expected):
        missing = [k for k in expected if k not in out]
        extra = [k for k in out if k not in expected]
        if missing or extra:
            raise DataError(
                f"responses differ from the first run's (missing {missing}, extra {extra})",
                where=f"run {run}",
            )
        out = {k: out[k] for k in expected}
    return out


def run_design(
    space: DesignSpace,
    *,
    runs: str | Path | Design | np.ndarray = defaults.RUNS,
    evaluator: Evaluator,
    out_dir: str | Path,
    seed: int = defaults.SEED,
    model: str | Sequence = defaults.SURFACE_MODEL,
    n_runs: int | None = None,
    n_center: int = 1,
    objective: str | None = None,
    sense: str = defaults.SENSE,
    constraints: Mapping[str, Any] | None = None,
    units: Mapping[str, str] | None = None,
    conservative: bool = False,
    progress: bool = True,
    jobs: int = 1,
    executor: str = "local",
    skip_failed: bool = False,
) -> DesignStudyResult:
    """Evaluate a design, fit a surface per response and find the constrained optimum.

    Parameters
    ----------
    space
        The design factors and their ranges.
    runs
        ``"ccd"`` (face-centred central composite, default), ``"bbd"``, ``"dopt"``, a CSV path
        of runs (see :func:`~bladelab.design.doe.read_runs_csv`), a Design or coded points.
    evaluator
        ``{factor: value in its unit} -> {response: value}``; called once per run.
    out_dir
        Output folder (created); a folder of an interrupted study with the same design resumes
        (finished runs are read back, not re-evaluated: use a new folder after changing the
        evaluator).
    seed
        Seed of the D-optimal design and of the optimiser's starting points.
    model
        Response-surface model for every response (checked against the design before any run).
    n_runs
        Runs of a D-optimal design (default: model terms + max(3, k)).
    n_center
        Centre points of ccd/bbd.
    objective, sense
        Response to maximise (``"max"``) or minimise (``"min"``); no optimum if None.
    constraints
        Response -> bound: a number or ``{"min": v}`` (the optimum must satisfy surface ≥ v),
        ``{"max": v}`` (surface ≤ v); :func:`~bladelab.design.optimum.read_bound`.
    units
        Response -> unit, for tables and plots (e.g. ``{"delta_vx_m_per_s": "m/s"}``).
    conservative
        Impose constraints on the prediction bound on their infeasible side.
    progress
        Show a progress bar.
    jobs, executor
        Worker processes and ``"local"`` (a process pool) or ``"ray"``
        (:mod:`bladelab.executors`); with ``jobs`` > 1 the evaluator must be picklable. Every
        finished run is stored before a failed one is reported.
    skip_failed
        False (default): a run whose evaluation fails stops the study (serially at once, in
        parallel after the other runs), its reason recorded in ``runs/run_NNNN.failed.json``;
        the next call evaluates it again. True: failed runs are recorded and left out, runs
        recorded as failed before are not evaluated again, and the surfaces are fitted to the
        runs that finished (refused, naming the failed runs, if those cannot estimate the
        model); ``failed.csv`` lists them.

    A stored run is read back, not evaluated again, unless the evaluator names the responses it
    gives (``evaluator.response_names``) and the run lacks one of them (stored by an older
    evaluator; a collocation design then reads its stored stride back).
    """
    if not callable(evaluator):
        raise SpecError("evaluator must be callable", where="evaluator")
    out = Path(out_dir)
    design = make_design(runs, space, n_runs=n_runs, n_center=n_center, model=model, seed=seed)
    terms = parse_terms(model, space.names)
    report = require_estimable(design, terms, space.names)  # refuse before any evaluation
    motion = getattr(evaluator, "motion", None)
    if motion is not None and hasattr(motion, "predict_point"):
        check_motion_factors(motion, space.names)
    else:
        motion = None
    constraints = dict(constraints or {})
    for name, value in constraints.items():  # a bad bound fails now, not after the runs
        read_bound(value, name=f"constraint {name}")
    units = dict(units or {})

    meta = {
        "space": space.to_dict(),
        "design": design.to_dict(),
        "model": model if isinstance(model, str) else [str(t) for t in model],
        "seed": seed,
        "objective": objective,
        "sense": sense,
        "constraints": constraints,
        "conservative": conservative,
        "motion": None if motion is None else "motion.json",
    }
    out.mkdir(parents=True, exist_ok=True)
    _check_same_evaluator(out, evaluator)
    write_json(out / "study.json", meta)
    if hasattr(evaluator, "to_dict"):
        write_json(out / "evaluator.json", evaluator.to_dict())
    if motion is not None:
        write_json(out / "motion.json", motion.to_dict())

    frame = design.to_frame(space)
    results: list[dict[str, float] | None] = [None] * design.n_runs
    failed: dict[int, str] = {}  # run index -> reason
    n_resumed = n_evaluated = 0
    expected: list[str] | None = None
    names = getattr(evaluator, "response_names", None)  # responses an evaluator always gives
    for i in range(design.n_runs):
        r = _read_run(run_file(out, i), design.coded[i])
        if r is not None and names is not None and set(r) != set(names):
            r = None  # stored by an older evaluator: evaluated again
        if r is not None:
            results[i] = r
            n_resumed += 1
            expected = expected or list(r)
        elif skip_failed and (why := _read_failure(failed_run_file(out, i),
                                                   design.coded[i])) is not None:
            failed[i] = why
    # centre outwards: an evaluator that warm-starts from solved neighbours (collocation) then
    # always finds a near one (a corner's nearest axial point, not the centre two units away)
    todo = sorted((i for i in range(design.n_runs) if results[i] is None and i not in failed),
                  key=lambda i: (round(float(np.linalg.norm(design.coded[i])), 9), i))
    finished = _evaluate_runs(evaluator, space, design, todo, jobs=jobs, executor=executor,
                              progress=progress)
    failed_now = []
    with timed_stage(out, RUNS_STAGE, jobs=jobs) as sitting:  # timing.json
        for i, raw, err in finished:
            sitting["designs"] += 1
            point = space.point(design.coded[i])
            if err is not None:
                why = err.message if isinstance(err, BladelabError) else str(err)
                write_json(failed_run_file(out, i),
                           {"run": i + 1, "coded": design.coded[i].tolist(), "point": point,
                            "error": why})
                failed[i] = why
                failed_now.append(f"run {i + 1} ({_point_text(point)}): {why}")
                if isinstance(err, BladelabError) and not skip_failed:  # serial: stop at once
                    raise type(err)(failed_now[-1], file=err.file, where=err.where,
                                    hint=err.hint) from err
                continue
            res = _check_responses(raw, i + 1, expected)
            expected = expected or list(res)
            write_json(
                run_file(out, i),
                {"run": i + 1, "coded": design.coded[i].tolist(), "point": point, "responses": res},
            )
            failed_run_file(out, i).unlink(missing_ok=True)
            results[i] = res
            n_evaluated += 1
    if failed_now and not skip_failed:
        raise BladelabError(
            f"{len(failed_now)} of {len(todo)} runs failed ({'; '.join(failed_now[:3])})",
            where="design runs", hint="the finished runs are stored; fix the cause and run "
                                      "again with the same output folder to resume, or give "
                                      "--skip-failed to fit the surfaces without them")
    done = [i for i in range(design.n_runs) if i not in failed]
    responses = tuple(expected or ())
    for i in done:
        if results[i] is None or list(results[i]) != list(responses):
            raise DataError(
                "stored responses differ from the other runs'",
                file=run_file(out, i),
                hint="delete that file to evaluate the run again",
            )
    if failed:
        try:
            report = require_estimable(design.coded[done], terms, space.names)
        except SpecError as err:
            raise SpecError(
                f"{len(failed)} runs failed (runs {', '.join(str(i + 1) for i in sorted(failed))}"
                f"), and the {len(done)} that finished cannot fit the model: {err.message}",
                where="design runs", hint=err.hint) from None
    _write_failed(out, frame, failed)
    frame = frame.iloc[done].reset_index(drop=True)
    for name in responses:
        frame[name] = [results[i][name] for i in done]  # type: ignore[index]
    with atomic_path(out / "results.csv") as tmp:
        frame.to_csv(tmp, index=False)

    surfaces = {
        name: fit_response(
            design.coded[done], frame[name].to_numpy(), factor_names=space.names, model=model,
            response=name, unit=units.get(name, ""),
        )
        for name in responses
    }
    write_json(out / "estimability.json", report.to_dict())
    write_json(out / "surfaces.json", {k: s.to_dict() for k, s in surfaces.items()})
    coef = pd.concat([s.coefficients() for s in surfaces.values()], ignore_index=True)
    anova = pd.concat([s.anova for s in surfaces.values()], ignore_index=True)
    with atomic_path(out / "coefficients.csv") as tmp:
        coef.to_csv(tmp, index=False)
    with atomic_path(out / "anova.csv") as tmp:
        anova.to_csv(tmp, index=False)

    optimum, optimum_error = None, None
    if objective is not None:
        unknown = [n for n in [objective, *constraints] if n not in surfaces]
        if unknown:
            raise SpecError(
                f"unknown response(s) {unknown}", where="objective/constraints",
                hint=f"the evaluator returned {list(responses)}",
            )
        cons = surface_constraints(surfaces, constraints)
        try:
            optimum = constrained_optimum(
                surfaces[objective], sense=sense, constraints=cons, space=space, seed=seed,
                conservative=conservative,
            )
            write_json(out / "optimum.json", optimum.to_dict())
        except OptimizationError as err:
            optimum_error = str(err)
            write_json(out / "optimum.json", {"error": optimum_error})
    return DesignStudyResult(
        space=space,
        design=design,
        table=frame,
        responses=responses,
        surfaces=surfaces,
        estimability=report,
        optimum=optimum,
        optimum_error=optimum_error,
        out_dir=out,
        n_evaluated=n_evaluated,
        n_resumed=n_resumed,
        failed={i + 1: why for i, why in sorted(failed.items())},
    )


def _write_failed(out: Path, frame: pd.DataFrame, failed: Mapping[int, str]) -> None:
    """``failed.csv``: the design's rows of the failed runs with their ``error`` (removed
    when no run failed)."""
    path = out / "failed.csv"
    if not failed:
        path.unlink(missing_ok=True)
        return
    rows = frame.iloc[sorted(failed)].assign(error=[failed[i] for i in sorted(failed)])
    with atomic_path(path) as tmp:
        rows.to_csv(tmp, index=False)
