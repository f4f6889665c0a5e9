"""Motion adaptation input: a *motion file* of gait cycles, each with the blade it was run with.

Seed 002 measured its runner with 9 blades (4 trials each) and fitted the period and the
time-normalised joint angles as second-order response surfaces of the design factors, so that a
new design gets a predicted motion. Here the cycles and their blades come from a motion file
(YAML or CSV), :func:`load_motion_model` fits
:func:`~bladelab.design.motion_model.fit_motion_model` to them and
:class:`~bladelab.design.transfemoral.RunnerEvaluator` (``motion=``) predicts each design's
cycle from it.

Motion file
-----------
One entry (row) per gait cycle. Keys (YAML) or columns (CSV):

- every design factor, by the design space's name and in its unit (e.g.
  ``stiffness_kN_per_m``, ``width_m``, ``height_m``, ``toe_length_m``): the blade the cycle was
  run with; a blade outside the design space's ranges is allowed (it is coded beyond ±1);
- ``gait``: a gait-cycle CSV (:func:`~bladelab.design.gait_cycle.read_gait_csv`), **or**
  ``trial``: a C3D trial with markers and force platforms whose mean cycle
  :func:`~bladelab.design.gait_cycle.gait_cycle_from_trial` extracts, with optional ``leg``
  (``right``/``left``: the prosthetic side, default ``right``), ``static`` (standing C3D
  trial), ``markers`` (YAML joint marker map), ``cutoff_hz`` (marker low-pass, default 20; 0:
  none), ``forward`` / ``up`` (file axes, default ``auto``);
- ``label`` (optional): a name for the blade.

Paths are relative to the motion file. Several entries may share a blade (trials repeated with
one blade). A YAML file is either a list of entries or a mapping with ``cycles:`` (the list) and
optionally ``model:`` (``auto`` — the default —, ``quadratic``, ``linear``, ``interaction``,
``pure_quadratic`` or a term list such as ``"stiffness_kN_per_m,width_m,stiffness_kN_per_m^2"``).
In a CSV an empty cell is an absent key. Any error names the file, the row (entry, from 1) and
the field.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from bladelab._io import read_yaml
from bladelab.design.gait_cycle import gait_cycle_from_trial, read_gait_csv
from bladelab.design.motion_model import MotionModel, fit_motion_model
from bladelab.errors import BladelabError, InputFileError, SpecError
from bladelab.trial import read_c3d
from bladelab.trial.joint_angles import load_joint_marker_map

__all__ = [
    "MOTION_KEYS",
    "MotionEntry",
    "MotionFile",
    "as_motion_model",
    "check_motion_factors",
    "load_motion_cycles",
    "load_motion_model",
    "read_motion_file",
]

#: Keys of a motion-file entry that are not design factors.
MOTION_KEYS: tuple[str, ...] = ("label", "gait", "trial", "leg", "static", "markers",
                                "cutoff_hz", "forward", "up")
_TRIAL_ONLY = ("leg", "static", "markers", "cutoff_hz", "forward", "up")
_TOP_KEYS = ("cycles", "model")


@dataclass(frozen=True)
class MotionEntry:
    """One gait cycle of a motion file.

    Attributes
    ----------
    row
        Entry number in the file (from 1).
    factors
        Factor name -> value in its unit: the blade of the cycle.
    gait, trial
        Gait-cycle CSV or C3D trial (exactly one is set), resolved against the motion file.
    leg, static, markers, cutoff_hz, forward, up
        Options of the trial extraction.
    label
        Name of the blade, if given.
    """

    row: int
    factors: Mapping[str, float]
    gait: Path | None = None
    trial: Path | None = None
    leg: str = "right"
    static: Path | None = None
    markers: Path | None = None
    cutoff_hz: float | None = 20.0
    forward: str = "auto"
    up: str = "auto"
    label: str = ""

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"row": self.row, "label": self.label, **dict(self.factors)}
        if self.gait is not None:
            d["gait"] = str(self.gait)
        else:
            d.update(trial=str(self.trial), leg=self.leg,
                     static=None if self.static is None else str(self.static),
                     markers=None if self.markers is None else str(self.markers),
                     cutoff_hz=self.cutoff_hz)
        return d


@dataclass(frozen=True)
class MotionFile:
    """A parsed motion file.

    Attributes
    ----------
    path
        The file.
    entries
        Its cycles.
    factor_names
        The design factors, in the design space's order (or the file's order without a space).
    model
        The ``model:`` key of a YAML file, or ``None``.
    """

    path: Path
    entries: tuple[MotionEntry, ...]
    factor_names: tuple[str, ...]
    model: str | None = None

    def values(self) -> np.ndarray:
        """Factor values of each entry (n_entries × n_factors), in the factors' units."""
        return np.array([[e.factors[n] for n in self.factor_names] for e in self.entries])

    def to_dict(self) -> dict:
        return {"path": str(self.path), "factors": list(self.factor_names), "model": self.model,
                "entries": [e.to_dict() for e in self.entries]}


