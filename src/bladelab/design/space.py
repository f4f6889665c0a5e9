"""Design factors coded to [-1, 1] over user ranges.

A :class:`Factor` is a named design variable with a range ``[low, high]`` in its own unit (for
example the blade's target vertical stiffness in kN/m). Response surfaces, designs of experiments
and the optimum all work in *coded* units, ``c = (x - mid) / half_range``, so that ``low -> -1``
and ``high -> +1`` (seed 002, figures 6 and 7: "interval of [-1, 1] represents minimum and maximum
values in the design domain").
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from bladelab.design import defaults
from bladelab.errors import SpecError

__all__ = ["Factor", "DesignSpace", "default_design_space", "CODED_TOLERANCE"]

#: How far outside [-1, 1] a coded value may lie before it is refused (rounding of user values).
CODED_TOLERANCE = 1e-6

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class Factor:
    """One design factor.

    Parameters
    ----------
    name
        Identifier (letters, digits, ``_``; starts with a letter), e.g. ``"stiffness_kN_per_m"``.
        Evaluators receive design points as ``{name: value}`` in the factor's unit.
    low, high
        The range in the factor's unit; coded -1 and +1.
    unit
        The unit of ``low``/``high`` for labels (``"kN/m"``, ``"m"``); free text.
    label
        A human-readable name for plots; defaults to ``name``.
    """

    name: str
    low: float
    high: float
    unit: str = ""
    label: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _NAME.match(self.name):
            raise SpecError(
                f"invalid factor name {self.name!r}",
                where="factors",
                hint="use letters, digits and '_', starting with a letter (e.g. width_m)",
            )
        for key in ("low", "high"):
            value = getattr(self, key)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise SpecError(
                    f"{key} = {value!r} is not a number", where=f"factor {self.name}"
                ) from None
            if not math.isfinite(value):
                raise SpecError(f"{key} = {value} is not finite", where=f"factor {self.name}")
            object.__setattr__(self, key, value)
        if not self.low < self.high:
            raise SpecError(
                f"low ({self.low:g}) must be smaller than high ({self.high:g})",
                where=f"factor {self.name}",
                hint="give the range as low:high",
            )
        if not self.label:
            object.__setattr__(self, "label", self.name)

    @property
    def mid(self) -> float:
        """Centre of the range (coded 0)."""
        return 0.5 * (self.low + self.high)

    @property
    def half_range(self) -> float:
        """Half the range (one coded unit in the factor's unit)."""
        return 0.5 * (self.high - self.low)

    @property
    def axis_label(self) -> str:
        """``"label [unit]"`` for plot axes."""
        return f"{self.label} [{self.unit}]" if self.unit else self.label

    @classmethod
    def parse(cls, text: str) -> Factor:
        """Parse ``"name=low:high"`` or ``"name=low:high unit"`` (e.g. ``"stiffness=18:32 kN/m"``)."""
        match = re.match(r"^\s*([^=\s]+)\s*=\s*([^:\s]+)\s*:\s*(\S+)\s*(.*?)\s*$", str(text))
        if not match:
            raise SpecError(
                f"cannot read factor {text!r}",
                where="factors",
                hint="write name=low:high or name=low:high unit, e.g. width_m=0.05:0.08",
            )
        name, low, high, unit = match.groups()
        try:
            low_f, high_f = float(low), float(high)
        except ValueError:
            raise SpecError(
                f"cannot read the range of {text!r}",
                where=f"factor {name}",
                hint="low and high must be numbers, e.g. width_m=0.05:0.08",
            ) from None
        return cls(name, low_f, high_f, unit)

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "low": self.low,
            "high": self.high,
            "unit": self.unit,
            "label": self.label,
        }


