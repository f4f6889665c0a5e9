"""``bladelab design --evaluator collocation --settle K``: settling passes over a study's
predicted strides (:func:`bladelab.design.collocation_evaluator.settle_strides`), their record
``settling.json``, and the run files of the designs whose stride changed (removed, so that the
study reads their new responses back).

A pass takes hours on two cores, so it is recorded design by design: ``settling.json`` is
rewritten (atomically) as each design finishes, with ``"complete": false`` until the pass
ends, and a run stopped mid-pass (Ctrl-C, SIGTERM, a lost machine) resumes that pass where it
stopped on the next ``--settle``, skipping the designs it had settled."""

from __future__ import annotations

import typer

from bladelab._io import read_json, write_json
from bladelab.errors import InputFileError

#: A pass that lowers no design's objective by more than this fraction has settled.
SETTLED_REL = 0.01
#: The record of the settling passes in a study's folder.
RECORD_NAME = "settling.json"


def _drop(row: dict) -> float:
    """Relative objective drop of one design's settling [-]."""
    return (row["before"] - row["after"]) / abs(row["before"])


def _read_record(out, points) -> list[dict]:
    """The passes recorded in ``out``; an error if they belong to other designs."""
    from bladelab.design.collocation_evaluator import point_file_stem

    path = out / RECORD_NAME
    if not path.is_file():
        return []
    record = read_json(path, what="settling record").get("passes", [])
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


def _run_pass(evaluator, points, current: dict, out, *, jobs: int, save,
              failed=frozenset()) -> bool:
    """Settle the designs of pass ``current`` not yet in it (nor the ``failed`` run indices,
    which have no stride), recording each as it finishes; True if a stride changed."""
    from bladelab.design.collocation_evaluator import settle_strides
    from bladelab.design.study import run_file

    changed = False

    def done(i: int, row: dict) -> None:
        nonlocal changed
        current["designs"].append({"run": i + 1, **row})
        if row["from"] is not None:
            changed = True
            run_file(out, i).unlink(missing_ok=True)
        save()

    settle_strides(evaluator, points, jobs=jobs, on_design=done,
                   skip=[r["run"] - 1 for r in current["designs"]] + sorted(failed))
    return changed


def settle_study(evaluator, result, *, passes: int, jobs: int) -> bool:
    """Run up to ``passes`` settling passes over ``result``'s designs (resuming an incomplete
    pass first); record them in ``settling.json``; return True if any stride changed (the
    study must be read again)."""
    space, design, out = result.space, result.design, result.out_dir
    points = [space.point(c) for c in design.coded]
    failed = frozenset(run - 1 for run in result.failed)  # no stride to settle
    record = _read_record(out, points)
    changed_any = False

    def save() -> None:
        write_json(out / RECORD_NAME, {"settled_below": SETTLED_REL, "passes": record})

    for _ in range(passes):
        if record and not record[-1]["complete"]:
            current = record[-1]
            typer.echo(f"resuming settling pass {current['pass']}: {len(current['designs'])} "
                       f"of {len(points)} designs already settled")
        else:
            current = {"pass": len(record) + 1, "complete": False, "designs": []}
            record.append(current)
            save()
        changed_any |= _run_pass(evaluator, points, current, out, jobs=jobs, save=save,
                                 failed=failed)
        worst = max(_drop(r) for r in current["designs"])
        current.update(complete=True, largest_objective_drop=worst,
                       improved=sum(r["from"] is not None for r in current["designs"]))
        save()
        typer.echo(f"settling pass {current['pass']}: {current['improved']} of "
                   f"{len(points) - len(failed)} designs improved, largest objective drop "
                   f"{100 * worst:.2f} %")
        if worst <= SETTLED_REL:
            break
    else:
        typer.echo(f"not settled after {passes} passes (largest drop above "
                   f"{100 * SETTLED_REL:g} %)", err=True)
    return changed_any
