"""A confirmation run: a study's optimum solved as one more design and set beside what its
surfaces predicted there.

A response-surface optimum is a prediction, and the field's last step is to run it (a
confirmation experiment: Myers, Montgomery and Anderson-Cook, *Response Surface Methodology*,
on checking a fitted optimum). On predicted strides it matters more: the surfaces are
quadratics over designs whose strides lie on two branches, and an optimum between them is the
quadratic's interpolation of a kink. Measured on the people's-stride transtibial study with the
socket moment capped at 150 N·m: predicted 3.836 J/(kg·m) and a residual-knee minimum of
−112 N·m, solved 3.918 J/(kg·m) and −191 N·m, on the knee-loading branch
(benchmarks/design/transtibial-socket-cap-2026-12-05).

:func:`confirm_optimum` solves the optimum's blade with the study's collocation evaluator as a
study solves a design: from its nearest strides (the study's own stride of that blade first,
when the optimum is one of its designs), then settled from its two nearest and the study's
cheapest (:meth:`~bladelab.design.collocation_evaluator.CollocationEvaluator.settle`),
the lowest clean objective kept. Its stride is kept in ``confirmation/strides/`` beside the
study's, not among them, so that no design of the study starts from it. It writes
``confirmation.json``:

==================  ============================================================================
``point``, ``coded``  the optimum's blade, in the factors' units and coded
``objective``       the study's objective and sense
``from``            the start file that gave the kept stride (``null``: its first solve's)
``starts``          per settling start solved: file, objective, status (the first solve's
                    start is not solved again)
``stride``          the kept stride's file (under ``confirmation/strides/``)
``wall_s``          the run's wall time [s]
``responses``       per fitted response that varies: ``predicted`` (the surface's mean), ``pi`` (its 95 %
                    prediction interval), ``solved``, ``inside`` (the solved value in the
                    interval)
``constraints``     per constraint of the optimum: ``bound``, ``upper`` (a maximum),
                    ``solved``, ``met``
==================  ============================================================================

A second call with the same optimum reads the record back; another optimum (a refitted study)
is solved anew.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from bladelab._io import read_json, write_json
from bladelab.design.collocation_evaluator import CollocationEvaluator
from bladelab.design.optimum import SurfaceConstraint
from bladelab.design.stride_files import point_file_stem
from bladelab.errors import SpecError

__all__ = ["CONFIRMATION_DIR", "CONFIRMATION_FILE", "confirm_optimum", "same_point"]

#: The record of a study's confirmation run, in the study's folder.
CONFIRMATION_FILE = "confirmation.json"
#: The folder of the confirmation run's strides, in the study's folder.
CONFIRMATION_DIR = "confirmation"


@dataclasses.dataclass(frozen=True)
class _FromStudy(CollocationEvaluator):
    """The study's evaluator keeping its strides in ``solutions_dir`` but starting from the
    study's (``study_strides``): the nearest and the cheapest designs."""

    study_strides: str | None = None

    def _neighbours(self, point):
        study = dataclasses.replace(self, solutions_dir=self.study_strides)
        # an optimum that is a design of the study: that design's stride first (a replicate
        # from its neighbours alone can end in a dearer optimum: measured, +2.7 %)
        own = Path(self.study_strides) / f"{point_file_stem(point)}.json"
        others = [f for f in CollocationEvaluator._neighbours(study, point)
                  if f.name != own.name]
        return ([own] if own.is_file() else []) + others


def same_point(a: dict, b: dict) -> bool:
    """True if two design points ({factor: value}) are the same blade (to 1e-9 relative)."""
    return a.keys() == b.keys() and all(math.isclose(a[k], b[k], rel_tol=1e-9) for k in a)


def confirm_optimum(evaluator: CollocationEvaluator, result, *,
                    say: Callable[[str], None] | None = None) -> dict:
    """Solve the optimum of a finished study ``result``
    (:class:`~bladelab.design.study.DesignStudyResult`) with its collocation ``evaluator`` and
    record it beside the prediction (module docstring); returns the record. ``say`` gets a
    line per start.

    Raises
    ------
    SpecError
        The study has no optimum, or its evaluator solves no strides.
    OptimizationError
        No start gave a clean stride of the optimum's blade.
    """
    if result.optimum is None or result.optimum.point is None:
        raise SpecError("the study has no optimum to confirm", where="confirmation",
                        hint=result.optimum_error or "give --objective")
    if not isinstance(evaluator, CollocationEvaluator) or evaluator.solutions_dir is None:
        raise SpecError("only a study of predicted strides (--evaluator collocation) solves "
                        "its optimum as a design", where="confirmation")
    out = Path(result.out_dir)
    optimum = result.optimum
    point = {k: float(v) for k, v in optimum.point.items()}
    path = out / CONFIRMATION_FILE
    if path.is_file():
        old = read_json(path, what="confirmation run")
        if same_point(old.get("point") or {}, point):
            return old
    strides = out / CONFIRMATION_DIR / "strides"
    ev = _FromStudy(**{f.name: getattr(evaluator, f.name)
                       for f in dataclasses.fields(CollocationEvaluator)}
                    | {"solutions_dir": str(strides),
                       "study_strides": str(evaluator.solutions_dir)})
    t0 = time.perf_counter()
    first = ev(point)  # from its nearest design's stride, as a run of the study
    # the start that gave the first stride is not solved again (IPOPT would retrace it)
    settled = ev.settle(point, neighbours=2, cheapest=True, known=ev.solved_from(point),
                        say=say)
    wall = time.perf_counter() - t0
    kept = first if settled["from"] is None else next(
        t["responses"] for t in settled["tries"] if t["from"] == settled["from"])
    coded = [optimum.coded[f] for f in result.space.names]
    responses = {}
    for name, surface in result.surfaces.items():
        value = kept.get(name)
        if value is None or not math.isfinite(value) or np.ptp(surface.y) == 0:
            continue  # not given, or prescribed (the mean speed): nothing predicted
        pred = surface.predict([coded])
        lo, hi = float(pred.pi_lower[0]), float(pred.pi_upper[0])
        responses[name] = {"predicted": float(pred.mean[0]), "pi": [lo, hi],
                           "solved": float(value), "inside": bool(lo <= value <= hi)}
    constraints = {}
    for name, row in optimum.constraints.items():
        upper = "maximum" in row
        con = SurfaceConstraint(result.surfaces[name], row["maximum" if upper else "minimum"],
                                upper)
        value = float(kept[name])
        constraints[name] = {"bound": float(con.bound), "upper": upper, "solved": value,
                             "met": bool(con.margin(value) >= 0)}
    record = {
        "point": point, "coded": dict(optimum.coded),
        "objective": {"name": optimum.objective, "sense": optimum.sense},
        "from": settled["from"],
        "starts": [{"from": t["from"], "objective": t["objective"], "status": t["status"]}
                   for t in settled["tries"]],
        "stride": f"{CONFIRMATION_DIR}/strides/{point_file_stem(point)}.json",
        "wall_s": wall, "responses": responses, "constraints": constraints,
    }
    write_json(path, record)
    return record
