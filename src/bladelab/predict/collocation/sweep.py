"""The collocation category sweep, ``bladelab sweep --method collocation``.

:func:`collocation_sweep` runs, for each model (the able model, the amputee with each blade
category: :func:`sweep_models`), the speed continuation and then the maximum speed
(:mod:`bladelab.predict.collocation.continuation`), each model in its own subfolder
(:func:`~bladelab.predict.collocation.continuation.model_folder`: ``able``,
``amputee-<blade>``), models in parallel processes with ``jobs`` > 1, and writes the table
:data:`SWEEP_TABLE` after each model (:func:`write_table`). A model that fails does not stop
the others.

A table row is one solve: :meth:`~bladelab.predict.collocation.continuation_records.SolveRecord.row`
(model, problem, convergence, speed, cost of transport, stride and contact times, peak forces;
described in the continuation module) followed by seed 001's per-stride quantities of the
solution, :func:`~bladelab.predict.collocation.analyses.stride_analyses` (K_leg, joint powers
P+/P− per joint, leg energies, the blade's energy; units in the column names).

With ``starts`` K > 1 each problem (each speed, and the maximum speed) is solved from up to K
starts and the best kept (:mod:`bladelab.predict.collocation.starts`: the warm start, its
barrier start, the template, the previous-but-one solution); the continuation goes on from the
kept solution, every start's file stays in the model folder, and a row is the kept solve's
plus the columns ``start``, ``starts``, ``objective``, ``objective_<start>`` and
``spread_pct``.

With ``settle`` a settling pass follows: each model's problems are solved again from its
neighbours' kept strides, from their primal and dual values, each as one more start (the
continuation's ``extra_starts``), and the lowest kept: one pass, from the strides the first
pass kept. The neighbours of a problem: the two nearest blade categories' strides at the same
problem (the categories ordered by stiffness, one on each side, at an end of the order the next
two: :func:`category_neighbours`; labels ``from-<category>``, files ``speed-4.from-Cat5.json``),
so that every amputee problem of a study of three or more categories has three starts; for a
model without a category (the able runner), two of its own other strides, the nearest problems
other than the one its continuation came from, and where it has fewer its shipped stride
(:func:`own_neighbours`; ``from-speed-5``, ``from-max-speed``, ``from-stored``). Measured on
the human body, the categories' starts land within 0.1–0.5 % of each other where the template
start does not converge (docs/collocation.md, "Several starts per problem"); the able runner's
5 m/s stride from its maximum-speed stride lay 22 % below (in objective) the one the
continuation reached from 4 m/s, where an amputee's faster starts landed 5–100 % above their
problems' best.
With ``mesh_check`` as well, every model is checked after the settling pass only (its kept
strides).

With ``mesh_check`` every converged solve is solved again on twice the mesh intervals from its
stride (:mod:`bladelab.predict.collocation.mesh_check`; the finer solves in
``<model folder>/mesh-check/<solve>/``) and its row gets :func:`mesh_check_columns`: the
settling evidence beside each number.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from bladelab._io import atomic_open
from bladelab.errors import SpecError
from bladelab.executors import make_executor
from bladelab.predict.collocation.analyses import stride_analyses
from bladelab.predict.collocation.continuation import (
    LazyRunner,
    check_speeds,
    max_speed,
    max_speed_settings,
    model_folder,
    problem_key,
    speed_continuation,
)
from bladelab.predict.collocation.continuation_records import ContinuationProgress, table_columns
from bladelab.predict.collocation.mesh_check import MESH_CHECK_DIR, mesh_check_in_folder
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.output_folder import check_output_folder
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.starting_guess import stored_stride_path
from bladelab.predict.collocation.starts import check_starts
from bladelab.predict.collocation.stored import (
    check_model_spec,
    model_label,
    params_from_spec,
    runner_from_spec,
)
from bladelab.runner.blade_categories import blade_category

__all__ = [
    "SWEEP_TABLE",
    "SweepResult",
    "category_neighbours",
    "collocation_sweep",
    "own_neighbours",
    "mesh_check_columns",
    "sweep_model_task",
    "sweep_models",
    "write_table",
]

#: The summary table of a sweep, in its output folder.
SWEEP_TABLE = "collocation-sweep.csv"


def write_table(path: str | Path, rows: Sequence[dict]) -> Path:
    """Write table rows as CSV, atomically (columns as :func:`table_columns`; a missing or
    non-finite value is an empty field). Returns the path."""
    path = Path(path)
    cols = table_columns(rows)

    def cell(v):
        if v is None or (isinstance(v, float) and not math.isfinite(v)):
            return ""
        return v

    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=cols)
        writer.writeheader()
        for row in rows:
            writer.writerow({c: cell(row.get(c)) for c in cols})
    return path


def sweep_models(categories: Sequence[str], *, able: bool = False,
                 body: str = "seed001", athlete: dict | None = None) -> list[dict]:
    """Model specifications of a sweep: the able model first when ``able``, then the amputee
    with each blade category (names as the catalogue spells them), all of one ``body``
    (:data:`bladelab.runner.params.BODIES`) and ``athlete`` (None: the parameter sets';
    :func:`~bladelab.predict.collocation.stored.check_model_spec`).

    The able runner takes the athlete without its residual limb and prosthesis
    (``residual_limb_length_m``, ``prosthesis_extra_length_m``: the amputee's). Every model's athlete is checked before anything is solved.

    Raises
    ------
    SpecError
        An unknown or repeated category, no model at all, or a bad athlete field.
    """
    amputee_only = ("residual_limb_length_m", "prosthesis_extra_length_m")
    able_athlete = ({k: v for k, v in athlete.items() if k not in amputee_only}
                    if athlete else athlete)
    models = ([check_model_spec({"model": "able", "body": body, "athlete": able_athlete})]
              if able else [])
    seen: set[str] = set()
    for c in categories:
        name = blade_category(c).name
        if name in seen:
            raise SpecError(f"category {name} given twice", where="categories")
        seen.add(name)
        models.append(check_model_spec({"model": "amputee", "blade": name, "body": body,
                                        "athlete": athlete}))
    if not models:
        raise SpecError("no model to sweep", where="categories",
                        hint="give --categories, --able, or both")
    for spec in models:
        params_from_spec(spec)
    return models


def _files(folder: Path) -> list[Path]:
    """The solve files of a model folder."""
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix == ".json" and (
        p.name.startswith("speed-") or p.name.startswith("max-speed")))


def sweep_model_task(payload: dict) -> dict:
    """One model of :func:`collocation_sweep` (a top-level function for the executors): the
    speed continuation, then the maximum speed from its fastest converged solution.

    ``payload``: ``model_spec``, ``speeds``, ``settings`` (:class:`CollocationSettings`),
    ``make_guess`` (``make_guess(runner, n=..., speed=...)``), ``out`` (the sweep folder),
    ``force``, ``progress`` (or None), ``starts`` (per problem; default 1), ``mesh_check``
    (each converged solve checked on twice the mesh intervals; default False),
    ``extra_starts`` (the settling pass's starts from other models' strides, by
    :func:`~bladelab.predict.collocation.continuation.problem_key`; default none). Returns
    ``label``, ``rows`` (module docstring) and
    ``failures`` (one line per solve that did not converge). With ``force``, files of the model
    folder that this run did not write are removed once the model is done.
    """
    spec = payload["model_spec"]
    settings = payload["settings"]
    speeds = payload["speeds"]
    out = Path(payload["out"])
    folder = out / model_folder(spec)
    make_guess = payload["make_guess"]
    force = bool(payload.get("force", False))
    progress = payload.get("progress")
    starts = int(payload.get("starts", 1))
    extra = payload.get("extra_starts")
    label = model_label(spec)
    get_runner = LazyRunner(None, spec)
    cont = speed_continuation(
        get_runner, speeds, settings,
        lambda r: make_guess(r, n=settings.mesh_intervals, speed=float(speeds[0])),
        model_spec=spec, out_dir=folder, progress=progress, force=force, starts=starts,
        extra_starts=extra)
    records = list(cont.records)
    failures = []
    if cont.failed is not None:
        f = cont.failed
        last = cont.last_converged_speed
        failures.append(f"{f.speed_mps:g} m/s not converged (IPOPT status "
                        f"{f.solution.nlp.status} in the {f.solution.stage} stage; best iterate "
                        f"{f.path.relative_to(out)}); last converged: "
                        + (f"{last:g} m/s" if last is not None else
                           "none (the first speed starts from --guess: try another one, "
                           "e.g. --guess trial or a converged solution file)"))
    fastest = cont.fastest
    if fastest is None:
        failures.append("maximum speed not attempted (no speed converged)")
    else:
        done = sorted((r for r in records if r.converged), key=lambda r: r.speed_mps)
        rec = max_speed(get_runner, max_speed_settings(settings), fastest.solution,
                        model_spec=spec, out_dir=folder, progress=progress, force=force,
                        starts=starts, extra_starts=extra,
                        previous=done[-2].solution if len(done) > 1 else None)
        records.append(rec)
        if not rec.converged:
            failures.append(f"maximum speed not converged (IPOPT status "
                            f"{rec.solution.nlp.status} in the {rec.solution.stage} stage; "
                            f"best iterate {rec.path.relative_to(out)})")
    if force:
        keep = {p.resolve() for r in records for p in r.files}
        for p in _files(folder):
            if p.resolve() not in keep:
                p.unlink(missing_ok=True)
    runner = get_runner()
    checks = (_mesh_checks(runner, records, folder, label, progress, force)
              if payload.get("mesh_check") else {})
    cm = build_collocation_model(runner)  # once for every row's analyses
    rows = [r.row(out) | stride_analyses(r.solution, runner, cm=cm)
            | mesh_check_columns(checks.get(r.path)) for r in records]
    return {"label": label, "rows": rows, "failures": failures}


def _mesh_checks(runner, records, folder: Path, label: str, progress, force: bool) -> dict:
    """The mesh-halving check of every converged record (:mod:`.mesh_check`), each in
    ``folder/mesh-check/<file stem>/`` (a check of the same stride there is read back; with
    ``force``, checks of strides no longer in the sweep are removed)."""
    root = folder / MESH_CHECK_DIR
    checks = {}
    for r in records:
        if not r.converged:
            continue
        problem = "maximum speed" if r.speed_mps is None else f"{r.speed_mps:g} m/s"

        def relay(p, problem=problem) -> None:
            if progress is not None:
                progress(ContinuationProgress(label, problem, "solve",
                                              solve=dataclasses.replace(
                                                  p, stage=f"mesh check: {p.stage}")))

        checks[r.path] = mesh_check_in_folder(root / r.path.stem, runner, r.solution,
                                              resume=True, progress=relay)
        if progress is not None:
            progress(ContinuationProgress(label, problem, "mesh check",
                                          message=checks[r.path].verdict()))
    if force and root.is_dir():
        kept = {r.path.stem for r in records}
        for sub in root.iterdir():
            if sub.is_dir() and sub.name not in kept:
                shutil.rmtree(sub)
    return checks


def mesh_check_columns(check) -> dict:
    """The sweep table's columns of one solve's mesh-halving check (empty without one):
    ``mesh_check_intervals``, ``mesh_check_converged``, ``mesh_check_settled``, the
    change [%] of the objective, the stride time and the cost of transport, and of its round
    trip (``MeshCheck.round_trip_pct``; empty without one): the round trip's objective against
    the solve's [%] and the mesh's own part of the objective and the stride time [%]."""
    if check is None:
        return {}
    (trip, own), (_, own_time) = (check.round_trip_pct("objective"),
                                  check.round_trip_pct("stride_time_s"))
    return {"mesh_check_intervals": check.fine_intervals,
            "mesh_check_converged": check.converged, "mesh_check_settled": check.settled,
            "mesh_check_objective_change_pct": check.change_pct("objective"),
            "mesh_check_stride_time_change_pct": check.change_pct("stride_time_s"),
            "mesh_check_cot_change_pct": check.change_pct("cost_of_transport_J_per_kg_m"),
            "mesh_check_round_trip_objective_pct": trip,
            "mesh_check_own_objective_pct": own,
            "mesh_check_own_stride_time_pct": own_time}


@dataclass(frozen=True)
class SweepResult:
    """What :func:`collocation_sweep` did.

    Attributes
    ----------
    table_path
        The summary table (:data:`SWEEP_TABLE`).
    rows
        Its rows (module docstring), models in the order asked.
    failures
        Per model label, what failed (solves that did not converge, or the error that stopped
        the model); empty when everything converged.
    """

    table_path: Path
    rows: list[dict]
    failures: dict[str, list[str]]

    def table(self):
        """The rows as a pandas DataFrame."""
        return pd.DataFrame(self.rows, columns=table_columns(self.rows))


def category_neighbours(models: Sequence[dict], count: int = 2) -> dict[int, list[int]]:
    """For each amputee model of ``models`` (by index), the indices of the ``count`` models
    whose blade categories are nearest its own when the categories are ordered by stiffness
    (Cat4 … Cat7): one on each side, and at either end of the order the next ones on the one
    side it has (Cat4 from Cat5 and Cat6). Nearest first, the stiffer first at equal rank
    distance; models without a blade (the able runner) have none."""
    bladed = sorted((i for i, m in enumerate(models) if m.get("blade")),
                    key=lambda i: blade_category(models[i]["blade"]).stiffness_n_per_m)
    out = {}
    for j, i in enumerate(bladed):
        others = sorted((k for k in range(len(bladed)) if k != j),
                        key=lambda k: (abs(k - j), k < j))
        out[i] = [bladed[k] for k in others[:count]]
    return out


def own_neighbours(model_rows: Sequence[dict], stored: str | Path | None = None,
                   count: int = 2) -> dict[str, list[tuple[str, str]]]:
    """For each problem of one model's kept solves (``model_rows``, a sweep's rows), up to
    ``count`` of the model's own other converged strides as starts: ``{problem_key: [(label,
    file), ...]}``, labels ``from-speed-<v>``, ``from-max-speed``, files as the rows have them.

    The problems in the continuation's order (the prescribed speeds rising, then the maximum
    speed); each problem's nearest others in that order, the faster first, leaving out the one
    its continuation came from (the previous problem), which its own first start already was.
    Where that leaves fewer than ``count``, the model's shipped stride ``stored`` (label
    ``from-stored``) when there is one."""
    converged = [r for r in model_rows if r.get("converged")]
    order = sorted((r for r in converged if r["problem"] != "max-speed"),
                   key=lambda r: r["prescribed_speed_mps"])
    order += [r for r in converged if r["problem"] == "max-speed"]
    out = {}
    for k, r in enumerate(order):
        others = sorted((m for m in range(len(order)) if m not in (k, k - 1)),
                        key=lambda m: (abs(m - k), m < k))
        starts = [(_own_label(order[m]), order[m]["file"]) for m in others[:count]]
        if len(starts) < count and stored is not None:
            starts.append(("from-stored", str(stored)))
        if starts:
            speed = None if r["problem"] == "max-speed" else r["prescribed_speed_mps"]
            out[problem_key(speed)] = starts
    return out


def _own_label(row: dict) -> str:
    return ("from-max-speed" if row["problem"] == "max-speed"
            else f"from-speed-{row['prescribed_speed_mps']:g}")


def _stored_stride(spec: dict, settings: CollocationSettings) -> str | None:
    """The shipped stride of the model ``spec`` as a settling start, where it is the body's own
    problem: the built-in body at its own athlete, the same mesh; else None."""
    if spec.get("athlete"):
        return None
    path = stored_stride_path(runner_from_spec(spec))
    if path is None or CollocationSolution.read(path).settings.mesh_intervals != \
            settings.mesh_intervals:
        return None
    return str(path)


def _settling_payload(i: int, payloads: Sequence[dict], rows: dict[int, list[dict]],
                      out: Path, mesh_check: bool) -> dict | None:
    """The settling pass's payload of model ``i``: the first pass's payload, reading its files
    back (``force`` off), with ``extra_starts`` from the neighbours' converged kept strides
    (the nearest categories' at the same problem, :func:`category_neighbours`; a model without
    a category, the able runner, its own other problems' and its shipped stride,
    :func:`own_neighbours`) and the mesh check the sweep asked for (the first pass leaves it to
    this one, so that only kept strides are checked); None for a model with no such start."""
    models = [p["model_spec"] for p in payloads]
    near_categories = category_neighbours(models)
    extra: dict[str, list[tuple[str, str]]] = {}
    for j in near_categories.get(i, []):
        for r in rows.get(j, []):
            if not r.get("converged"):
                continue
            speed = None if r["problem"] == "max-speed" else r["prescribed_speed_mps"]
            extra.setdefault(problem_key(speed), []).append(
                (f"from-{models[j]['blade']}", str(out / r["file"])))
    if i not in near_categories:  # the able runner: its own other strides instead
        stored = _stored_stride(models[i], payloads[i]["settings"])
        for key, starts in own_neighbours(rows.get(i, []), stored).items():
            extra.setdefault(key, []).extend(
                (label, file if label == "from-stored" else str(out / file))
                for label, file in starts)
    if not extra:
        return None
    return {**payloads[i], "force": False, "extra_starts": extra,
            "mesh_check": bool(mesh_check)}


def _settling_needs(models: Sequence[dict]) -> dict[int, set[int]]:
    """The models whose first pass each model's settling pass needs: its own and its
    neighbouring categories' (:func:`category_neighbours`)."""
    near = category_neighbours(models)
    return {i: {i, *near.get(i, [])} for i in range(len(models))}


