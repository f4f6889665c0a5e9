"""Where a design's stride is kept and what it was solved from.

- :func:`point_file_stem` names a design's stride file ``name=value__name=value`` (values to 6
  digits) and :func:`point_from_stem` reads a point back from such a name;
- :func:`start_identity` says what makes a start stride the same start, and
  :func:`start_text` / :func:`solved_from_text` write and read the guess source that records it
  in the solved stride (so that a settling pass does not solve again from an unchanged start).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

__all__ = ["point_file_stem", "point_from_stem", "solved_from_text", "start_identity",
           "start_text"]

_SEP = "__"


def point_file_stem(point: Mapping[str, float]) -> str:
    """File name stem of a design point: ``name=value__name=value`` (values to 6 digits)."""
    return _SEP.join(f"{k}={float(v):.6g}" for k, v in point.items())


def point_from_stem(stem: str) -> dict[str, float] | None:
    try:
        return {k: float(v) for k, v in (item.split("=", 1) for item in stem.split(_SEP))}
    except ValueError:
        return None



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
