"""Settling passes over a predicted-gait design study, and their record ``settling.json``.

A settling pass solves each design's stride again from its two nearest neighbours' strides and
the study's cheapest stride of another design, and keeps the lowest objective
(:func:`settle_strides`); the run files of the designs
whose stride changed are removed, so that the study reads their new responses back
(:func:`settle_study` returns whether it must). ``bladelab design --evaluator collocation
--settle K`` runs up to K passes.

A pass takes hours on two cores, so it is recorded design by design: ``settling.json`` (in the
study's folder) is rewritten atomically as each design finishes, with ``"complete": false``
until the pass ends, and a run stopped mid-pass (Ctrl-C, SIGTERM, a lost machine) resumes that
pass where it stopped, skipping the designs it had settled. The record::

    {"settled_below": 0.01,
     "passes": [{"pass": 1, "complete": true, "largest_objective_drop": 0.004, "improved": 3,
                 "from_cheapest": true,
                 "designs": [{"run": 1, "point": {...}, "before": ..., "after": ...,
                              "from": "<neighbour's stride>" | null, "tries": [...],
                              "unchanged": [...]}, ...]}, ...]}

A start a design was solved from in an earlier pass and whose stride has not changed since
(:func:`~bladelab.design.stride_files.start_identity`) is not solved again.

:func:`bladelab.design.start_spread.start_spread` reads it back.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from tqdm.auto import tqdm

from bladelab._io import read_json, write_json
from bladelab.design import defaults
from bladelab.design.stride_files import point_file_stem
from bladelab.design.study import DesignStudyResult, run_design, run_file
from bladelab.design.timing import settling_stage, timed_stage
from bladelab.errors import InputFileError, OptimizationError
from bladelab.executors import make_executor, say_to_stderr

__all__ = ["RECORD_NAME", "SETTLED_REL", "SETTLE_FROM_CHEAPEST", "SettlingOutcome", "is_settled",
           "objective_drop", "read_settling_record", "run_settled_design", "settle_strides",
           "settle_study"]

#: A pass that lowers no design's objective by more than this fraction [-] has settled.
SETTLED_REL = defaults.SETTLED_REL
#: New passes also start each design from the study's cheapest stride (recorded per pass as
#: ``"from_cheapest"``; a pass recorded without it resumes without it).
SETTLE_FROM_CHEAPEST = defaults.SETTLE_FROM_CHEAPEST
#: The record of the settling passes in a study's folder.
RECORD_NAME = "settling.json"


@dataclass(frozen=True)
class SettlingOutcome:
    """What :func:`settle_study` did.

    Attributes
    ----------
    changed
        A design's stride changed: the study must be read again (its run files were removed).
    settled
        The last pass lowered no objective by more than :data:`SETTLED_REL`.
    passes
        Passes run (or finished, when resumed) by this call.
    largest_objective_drop
        Largest relative objective drop of the last pass [-]; NaN when no pass ran.
    """

    changed: bool
    settled: bool
    passes: int
    largest_objective_drop: float


def objective_drop(row: dict) -> float:
    """Relative objective drop of one design's settling [-]."""
    return (row["before"] - row["after"]) / abs(row["before"])


def is_settled(record: Sequence[dict]) -> bool:
    """Whether a study's settling passes (:func:`read_settling_record`) have settled: its last
    pass is complete and lowered no objective by more than :data:`SETTLED_REL`."""
    return bool(record) and bool(record[-1].get("complete")) and (
        record[-1]["largest_objective_drop"] <= SETTLED_REL)


def read_settling_record(out: str | Path, points: Sequence[dict] | None = None) -> list[dict]:
    """The passes recorded in the study folder ``out`` (``settling.json``; none: ``[]``).

    With ``points`` (the study's design points, run 1 first), every recorded design must be
    the study's run of the same point.

    Raises
    ------
    InputFileError
        A recorded design is not the study's run of that number.
    """
    path = Path(out) / RECORD_NAME
    if not path.is_file():
        return []
    record = read_json(path, what="settling record").get("passes", [])
    if points is None:
        return record
    stems = [point_file_stem(p) for p in points]
    for rec in record:
        for row in rec.get("designs", []):
            run = row.get("run")
            if not (isinstance(run, int) and 1 <= run <= len(points)
                    and point_file_stem(row["point"]) == stems[run - 1]):
                raise InputFileError(
                    f"a settled design ({row.get('point')}) is not run {run} of this study",
                    file=path, hint="settle in the study's own folder, or remove the file")
    return record