def _raw_rows(path: Path) -> tuple[list[Any], str | None]:
    """The file's entries as mappings of raw values, and the YAML ``model:`` key."""
    suffix = path.suffix.lower()
    if suffix == ".csv":
        try:
            df = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
        except (OSError, ValueError) as err:
            raise InputFileError(f"cannot read the motion file: {err}", file=path) from None
        rows = [{str(k).strip(): v.strip() for k, v in rec.items() if str(v).strip() != ""}
                for rec in df.to_dict(orient="records")]
        return rows, None
    if suffix not in (".yaml", ".yml"):
        raise InputFileError("a motion file is YAML (.yaml, .yml) or CSV (.csv)", file=path,
                             hint="docs/design.md, 'Motion adaptation'")
    data = read_yaml(path, what="motion file", hint="docs/design.md, 'Motion adaptation'")
    model = None
    if isinstance(data, Mapping):
        unknown = [str(k) for k in data if k not in _TOP_KEYS]
        if unknown:
            raise SpecError(f"unknown key(s) {unknown}", file=path,
                            hint=f"a motion file has {list(_TOP_KEYS)} (or is a list of cycles)")
        model = data.get("model")
        if model is not None and not isinstance(model, str):
            raise SpecError(f"model must be text, got {model!r}", file=path, where="model",
                            hint="auto, quadratic, linear, or a comma-separated term list")
        data = data.get("cycles")
    if not isinstance(data, list):
        raise SpecError("no list of cycles", file=path,
                        hint="write 'cycles:' followed by one entry per gait cycle")
    return data, model


def _number(value: Any, file: Path, where: str) -> float:
    if isinstance(value, bool):
        raise SpecError(f"{value!r} is not a number", file=file, where=where)
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise SpecError(f"{value!r} is not a number", file=file, where=where) from None
    if not math.isfinite(v):
        raise SpecError(f"{value!r} is not a finite number", file=file, where=where)
    return v


def _file(value: Any, base: Path, file: Path, where: str) -> Path:
    if not isinstance(value, str) or not value.strip():
        raise SpecError(f"{value!r} is not a path", file=file, where=where)
    p = Path(value.strip())
    p = p if p.is_absolute() else base / p
    if not p.is_file():
        raise InputFileError(f"no such file {value!r} (looked for {p})", file=file, where=where,
                             hint="paths are relative to the motion file")
    return p