@dataclass(frozen=True)
class DesignSpace:
    """An ordered set of factors; codes and decodes design points.

    Arrays of design points have shape ``(n_runs, n_factors)`` with columns in factor order.
    """

    factors: tuple[Factor, ...]

    def __post_init__(self) -> None:
        factors = tuple(self.factors)
        if not factors:
            raise SpecError("a design space needs at least one factor", where="factors")
        for f in factors:
            if not isinstance(f, Factor):
                raise SpecError(f"{f!r} is not a Factor", where="factors")
        names = [f.name for f in factors]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise SpecError(f"duplicate factor names {dup}", where="factors")
        object.__setattr__(self, "factors", factors)

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def parse(cls, specs: Iterable[str] | str) -> DesignSpace:
        """Build from ``"name=low:high[ unit]"`` strings (a list, or one comma-separated string)."""
        if isinstance(specs, str):
            specs = [s for s in specs.split(",") if s.strip()]
        return cls(tuple(Factor.parse(s) for s in specs))

    @classmethod
    def from_dict(cls, data: Mapping | Sequence) -> DesignSpace:
        """Build from ``[{name, low, high, unit?, label?}, ...]`` or ``{"factors": [...]}``."""
        items = data.get("factors") if isinstance(data, Mapping) else data
        if not isinstance(items, Sequence):
            raise SpecError("expected a list of factors", where="factors")
        factors = []
        for i, item in enumerate(items):
            if not isinstance(item, Mapping) or not {"name", "low", "high"} <= set(item):
                raise SpecError(
                    f"factor #{i} must have name, low and high", where="factors"
                )
            factors.append(
                Factor(
                    item["name"], item["low"], item["high"], item.get("unit", ""),
                    item.get("label", ""),
                )
            )
        return cls(tuple(factors))

    # -- properties ---------------------------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.factors)

    @property
    def n_factors(self) -> int:
        return len(self.factors)

    def __len__(self) -> int:
        return len(self.factors)

    def factor(self, name: str) -> Factor:
        """The factor called ``name``."""
        for f in self.factors:
            if f.name == name:
                return f
        raise SpecError(
            f"no factor named {name!r}", where="factors", hint=f"known factors: {list(self.names)}"
        )

    def index(self, name: str) -> int:
        """Column index of factor ``name``."""
        return self.names.index(self.factor(name).name)

    # -- coding -------------------------------------------------------------------------------
    def _as_2d(self, values: np.ndarray | Sequence, what: str) -> tuple[np.ndarray, bool]:
        arr = np.asarray(values, dtype=float)
        single = arr.ndim == 1
        arr = np.atleast_2d(arr)
        if arr.ndim != 2 or arr.shape[1] != self.n_factors:
            raise SpecError(
                f"{what} must have {self.n_factors} columns ({', '.join(self.names)}), "
                f"got shape {np.shape(values)}",
                where="design points",
            )
        if not np.all(np.isfinite(arr)):
            raise SpecError(f"{what} contain non-finite values", where="design points")
        return arr, single

    def code(self, values: np.ndarray | Sequence, *, check: bool = True) -> np.ndarray:
        """User units -> coded units (``low -> -1``, ``high -> +1``).

        Raises :class:`SpecError` naming the factor if a value lies outside its range
        (``check=False`` allows extrapolation).
        """
        arr, single = self._as_2d(values, "design points")
        mid = np.array([f.mid for f in self.factors])
        half = np.array([f.half_range for f in self.factors])
        coded = (arr - mid) / half
        if check:
            self.check_coded(coded, what="design points")
        return coded[0] if single else coded

    def decode(self, coded: np.ndarray | Sequence, *, check: bool = True) -> np.ndarray:
        """Coded units -> user units."""
        arr, single = self._as_2d(coded, "coded design points")
        if check:
            self.check_coded(arr, what="coded design points")
        mid = np.array([f.mid for f in self.factors])
        half = np.array([f.half_range for f in self.factors])
        out = mid + arr * half
        return out[0] if single else out

    def check_coded(self, coded: np.ndarray, *, what: str = "design points") -> None:
        """Raise :class:`SpecError` if any coded value lies outside [-1, 1]."""
        coded = np.atleast_2d(np.asarray(coded, dtype=float))
        bad = np.argwhere(np.abs(coded) > 1.0 + CODED_TOLERANCE)
        if bad.size:
            run, col = (int(v) for v in bad[0])
            f = self.factors[col]
            value = f.mid + coded[run, col] * f.half_range
            raise SpecError(
                f"run {run + 1} of the {what}: {f.name} = {value:g} {f.unit} lies outside the "
                f"range {f.low:g}..{f.high:g}",
                where=f"factor {f.name}",
                hint="widen the factor's range or correct the run",
            )

    def point(self, coded: np.ndarray | Sequence) -> dict[str, float]:
        """One coded point -> ``{name: value in the factor's unit}`` (what evaluators receive)."""
        values = self.decode(np.asarray(coded, dtype=float).reshape(-1))
        return {f.name: float(v) for f, v in zip(self.factors, values, strict=True)}

    def to_dict(self) -> dict:
        return {"factors": [f.to_dict() for f in self.factors]}


def default_design_space() -> DesignSpace:
    """The four factors of seed 002 with illustrative ranges.

    Vertical stiffness target 18-32 kN/m (seed 000 §3.5: peak K_c of category 2-5 blades), width
    0.05-0.08 m, build height 0.40-0.48 m and toe length 0.19-0.25 m (around the built-in
    ``xtreme`` blade, the blade generator's default base). Replace them with the ranges of the
    blades you can build.
    """
    return DesignSpace(tuple(Factor(*f) for f in defaults.DESIGN_FACTORS))