def _known_starts(passes: Sequence[dict], points: Sequence[dict],
                  evaluator=None) -> list[dict[str, str]]:
    """Per design (run 1 first): start file name -> the identity of that start when the
    design was last solved from it, over the recorded ``passes`` (older records, without
    identities, give none) and the solve that gave its stored stride (the evaluator's
    ``solved_from``)."""
    known: list[dict[str, str]] = [{} for _ in points]
    for rec in passes:
        for row in rec.get("designs", []):
            for t in row.get("tries", []):
                if t.get("start") is not None:
                    known[int(row["run"]) - 1][t["from"]] = t["start"]
    solved_from = getattr(evaluator, "solved_from", None)
    if solved_from is not None:
        for i, point in enumerate(points):
            known[i].update(solved_from(point))
    return known


def _run_pass(evaluator, points, current: dict, out: Path, *, jobs: int, save,
              failed=frozenset(), record_before: Sequence[dict] = ()) -> bool:
    """Settle the designs of pass ``current`` not yet in it (nor the ``failed`` run indices,
    which have no stride), recording each as it finishes (and the sitting's wall time in
    ``timing.json``), skipping the starts unchanged since the passes ``record_before``; True
    if a stride changed."""
    changed = False
    with timed_stage(out, settling_stage(current["pass"]), jobs=jobs) as sitting:
        def done(i: int, row: dict) -> None:
            nonlocal changed
            current["designs"].append({"run": i + 1, **row})
            sitting["designs"] += 1
            if row["from"] is not None:
                changed = True
                run_file(out, i).unlink(missing_ok=True)
            save()

        settle_strides(
            evaluator, points, jobs=jobs, on_design=done,
            cheapest=bool(current.get("from_cheapest", False)),
            known=_known_starts(record_before, points, evaluator),
            skip=[r["run"] - 1 for r in current["designs"]] + sorted(failed))
    return changed


def settle_study(evaluator, result, *, passes: int, jobs: int = 1,
                 progress: Callable[[str], None] | None = None) -> SettlingOutcome:
    """Run up to ``passes`` settling passes over the designs of a study ``result``
    (:class:`~bladelab.design.study.DesignStudyResult`) with its collocation ``evaluator``,
    resuming an incomplete pass first, ``jobs`` designs at a time; record them in the study's
    ``settling.json`` (module docstring). Stops at the first pass that settles (no objective
    lowered by more than :data:`SETTLED_REL`); a study whose last recorded pass settled gets
    none (``passes`` 0 in the outcome). ``progress`` receives one line per pass.

    Raises
    ------
    InputFileError
        The folder's record belongs to other designs.
    """
    space, design, out = result.space, result.design, Path(result.out_dir)
    points = [space.point(c) for c in design.coded]
    failed = frozenset(run - 1 for run in result.failed)  # no stride to settle
    record = read_settling_record(out, points)
    say = progress or (lambda line: None)
    changed_any = False
    ran = 0
    worst = float("nan")

    def save() -> None:
        write_json(out / RECORD_NAME, {"settled_below": SETTLED_REL, "passes": record})

    if is_settled(record):
        say(f"settled: pass {record[-1]['pass']} lowered no objective by more than "
            f"{100 * SETTLED_REL:g} %; no further pass")
        return SettlingOutcome(False, True, 0, record[-1]["largest_objective_drop"])
    for _ in range(passes):
        if record and not record[-1]["complete"]:
            current = record[-1]
            say(f"resuming settling pass {current['pass']}: {len(current['designs'])} of "
                f"{len(points)} designs already settled")
        else:
            current = {"pass": len(record) + 1, "complete": False,
                       "from_cheapest": SETTLE_FROM_CHEAPEST, "designs": []}
            record.append(current)
            save()
        changed_any |= _run_pass(evaluator, points, current, out, jobs=jobs, save=save,
                                 failed=failed, record_before=record[:-1])
        worst = max(objective_drop(r) for r in current["designs"])
        current.update(complete=True, largest_objective_drop=worst,
                       improved=sum(r["from"] is not None for r in current["designs"]))
        save()
        ran += 1
        say(f"settling pass {current['pass']}: {current['improved']} of "
            f"{len(points) - len(failed)} designs improved, largest objective drop "
            f"{100 * worst:.2f} %")
        if worst <= SETTLED_REL:
            return SettlingOutcome(changed_any, True, ran, worst)
    return SettlingOutcome(changed_any, False, ran, worst)