def read_motion_file(path: str | Path, *, space=None) -> MotionFile:
    """Read and check a motion file (see the module notes) without loading the cycles.

    Parameters
    ----------
    path
        YAML or CSV motion file.
    space
        The study's :class:`~bladelab.design.space.DesignSpace`: every entry must give exactly its
        factors. Without it the factors are the entries' non-reserved keys (every entry must give
        them all).

    Raises
    ------
    InputFileError
        The file, or a file it names, is missing or unreadable.
    SpecError
        A missing or unknown factor, a bad value, both or neither of ``gait``/``trial``; the
        message names the file, the row and the field.
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError("no such motion file", file=path,
                             hint="a YAML or CSV list of gait cycles with their blades "
                                  "(docs/design.md, 'Motion adaptation')")
    raw, model = _raw_rows(path)
    if not raw:
        raise SpecError("the motion file lists no cycles", file=path)
    base = path.parent
    for i, rec in enumerate(raw, start=1):
        if not isinstance(rec, Mapping):
            raise SpecError(f"an entry must be a mapping of keys to values, got {rec!r}",
                            file=path, where=f"row {i}")
    if space is not None:
        names = tuple(space.names)
        units = {f.name: f.unit for f in space.factors}
    else:
        seen: dict[str, None] = {}
        for rec in raw:
            for k in rec:
                if k not in MOTION_KEYS:
                    seen.setdefault(str(k), None)
        names, units = tuple(seen), {}
    if not names:
        raise SpecError("no design factors in the motion file", file=path,
                        hint="give each cycle's blade as factor values, e.g. "
                             "stiffness_kN_per_m: 25")
    entries = []
    for i, rec in enumerate(raw, start=1):
        row = f"row {i}"
        unknown = [str(k) for k in rec if k not in MOTION_KEYS and k not in names]
        if unknown:
            raise SpecError(f"unknown factor {unknown[0]!r}", file=path,
                            where=f"{row}, {unknown[0]}",
                            hint=f"the design factors are {list(names)}; other keys: "
                                 f"{list(MOTION_KEYS)}")
        factors = {}
        for n in names:
            if n not in rec:
                unit = f" [{units[n]}]" if units.get(n) else ""
                raise SpecError(f"missing factor {n!r}", file=path, where=f"{row}, {n}",
                                hint=f"give the value{unit} of {n} of the blade this cycle was "
                                     "run with")
            factors[n] = _number(rec[n], path, f"{row}, {n}")
        has_gait, has_trial = "gait" in rec, "trial" in rec
        if has_gait == has_trial:
            raise SpecError("give either 'gait' (a gait-cycle CSV) or 'trial' (a C3D trial)"
                            + (", not both" if has_gait else ""), file=path,
                            where=f"{row}, {'gait/trial'}")
        label = str(rec.get("label", ""))
        if has_gait:
            extra = [k for k in _TRIAL_ONLY if k in rec]
            if extra:
                raise SpecError(f"{extra[0]!r} applies to a 'trial' entry only", file=path,
                                where=f"{row}, {extra[0]}")
            entries.append(MotionEntry(i, factors, gait=_file(rec["gait"], base, path,
                                                               f"{row}, gait"), label=label))
            continue
        leg = str(rec.get("leg", "right")).strip()
        if leg not in ("left", "right"):
            raise SpecError(f"leg must be 'left' or 'right', got {leg!r}", file=path,
                            where=f"{row}, leg")
        cutoff = _number(rec.get("cutoff_hz", 20.0), path, f"{row}, cutoff_hz")
        if cutoff < 0:
            raise SpecError(f"cutoff_hz must be >= 0, got {cutoff}", file=path,
                            where=f"{row}, cutoff_hz")
        entries.append(MotionEntry(
            i, factors, trial=_file(rec["trial"], base, path, f"{row}, trial"), leg=leg,
            static=(None if "static" not in rec
                    else _file(rec["static"], base, path, f"{row}, static")),
            markers=(None if "markers" not in rec
                     else _file(rec["markers"], base, path, f"{row}, markers")),
            cutoff_hz=cutoff if cutoff > 0 else None,
            forward=str(rec.get("forward", "auto")), up=str(rec.get("up", "auto")),
            label=label))
    return MotionFile(path, tuple(entries), names, model)


def _with_row(err: BladelabError, motion: MotionFile, row: int) -> BladelabError:
    where = f"motion file {motion.path} row {row}" + (f", {err.where}" if err.where else "")
    return type(err)(err.message, file=err.file or motion.path, where=where, hint=err.hint)


def load_motion_cycles(motion: MotionFile, *, n: int = 100, progress: bool = False) -> list:
    """The gait cycle of every entry (:class:`~bladelab.design.gait_cycle.GaitCycle`).

    ``gait`` entries are read; ``trial`` entries give their mean cycle of ``n`` samples (a C3D
    file named by several entries is read once). Each cycle's ``source`` starts with its row.
    """
    trials: dict = {}

    def c3d(p: Path, forward: str, up: str):
        key = (p, forward, up)
        if key not in trials:
            trials[key] = read_c3d(p, forward=forward, up=up)
        return trials[key]

    cycles = []
    for e in tqdm(motion.entries, desc="motion cycles", unit="cycle", disable=not progress):
        try:
            if e.gait is not None:
                c = read_gait_csv(e.gait)
            else:
                tr = c3d(e.trial, e.forward, e.up)
                ax = tr.metadata.get("axes", {})
                st = (None if e.static is None else
                      c3d(e.static, ax.get("forward", e.forward), ax.get("up", e.up)))
                mm = None if e.markers is None else load_joint_marker_map(e.markers)
                c = gait_cycle_from_trial(tr, leg=e.leg, markers=mm, static=st,
                                          cutoff_hz=e.cutoff_hz, n=n)
        except BladelabError as err:
            raise _with_row(err, motion, e.row) from None
        name = f" ({e.label})" if e.label else ""
        cycles.append(replace(c, source=f"row {e.row}{name}: {c.source}"))
    return cycles


def load_motion_model(
    path: str | Path,
    *,
    space=None,
    model: str | Sequence | None = None,
    n_nodes: int = 51,
    progress: bool = False,
):
    """Read a motion file, load its cycles and fit seed 002's motion model.

    Parameters
    ----------
    path
        YAML or CSV motion file.
    space
        The study's design space: its factors must be exactly the file's, and it sets the coding
        (c = (x − mid)/half_range, seed 002's [−1, 1] over the design domain). Without it the
        coding spans the cycles' own blades.
    model
        Motion model (overrides the file's ``model:``; default ``"auto"``: the full quadratic
        if the cycles can estimate it with a residual degree of freedom left, else the linear
        model; refused if neither).
    n_nodes
        Normalised times of the angle surfaces.
    progress
        Progress bar over the cycles.

    Returns
    -------
    MotionModel
        With its coding, so that ``predict_point({factor: value})`` works; ``to_dict()`` gives
        the model, its terms and the leave-one-blade-out errors (period [s], angles [deg]).
    """
    motion = read_motion_file(path, space=space)
    cycles = load_motion_cycles(motion, progress=progress)
    x = motion.values()
    if space is not None:
        centre = np.array([f.mid for f in space.factors])
        half = np.array([f.half_range for f in space.factors])
    else:
        lo, hi = x.min(axis=0), x.max(axis=0)
        centre = 0.5 * (lo + hi)
        half = np.where(hi > lo, 0.5 * (hi - lo), 1.0)
    chosen = model if model is not None else (motion.model or "auto")
    try:
        return fit_motion_model((x - centre) / half, cycles, factor_names=motion.factor_names,
                                model=chosen, n_nodes=n_nodes, centre=centre, half_range=half)
    except BladelabError as err:
        raise type(err)(err.message, file=motion.path, where=err.where, hint=err.hint) from None


def check_motion_factors(motion, names: Sequence[str]) -> None:
    """Refuse a motion model whose factors are not exactly the design factors ``names``.

    Raises
    ------
    SpecError
        Naming the missing (design factor not in the motion model) or unknown factors.
    """
    have = list(motion.factor_names)
    missing = [n for n in names if n not in have]
    unknown = [n for n in have if n not in names]
    if missing:
        raise SpecError(f"missing factor(s) {missing} in the motion model", where="motion",
                        hint="every design factor must be given for each motion cycle")
    if unknown:
        raise SpecError(f"unknown factor(s) {unknown} in the motion model", where="motion",
                        hint=f"the design factors are {list(names)}")


def as_motion_model(motion):
    """A :class:`~bladelab.design.motion_model.MotionModel` as it is, or one fitted from a motion
    file path (:func:`load_motion_model`, coded over the cycles' own blades)."""
    if isinstance(motion, MotionModel):
        return motion
    if isinstance(motion, (str, Path)):
        return load_motion_model(motion)
    raise SpecError(f"motion must be a MotionModel or a motion file, got "
                    f"{type(motion).__name__}", where="motion")
