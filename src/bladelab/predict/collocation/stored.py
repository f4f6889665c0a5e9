"""A stored solve's model specification and its file's fields.

The helpers around :class:`~bladelab.predict.collocation.solution.CollocationSolution`'s file:

- the model specification ``{"model": "able" | "amputee", "blade": name | None}``:
  :func:`check_model_spec`, :func:`model_label`, :func:`runner_from_spec`, and
  :func:`describe_problem` (model, speed and mesh of a problem, for messages);
- :class:`FieldReader`: a JSON object's fields, with errors naming the file and the field.

Reading a stored solve back for a resume and writing one are
:func:`~bladelab.predict.collocation.output_folder.read_stored` and
:func:`~bladelab.predict.collocation.output_folder.write_solve`.
"""

from __future__ import annotations

import math

import numpy as np

from bladelab.blade.spec import spec_from_dict
from bladelab.errors import DataError, SpecError
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.runner.model import build_runner
from bladelab.runner.params import BODIES, KINDS, default_runner_params
from bladelab.runner.scaling import ATHLETE_FIELDS, athlete_params

__all__ = [
    "FieldReader",
    "athlete_label",
    "athlete_text",
    "check_athlete",
    "check_model_spec",
    "describe_problem",
    "model_label",
    "params_from_spec",
    "runner_from_spec",
    "same_model_spec",
]

#: Relative tolerance of :func:`same_model_spec` on numbers: a blade generated again on another
#: machine differs from its stored specification by an ulp or two (its libm's round-off).
SPEC_REL_TOL = 1e-9