def run_settled_design(space, *, evaluator, out_dir: str | Path, settle_passes: int = 0,
                       jobs: int = 1, progress: Callable[[str], None] | None = None,
                       **options) -> tuple[DesignStudyResult, SettlingOutcome | None]:
    """:func:`~bladelab.design.study.run_design` of ``space`` with ``evaluator`` into
    ``out_dir`` (``jobs`` and the other ``options`` are its own), then up to
    ``settle_passes`` settling passes over its designs (:func:`settle_study`); when a stride
    changed, the study again (the settled strides' responses read back, not solved). Returns
    the study's result and the settling's outcome (None without settling passes)."""
    def study() -> DesignStudyResult:
        return run_design(space, evaluator=evaluator, out_dir=out_dir, jobs=jobs, **options)

    result = study()
    if settle_passes <= 0:
        return result, None
    outcome = settle_study(evaluator, result, passes=settle_passes, jobs=jobs,
                           progress=progress)
    if outcome.changed:
        result = study()
    return result, outcome


def settle_design_point(payload: dict) -> dict:
    """One design's :meth:`~bladelab.design.collocation_evaluator.CollocationEvaluator.settle`
    in a worker process (a line per start on standard error with ``payload["progress"]``)."""
    return payload["evaluator"].settle(payload["point"], payload["neighbours"],
                                       payload.get("cheapest", False), payload.get("known"),
                                       say_to_stderr if payload.get("progress") else None)


def settle_strides(evaluator, points, *, neighbours: int = 2,
                   cheapest: bool = False, jobs: int = 1, progress: bool = True, skip=(),
                   known: Sequence[Mapping[str, str]] | None = None,
                   on_design: Callable[[int, dict], None] | None = None) -> list[dict | None]:
    """One settling pass over a study's designs: the collocation ``evaluator``'s ``settle``
    for each point from its ``neighbours`` nearest strides and, with ``cheapest``, the study's
    cheapest one; ``jobs`` worker processes, each writing a line per start with ``progress``. A design's stride depends on the start it was solved
    from (local optima); a pass that lowers no objective by more than 1 % is the study's
    evidence that its strides have settled (docs/design.md).

    ``skip``: indices of designs already settled in this pass (a resumed pass; their rows are
    None in the result). ``known``: per point, the starts it was solved from before
    (the evaluator's ``settle``), not solved again while unchanged.
    ``on_design(i, row)`` is called in this process as each design finishes, so that a caller
    can record the pass as it goes."""
    skip = set(skip)
    todo = [i for i in range(len(points)) if i not in skip]
    payloads = [{"evaluator": evaluator, "point": dict(points[i]), "neighbours": int(neighbours),
                 "cheapest": bool(cheapest), "known": dict(known[i]) if known else None,
                 "progress": bool(progress)}
                for i in todo]
    out: list[dict | None] = [None] * len(points)
    failed = []
    bar = tqdm(total=len(points), initial=len(points) - len(todo), desc="settling strides",
               unit="design", disable=not progress)
    for k, status, value in make_executor("local", jobs).run(
            settle_design_point, payloads):
        bar.update()
        if status == "ok":
            out[todo[k]] = value  # in the order of the points
            if on_design is not None:
                on_design(todo[k], value)
        else:
            failed.append(f"{point_file_stem(payloads[k]['point'])}: {value}")
    bar.close()
    if failed:
        raise OptimizationError(f"{len(failed)} designs could not be settled "
                                f"({'; '.join(failed[:3])})", where="settle")
    return out
