"""Staged optimisation of one blade category and seed: a recipe of CMA-ES stages.

One stage of seed 001's objective from SCONE's parameters does not find a running gait at
4 m/s, and a gait found without perturbations is a slow fall (docs/predictive.md, "Warm start
from a collocation stride"). What found stable gaits for Cat6 is a sequence of stages, each
warm-started from the one before (:data:`STABLE_GAIT_RECIPE`):

1. ``track``: seed 001's objective plus a term pulling the gait towards the collocation stride
   of the same runner, blade and speed (``--track``), 4 s;
2. ``stable``: seed 001's objective over twice the acceptance's 10 s, with copies that break
   the floating-point path (new every generation); in these two the reflexes on the forward
   speed stay off (held at gain 0);
3. ``basin``: 15 s with the copies pushed by ±2 % of their forward speed in mid-run, and the
   mean-speed reflexes acting from the start (``run_up``);
4. ``start``, ``start5``: copies that also start at ±3 %, then ±5 % of the initial speed;
5. ``clear``: and the swinging blade's strikes and the trunk's lean in the objective
   (``strike_limit_bw`` 0.5, ``w_lean`` 2), the stable-gait acceptance's last two criteria.

Then the speed is raised by **continuation on the speed reached** (not a fixed
grid): the recipe's ``continuation`` stage runs at the speed the last level reached plus
``speed_step`` [m/s], from that level's gait and starting at that speed, until a level does not
settle in the time step (falls in its nominal 10 s, at the recipe's step, at half or at a
quarter of it) or its settled speed gains less than ``min_gain`` [m/s]. A level's **settled
speed** (:func:`settled_speed`) is its mean speed at a quarter of the step: at Newmark's 1 ms
the gaits run 0.09–0.25 m/s faster than at finer steps (docs/predictive.md). The
prescription follows the speed at the recipe's own step, the one the optimiser mostly sees.
The maximum speed is the fastest settled speed of a level that settles.

Output of one task (:func:`run_recipe`), ``OUT/<category>/seed-<n>/``: ``recipe.json`` (the
recipe, the task and its warm start: running again with another is an error), one folder per
level (``1-track``, ..., ``speed-4.25``; each an :func:`optimize_controller` run folder) and
``levels.json``, one row per finished level (its 10 s re-simulation, :func:`level_row`),
rewritten atomically after each. Running the same task again continues it: finished levels
are read back, an interrupted one resumes from its checkpoint. A recipe may grow between runs
(stages added after the finished ones, more or fewer continuation levels); one that defines a
finished level otherwise is refused.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from fnmatch import fnmatch
from pathlib import Path

import numpy as np
from tqdm import tqdm

from bladelab._io import read_json, write_json
from bladelab.errors import InputFileError, SpecError
from bladelab.predict.reflex.acceptance import acceptance_runs, judged_runs, meets_acceptance
from bladelab.predict.reflex.controller import parameter_digest, read_parameters
from bladelab.predict.reflex.objective import ObjectiveSettings
from bladelab.predict.reflex.optimize import CHECKPOINT_NAME, optimize_controller, runner_and_layout
from bladelab.runner.blade_categories import blade_category
from bladelab.runner.params import REFLEX_STARTS_DIR

__all__ = ["ABLE", "STABLE_GAIT_RECIPE", "Recipe", "Stage", "level_row", "maximum_speed",
           "model_of", "recipe_task", "run_recipe", "settled_speed", "track_file"]

RECIPE_NAME = "recipe.json"
LEVELS_NAME = "levels.json"
RECIPE_FORMAT = 1
#: The first stage's warm start unless told otherwise: seed 001's gait of the model (a file
#: of :data:`~bladelab.runner.params.REFLEX_STARTS_DIR`).
REFLEX_START = {"amputee": "amputee-Cat6-3.5.json", "able": "able-3.5.json"}
#: The pseudo-category of the able-bodied runner (its tasks sit beside the blade categories').
ABLE = "able"
#: The collocation stride's weight in a tracking stage [1/rad²] (docs/predictive.md).
TRACK_WEIGHT = 1000.0


@dataclass(frozen=True)
class Stage:
    """One CMA-ES run of a recipe: ``generations``, initial step ``sigma`` (× each parameter's
    scale), ``popsize`` candidates; ``track``: add the collocation stride's tracking term;
    ``settings``: :class:`ObjectiveSettings` fields for this stage (over the recipe's
    ``base``); ``fixed``: patterns (``fnmatch``) of parameter names held at their values from
    the stage before; ``free``: if given, patterns of the only parameters searched (the others
    held as by ``fixed``)."""

    name: str
    generations: int
    sigma: float
    popsize: int = 16
    track: bool = False
    settings: dict = field(default_factory=dict)
    fixed: tuple[str, ...] = ()
    free: tuple[str, ...] = ()

    def fixed_indices(self, names: tuple[str, ...]) -> list[int]:
        """Indices of the parameters held among ``names``: those ``fixed`` names, and with
        ``free`` those it does not name."""
        return [i for i, n in enumerate(names)
                if any(fnmatch(n, p) for p in self.fixed)
                or (self.free and not any(fnmatch(n, p) for p in self.free))]

    def __post_init__(self) -> None:
        object.__setattr__(self, "fixed", tuple(self.fixed))
        object.__setattr__(self, "free", tuple(self.free))
        if not self.name or "/" in self.name:
            raise SpecError(f"a stage needs a plain name, got {self.name!r}", where="stage.name")
        if self.generations < 1 or self.popsize < 2 or not self.sigma > 0:
            raise SpecError(f"stage {self.name!r} needs generations >= 1, popsize >= 2 and "
                            "sigma > 0", where=f"stage {self.name}")


@dataclass(frozen=True)
class Recipe:
    """The stages of a task and its speed continuation. Speeds [m/s]."""

    stages: tuple[Stage, ...]
    continuation: Stage | None = None
    base: dict = field(default_factory=dict)
    speed: float = 4.0
    initial_speed: float = 3.5
    speed_step: float = 0.2
    min_gain: float = 0.05
    max_levels: int = 6

    def __post_init__(self) -> None:
        if not self.stages:
            raise SpecError("a recipe needs at least one stage", where="stages")
        names = [s.name for s in self.stages]
        if len(set(names)) != len(names):
            raise SpecError(f"stage names repeat: {names}", where="stages")
        if not (self.speed > 0 and self.initial_speed > 0 and self.speed_step > 0
                and self.min_gain >= 0 and self.max_levels >= 0):
            raise SpecError("a recipe needs speed, initial_speed, speed_step > 0, min_gain >= 0 "
                            "and max_levels >= 0", where="recipe")
        for stage in (*self.stages, *([self.continuation] if self.continuation else [])):
            self.settings_for(stage, self.speed, self.initial_speed, None)  # checks the fields

    def settings_for(self, stage: Stage, speed: float, initial_speed: float,
                     track: Path | None) -> ObjectiveSettings:
        """The objective settings of ``stage`` at ``speed`` from ``initial_speed`` [m/s]."""
        known = set(ObjectiveSettings.__dataclass_fields__)
        given = {**self.base, **stage.settings}
        unknown = sorted(set(given) - known)
        if unknown:
            raise SpecError(f"unknown objective setting(s) {unknown} in stage {stage.name!r}",
                            where="recipe", hint=f"known: {', '.join(sorted(known))}")
        d = {**given, "speed": float(speed), "initial_speed": float(initial_speed)}
        if stage.track and track is not None:
            d.update(track=str(track), w_track=TRACK_WEIGHT)
        return ObjectiveSettings.from_dict(d)

    def to_dict(self) -> dict:
        d = asdict(self)
        for stage in (*d["stages"], d["continuation"] or {}):
            if not stage.get("free", True):  # as written before stages had it
                del stage["free"]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Recipe:
        d = dict(d)
        try:
            d["stages"] = tuple(Stage(**s) for s in d["stages"])
            if d.get("continuation") is not None:
                d["continuation"] = Stage(**d["continuation"])
            return cls(**d)
        except (KeyError, TypeError) as e:
            raise SpecError(f"not a recipe: {e}", where="recipe",
                            hint="see bladelab.predict.reflex.recipe.STABLE_GAIT_RECIPE") from e

    @classmethod
    def read(cls, path: str | Path) -> Recipe:
        """A recipe from a JSON file: :meth:`to_dict`'s form, or a task's ``recipe.json``
        (the recipe it was made with)."""
        data = read_json(path, what="recipe")
        if isinstance(data, dict) and "stages" not in data and isinstance(data.get("recipe"),
                                                                          dict):
            data = data["recipe"]
        try:
            return cls.from_dict(data)
        except SpecError as e:
            raise InputFileError(str(e), file=path, hint=e.hint) from e


#: The recipes' scheme: Newmark at 1 ms (bladelab.runner.implicit; until 2026-11-27 the
#: first-order "implicit" one, whose gaits fall within 2 s under Newmark: a task folder made
#: with it continues with its own recipe.json's recipe, --recipe FILE).
_FAST = {"integrator": "newmark", "dt": 1e-3}
#: Every robust stage runs its last copy at half the step (from 2026-11-27: a Newmark gait
#: found without it ran 10 s at 1 ms and fell at 1.95 s at 0.5 ms; 60 generations with it
#: took the fall to 7.0 s while the 1 ms run went on; docs/predictive.md).
_COPIES = {"robust_jitter": 1e-6, "robust_directions": "per-generation",
           "robust_half_step": True}
_STARTS = {**_COPIES, "duration": 15.0, "robust_samples": 5, "robust_push": 0.03,
           "run_up": True}
_CLEAR = {**_STARTS, "robust_speed_change": 0.05, "strike_limit_bw": 0.5, "w_lean": 2.0}
#: The reflexes on the forward speed (controller.py: placement and trunk pitch), held at their
#: defaults (gain 0) until a gait runs: sampled from the start (search scale 0.5 per m/s) with
#: S0 = 3.5 m/s and a gait at 1–3 m/s they add about ±0.3 excitation to every candidate
#: (measured 2026-11-27: a tracking stage with them ended at cost 189 with a gait falling at
#: 3.8 s; one run before these terms existed, at 148 with a gait running 4 s).
_SPEED_TERMS = ("*-pelvis_tx.*",)

#: The stages that found Cat6's stable and start-robust gaits at 4 m/s
#: (docs/predictive.md "Warm start from a collocation stride", stages 1, 2L, P, S), on the fast
#: scheme (implicit, 1 ms): tracking, a long horizon, pushes, then the starts taught step by
#: step with the run-up, and last the blade's clearance and the lean. Several hours of one core
#: per category and seed.
STABLE_GAIT_RECIPE = Recipe(
    stages=(
        Stage("track", 1000, 0.3, popsize=32, track=True, settings={"duration": 4.0},
              fixed=_SPEED_TERMS),
        Stage("stable", 600, 0.2, settings={"duration": 20.0, "robust_samples": 3, **_COPIES},
              fixed=_SPEED_TERMS),
        Stage("basin", 400, 0.1, settings={"duration": 15.0, "robust_samples": 3,
                                           "robust_push": 0.02, "run_up": True, **_COPIES}),
        Stage("start", 200, 0.1, settings={**_STARTS, "robust_speed_change": 0.03}),
        Stage("start5", 200, 0.1, settings={**_STARTS, "robust_speed_change": 0.05}),
        Stage("clear", 400, 0.1, settings=_CLEAR),
    ),
    continuation=Stage("faster", 200, 0.1, settings=_CLEAR),
    base=_FAST,
)


def model_of(category: str) -> tuple[str, str | None]:
    """(model, blade) of a task's category: ``"able"`` is the able-bodied runner, any other
    name a blade category of the amputee (checked)."""
    if category == ABLE:
        return "able", None
    blade_category(category)
    return "amputee", category


def track_file(study: str | Path, category: str, speed: float) -> Path:
    """The collocation stride of ``category`` (``"able"`` or a blade category) at ``speed``
    [m/s] in a collocation study folder (``STUDY/amputee-<category>/speed-<v>.json`` or
    ``STUDY/able/speed-<v>.json``, or one level down under ``amputee/`` or ``able/``)."""
    study = Path(study)
    model, _ = model_of(category)
    name = Path(ABLE if model == "able" else f"amputee-{category}") / f"speed-{speed:g}.json"
    for path in (study / name, study / model / name):
        if path.is_file():
            return path.resolve()
    raise InputFileError(f"no collocation stride of {category} at {speed:g} m/s",
                         file=study / name, where="--track-study",
                         hint="bladelab study collocation writes one (docs/collocation.md)")


def level_row(path: Path) -> dict:
    """A finished level's gait (its ``best.json``) re-simulated for 10 s and judged by the
    stable-gait acceptance (:func:`~bladelab.predict.reflex.acceptance.acceptance_runs`) at the speed
    it reached (rounded to 0.01 m/s): a gait is judged at its own speed, and its copies and
    changed starts must reach that speed too (±0.1 m/s). Returns the nominal run's cost (the
    objective at the level's prescribed speed), mean speed [m/s], fell, swing contacts and
    their peak [body weights], mean pelvis tilt [deg]; for a gait that runs, the speed judged
    at [m/s] and the verdicts (for one that falls: None and False); and whether the nominal
    run also runs at half and at a quarter of the time step, its mean speed there [m/s]
    (None where it falls), how much that speed changed from half to a quarter of the step
    [m/s] (the step's uncertainty of the speed) and whether it meets the acceptance at half
    the step (reported, not judged). The quarter-step speed is the level's
    :func:`settled_speed`."""
    acc = acceptance_runs(path, 10.0, pushes=False, speed="reached", refined=2)
    runs = not acc["fell"]
    half, quarter = acc["refined"]
    speeds = [None if r["fell"] else float(r["mean_speed_m_per_s"]) for r in (half, quarter)]
    return {
        "cost": float(acc["cost"]),
        "mean_speed_m_per_s": float(acc["mean_speed_m_per_s"]),
        "fell": bool(acc["fell"]),
        "simulated_s": float(acc["duration_s"]),
        "swing_contacts": int(acc["swing_contacts"]),
        "swing_contact_peak_bw": float(acc["swing_contact_peak_bw"]),
        "pelvis_tilt_mean_deg": float(acc["pelvis_tilt_mean_deg"]),
        "judged_at_m_per_s": acc["judged_at_m_per_s"] if runs else None,
        "nominal_meets_acceptance": runs and meets_acceptance(judged_runs(acc)[0][1]),
        "accepted": runs and bool(acc["accepted"]),
        "runs_at_half_step": not half["fell"],
        "half_step_speed_m_per_s": speeds[0],
        "half_step_meets_acceptance": meets_acceptance(half),
        "runs_at_quarter_step": not quarter["fell"],
        "quarter_step_speed_m_per_s": speeds[1],
        "step_speed_change_m_per_s": (None if None in speeds
                                      else abs(speeds[1] - speeds[0])),
    }


def run_recipe(
    category: str,
    seed: int,
    *,
    out: str | Path,
    recipe: Recipe = STABLE_GAIT_RECIPE,
    init: str | Path | None = None,
    track_study: str | Path | None = None,
    checkpoint_every: int = 5,
    progress: Callable[[str, dict], None] | None = None,
) -> list[dict]:
    """Run (or continue) ``recipe`` for the amputee with blade ``category`` (or the able-bodied
    runner: ``"able"``) and CMA-ES seed ``seed`` in ``out/<category>/seed-<seed>/``; returns
    the rows of ``levels.json`` (see the module docstring). ``init``: the first stage's warm
    start (parameters JSON; default seed 001's gait of the model, :data:`REFLEX_START`);
    ``track_study``: the collocation study of the tracking stages (:func:`track_file`);
    ``progress(level, row)`` after each finished level."""
    model, blade = model_of(category)
    folder = Path(out) / category / f"seed-{seed}"
    _, layout = runner_and_layout(model, blade)
    init = (Path(init) if init is not None
            else REFLEX_STARTS_DIR / REFLEX_START[model])
    x = read_parameters(init, layout, transfer=True)
    track = None
    if any(s.track for s in recipe.stages):
        if track_study is None:
            raise SpecError("the recipe tracks a collocation stride: give the study",
                            where="--track-study")
        track = track_file(track_study, category, recipe.speed)
    task = {"format": RECIPE_FORMAT, "category": category, "seed": int(seed),
            "recipe": recipe.to_dict(), "init_sha256": parameter_digest(x, layout),
            "track": None if track is None else str(track),
            "track_sha256": None if track is None else hashlib.sha256(
                track.read_bytes()).hexdigest()}
    held = folder / RECIPE_NAME
    rows = _read_levels(folder)
    if held.is_file():
        _check_same_task(read_json(held, what="recipe task"), _as_json(task), rows, held)
    write_json(held, task)
    done = {r["level"]: r for r in rows}

    def level(name: str, stage: Stage, speed: float, start: float, x0: np.ndarray) -> dict:
        sub = folder / name
        if name in done:
            return done[name]
        settings = recipe.settings_for(stage, speed, start, track if stage.track else None)
        resume = (sub / CHECKPOINT_NAME).is_file()
        res = optimize_controller(model, blade=blade, speed=speed, x0=x0,
                                  generations=stage.generations, popsize=stage.popsize,
                                  sigma=stage.sigma, seed=int(seed), jobs=1, out=sub,
                                  resume=resume, force=not resume,
                                  checkpoint_every=checkpoint_every, settings=settings,
                                  fixed=stage.fixed_indices(layout.names))
        row = {"category": category, "seed": int(seed), "level": name, "stage": stage.name,
               "prescribed_speed_m_per_s": float(speed), "initial_speed_m_per_s": float(start),
               "generations": res.generations, "wall_time_s": res.wall_time_s,
               "best_cost_in_run": res.best_cost, **level_row(sub / "best.json")}
        rows.append(row)
        write_json(folder / LEVELS_NAME, rows)
        if progress is not None:
            progress(f"{category} seed {seed} {name}", row)
        return row

    speed, start = recipe.speed, recipe.initial_speed
    for i, stage in enumerate(recipe.stages, start=1):
        name = f"{i}-{stage.name}"
        row = level(name, stage, speed, start, x)
        x = read_parameters(folder / name / "best.json", layout)
    settled = settled_speed(row)
    if recipe.continuation is None or settled is None:
        return rows
    reached = row["mean_speed_m_per_s"]  # at the recipe's step: sets the prescription
    for _ in range(recipe.max_levels):
        target = round(reached + recipe.speed_step, 2)
        start = round(reached, 2)
        name = f"speed-{target:g}"
        row = level(name, recipe.continuation, target, start, x)
        gained = settled_speed(row)
        if gained is None or gained < settled + recipe.min_gain:
            break
        reached, settled = row["mean_speed_m_per_s"], gained
        x = read_parameters(folder / name / "best.json", layout)
    return rows


def _check_same_task(old: dict, new: dict, rows: list[dict], path: Path) -> None:
    """Refuse a task folder started with another warm start or stride (compared by content),
    or whose finished levels the new recipe defines otherwise (stages may be added after them,
    the number of continuation levels may change)."""
    # by content: a task folder copied with its study to another machine or folder continues
    for key, what in (("format", "format"), ("category", "category"), ("seed", "seed"),
                      ("init_sha256", "warm start (--init)"),
                      ("track_sha256", "tracked stride")):
        if old.get(key) != new.get(key):
            raise InputFileError(f"this task folder was started with another {what}", file=path,
                                 hint="use the first run's options, or another --out")
    a, b = old["recipe"], new["recipe"]
    same = {k: a.get(k) == b.get(k) for k in a}
    for row in rows:
        level = row["level"]
        if level.startswith("speed-"):
            keys = ("continuation", "stages", "base", "speed", "initial_speed", "speed_step",
                    "min_gain")
            changed = not all(same.get(k, False) for k in keys)
        else:
            i = int(level.split("-", 1)[0]) - 1
            changed = (not (same["base"] and same["speed"] and same["initial_speed"])
                       or i >= len(b["stages"]) or a["stages"][i] != b["stages"][i])
        if changed:
            raise InputFileError(f"this task folder was started with another recipe: its "
                                 f"finished level {level} would be defined otherwise", file=path,
                                 hint="use the first run's recipe (stages may be added after "
                                 "the finished ones), or another --out")


def _as_json(obj: dict) -> dict:
    """``obj`` as it reads back from JSON (tuples become lists)."""
    return json.loads(json.dumps(obj))


def _read_levels(folder: Path) -> list[dict]:
    path = folder / LEVELS_NAME
    if not path.is_file():
        return []
    rows = read_json(path, what="levels of a recipe task")
    if not isinstance(rows, list):
        raise InputFileError("not a list of levels", file=path, hint="delete it to re-check "
                             "the levels (their runs are kept)")
    return rows


def recipe_task(payload: dict) -> list[dict]:
    """:func:`run_recipe` for executors: ``payload`` holds its arguments (the recipe as a
    dict; ``announce``: print a line per finished level)."""
    payload = dict(payload)
    recipe = Recipe.from_dict(payload.pop("recipe"))
    category, seed = payload.pop("category"), payload.pop("seed")
    if payload.pop("announce", False):
        payload["progress"] = _announce
    return run_recipe(category, seed, recipe=recipe, **payload)


def _announce(level: str, row: dict) -> None:
    """One line per finished level (a sweep's tasks run for hours)."""
    verdict = (f"falls at {row['simulated_s']:.2f} s" if row["fell"] else
               "runs 10 s" + (", meets the stable-gait acceptance" if row["accepted"] else ""))
    settled = settled_speed(row)
    finer = ("" if "runs_at_quarter_step" not in row or row["fell"] else
             " (falls at a finer step)" if settled is None else
             f" ({settled:.2f} m/s at a quarter of the step)")
    tqdm.write(f"{level}: {row['generations']} generations, {verdict}, "
               f"{row['mean_speed_m_per_s']:.2f} m/s{finer}, cost {row['cost']:.4g}")


#: A level's runs at finer time steps (:func:`level_row`): whether it runs, its speed [m/s];
#: coarse to fine.
_REFINED = (("runs_at_half_step", "half_step_speed_m_per_s"),
            ("runs_at_quarter_step", "quarter_step_speed_m_per_s"))


def settled_speed(row: dict) -> float | None:
    """A level's speed at the finest time step it was simulated at [m/s] (:func:`level_row`:
    a quarter of its step); None if it falls at any step. At Newmark's 1 ms the gaits run
    0.09–0.25 m/s faster than at an eighth of it, and each halving still moves the speed by
    up to 0.11 m/s (``step_speed_change_m_per_s``; docs/predictive.md). A row
    written before levels were simulated at finer steps (no quarter step, or no
    half step, or no speed kept there; NaN in a table) gives the finest speed it holds."""
    if bool(row["fell"]):
        return None
    speed = float(row["mean_speed_m_per_s"])
    for runs_key, speed_key in _REFINED:
        runs = row.get(runs_key)
        if _missing(runs):
            continue
        if not bool(runs):
            return None
        if not _missing(row.get(speed_key)):
            speed = float(row[speed_key])
    return speed


def _missing(value) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))


def maximum_speed(rows: list[dict], *, accepted: bool = False) -> tuple[float, dict | None]:
    """The fastest :func:`settled_speed` of the levels that settle [m/s] and its row (NaN,
    None: none does); with ``accepted``, of the levels that also meet the stable-gait
    acceptance (the row's ``accepted``: the maximum speed meeting the acceptance,
    docs/predictive.md)."""
    ran = [(v, r) for r in rows if (v := settled_speed(r)) is not None
           and (not accepted or r.get("accepted") == 1)]  # True (numpy's too); not None, NaN
    if not ran:
        return math.nan, None
    return max(ran, key=lambda vr: vr[0])
