"""``bladelab design --evaluator collocation --settle K``: settling passes over a study's
predicted strides (:func:`bladelab.design.collocation_evaluator.settle_strides`), their record
``settling.json``, and the run files of the designs whose stride changed (removed, so that the
study reads their new responses back)."""

from __future__ import annotations

import typer

from bladelab._io import write_json

#: A pass that lowers no design's objective by more than this fraction has settled.
SETTLED_REL = 0.01


def settle_study(evaluator, result, *, passes: int, jobs: int) -> bool:
    """Run up to ``passes`` settling passes over ``result``'s designs; write
    ``settling.json``; return True if any stride changed (the study must be read again)."""
    from bladelab.design.collocation_evaluator import settle_strides
    from bladelab.design.study import run_file

    space, design, out = result.space, result.design, result.out_dir
    points = [space.point(c) for c in design.coded]
    record, changed_any = [], False
    for k in range(passes):
        rows = settle_strides(evaluator, points, jobs=jobs)
        drops = [(r["before"] - r["after"]) / abs(r["before"]) for r in rows]
        for i, r in enumerate(rows):
            if r["from"] is not None:
                changed_any = True
                run_file(out, i).unlink(missing_ok=True)
        worst = max(drops)
        record.append({"pass": k + 1, "designs": rows, "largest_objective_drop": worst,
                       "improved": sum(r["from"] is not None for r in rows)})
        write_json(out / "settling.json", {"settled_below": SETTLED_REL, "passes": record})
        typer.echo(f"settling pass {k + 1}: {record[-1]['improved']} of {len(rows)} designs "
                   f"improved, largest objective drop {100 * worst:.2f} %")
        if worst <= SETTLED_REL:
            break
    else:
        typer.echo(f"not settled after {passes} passes (largest drop above "
                   f"{100 * SETTLED_REL:g} %)", err=True)
    return changed_any
