"""``bladelab predict`` and ``bladelab sweep`` with the reflex controller (CMA-ES): parse the
options, call :mod:`bladelab.predict.reflex.named_runs` or
:func:`~bladelab.predict.reflex.sweep.run_sweep`, print the result.

Errors of the library name its arguments (``w_lean``); :data:`OPTIONS` turns them into the
options that set them (``--lean-weight``).
"""

from __future__ import annotations

import json
from pathlib import Path

import typer

from bladelab.cli.panels import renamed
from bladelab.cli.values import parse_list
from bladelab.errors import BladelabError, SpecError
from bladelab.predict.reflex.named_runs import (
    body_integrator,
    check_run_settings,
    optimize_named,
    recipe_sweep_named,
)
from bladelab.predict.reflex.objective import ObjectiveSettings, check_robust_copies
from bladelab.predict.reflex.sweep import run_sweep

__all__ = ["OPTIONS", "run_recipe_sweep", "run_reflex", "run_reflex_sweep"]

#: Library argument or ``ObjectiveSettings`` field -> the option that sets it.
OPTIONS = {
    "model": "--model", "blade": "--blade", "body": "--body", "init": "--init",
    "recipe": "--recipe",
    "speed": "--speed", "duration": "--duration", "dt": "--dt",
    "robust_samples": "--robust-samples", "robust_jitter": "--robust-jitter",
    "initial_speed": "--initial-speed", "strike_limit_bw": "--strike-limit",
    "w_lean": "--lean-weight", "integrator": "--integrator", "track": "--track",
    "w_track": "--track-weight", "start_stride": "--start-stride", "hold": "--hold",
}
_ROBUST_OPTIONS = ("--robust-directions", "--robust-speed-change", "--robust-push",
                   "--duration", "--robust-half-step", "--robust-samples")


def run_reflex(*, out: Path, model: str, blade: str | None, body: str, speed: float,
               init: Path | None,
               seeds: str, generations: int, popsize: int, sigma: float, jobs: int,
               executor: str, resume: bool, force: bool, checkpoint_every: int,
               duration: float, dt: float, robust_samples: int, robust_jitter: float,
               robust_directions: str, robust_speed_change: float, robust_push: float,
               robust_half_step: bool, initial_speed: float | None, strike_limit: float,
               lean_weight: float, run_up: bool, integrator: str | None, track: Path | None,
               track_weight: float, start_stride: Path | None = None,
               hold: str | None = None) -> None:
    """``bladelab predict`` (reflex): CMA-ES once per seed; prints each generation and the
    best run as JSON. ``hold``: comma-separated name patterns of parameters kept at their
    start values; ``integrator`` None: the body's own (:func:`body_integrator`)."""
    check_robust_copies(robust_directions, robust_speed_change, robust_push, duration,
                        half_step=robust_half_step, samples=robust_samples,
                        where=_ROBUST_OPTIONS)
    seed_list = parse_list(seeds, "--seeds", int)

    def show(seed: int, gen: int, best: float, median: float) -> None:
        typer.echo(f"seed {seed} generation {gen}: best {best:.4g}, median {median:.4g}")

    try:
        settings = ObjectiveSettings(
            speed=speed, duration=duration, dt=dt, robust_samples=robust_samples,
            robust_jitter=robust_jitter, robust_directions=robust_directions,
            robust_speed_change=robust_speed_change, robust_push=robust_push,
            robust_half_step=robust_half_step, initial_speed=initial_speed,
            strike_limit_bw=strike_limit, w_lean=lean_weight, run_up=run_up,
            integrator=body_integrator(model, body, integrator, blade),
            track=None if track is None else str(track),
            w_track=0.0 if track is None else track_weight,
            start_stride=None if start_stride is None else str(start_stride))
        results = optimize_named(
            model, out=out, seeds=seed_list, blade=blade, body=body, init=init,
            settings=settings, hold=parse_list(hold, "--hold") if hold else (),
            progress=show, generations=generations, popsize=popsize, sigma=sigma, jobs=jobs,
            executor=executor, resume=resume, force=force, checkpoint_every=checkpoint_every)
    except BladelabError as err:
        raise renamed(err, OPTIONS) from None
    best = min(results, key=lambda r: r.best_cost)
    typer.echo(json.dumps(best.to_dict(), indent=2))


def run_reflex_sweep(*, out: Path, categories: str, speeds: str, init: Path | None,
                     generations: int, popsize: int, sigma: float, seed: int, jobs: int,
                     executor: str, duration: float, dt: float, robust_samples: int,
                     robust_jitter: float, initial_speed: float | None, checkpoint_every: int,
                     chain_from: str | None) -> None:
    """``bladelab sweep`` (reflex speed grid): the category × speed grid; prints its table."""
    try:
        check_run_settings(duration=duration, dt=dt, robust_samples=robust_samples,
                           robust_jitter=robust_jitter)
    except BladelabError as err:
        raise renamed(err, OPTIONS) from None
    if init is not None and not init.is_file():
        raise SpecError("file not found", file=init, where="--init")
    table = run_sweep(
        parse_list(categories, "--categories"), parse_list(speeds, "--speeds", float),
        out=out, init=init, generations=generations, popsize=popsize, sigma=sigma,
        seed=seed, jobs=jobs, executor=executor, duration=duration, dt=dt,
        robust_samples=robust_samples, robust_jitter=robust_jitter,
        initial_speed=initial_speed, checkpoint_every=checkpoint_every,
        chain_from=chain_from)
    typer.echo(table.to_string(index=False))


def run_recipe_sweep(*, out: Path, categories: str, recipe: str, seeds: str,
                     track_study: Path | None, init: Path | None, jobs: int, executor: str,
                     checkpoint_every: int) -> None:
    """``bladelab sweep --recipe``: the recipe (a name or a JSON file) per category × seed;
    prints the per-category summary."""
    cats = parse_list(categories, "--categories")
    seed_list = parse_list(seeds, "--seeds", int)
    try:
        table = recipe_sweep_named(cats, seed_list, out=out, recipe=recipe, init=init,
                                   track_study=track_study, jobs=jobs, executor=executor,
                                   checkpoint_every=checkpoint_every)
    except BladelabError as err:
        raise renamed(err, OPTIONS) from None
    typer.echo(table.to_string(index=False))
