"""The ``study.yaml`` model: athletes, blades and categories, configurations, trials.

See ``docs/study-yaml.md``. Loading validates the whole file with pydantic and reports every problem
with its field path (``trials[3].athlete: ...``). Trial files are *not* required to exist at load
time: a missing file is reported when the study runs, and the other trials still run.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from bladelab._io import read_yaml
from bladelab.errors import InputFileError, SpecError

STUDY_FILE = "study.yaml"
RESULTS_FILE = "results.sqlite"


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Athlete(_Model):
    """An athlete: ``id``, ``mass_kg``, ``amputation`` level, optional ``height_m``, ``side``."""

    id: str = Field(min_length=1)
    mass_kg: float = Field(gt=20, lt=250)
    amputation: Literal["transtibial", "transfemoral", "knee_disarticulation", "bilateral_transtibial",
                        "bilateral_transfemoral", "other"]
    height_m: float | None = Field(default=None, gt=0.8, lt=2.5)
    side: Literal["left", "right", "both"] | None = None


class BladeEntry(_Model):
    """A blade used in the study: ``id``, ``blade`` (built-in name or spec file), ``category``."""

    id: str = Field(min_length=1)
    blade: str = Field(min_length=1, description="built-in blade name or path to a blade spec YAML")
    category: int | str | None = None


class Configuration(_Model):
    """A prosthetic configuration, e.g. a pylon height [m]."""

    id: str = Field(min_length=1)
    pylon_height_m: float | None = Field(default=None, gt=0, lt=2)
    description: str | None = None


class Trial(_Model):
    """One trial: its stance file and what it belongs to."""

    id: str = Field(min_length=1)
    file: str = Field(min_length=1, description="stance CSV, relative to the study folder")
    athlete: str
    blade: str
    configuration: str | None = None
    speed_pct_pb: float | None = Field(default=None, gt=0, le=120,
                                       description="running speed as % of personal best")
    stance: int = Field(default=1, ge=1, description="which stance of the file to use (1-based)")

    @field_validator("id")
    @classmethod
    def _id_chars(cls, v: str) -> str:
        if any(c in v for c in "/\\\n"):
            raise ValueError("must not contain '/', '\\' or newlines")
        return v


class IdentificationSettings(_Model):
    """Default identification settings for every trial (the CLI may override them)."""

    optimizer: Literal["pso", "cmaes"] = "pso"
    max_evals: int = Field(default=600, ge=10)
    polish: bool | None = None  # None: on for the nonlinear spring, off for the linear one
    weights: tuple[float, float] = (0.5, 0.5)
    grf_components: tuple[Literal["z", "x"], ...] = ("z",)
    nonlinear: bool = False
    joint: int | None = None
    identifiability: bool = True
    # how the stance drives the model (bladelab.identify.formulations); "seed" = seed 000 exactly
    formulation: Literal["utilised-friction", "seed", "grf-driven"] = "utilised-friction"


class Study(_Model):
    """A whole study (``study.yaml``)."""

    name: str = Field(min_length=1)
    seed: int = Field(default=0, ge=0)
    athletes: tuple[Athlete, ...] = Field(min_length=1)
    blades: tuple[BladeEntry, ...] = Field(min_length=1)
    configurations: tuple[Configuration, ...] = ()
    trials: tuple[Trial, ...] = Field(min_length=1)
    identification: IdentificationSettings = IdentificationSettings()

    @model_validator(mode="after")
    def _references(self) -> Study:
        problems: list[str] = []
        for field in ("athletes", "blades", "configurations", "trials"):
            seen: set[str] = set()
            for i, item in enumerate(getattr(self, field)):
                if item.id in seen:
                    problems.append(f"{field}[{i}].id: duplicate id {item.id!r}")
                seen.add(item.id)
        names = {f: [x.id for x in getattr(self, f)] for f in ("athletes", "blades", "configurations")}
        for i, trial in enumerate(self.trials):
            for attr, field in (("athlete", "athletes"), ("blade", "blades"),
                                ("configuration", "configurations")):
                ref = getattr(trial, attr)
                if ref is not None and ref not in names[field]:
                    known = ", ".join(names[field]) or "none defined"
                    problems.append(f"trials[{i}].{attr}: {ref!r} is not one of the {field} ({known})")
        if problems:
            raise ValueError("; ".join(problems))
        return self

    def athlete(self, athlete_id: str) -> Athlete:
        """The athlete with this id."""
        return next(a for a in self.athletes if a.id == athlete_id)

    def blade(self, blade_id: str) -> BladeEntry:
        """The blade entry with this id."""
        return next(b for b in self.blades if b.id == blade_id)


def _loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out or "study"


def parse_study(data: dict, *, file: str | Path | None = None) -> Study:
    """Validate a study dictionary.

    Raises
    ------
    SpecError
        With the field path(s) of every problem.
    """
    if not isinstance(data, dict):
        raise SpecError("the study file must be a YAML mapping", file=file)
    try:
        return Study.model_validate(data)
    except ValidationError as err:
        msgs = []
        for e in err.errors():
            loc = _loc(tuple(p for p in e["loc"] if p not in ("function-after[_references(), Study]",)))
            msg = e["msg"].removeprefix("Value error, ")
            msgs.append(msg if loc == "study" and ":" in msg else f"{loc}: {msg}")
        raise SpecError("; ".join(msgs), file=file,
                        hint="see docs/study-yaml.md for the study.yaml format") from None


def load_study(path: str | Path) -> tuple[Study, Path]:
    """Load ``study.yaml`` from a study folder (or the file itself); return (study, folder).

    Raises
    ------
    InputFileError
        The folder or file does not exist or is not YAML.
    SpecError
        The content is invalid (field paths in the message).
    """
    p = Path(path)
    file = p / STUDY_FILE if p.is_dir() else p
    if not file.is_file():
        raise InputFileError(f"no {STUDY_FILE} found", file=file,
                             hint="a study folder holds study.yaml, the trial files and results.sqlite")
    data = read_yaml(file, what=STUDY_FILE)
    return parse_study(data, file=file), file.parent