def same_model_spec(a, b) -> bool:
    """True if two model specifications (:func:`check_model_spec`'s form, e.g. a stored
    solve's and a problem's) describe the same runner: equal keys and strings, numbers equal
    to :data:`SPEC_REL_TOL` relative (not to the last bit)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_model_spec(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(same_model_spec(x, y) for x, y in zip(a, b, strict=True))
    numbers = (int, float)
    if (isinstance(a, numbers) and isinstance(b, numbers)
            and not isinstance(a, bool) and not isinstance(b, bool)):
        return math.isclose(a, b, rel_tol=SPEC_REL_TOL, abs_tol=1e-300)
    return a == b


def check_model_spec(spec) -> dict:
    """The model specification ``{"model": "able" | "amputee" | "transfemoral", "blade": name |
    None}``, plus
    ``"body"`` where it is not seed 001's (:data:`bladelab.runner.params.BODIES`) and
    ``"blade_spec"`` where the runner wears a multi-link blade (the blade file's contents, as
    :func:`bladelab.blade.spec.spec_from_dict` reads them; ``"blade"`` is then its name), plus
    ``"athlete"`` where the runner is scaled to another athlete than the parameter set's
    (``{"body_mass_kg": kg, "height_m": m, "muscle_strength": factor,
    "max_shortening_velocity": l_opt/s, "residual_limb_length_m": m, "thigh_length_m": m,
    "shank_length_m": m, "prosthesis_extra_length_m": m}``, any of them;
    :func:`bladelab.runner.scaling.athlete_params`), checked and normalised (the able model has
    no blade; the amputee needs one; files written before the bodies existed have no
    ``"body"`` and mean seed 001's)."""
    if not isinstance(spec, dict) or "model" not in spec:
        raise SpecError(f"expected {{'model': ..., 'blade': ...}}, got {spec!r}",
                        where="model_spec")
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
    athlete = check_athlete(spec.get("athlete"))
    if athlete:
        out["athlete"] = athlete
    return out


def check_athlete(athlete) -> dict:
    """The athlete of a model specification: known fields, each a finite number > 0 (the
    prosthetic leg's extra length ≥ 0; an empty dict for None)."""
    if athlete is None:
        return {}
    if not isinstance(athlete, dict):
        raise SpecError(f"athlete must be a mapping, got {athlete!r}", where="athlete",
                        hint="e.g. {'body_mass_kg': 68, 'height_m': 1.75}")
    out = {}
    for name, value in athlete.items():
        if name not in ATHLETE_FIELDS:
            raise SpecError(f"unknown athlete field {name!r}", where="athlete",
                            hint=" or ".join(ATHLETE_FIELDS))
        if value is None:
            continue
        least = ">=" if name == "prosthesis_extra_length_m" else ">"
        if (isinstance(value, bool) or not isinstance(value, int | float)
                or not math.isfinite(value) or value < 0 or (least == ">" and value == 0)):
            raise SpecError(f"{name} must be a number {least} 0 [{ATHLETE_FIELDS[name]}], got "
                            f"{value!r}", where=f"athlete.{name}")
        out[name] = float(value)
    return out


def model_label(spec: dict) -> str:
    """``"able"``, ``"amputee <blade>"`` or ``"transfemoral <blade>"`` for a model
    specification, with its body and athlete where they are not the defaults (e.g.
    ``"amputee Cat6 (human body; 68 kg, 1.75 m, muscle strength ×1.5)"``)."""
    spec = check_model_spec(spec)
    label = spec["model"] if spec["blade"] is None else f"{spec['model']} {spec['blade']}"
    notes = [f"{spec['body']} body"] if "body" in spec else []
    notes += [athlete_label(spec)] if "athlete" in spec else []
    return label + (f" ({'; '.join(notes)})" if notes else "")


def athlete_label(spec: dict) -> str:
    """The athlete of a model specification where it is not the parameter set's, e.g.
    ``"68 kg, 1.75 m, muscle strength ×1.5"`` (empty for the parameter set's own)."""
    return athlete_text(check_model_spec(spec).get("athlete", {}))


def athlete_text(athlete: dict) -> str:
    """An athlete's fields (:func:`check_athlete`) in words, e.g. ``"68 kg, 1.75 m, muscle
    strength ×1.5"`` (empty for none)."""
    parts = [f"{athlete['body_mass_kg']:g} kg"] if "body_mass_kg" in athlete else []
    parts += [f"{athlete['height_m']:g} m"] if "height_m" in athlete else []
    parts += ([f"muscle strength ×{athlete['muscle_strength']:g}"]
              if "muscle_strength" in athlete else [])
    parts += ([f"fibres' maximum velocity {athlete['max_shortening_velocity']:g} l_opt/s"]
              if "max_shortening_velocity" in athlete else [])
    parts += ([f"residual limb {athlete['residual_limb_length_m']:g} m"]
              if "residual_limb_length_m" in athlete else [])
    parts += [f"{name} {athlete[f'{name}_length_m']:.3g} m" for name in ("thigh", "shank")
              if f"{name}_length_m" in athlete]
    parts += ([f"prosthetic leg {100 * athlete['prosthesis_extra_length_m']:.3g} cm longer"]
              if "prosthesis_extra_length_m" in athlete else [])
    return ", ".join(parts)


def describe_problem(spec: dict, settings: CollocationSettings) -> str:
    """``"<model>, <speed>, <n> mesh intervals"`` of a problem (for messages)."""
    speed = ("maximum speed" if settings.speed_m_per_s is None
             else f"{settings.speed_m_per_s:g} m/s")
    return f"{model_label(spec)}, {speed}, {settings.mesh_intervals} mesh intervals"


def params_from_spec(spec: dict):
    """The runner parameter set of a model specification (:func:`check_model_spec`), scaled
    to its athlete; a bad athlete field raises its :class:`~bladelab.errors.SpecError`
    (``where`` ``"athlete.<field>"`` or the field's)."""
    spec = check_model_spec(spec)
    params = default_runner_params(spec["model"], body=spec.get("body", "seed001"),
                                   blade=None if "blade_spec" in spec else spec["blade"])
    return athlete_params(params, **spec["athlete"]) if "athlete" in spec else params


def runner_from_spec(spec: dict):
    """Build the forward runner of a model specification (:func:`check_model_spec`)."""
    spec = check_model_spec(spec)
    blade_model = (spec_from_dict(spec["blade_spec"]).build() if "blade_spec" in spec
                   else None)
    return build_runner(params_from_spec(spec), blade_model=blade_model)


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
