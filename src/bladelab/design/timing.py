"""The wall time a design study took, stage by stage (``timing.json`` in its folder).

A study runs in stages: its runs, then each settling pass (:mod:`bladelab.design.settling`).
Each stage can be stopped and resumed, so it may take several sittings. Every sitting that
evaluated something appends one segment, rewritten atomically when it ends::

    {"segments": [{"stage": "runs", "started": "2026-12-04T17:00:00+00:00",
                   "wall_s": 960.2, "designs": 25, "jobs": 2}, ...]}

A stage's wall time is the sum of its segments' (:func:`stage_walls`): the time the study
held its workers, not the calendar time between its first and last sitting. ``designs`` counts
what the sitting evaluated, a run read back from its stored stride included (after a settling
pass the study reads its changed strides back: a "runs" sitting of seconds).
"""

from __future__ import annotations

import datetime as _dt
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from bladelab._io import read_json, write_json

__all__ = ["RUNS_STAGE", "TIMING_NAME", "read_segments", "settling_stage", "stage_walls",
           "timed_stage"]

#: The record's file name in a study folder.
TIMING_NAME = "timing.json"
#: The stage of the study's runs.
RUNS_STAGE = "runs"


def settling_stage(n: int) -> str:
    """The stage name of settling pass ``n`` (1 first)."""
    return f"settling pass {n}"


def read_segments(out: str | Path) -> list[dict]:
    """The recorded segments of the study folder ``out`` (none: ``[]``)."""
    path = Path(out) / TIMING_NAME
    if not path.is_file():
        return []
    return list(read_json(path, what="study timing").get("segments", []))


def stage_walls(out: str | Path) -> dict[str, dict]:
    """Stage -> {"wall_s": summed wall time [s], "designs": designs evaluated, "sittings": n,
    "jobs": the largest worker count}, in the order the stages first ran."""
    walls: dict[str, dict] = {}
    for seg in read_segments(out):
        w = walls.setdefault(seg["stage"], {"wall_s": 0.0, "designs": 0, "sittings": 0,
                                            "jobs": 0})
        w["wall_s"] += float(seg["wall_s"])
        w["designs"] += int(seg.get("designs", 0))
        w["sittings"] += 1
        w["jobs"] = max(w["jobs"], int(seg.get("jobs", 1)))
    return walls


@contextmanager
def timed_stage(out: str | Path, stage: str, *, jobs: int) -> Iterator[dict]:
    """Time one sitting of ``stage``: the caller sets ``["designs"]`` of the yielded dict to
    what it evaluated; a sitting that evaluated nothing is not recorded. Recorded also when
    the sitting is stopped by an error or Ctrl-C (its finished designs are kept)."""
    started = _dt.datetime.now(_dt.UTC).replace(microsecond=0)
    t0 = time.perf_counter()
    seg = {"designs": 0}
    try:
        yield seg
    finally:
        if seg["designs"]:
            path = Path(out) / TIMING_NAME
            data = read_json(path, what="study timing") if path.is_file() else {}
            data.setdefault("segments", []).append(
                {"stage": stage, "started": started.isoformat(),
                 "wall_s": round(time.perf_counter() - t0, 1),
                 "designs": int(seg["designs"]), "jobs": int(jobs)})
            write_json(path, data)  # other keys (a note written by hand) kept
