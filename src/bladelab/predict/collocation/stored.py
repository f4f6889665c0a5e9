"""A stored solve: its model specification, its file's fields, reading it back and writing it.

The helpers around :class:`~bladelab.predict.collocation.solution.CollocationSolution`'s file
that ``bladelab predict --method collocation --resume`` and the speed continuation
(:mod:`bladelab.predict.collocation.continuation`) share:

- the model specification ``{"model": "able" | "amputee", "blade": name | None}``:
  :func:`check_model_spec`, :func:`model_label`, :func:`runner_from_spec`, and
  :func:`describe_problem` (model, speed and mesh of a problem, for messages);
- :class:`FieldReader`: a JSON object's fields, with errors naming the file and the field;
- :func:`read_stored` (the converged solution or best iterate of one problem, refusing a file
  of another problem) and :func:`write_solve` (write one, remove the stale other).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bladelab.errors import DataError, InputFileError, SpecError

if TYPE_CHECKING:
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.predict.collocation.solve import CollocationSettings

__all__ = [
    "FieldReader",
    "check_model_spec",
    "describe_problem",
    "model_label",
    "read_stored",
    "runner_from_spec",
    "write_solve",
]


def check_model_spec(spec) -> dict:
    """The model specification ``{"model": "able" | "amputee" | "transfemoral", "blade": name |
    None}``, plus
    ``"body"`` where it is not seed 001's (:data:`bladelab.runner.params.BODIES`) and
    ``"blade_spec"`` where the runner wears a multi-link blade (the blade file's contents, as
    :func:`bladelab.blade.spec.spec_from_dict` reads them; ``"blade"`` is then its name),
    checked and normalised (the able model has no blade; the amputee needs one; files written
    before the bodies existed have no ``"body"`` and mean seed 001's)."""
    if not isinstance(spec, dict) or "model" not in spec:
        raise SpecError(f"expected {{'model': ..., 'blade': ...}}, got {spec!r}",
                        where="model_spec")
    from bladelab.runner.params import BODIES, KINDS

    model = spec["model"]
    if model not in KINDS:
        raise SpecError(f"unknown model {model!r}", where="model", hint=" or ".join(KINDS))
    blade = spec.get("blade")
    if model == "able":
        blade = None
    elif not isinstance(blade, str) or not blade:
        raise SpecError(f"the {model} model needs a blade category", where="blade",
                        hint="e.g. Cat6")

    body = spec.get("body", "seed001")
    if body not in BODIES:
        raise SpecError(f"unknown body {body!r}", where="body", hint=" or ".join(BODIES))
    out = {"model": model, "blade": blade} | ({} if body == "seed001" else {"body": body})
    blade_spec = spec.get("blade_spec")
    if blade_spec is not None:
        if model == "able" or not isinstance(blade_spec, dict):
            raise SpecError("blade_spec must be a multi-link blade's specification (a mapping) "
                            "of an amputee model", where="blade_spec")
        out["blade_spec"] = blade_spec
    return out


def model_label(spec: dict) -> str:
    """``"able"``, ``"amputee <blade>"`` or ``"transfemoral <blade>"`` for a model
    specification."""
    spec = check_model_spec(spec)
    label = spec["model"] if spec["blade"] is None else f"{spec['model']} {spec['blade']}"
    return label + (f" ({spec['body']} body)" if "body" in spec else "")


def describe_problem(spec: dict, settings: CollocationSettings) -> str:
    """``"<model>, <speed>, <n> mesh intervals"`` of a problem (for messages)."""
    speed = ("maximum speed" if settings.speed_m_per_s is None
             else f"{settings.speed_m_per_s:g} m/s")
    return f"{model_label(spec)}, {speed}, {settings.mesh_intervals} mesh intervals"


def runner_from_spec(spec: dict):
    """Build the forward runner of a model specification (:func:`check_model_spec`)."""
    from bladelab.runner import build_runner

    spec = check_model_spec(spec)
    if "blade_spec" in spec:
        from bladelab.blade.spec import spec_from_dict

        blade = spec_from_dict(spec["blade_spec"]).build()
        return build_runner(spec["model"], blade_model=blade, body=spec.get("body", "seed001"))
    return build_runner(spec["model"], blade=spec["blade"], body=spec.get("body", "seed001"))


def read_stored(ok: Path, best: Path, spec: dict, settings: CollocationSettings):
    """(converged solution, best iterate) of one problem stored as ``ok`` / ``best`` (a
    solution file and a best-iterate file), each None if absent; the solution is preferred.

    Raises
    ------
    InputFileError
        A file holds another problem (model, mesh, speed or weights).
    """
    from bladelab.predict.collocation.solution import CollocationSolution

    for path in (Path(ok), Path(best)):
        if not path.is_file():
            continue
        sol = CollocationSolution.read(path)
        if sol.model_spec != check_model_spec(spec) or not sol.settings.same_problem(settings):
            there, asked = describe_problem(sol.model_spec, sol.settings), describe_problem(
                spec, settings)
            if there == asked:
                there, asked = (f"{there}, weights {sol.settings.weights.to_dict()}",
                                f"weights {settings.weights.to_dict()}")
            raise InputFileError(
                f"holds another problem ({there}; asked: {asked})", file=path,
                hint="resume with the same model, blade, speed and mesh, --force to start "
                     "over, or choose another --out")
        if path == Path(ok) and sol.converged:
            return sol, None
        return None, sol
    return None, None


def write_solve(sol: CollocationSolution, ok: Path, best: Path) -> Path:
    """Write a solve as ``ok`` (converged) or ``best`` (best iterate), then remove the other,
    now stale, file; returns the path written."""
    target, stale = (Path(ok), Path(best)) if sol.converged else (Path(best), Path(ok))
    sol.write(target)
    stale.unlink(missing_ok=True)
    return target


class FieldReader:
    """Field access to a JSON object (``data``, read from ``file``) with errors
    (:class:`~bladelab.errors.DataError`) that name the file and the field."""

    _KIND = {str: "a string", int: "an integer", bool: "true or false", dict: "an object",
             list: "a list"}

    def __init__(self, data: dict, file) -> None:
        self.data, self.file = data, file

    def get(self, key: str, typ: type):
        """The field ``key``, which must be of type ``typ`` (str, int, bool, dict or list)."""
        if key not in self.data:
            raise DataError("missing field", file=self.file, where=key)
        v = self.data[key]
        ok = isinstance(v, typ) and not (typ is int and isinstance(v, bool))
        if not ok:
            raise DataError(f"expected {self._KIND[typ]}, got {type(v).__name__}",
                            file=self.file, where=key)
        return v

    def number(self, key: str) -> float:
        """The number ``key`` as a float (null: NaN)."""
        if key not in self.data:
            raise DataError("missing field", file=self.file, where=key)
        v = self.data[key]
        if v is None:
            return math.nan
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise DataError(f"expected a number, got {type(v).__name__}", file=self.file,
                            where=key)
        return float(v)

    def names(self, key: str) -> list[str]:
        """The list of strings ``key``."""
        v = self.get(key, list)
        if not all(isinstance(x, str) for x in v):
            raise DataError("expected a list of names", file=self.file, where=key)
        return v

    def array(self, key: str, ndim: int, shape: tuple | None = None) -> np.ndarray:
        """The nested list ``key`` as a finite float array of ``ndim`` dimensions (and
        ``shape``, if given)."""
        v = self.get(key, list)
        try:
            a = np.array(v, dtype=float)
        except (TypeError, ValueError):
            raise DataError("expected numbers", file=self.file, where=key) from None
        if a.ndim != ndim or (shape is not None and a.shape != shape):
            want = shape if shape is not None else f"{ndim} dimensions"
            raise DataError(f"expected shape {want}, got {a.shape}", file=self.file, where=key)
        if not np.all(np.isfinite(a)):
            raise DataError("holds a missing or non-finite value", file=self.file, where=key)
        return a
