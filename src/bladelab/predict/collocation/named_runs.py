"""A stride solve and a speed sweep of runners named by words, into a folder.

:func:`solve_named_stride` builds the runner named by its model, blade and body
(:func:`~bladelab.predict.collocation.stored.runner_from_spec`) and the initial guess named by
a word or a file (:mod:`~bladelab.predict.collocation.starting_guess`), and solves one stride
into a folder (:func:`~bladelab.predict.collocation.output_folder.predict_stride_in_folder`).
:func:`sweep_named_models` does the same for the speed continuation and maximum speed of the
able runner and the amputee with each blade category
(:func:`~bladelab.predict.collocation.sweep.collocation_sweep`). ``bladelab predict --method
collocation`` and ``bladelab sweep --method collocation`` call them.

Errors name the argument concerned (``where``: ``model``, ``blade``, ``body``, ``guess``,
``categories``, ``jobs``, or a :class:`~bladelab.predict.collocation.settings.CollocationSettings`
field).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from bladelab.errors import SpecError
from bladelab.predict import defaults
from bladelab.predict.collocation.folder_starts import (
    check_stride_starts,
    predict_stride_from_starts,
)
from bladelab.predict.collocation.output_folder import predict_stride_in_folder
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.starting_guess import make_guess, resolve_guess
from bladelab.predict.collocation.starts import check_starts
from bladelab.predict.collocation.stored import check_model_spec, runner_from_spec
from bladelab.predict.collocation.sweep import collocation_sweep, sweep_models
from bladelab.runner.params import KINDS, default_runner_params

if TYPE_CHECKING:
    from bladelab.predict.collocation.output_folder import FolderResult
    from bladelab.predict.collocation.solve import SolveProgress
    from bladelab.predict.collocation.sweep import SweepResult

__all__ = ["PROSTHETIC_KNEE_SETTINGS", "solve_named_stride", "sweep_named_models"]

#: Settings of a prosthetic knee: only the transfemoral runner has one.
PROSTHETIC_KNEE_SETTINGS = ("knee_moment_min_nm", "knee_flexion_max_loaded_deg")


def solve_named_stride(
    out: str | Path,
    *,
    model: str = "able",
    blade: str | None = None,
    body: str = defaults.BODY,
    settings: CollocationSettings | None = None,
    guess: str = defaults.GUESS,
    athlete: dict | None = None,
    starts: int = defaults.STARTS,
    resume: bool = False,
    force: bool = False,
    progress: Callable[[SolveProgress], None] | None = None,
    say: Callable[[str], None] | None = None,
) -> FolderResult:
    """Solve one stride of the runner ``model`` (``able``, ``amputee``, ``transfemoral``)
    wearing ``blade`` (None: the model's default blade) with the ``body`` (seed 001's, or
    ``toes``), from the initial guess ``guess`` (module docstring), into the folder ``out``;
    ``athlete`` (``body_mass_kg`` [kg], ``height_m`` [m], ``muscle_strength`` [-],
    ``max_shortening_velocity`` [l_opt/s], ``residual_limb_length_m``, ``thigh_length_m``,
    ``shank_length_m``, ``prosthesis_extra_length_m`` [m], any of them;
    :func:`bladelab.runner.scaling.athlete_params`) scales the runner to another athlete.

    ``settings`` (default :class:`CollocationSettings`) say the problem (mesh intervals [-],
    speed [m/s] or None for the maximum speed, constraints); ``resume``, ``force`` and
    ``progress`` are those of :func:`predict_stride_in_folder`, which owns the folder
    (``solution.json``, or ``best_iterate.json`` when IPOPT does not converge). ``starts``
    > 1: the stride solved from that many starts, the best kept
    (:func:`~bladelab.predict.collocation.folder_starts.predict_stride_from_starts`; ``say``
    gets its lines about the starts).

    Raises
    ------
    SpecError
        An unknown model, blade or body; a bad athlete field; prosthetic-knee settings for a
        runner without a prosthetic knee; a guess that is neither a word nor a file.
    """
    if model not in KINDS:
        raise SpecError(f"unknown model {model!r}", where="model", hint=" or ".join(KINDS))
    settings = CollocationSettings() if settings is None else settings
    if model != "transfemoral":
        for name in PROSTHETIC_KNEE_SETTINGS:
            if getattr(settings, name) is not None:
                raise SpecError(f"the {model} model has no prosthetic knee", where=name,
                                hint="a setting of the transfemoral model")
    if blade is None and model != "able":
        blade = default_runner_params(model).blade
    spec = check_model_spec({"model": model, "blade": blade, "body": body, "athlete": athlete})
    runner = runner_from_spec(spec)
    n, speed = settings.mesh_intervals, settings.speed_m_per_s
    if check_stride_starts(starts) > 1:
        return predict_stride_from_starts(
            out, runner, settings, lambda: make_guess(runner, guess, n=n, speed=speed),
            lambda: make_guess(runner, "template", n=n, speed=speed), starts=starts,
            model_spec=spec, resume=resume, force=force, progress=progress, say=say)
    return predict_stride_in_folder(
        out, runner, settings, lambda: make_guess(runner, guess, n=n, speed=speed),
        model_spec=spec, resume=resume, force=force, progress=progress)


def sweep_named_models(
    out: str | Path,
    *,
    categories: Sequence[str],
    speeds: Sequence[float],
    able: bool = False,
    body: str = defaults.BODY,
    guess: str = defaults.GUESS,
    mesh_intervals: int = defaults.MESH_INTERVALS,
    max_iter: int = defaults.MAX_ITER,
    people_weight: float | None = None,
    swing_knee_deg: float | None = None,
    step_phase_tolerance: float | None = None,
    stride_time_people: bool = False,
    athlete: dict | None = None,
    starts: int = defaults.STARTS,
    mesh_check: bool = False,
    settle: bool = False,
    jobs: int = 1,
    executor: str = "local",
    resume: bool = False,
    force: bool = False,
    progress: Callable | None = None,
) -> SweepResult:
    """The speed continuation over ``speeds`` [m/s] and the maximum speed of the able runner
    (when ``able``, first) and of the amputee with each blade category of ``categories``, all
    with the ``body``, into the folder ``out``
    (:func:`~bladelab.predict.collocation.sweep.collocation_sweep`, which owns the folder and
    returns its :class:`~bladelab.predict.collocation.sweep.SweepResult`).

    Each model's first speed starts from ``guess`` (module docstring); ``mesh_intervals`` and
    ``max_iter`` (IPOPT's iterations per stage) set its :class:`CollocationSettings`;
    ``people_weight`` [1/rad²]: the weight of people's joint angles in the objective
    (:mod:`~bladelab.predict.collocation.people`; 0: none; None: the body's default,
    :func:`bladelab.predict.defaults.people_weight_for`); ``swing_knee_deg`` [deg]: every
    person's knee flexed at least this much in swing (0: free; None: the body's default,
    :func:`bladelab.predict.defaults.swing_knee_for`); ``step_phase_tolerance``: every
    stride's steps alternating within this fraction of the stride
    (:attr:`CollocationSettings.step_phase_tolerance`; None: free); ``stride_time_people``:
    every prescribed speed's stride time within people's band at that speed
    (:attr:`CollocationSettings.stride_time_people`; the maximum speed free); ``athlete``: every model
    scaled to this athlete (as in :func:`solve_named_stride`); ``starts``: starts per
    problem, the best kept (:mod:`~bladelab.predict.collocation.starts`); ``mesh_check``:
    every converged solve checked on twice the mesh intervals
    (:mod:`~bladelab.predict.collocation.mesh_check`); ``settle``: a settling pass from the
    neighbouring categories' strides (:func:`~bladelab.predict.collocation.sweep.collocation_sweep`);
    ``jobs`` models at a time on ``executor``.

    Raises
    ------
    SpecError
        Bad settings, starts or jobs; an unknown or repeated category, an unknown body, no
        model; a guess that is neither a word nor a file.
    """
    if len(speeds) == 0:
        raise SpecError("no speed given", where="speeds")
    settings = CollocationSettings(mesh_intervals=mesh_intervals, speed_m_per_s=speeds[0],
                                   max_iter=max_iter, step_phase_tolerance=step_phase_tolerance,
                                   stride_time_people=stride_time_people,
                                   **people_settings(body, people_weight, swing_knee_deg))
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise SpecError(f"need at least 1 job, got {jobs}", where="jobs")
    check_starts(starts)
    models = sweep_models(categories, able=able, body=body, athlete=athlete)
    guess = resolve_guess(guess)
    return collocation_sweep(
        models, speeds, settings, functools.partial(make_guess, guess=guess), out=out,
        jobs=jobs, executor=executor, resume=resume, force=force, progress=progress,
        starts=starts, mesh_check=mesh_check, settle=settle)
