"""A reflex-controller optimisation and a recipe sweep set up from names and files.

:func:`optimize_named` checks the objective's settings, reads the warm start (a parameter file,
transferred between the able and amputee runners) and the collocation stride to track, and
runs CMA-ES once per seed (:func:`~bladelab.predict.reflex.optimize.optimize_seeds`).
:func:`recipe_sweep_named` runs a recipe named by a word or a file for each category and seed
(:func:`~bladelab.predict.reflex.recipe_sweep.run_recipe_sweep`). ``bladelab predict`` and
``bladelab sweep --recipe`` call them; :func:`check_run_settings` also checks the settings of
``bladelab sweep``'s speed grid.

Errors name the argument concerned (``where``: ``model``, ``init``, ``recipe``, ``hold``, or an
:class:`~bladelab.predict.reflex.objective.ObjectiveSettings` field).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from fnmatch import fnmatch
from pathlib import Path

from bladelab.errors import SpecError
from bladelab.predict import defaults
from bladelab.predict.reflex.controller import read_parameters
from bladelab.predict.reflex.objective import ObjectiveSettings, stride_initial_state
from bladelab.predict.reflex.optimize import OptimizationResult, optimize_seeds, runner_and_layout
from bladelab.predict.reflex.recipe import STABLE_GAIT_RECIPE, Recipe
from bladelab.predict.reflex.recipe_sweep import run_recipe_sweep
from bladelab.predict.reflex.tracking import GaitReference
from bladelab.runner.implicit import INTEGRATORS
from bladelab.runner.simulate import integrator_for

__all__ = ["MAX_TIME_STEP_S", "RECIPES", "REFLEX_MODELS", "body_integrator",
           "check_run_settings",
           "held_parameters", "named_recipe", "optimize_named", "recipe_sweep_named"]

#: The runners the reflex controller drives.
REFLEX_MODELS = ("able", "amputee")
#: The largest time step of the closed loop [s].
MAX_TIME_STEP_S = 2e-3
#: The built-in recipes by name.
RECIPES: dict[str, Recipe] = {"stable-gait": STABLE_GAIT_RECIPE}


def body_integrator(model: str, body: str = defaults.REFLEX_BODY,
                    integrator: str | None = None, blade: str | None = None) -> str:
    """The closed loop's forward scheme for the runner ``model`` (the amputee wearing
    ``blade``, default :data:`~bladelab.predict.defaults.REFLEX_BLADE`) on ``body``:
    ``integrator`` when given, else the one the body's joint dampers allow at the explicit step
    (:func:`bladelab.runner.integrator_for`: explicit on seed 001's and the toes body, Newmark
    on the human body). The runner is the one :func:`optimize_named` then reuses."""
    if integrator is not None:
        return integrator
    if model not in REFLEX_MODELS:
        raise SpecError(f"unknown model {model!r}", where="model",
                        hint=" or ".join(REFLEX_MODELS))
    worn = (blade or defaults.REFLEX_BLADE) if model == "amputee" else None
    return integrator_for(runner_and_layout(model, worn, body)[0])[0]


def check_run_settings(*, speed: float | None = None, duration: float | None = None,
                       dt: float | None = None, robust_samples: int | None = None,
                       robust_jitter: float | None = None, integrator: str | None = None,
                       w_lean: float | None = None,
                       strike_limit_bw: float | None = None) -> None:
    """Refuse objective settings (:class:`ObjectiveSettings` fields, each checked when given)
    that a run cannot use: speed [m/s] and duration [s] > 0, time step in
    (0, :data:`MAX_TIME_STEP_S`] s, at least one sample, a relative jitter in (0, 0.1), a
    known integrator, a lean weight [1/deg] and strike limit [body weights] >= 0."""
    if speed is not None and not (math.isfinite(speed) and speed > 0):
        raise SpecError("speed must be positive", where="speed")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise SpecError("must be positive", where="duration")
    if dt is not None and not (math.isfinite(dt) and 0 < dt <= MAX_TIME_STEP_S):
        raise SpecError(f"time step must be in (0, {MAX_TIME_STEP_S:g}] s", where="dt")
    if robust_samples is not None and robust_samples < 1:
        raise SpecError("must be at least 1", where="robust_samples")
    if robust_jitter is not None and not (math.isfinite(robust_jitter)
                                          and 0 < robust_jitter < 0.1):
        raise SpecError("must be in (0, 0.1)", where="robust_jitter")
    if integrator is not None and integrator not in INTEGRATORS:
        raise SpecError(f"unknown integrator {integrator!r}", where="integrator",
                        hint=f"one of {', '.join(INTEGRATORS)}")
    if w_lean is not None and not (math.isfinite(w_lean) and w_lean >= 0):
        raise SpecError("must be >= 0", where="w_lean")
    if strike_limit_bw is not None and not (math.isfinite(strike_limit_bw)
                                            and strike_limit_bw >= 0):
        raise SpecError("must be >= 0 body weights (0: a strike takes all the step's credit)",
                        where="strike_limit_bw")


def optimize_named(
    model: str = "able",
    *,
    out: str | Path,
    seeds: Sequence[int] = (defaults.SEED,),
    blade: str | None = None,
    body: str = defaults.REFLEX_BODY,
    init: str | Path | None = None,
    settings: ObjectiveSettings | None = None,
    progress: Callable[[int, int, float, float], None] | None = None,
    hold: Sequence[str] = (),
    **options,
) -> list[OptimizationResult]:
    """Optimise the reflex controller of the runner ``model`` (``able`` or ``amputee`` with
    ``blade``, default :data:`~bladelab.predict.defaults.REFLEX_BLADE`) once per seed into
    ``out`` (:func:`~bladelab.predict.reflex.optimize.optimize_seeds`), on ``body``
    (:data:`~bladelab.predict.defaults.REFLEX_BODY`: seed 001's), from the parameter
    file ``init`` (None: SCONE's parameters), with the objective ``settings``; a stride to
    track (``settings.track``) must be of the same runner. ``hold``: name patterns
    (:func:`held_parameters`) of parameters kept at their start values. ``progress`` and
    ``options`` (CMA-ES generations, popsize, sigma, jobs, executor, resume, force,
    checkpoint_every) are :func:`optimize_seeds`'s."""
    if model not in REFLEX_MODELS:
        raise SpecError(f"unknown model {model!r}", where="model",
                        hint=" or ".join(REFLEX_MODELS))
    settings = ObjectiveSettings() if settings is None else settings
    check_run_settings(speed=settings.speed, dt=settings.dt,
                       robust_samples=settings.robust_samples,
                       robust_jitter=settings.robust_jitter, integrator=settings.integrator,
                       w_lean=settings.w_lean, strike_limit_bw=settings.strike_limit_bw)
    blade = blade or defaults.REFLEX_BLADE
    worn = blade if model == "amputee" else None
    runner, layout = runner_and_layout(model, worn, body)
    if settings.start_stride is not None:
        stride_initial_state(runner, settings.start_stride, settings.start_speed,
                             where="start_stride")
    if settings.track is not None:
        if not (math.isfinite(settings.w_track) and settings.w_track > 0):
            raise SpecError("must be > 0", where="w_track")
        GaitReference.read(settings.track).check_model(model, worn, "track", body=body)
    x0 = (read_parameters(init, layout, transfer=True, body=body) if init is not None
          else None)
    fixed = held_parameters(layout.names, hold)
    return optimize_seeds(model, seeds=list(seeds), out=out, progress=progress, blade=blade,
                          body=body, speed=settings.speed, x0=x0, settings=settings,
                          **({"fixed": fixed} if fixed else {}), **options)


def held_parameters(names: Sequence[str], patterns: Sequence[str]) -> list[int]:
    """Indices of the controller parameters ``names`` that match any of the shell-style
    ``patterns`` (``fnmatch``, e.g. ``*-pelvis_tx.*`` for the foot-placement reflexes,
    ``S11100.iliopsoas_?-hamstrings.*`` for the hamstrings' inhibition of the swinging hip
    flexor); SpecError naming a pattern that matches none."""
    for pattern in patterns:
        if not any(fnmatch(n, pattern) for n in names):
            raise SpecError(f"no controller parameter matches {pattern!r}", where="hold",
                            hint="a pattern of parameter names as in a parameter file, e.g. "
                                 "'*-pelvis_tx.*'")
    return [i for i, n in enumerate(names) if any(fnmatch(n, p) for p in patterns)]


def named_recipe(recipe: str | Path | Recipe) -> Recipe:
    """A recipe by name (:data:`RECIPES`) or from its JSON file."""
    if isinstance(recipe, Recipe):
        return recipe
    if str(recipe) in RECIPES:
        return RECIPES[str(recipe)]
    if Path(recipe).is_file():
        return Recipe.read(recipe)
    raise SpecError(f"no recipe {str(recipe)!r}", where="recipe",
                    hint=f"{', '.join(RECIPES)}, or the path of a recipe JSON")


def recipe_sweep_named(categories: Sequence[str], seeds: Sequence[int], *, out: str | Path,
                       recipe: str | Path | Recipe = "stable-gait",
                       init: str | Path | None = None, **options):
    """:func:`~bladelab.predict.reflex.recipe_sweep.run_recipe_sweep` of the recipe named by
    ``recipe`` (:func:`named_recipe`) for each category × seed, from the parameter file
    ``init`` (None: each model's reflex start, seed 001's gait); ``options`` (track_study,
    jobs, executor, checkpoint_every) are its own. Returns its per-category summary."""
    chosen = named_recipe(recipe)
    if init is not None and not Path(init).is_file():
        raise SpecError("file not found", file=init, where="init")
    return run_recipe_sweep(list(categories), list(seeds), out=out, recipe=chosen, init=init,
                            **options)
