"""Where a design's stride is kept and what it was solved from.

- :func:`point_file_stem` names a design's stride file ``name=value__name=value`` (values to 6
  digits) and :func:`point_from_stem` reads a point back from such a name;
- :func:`stored_neighbours` lists the strides of the other designs in a folder, nearest first
  in coded units (:func:`coded_distance`);
- :func:`start_identity` says what makes a start stride the same start, and
  :func:`start_text` / :func:`solved_from_text` write and read the guess source that records it
  in the solved stride (so that a settling pass does not solve again from an unchanged start).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path

__all__ = ["coded_distance", "point_file_stem", "point_from_stem", "solved_from_text",
           "start_identity", "start_text", "stored_neighbours"]

_SEP = "__"


def point_file_stem(point: Mapping[str, float]) -> str:
    """File name stem of a design point: ``name=value__name=value`` (values to 6 digits)."""
    return _SEP.join(f"{k}={float(v):.6g}" for k, v in point.items())


def point_from_stem(stem: str) -> dict[str, float] | None:
    """The design point named by a stride file's stem (:func:`point_file_stem`); None for a
    name that is not one."""
    try:
        return {k: float(v) for k, v in (item.split("=", 1) for item in stem.split(_SEP))}
    except ValueError:
        return None


def coded_distance(a: Mapping[str, float], b: Mapping[str, float],
                   factor_ranges: Mapping[str, tuple[float, float]]) -> float:
    """Euclidean distance of two design points in coded units (each factor's half range of
    ``factor_ranges`` is 1; a factor without a range: relative to its value in ``a``); inf for
    points of different factors."""
    if set(a) != set(b):
        return math.inf
    total = 0.0
    for k, v in a.items():
        lo, hi = factor_ranges.get(k, (0.0, 0.0))
        span = (hi - lo) / 2 if hi > lo else max(abs(v), 1e-12)
        total += ((v - b[k]) / span) ** 2
    return math.sqrt(total)


def stored_neighbours(folder: str | Path, point: Mapping[str, float],
                      factor_ranges: Mapping[str, tuple[float, float]]) -> list[Path]:
    """Stride files of the other designs in ``folder``, nearest to ``point`` first
    (:func:`coded_distance`, ties by file name); a failed solve's last iterate
    (``.best_iterate.json``) and a replaced stride (``.previous.json``) are not strides of a
    design. [] for a folder that does not exist."""
    found = []
    if Path(folder).is_dir():
        for f in Path(folder).glob("*.json"):
            if f.name.endswith((".best_iterate.json", ".previous.json")):
                continue
            p = point_from_stem(f.stem)
            if p is not None and p != dict(point):
                found.append((coded_distance(point, p, factor_ranges), f.name, f))
    return [f for _, _, f in sorted(found)]


def start_identity(solution, speed_floor: float | None = None) -> str:
    """What makes a start stride the same start: its objective to the last digit and whether
    it carries IPOPT's multipliers (a stride stored without them starts elsewhere); in a
    maximum-speed problem also the speed floor [m/s] the solve from it was given, when one
    was (another floor is another problem from the same start)."""
    identity = (f"{float(solution.nlp.objective)!r} "
                + ("primal" if solution.nlp.multipliers is None else "primal-dual"))
    return identity if speed_floor is None else f"{identity}, floor {speed_floor!r} m/s"


#: A stride's guess source when it was solved from another stride as it is (``start_text``).
_START_TEXT = re.compile(r"^collocation solution (?P<name>\S+\.json), start (?P<id>.+)$")


def start_text(path: Path, start, speed_floor: float | None = None) -> str:
    """The guess source of a solve from the stride ``start`` read from ``path``: its file and
    its :func:`start_identity`, so that the solved stride says what it was solved from."""
    return f"collocation solution {path.name}, start {start_identity(start, speed_floor)}"


def solved_from_text(source: str | None) -> dict[str, str]:
    """{start file name: its identity} from a stride's guess source written by
    :func:`start_text`; {} for any other source (a tracking stage, a continuation)."""
    match = _START_TEXT.match(source or "")
    return {match["name"]: match["id"]} if match else {}