def _held(out: Path) -> list[str]:
    if not out.is_dir():
        return []
    held = [SWEEP_TABLE] if (out / SWEEP_TABLE).exists() else []
    for sub in sorted(p for p in out.iterdir() if p.is_dir()):
        held.extend(f"{sub.name}/{p.name}" for p in _files(sub))
    return held


def collocation_sweep(
    models: Sequence[dict],
    speeds: Sequence[float],
    settings: CollocationSettings,
    make_guess: Callable[..., object],
    *,
    out: str | Path,
    jobs: int = 1,
    executor: str = "local",
    resume: bool = False,
    force: bool = False,
    progress: Callable[[ContinuationProgress], None] | None = None,
    starts: int = 1,
    mesh_check: bool = False,
    settle: bool = False,
) -> SweepResult:
    """For each model, the speed continuation then the maximum speed (module docstring); each
    model in ``out/<model_folder>``, the table ``out/collocation-sweep.csv`` rewritten
    (atomically) after each model. A model that fails does not stop the others.

    Parameters
    ----------
    models
        Model specifications (:func:`sweep_models`).
    speeds
        Prescribed speeds [m/s] of the continuation, in order.
    settings
        Settings of the prescribed-speed problems (:func:`speed_continuation`); the maximum
        speed uses :func:`max_speed_settings` of them.
    make_guess
        ``make_guess(runner, n=mesh_intervals, speed=first speed)`` -> the first speed's
        initial guess of a model; picklable (a top-level function or a ``functools.partial``
        of one) when ``jobs`` > 1.
    out
        Output folder.
    jobs, executor
        Models run in parallel on ``executor`` (:func:`bladelab.executors.make_executor`:
        ``local`` processes, ``ray``) with ``jobs`` workers; 1: in this process.
    resume
        Continue a sweep in ``out``: solves already done (same problem) are read back.
    force
        Start over in a used ``out``: files are replaced; a model's files that this run did
        not write are removed once the model is done.
    progress
        Called with each :class:`ContinuationProgress` (in the worker process when
        ``jobs`` > 1, so it must be picklable then).
    starts
        Starts per problem, 1 to 5 (module docstring): 1 the continuation's warm start only;
        more, the best of several kept.
    mesh_check
        Solve every converged problem again on twice the mesh intervals from its stride
        (:mod:`~bladelab.predict.collocation.mesh_check`, in ``<model folder>/mesh-check/``)
        and add its columns to the table (:func:`mesh_check_columns`).
    settle
        After every model, a settling pass (module docstring): each amputee model's problems
        solved again from its neighbouring categories' kept strides, the lowest kept.

    Raises
    ------
    InputFileError
        ``out`` holds a sweep and neither ``resume`` nor ``force`` is given, or ``resume``
        without one.
    SpecError
        Bad speeds, settings or models; ``resume`` with ``force``.
    """
    speeds = check_speeds(speeds)
    if not isinstance(settings, CollocationSettings) or settings.max_speed:
        raise SpecError("expected the CollocationSettings of a prescribed-speed problem",
                        where="settings")
    models = [check_model_spec(m) for m in models]
    if not models:
        raise SpecError("no model to sweep", where="models")
    labels = [model_label(m) for m in models]
    if len(set(labels)) != len(labels):
        raise SpecError("a model is given twice", where="models")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise SpecError(f"need at least 1 job, got {jobs!r}", where="jobs")
    out = Path(out)
    check_output_folder(out, resume=resume, force=force, held=_held, what="collocation sweep")
    starts = check_starts(starts)
    out.mkdir(parents=True, exist_ok=True)
    payloads = [{"model_spec": m, "speeds": list(speeds), "settings": settings,
                 "make_guess": make_guess, "out": str(out.resolve()), "force": bool(force),
                 "progress": progress, "starts": starts, "mesh_check": bool(mesh_check)}
                for m in models]
    table = out / SWEEP_TABLE
    rows: dict[int, list[dict]] = {}
    failures: dict[int, list[str]] = {}

    # One pool for both passes: the first passes in the order given, then each model's
    # settling (or, with no neighbour, its mesh check) as soon as the first passes it needs
    # are done, the first passes before them, so that no worker waits for a whole pass.
    needs = _settling_needs(models)
    first_queue = list(range(len(payloads)))
    ready: list[int] = []
    first_done: set[int] = set()
    second_seen: set[int] = set()
    handed: list[dict] = []
    what: list[tuple[str, int]] = []
    busy = 0
    n_jobs = 1 if executor == "serial" else jobs

    def hand_out() -> None:
        nonlocal busy
        while busy < n_jobs and (first_queue or ready):
            if first_queue:
                i = first_queue.pop(0)
                handed.append({**payloads[i], "mesh_check": payloads[i]["mesh_check"]
                               and not settle})
                what.append(("first", i))
            else:
                i = ready.pop(0)
                handed.append(second[i])
                what.append(("second", i))
            busy += 1

    def second_ready() -> None:
        for i in range(len(payloads)):
            if i in second_seen or not needs[i] <= first_done:
                continue
            second_seen.add(i)
            task = _settling_payload(i, payloads, first_rows, out.resolve(), bool(mesh_check))
            if task is None and i in rows and mesh_check:  # no neighbour: checked alone
                task = {**payloads[i], "force": False}
            if task is not None:
                second[i] = task
                ready.append(i)

    second: dict[int, dict] = {}
    first_rows: dict[int, list[dict]] = {}  # the settling starts come from the first pass
    hand_out()
    for n, status, value in make_executor(executor, jobs).run(sweep_model_task, handed):
        busy -= 1
        phase, i = what[n]
        failures.pop(i, None)
        if status == "ok":
            rows[i] = value["rows"]
            if value["failures"]:
                failures[i] = value["failures"]
        else:
            failures[i] = [f"stopped by an error: {value}"]
        write_table(table, [r for k in sorted(rows) for r in rows[k]])
        if phase == "first":
            first_done.add(i)
            if i in rows:
                first_rows[i] = rows[i]
            if settle:
                second_ready()
        hand_out()
    all_rows = [r for k in sorted(rows) for r in rows[k]]
    if not rows:
        write_table(table, [])
    return SweepResult(table, all_rows, {labels[k]: failures[k] for k in sorted(failures)})
