"""``bladelab predict`` and ``bladelab sweep``: predictive running (seed 001 §2.2)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from bladelab.cli.defaults import COLLOCATION_MAX_ITER, COLLOCATION_MESH, TRACK_WEIGHT
from bladelab.cli.defaults import RUNNER_DT as DEFAULT_DT
from bladelab.errors import SpecError


def _parse_list(text: str, what: str, conv=str) -> list:
    try:
        items = [conv(t.strip()) for t in text.split(",") if t.strip()]
    except ValueError:
        raise SpecError(
            f"cannot read {what} {text!r}", where=what, hint="comma-separated"
        ) from None
    if not items:
        raise SpecError(f"no {what} given", where=what)
    return items


def _run_recipe_sweep(out, categories, recipe, seeds, track_study, init, jobs, executor,
                      checkpoint_every) -> None:
    """``bladelab sweep --recipe``: the recipe (a name or a JSON file) per category × seed."""
    from bladelab.predict.reflex.recipe import STABLE_GAIT_RECIPE, Recipe
    from bladelab.predict.reflex.recipe_sweep import run_recipe_sweep

    if recipe == "stable-gait":
        chosen = STABLE_GAIT_RECIPE
    elif Path(recipe).is_file():
        chosen = Recipe.read(recipe)
    else:
        raise SpecError(f"no recipe {recipe!r}", where="--recipe",
                        hint="stable-gait, or the path of a recipe JSON")
    if init is not None and not init.is_file():
        raise SpecError("file not found", file=init, where="--init")
    table = run_recipe_sweep(
        _parse_list(categories, "--categories"),
        _parse_list(seeds or "1,2,3", "--seeds", int),
        out=out, recipe=chosen, init=init, track_study=track_study, jobs=jobs,
        executor=executor, checkpoint_every=checkpoint_every)
    typer.echo(table.to_string(index=False))


def _check_simulation_options(dt: float, robust_samples: int, robust_jitter: float) -> None:
    """The time step [s] and the robust-evaluation options shared by predict and sweep."""
    if not (math.isfinite(dt) and 0 < dt <= 2e-3):
        raise SpecError("time step must be in (0, 2e-3] s", where="--dt")
    if robust_samples < 1:
        raise SpecError("must be at least 1", where="--robust-samples")
    if not (math.isfinite(robust_jitter) and 0 < robust_jitter < 0.1):
        raise SpecError("must be in (0, 0.1)", where="--robust-jitter")


def register(app: typer.Typer) -> None:
    @app.command("predict")
    def predict(
        out: Path = typer.Option(..., "--out", help="Output folder (checkpoint, best.json)."),
        model: str = typer.Option(
            "able", "--model", help="able | amputee | transfemoral (collocation only)."),
        blade: str | None = typer.Option(
            None, "--blade", help="Blade category of the amputee (default Cat6; the "
            "transfemoral runner's: Cat4)."),
        speed: float = typer.Option(3.5, "--speed", help="Prescribed speed (m/s)."),
        init: Path | None = typer.Option(None, "--init", help="Warm start: parameters JSON."),
        generations: int = typer.Option(100, "--generations", help="CMA-ES generations."),
        popsize: int = typer.Option(16, "--popsize", help="Candidates per generation."),
        sigma: float = typer.Option(1.0, "--sigma", help="Initial step (× parameter scale)."),
        seeds: str = typer.Option("1", "--seeds", help="Comma-separated seeds: one run each."),
        jobs: int = typer.Option(1, "--jobs", help="Parallel worker processes."),
        executor: str = typer.Option("local", "--executor", help="local | ray"),
        resume: bool = typer.Option(False, "--resume", help="Continue from the checkpoint."),
        force: bool = typer.Option(
            False, "--force", help="Start over in an --out that holds a run (replacing it)."
        ),
        duration: float = typer.Option(10.0, "--duration", help="Simulated time (s)."),
        checkpoint_every: int = typer.Option(5, "--checkpoint-every", help="Generations."),
        dt: float = typer.Option(
            DEFAULT_DT, "--dt", help="Time step (s); 5e-4 only for quick exploratory runs."
        ),
        robust_samples: int = typer.Option(
            1, "--robust-samples", help="Simulations per candidate (nominal + jittered copies)."
        ),
        robust_jitter: float = typer.Option(
            1e-6, "--robust-jitter", help="Relative parameter jitter of the copies."
        ),
        robust_directions: str = typer.Option(
            "fixed", "--robust-directions", help="fixed (the copies' jitter directions drawn "
            "once per run) | per-generation (drawn anew every generation; the best so far is "
            "simulated on each generation's copies too)."
        ),
        robust_speed_change: float = typer.Option(
            0.0, "--robust-speed-change", help="Start the copies at (1 + s), (1 - s), ... × the "
            "initial speed (relative; 0.05: the ±5 % acceptance test inside the objective)."
        ),
        robust_push: float = typer.Option(
            0.0, "--robust-push", help="Push each copy once in mid-run: its forward speed "
            "times (1 + p), (1 - p), ... at a seeded time (relative; tests the gait's basin)."
        ),
        robust_half_step: bool = typer.Option(
            False, "--robust-half-step", help="Run the last copy at half the time step (a gait "
            "must not live on the discretisation; needs --robust-samples 2 or more)."
        ),
        initial_speed: float | None = typer.Option(
            None, "--initial-speed", help="Forward speed of the initial state (m/s); default --speed."
        ),
        strike_limit: float = typer.Option(
            1.0, "--strike-limit", help="A step whose swinging foot strikes the ground earns "
            "max(0, 1 - peak/limit) of its credit (body weights; issue 20 accepts at most 0.2)."
        ),
        lean_weight: float = typer.Option(
            0.1, "--lean-weight", help="Weight of the pelvis tilt outside -16...-2 deg "
            "(seed 001's 0.1 per degree, averaged over the run)."
        ),
        run_up: bool = typer.Option(
            False, "--run-up", help="Reflex: the reflexes on the mean forward speed act from "
            "the start, as if the runner had moved at the initial speed before it (else they "
            "wait for a full window of the run)."
        ),
        integrator: str = typer.Option(
            "explicit", "--integrator", help="Reflex: explicit (the default 0.25 ms scheme) | "
            "newmark (stiff forces linearly implicit, second-order rule, at --dt 1e-3 more "
            "accurate than explicit at 0.25 ms and 4x cheaper) | implicit (its first-order "
            "predecessor, for runs made with it)."
        ),
        track: Path | None = typer.Option(
            None, "--track", help="Reflex: add a term that pulls the gait towards this "
            "collocation stride of the same runner (solution.json; its joint angles and stride "
            "time, stride by stride); then run again with --init OUT/best.json and no --track."
        ),
        track_weight: float = typer.Option(
            TRACK_WEIGHT, "--track-weight", help="Reflex: weight of the tracking term "
            "[1/rad²] (with --track)."
        ),
        method: str = typer.Option(
            "reflex", "--method", help="reflex (CMA-ES on the reflex controller) | collocation "
            "(one periodic stride by direct collocation, CasADi + IPOPT)."
        ),
        max_speed: bool = typer.Option(
            False, "--max-speed", help="Collocation: maximise the mean speed instead of --speed."
        ),
        mesh: int = typer.Option(COLLOCATION_MESH, "--mesh",
                                  help="Collocation: mesh intervals of the stride."),
        guess: str = typer.Option(
            "template", "--guess", help="Collocation: initial guess: template | trial (the "
            "Fukuchi 3.5 m/s trial) | FILE (solution.json, best_iterate.json or reflex JSON)."
        ),
        max_iter: int = typer.Option(
            COLLOCATION_MAX_ITER, "--max-iter", help="Collocation: IPOPT iterations per stage."
        ),
        as_json: bool = typer.Option(
            False, "--json", help="Collocation: print the summary as one JSON object."
        ),
        body: str = typer.Option(
            "seed001", "--body", help="Collocation: seed001 (seed 001's model) | toes (a toe "
            "segment and compliant Achilles tendons; docs/runner-model.md)."
        ),
        swing_clearance: float = typer.Option(
            0.0, "--swing-clearance", help="Collocation: keep every swinging foot or blade "
            "this high above the ground [m] (0: no constraint)."
        ),
        knee_moment_min: float | None = typer.Option(
            None, "--knee-moment-min", help="Collocation, transfemoral: keep the ground force's "
            "extension moment about the prosthetic knee at or above this [N·m] (<= 0; 0: the "
            "knee never buckles)."
        ),
        knee_flexion_max: float | None = typer.Option(
            None, "--knee-flexion-max", help="Collocation, transfemoral: keep the prosthetic "
            "knee within this flexion [deg] while its blade is loaded (the straight stance)."
        ),
        tilt_range: str | None = typer.Option(
            None, "--tilt-range", help="Collocation: keep the pelvis tilt within LO,HI [deg] "
            "at every node (forward lean negative), e.g. --tilt-range=-16,-2 (seed 001's "
            "window)."
        ),
    ) -> None:
        """Optimise the reflex controller of the runner with CMA-ES (seed 001 eq. 2.4), or with
        --method collocation solve one periodic stride by direct collocation (writes
        DIR/solution.json; exit status 2 and DIR/best_iterate.json if IPOPT does not converge)."""
        if method == "collocation":
            from bladelab.cli.collocation import run_collocation

            for given, option in ((track is not None, "--track"),
                                  (integrator != "explicit", "--integrator")):
                if given:
                    raise SpecError("only with --method reflex", where=option)

            code = run_collocation(out=out, model=model, blade=blade, speed=speed,
                                   max_speed=max_speed, mesh=mesh, guess=guess,
                                   max_iter=max_iter, resume=resume, force=force,
                                   as_json=as_json, body=body,
                                   swing_clearance=swing_clearance,
                                   knee_moment_min=knee_moment_min,
                                   knee_flexion_max=knee_flexion_max,
                                   tilt_range=tilt_range)
            raise typer.Exit(code)
        if method != "reflex":
            raise SpecError(f"unknown method {method!r}", where="--method",
                            hint="reflex or collocation")
        if body != "seed001":
            raise SpecError("only with --method collocation", where="--body",
                            hint="the reflex controller is tuned to seed 001's body")
        if tilt_range is not None:
            raise SpecError("only with --method collocation", where="--tilt-range",
                            hint="the reflex objective's window: --lean-weight")
        from bladelab.predict.reflex.controller import read_parameters
        from bladelab.predict.reflex.objective import ObjectiveSettings, check_robust_copies
        from bladelab.predict.reflex.optimize import optimize_seeds, runner_and_layout
        from bladelab.runner.implicit import INTEGRATORS

        if model not in ("able", "amputee"):
            raise SpecError(f"unknown model {model!r}", where="--model", hint="able or amputee")
        if not (math.isfinite(speed) and speed > 0):
            raise SpecError("speed must be positive", where="--speed")
        _check_simulation_options(dt, robust_samples, robust_jitter)
        check_robust_copies(robust_directions, robust_speed_change, robust_push, duration,
                            half_step=robust_half_step, samples=robust_samples,
                            where=("--robust-directions", "--robust-speed-change",
                                   "--robust-push", "--duration", "--robust-half-step",
                                   "--robust-samples"))
        if integrator not in INTEGRATORS:
            raise SpecError(f"unknown integrator {integrator!r}", where="--integrator",
                            hint=f"one of {', '.join(INTEGRATORS)}")
        if not (math.isfinite(lean_weight) and lean_weight >= 0):
            raise SpecError("must be >= 0", where="--lean-weight")
        if not (math.isfinite(strike_limit) and strike_limit >= 0):
            raise SpecError("must be >= 0 body weights (0: a strike takes all the step's credit)",
                            where="--strike-limit")
        blade = blade or "Cat6"
        _, layout = runner_and_layout(model, blade if model == "amputee" else None)
        if track is not None:
            from bladelab.predict.reflex.tracking import GaitReference

            if not (math.isfinite(track_weight) and track_weight > 0):
                raise SpecError("must be > 0", where="--track-weight")
            reference = GaitReference.read(track)
            reference.check_model(model, blade if model == "amputee" else None, "--track")
        x0 = read_parameters(init, layout, transfer=True) if init is not None else None
        seed_list = _parse_list(seeds, "--seeds", int)

        def show(seed: int, gen: int, best: float, median: float) -> None:
            typer.echo(f"seed {seed} generation {gen}: best {best:.4g}, median {median:.4g}")

        results = optimize_seeds(
            model,
            seeds=seed_list,
            out=out,
            progress=show,
            blade=blade,
            speed=speed,
            x0=x0,
            generations=generations,
            popsize=popsize,
            sigma=sigma,
            jobs=jobs,
            executor=executor,
            resume=resume,
            force=force,
            checkpoint_every=checkpoint_every,
            settings=ObjectiveSettings(
                speed=speed,
                duration=duration,
                dt=dt,
                robust_samples=robust_samples,
                robust_jitter=robust_jitter,
                robust_directions=robust_directions,
                robust_speed_change=robust_speed_change,
                robust_push=robust_push,
                robust_half_step=robust_half_step,
                initial_speed=initial_speed,
                strike_limit_bw=strike_limit,
                w_lean=lean_weight,
                run_up=run_up,
                integrator=integrator,
                track=None if track is None else str(track),
                w_track=0.0 if track is None else track_weight,
            ),
        )
        best = min(results, key=lambda r: r.best_cost)
        typer.echo(json.dumps(best.to_dict(), indent=2))

    @app.command("sweep")
    def sweep(
        out: Path = typer.Option(..., "--out", help="Output folder (re-run to continue)."),
        categories: str = typer.Option("Cat4,Cat5,Cat6,Cat6High,Cat7", "--categories"),
        speeds: str = typer.Option("3.5,4.0,4.5,5.0", "--speeds", help="Speeds (m/s), rising."),
        init: Path | None = typer.Option(None, "--init", help="Amputee parameters JSON."),
        generations: int = typer.Option(100, "--generations"),
        popsize: int = typer.Option(16, "--popsize"),
        sigma: float = typer.Option(
            1.0, "--sigma", help="Initial step (× parameter scale); 0.05–0.2 from a solution."
        ),
        seed: int = typer.Option(1, "--seed"),
        jobs: int = typer.Option(1, "--jobs"),
        executor: str = typer.Option("local", "--executor", help="local | ray"),
        duration: float = typer.Option(10.0, "--duration", help="Simulated time (s)."),
        dt: float = typer.Option(DEFAULT_DT, "--dt", help="Time step (s)."),
        robust_samples: int = typer.Option(
            1, "--robust-samples", help="Simulations per candidate (nominal + jittered copies)."
        ),
        robust_jitter: float = typer.Option(
            1e-6, "--robust-jitter", help="Relative parameter jitter of the copies."
        ),
        initial_speed: float | None = typer.Option(
            None,
            "--initial-speed",
            help="Forward speed of every cell's initial state (m/s); default the first speed.",
        ),
        checkpoint_every: int = typer.Option(5, "--checkpoint-every", help="Generations."),
        chain_from: str | None = typer.Option(
            None, "--chain-from", help="Warm-start categories outwards from this one (e.g. Cat6)."
        ),
        method: str = typer.Option(
            "reflex", "--method", help="reflex (CMA-ES on the reflex controller) | collocation "
            "(speed continuation and maximum speed by direct collocation, CasADi + IPOPT)."
        ),
        able: bool = typer.Option(
            False, "--able", help="Collocation: sweep the able model too (first)."
        ),
        mesh: int | None = typer.Option(
            None, "--mesh", help=f"Collocation: mesh intervals of the stride [default: {COLLOCATION_MESH}]."
        ),
        guess: str | None = typer.Option(
            None, "--guess", help="Collocation: initial guess of each model's first speed: "
            "template | trial | FILE [default: template]."
        ),
        max_iter: int | None = typer.Option(
            None, "--max-iter", help=f"Collocation: IPOPT iterations per stage [default: {COLLOCATION_MAX_ITER}]."
        ),
        resume: bool = typer.Option(
            False, "--resume", help="Collocation: continue the sweep in --out (done solves "
            "are read back)."
        ),
        force: bool = typer.Option(
            False, "--force", help="Collocation: start over in an --out that holds a sweep."
        ),
        as_json: bool = typer.Option(
            False, "--json", help="Collocation: print the table as one JSON object."
        ),
        starts: int | None = typer.Option(
            None, "--starts", help="Collocation: solve each problem from up to K starts (warm "
            "start, barrier start 1e-4, template, previous-but-one solution) and keep the "
            "best [default: 1]."
        ),
        body: str | None = typer.Option(
            None, "--body", help="Collocation: seed001 (seed 001's model) | toes (a toe "
            "segment and compliant Achilles tendons) [default: seed001]."
        ),
        recipe: str | None = typer.Option(
            None, "--recipe", help="Reflex: run a recipe of stages per category and seed "
            "instead of the speed grid: stable-gait (issue 20's stages, then speed "
            "continuation on the speed reached) | FILE (a recipe JSON); 'able' among "
            "--categories adds the able-bodied runner."
        ),
        seeds: str | None = typer.Option(
            None, "--seeds", help="Reflex, with --recipe: CMA-ES seeds per category "
            "[default: 1,2,3]."
        ),
        track_study: Path | None = typer.Option(
            None, "--track-study", help="Reflex, with --recipe: the collocation study whose "
            "strides the tracking stages follow (amputee-<category>/speed-<v>.json)."
        ),
    ) -> None:
        """Category × speed grid: warm-started optimisations, maximum speed, cost at 4 m/s,
        200 m and 400 m times, contact times (seed 001 §2.2.2 B–C, Table 3.1). Running it again
        with the same --out continues: finished cells are read back, interrupted ones resumed.

        With --method collocation: per model (--able, and the amputee with each category), the
        speed continuation over --speeds (each speed warm-started from the previous solution)
        and the maximum speed; DIR/<model>/speed-<v>.json, max-speed.json and the table
        DIR/collocation-sweep.csv. A used --out needs --resume or --force; exit status 2 when a
        model failed (after the others). --starts K solves each problem from up to K starts
        and keeps the best. The CMA-ES options do not apply.

        With --recipe: per category and seed (--seeds), the recipe's stages, each warm-started
        from the one before, then the speed raised by continuation on the speed reached;
        DIR/<category>/seed-<n>/ (one folder per level, levels.json), DIR/levels.csv and
        DIR/summary.csv (whether each category's seeds agree, maximum speeds). The grid options
        (--speeds, --generations, --popsize, --sigma, --duration, --dt, --robust-*) are the
        recipe's. Running it again with the same --out continues."""
        if method == "collocation":
            from bladelab.cli.collocation_sweep import run_collocation_sweep

            for given, option in ((init is not None, "--init"),
                                  (chain_from is not None, "--chain-from")):
                if given:
                    raise SpecError("only with --method reflex", where=option)
            code = run_collocation_sweep(
                out=out, categories=categories, able=able, speeds=speeds,
                mesh=50 if mesh is None else mesh,
                guess="template" if guess is None else guess,
                max_iter=3000 if max_iter is None else max_iter, jobs=jobs,
                executor=executor, resume=resume, force=force, as_json=as_json,
                starts=1 if starts is None else starts,
                body="seed001" if body is None else body)
            raise typer.Exit(code)
        if method != "reflex":
            raise SpecError(f"unknown method {method!r}", where="--method",
                            hint="reflex or collocation")
        for given, option in ((able, "--able"), (mesh is not None, "--mesh"),
                              (guess is not None, "--guess"), (max_iter is not None, "--max-iter"),
                              (resume, "--resume"), (force, "--force"), (as_json, "--json"),
                              (starts is not None, "--starts"), (body is not None, "--body")):
            if given:
                raise SpecError("only with --method collocation", where=option,
                                hint="a reflex sweep continues by itself in the same --out")
        if recipe is not None:
            for given, option in ((initial_speed is not None, "--initial-speed"),
                                  (chain_from is not None, "--chain-from")):
                if given:
                    raise SpecError("not with --recipe (the recipe sets it)", where=option)
            _run_recipe_sweep(out, categories, recipe, seeds, track_study, init, jobs,
                              executor, checkpoint_every)
            return
        for given, option in ((seeds is not None, "--seeds"),
                              (track_study is not None, "--track-study")):
            if given:
                raise SpecError("only with --recipe", where=option)
        from bladelab.predict.reflex.sweep import run_sweep

        if not (math.isfinite(duration) and duration > 0):
            raise SpecError("must be positive", where="--duration")
        _check_simulation_options(dt, robust_samples, robust_jitter)
        if init is not None and not init.is_file():
            raise SpecError("file not found", file=init, where="--init")
        table = run_sweep(
            _parse_list(categories, "--categories"),
            _parse_list(speeds, "--speeds", float),
            out=out,
            init=init,
            generations=generations,
            popsize=popsize,
            sigma=sigma,
            seed=seed,
            jobs=jobs,
            executor=executor,
            duration=duration,
            dt=dt,
            robust_samples=robust_samples,
            robust_jitter=robust_jitter,
            initial_speed=initial_speed,
            checkpoint_every=checkpoint_every,
            chain_from=chain_from,
        )
        typer.echo(table.to_string(index=False))
