"""The file of a collocation solution: its fields, written and read.

:func:`solution_fields` gives a :class:`~bladelab.predict.collocation.solution.
CollocationSolution`'s JSON content and :func:`solution_arguments` checks such content field by
field and gives the solution's constructor arguments (``CollocationSolution.to_dict`` and
``from_dict`` call them). ``"kind"`` is :data:`SOLUTION_KIND` for a converged solve and
:data:`BEST_ITERATE_KIND` for the last iterate of one that did not converge; units are in the
field names (``_s``, ``_m``, ``_N``, ``_J``, ``_mps``); node arrays are rows per node, in the
order of ``dof_names`` and ``muscle_names``; non-finite numbers are written as null.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from bladelab.errors import DataError, SpecError
from bladelab.predict.collocation.nlp_solution import NLPSolution
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.stored import FieldReader, check_model_spec

__all__ = ["BEST_ITERATE_KIND", "FORMAT_VERSION", "SOLUTION_KIND", "solution_arguments",
           "solution_fields"]

#: ``"kind"`` of a converged solve's file.
SOLUTION_KIND = "collocation-solution"
#: ``"kind"`` of the last iterate of a solve that did not converge.
BEST_ITERATE_KIND = "collocation-best-iterate"
#: The file's format version (a newer file is refused).
FORMAT_VERSION = 1

# node arrays: (file field, NLPSolution attribute, columns: "dof" or "muscle")
_NODE_FIELDS = (
    ("q", "q", "dof"),
    ("qd", "qd", "dof"),
    ("qdd", "qdd", "dof"),
    ("activation", "activation", "muscle"),
    ("tendon_force_per_Fmax", "tendon_force", "muscle"),
    ("excitation", "excitation", "muscle"),
    ("tendon_force_rate_per_Fmax_per_s", "tendon_force_rate", "muscle"),
)


def _num(x) -> float | None:
    """A float for JSON: non-finite values as null."""
    x = float(x)
    return x if math.isfinite(x) else None


def _array(a: np.ndarray) -> list:
    a = np.asarray(a, dtype=float)
    return np.where(np.isfinite(a), a, None).tolist() if not np.all(np.isfinite(a)) \
        else a.tolist()


def solution_fields(solution) -> dict:
    """The JSON content of a ``CollocationSolution`` (module docstring)."""
    s = solution.nlp
    return {
        "kind": solution.kind,
        "format_version": FORMAT_VERSION,
        "model": dict(solution.model_spec),
        "settings": solution.settings.to_dict(),
        "guess_source": solution.guess_source,
        "stage": solution.stage,
        "converged": solution.converged,
        "status": str(s.status),
        "success": bool(s.success),
        "iterations": int(s.iterations),
        "wall_s": _num(s.wall_s),
        "objective": _num(s.objective),
        "objective_terms": {k: _num(v) for k, v in s.objective_terms.items()},
        "max_violation": _num(s.max_violation),
        "worst_constraints": [[name, _num(v)] for name, v in s.worst_constraints],
        "timings": {k: _num(v) for k, v in s.timings.items()},
        "reference_phase": solution.reference_phase,
        "speed_floor_mps": solution.speed_floor_mps,
        "tracking": None if solution.tracking is None else {
            k: (_num(v) if isinstance(v, float) else v) for k, v in solution.tracking.items()},
        "summary": solution.summary(),
        "period_s": _num(s.period),
        "dof_names": list(solution.dof_names),
        "muscle_names": list(solution.muscle_names),
        "time_s": _array(s.time),
        **{name: _array(getattr(s, attr)) for name, attr, _ in _NODE_FIELDS},
        "contact_forces_N": _array(solution.contact_forces),
        "contact_legs": [int(v) for v in solution.contact_legs],
        "leg_names": list(solution.leg_names),
        "body_mass_kg": _num(solution.body_mass_kg),
        "body_weight_N": _num(solution.body_weight_N),
        "metabolic_energy_J": _num(solution.metabolic_energy_J),
        "consistency": _jsonable(solution.residual),
        "multipliers": None if s.multipliers is None else {
            "bounds": _array(s.multipliers[0]), "constraints": _array(s.multipliers[1])},
    }


def solution_arguments(data, file: str | Path | None = None) -> dict:
    """The ``CollocationSolution`` constructor's arguments from :func:`solution_fields`'s
    content, checked field by field.

    Raises
    ------
    DataError
        A field is missing or of the wrong kind or shape (the error names ``file`` and the
        field), or the file is of a newer format.
    """
    if not isinstance(data, dict):
        raise DataError("expected a JSON object", file=file)
    r = FieldReader(data, file)
    kind = r.get("kind", str)
    if kind not in (SOLUTION_KIND, BEST_ITERATE_KIND):
        raise DataError(f"not a collocation solution (kind {kind!r})", file=file,
                        where="kind", hint=f"expected {SOLUTION_KIND!r} or "
                                           f"{BEST_ITERATE_KIND!r}")
    version = r.get("format_version", int)
    if version > FORMAT_VERSION:
        raise DataError(f"format version {version} is newer than this bladelab's "
                        f"({FORMAT_VERSION})", file=file, where="format_version",
                        hint="update bladelab")
    try:
        spec = check_model_spec(r.get("model", dict))
        settings = CollocationSettings.from_dict(r.get("settings", dict))
    except SpecError as err:
        raise DataError(err.message, file=file, where=err.where, hint=err.hint) from None
    dofs = tuple(r.names("dof_names"))
    muscles = tuple(r.names("muscle_names"))
    time_s = r.array("time_s", 1)
    n1 = time_s.shape[0]
    if n1 < 2:
        raise DataError("need at least 2 nodes", file=file, where="time_s")
    arrays = {}
    for name, attr, cols in _NODE_FIELDS:
        width = len(dofs) if cols == "dof" else len(muscles)
        arrays[attr] = r.array(name, 2, (n1, width))
    legs = r.get("leg_names", list)
    if len(legs) != 2 or not all(isinstance(v, str) for v in legs):
        raise DataError("expected two leg names", file=file, where="leg_names")
    contact_legs = np.asarray(r.get("contact_legs", list))
    if contact_legs.ndim != 1 or not np.isin(contact_legs, (0, 1)).all():
        raise DataError("expected a leg index 0 or 1 per contact", file=file,
                        where="contact_legs")
    forces = r.array("contact_forces_N", 3, (n1, contact_legs.size, 2))
    tracking = data.get("tracking")
    if tracking is not None and not isinstance(tracking, dict):
        raise DataError("expected an object or null", file=file, where="tracking")
    stage = r.get("stage", str)
    if stage not in ("predictive", "tracking"):
        raise DataError(f"unknown stage {stage!r}", file=file, where="stage")
    worst = r.get("worst_constraints", list)
    try:
        worst = tuple((str(a), _float(b)) for a, b in worst)
    except (TypeError, ValueError):
        raise DataError("expected [name, value] pairs", file=file,
                        where="worst_constraints") from None
    nlp = NLPSolution(
        time=time_s, **arrays,
        period=r.number("period_s"),
        objective=r.number("objective"),
        objective_terms={str(k): _float(v) for k, v in
                         r.get("objective_terms", dict).items()},
        success=r.get("success", bool),
        status=r.get("status", str),
        iterations=r.get("iterations", int),
        wall_s=r.number("wall_s"),
        timings={str(k): _float(v) for k, v in r.get("timings", dict).items()},
        max_violation=r.number("max_violation"),
        worst_constraints=worst,
    )
    if not (nlp.period > 0):
        raise DataError(f"stride time must be > 0 s, got {nlp.period}", file=file,
                        where="period_s")
    nlp = replace(nlp, multipliers=_read_multipliers(data.get("multipliers"), file))
    if kind == SOLUTION_KIND and not (nlp.success and stage == "predictive"):
        raise DataError("marked as a solution but did not converge", file=file,
                        where="kind")
    return dict(
        nlp=nlp, settings=settings, model_spec=spec, guess_source=r.get("guess_source", str),
        stage=stage, tracking=tracking, dof_names=dofs, muscle_names=muscles,
        contact_forces=forces, contact_legs=contact_legs.astype(int),
        leg_names=(legs[0], legs[1]), body_mass_kg=r.number("body_mass_kg"),
        body_weight_N=r.number("body_weight_N"),
        metabolic_energy_J=r.number("metabolic_energy_J"),
        residual=r.get("consistency", dict),
        reference_phase=(None if data.get("reference_phase") is None
                         else r.number("reference_phase")),
        speed_floor_mps=(None if data.get("speed_floor_mps") is None
                         else r.number("speed_floor_mps")),
    )


def _read_multipliers(value, file) -> tuple[np.ndarray, np.ndarray] | None:
    """The optional ``multipliers`` field: ``{"bounds": [...], "constraints": [...]}``."""
    if value is None:
        return None
    if not isinstance(value, dict):
        raise DataError("expected an object or null", file=file, where="multipliers")
    r = FieldReader(value, file)
    try:
        return r.array("bounds", 1), r.array("constraints", 1)
    except DataError as err:
        raise DataError(err.message, file=file, where=f"multipliers.{err.where}",
                        hint=err.hint) from None


def _float(v) -> float:
    return math.nan if v is None else float(v)


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, float | np.floating):
        return _num(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    return obj

