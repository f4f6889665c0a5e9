"""``bladelab predict`` and ``bladelab sweep``: predictive running (seed 001 §2.2).

Each command has two methods behind ``--method``: ``reflex`` (CMA-ES on the reflex controller,
:mod:`bladelab.cli.reflex`) and ``collocation`` (direct collocation with CasADi and IPOPT,
:mod:`bladelab.cli.collocation`, :mod:`bladelab.cli.collocation_sweep`). Every option sits in
one help panel, and the panel says which method it belongs to (:data:`PREDICT_PANELS`,
:data:`SWEEP_PANELS`): ``--help`` lists the options panel by panel, and an option given for
another method is refused, naming the option and its method
(:func:`~bladelab.cli.panels.refuse_other_methods`). The option defaults are the library's
(:mod:`bladelab.predict.defaults`, which imports nothing: ``--help`` stays fast).
"""

from __future__ import annotations

from pathlib import Path

import typer

from bladelab.cli.collocation_options import (
    COLLOCATION,
    alternating_steps_option,
    athlete_from_options,
    athlete_option,
    people_weight_option,
    static_option,
    swing_knee_option,
)
from bladelab.cli.panels import Panel, PanelCommand, refuse_other_methods
from bladelab.errors import SpecError
from bladelab.predict import defaults

__all__ = ["METHODS", "PREDICT_PANELS", "SWEEP_PANELS", "register"]

#: The methods of ``--method``.
METHODS = ("reflex", "collocation")

COMMON = "Common"
REFLEX = "Reflex controller (CMA-ES)"
GRID = "Reflex speed grid (without --recipe)"
RECIPE = "Reflex recipe (with --recipe)"

#: ``bladelab predict``: its panels and the methods their options belong to.
PREDICT_PANELS = (Panel(COMMON), Panel(REFLEX, ("reflex",)),
                  Panel(COLLOCATION, ("collocation",)))
#: ``bladelab sweep``: the reflex method runs the speed grid, or with ``--recipe`` a recipe.
SWEEP_PANELS = (Panel(COMMON), Panel(REFLEX, ("reflex", "recipe")), Panel(GRID, ("reflex",)),
                Panel(RECIPE, ("recipe",)), Panel(COLLOCATION, ("collocation",)))
#: How the command line selects each method (in error messages).
LABELS = {"reflex": "--method reflex", "recipe": "--recipe",
          "collocation": "--method collocation"}
#: Hints added to the error of an option given for another method.
PREDICT_HINTS = {
    "--tilt-range": "the reflex objective's pelvis window: --lean-weight",
}
SWEEP_HINTS = {
    "--resume": "a reflex sweep continues by itself in the same --out",
    "--force": "a reflex sweep continues by itself in the same --out",
    **{option: "the recipe sets it" for option in (
        "--generations", "--popsize", "--sigma", "--seed", "--duration", "--dt",
        "--robust-samples", "--robust-jitter", "--initial-speed", "--chain-from")},
}

_METHOD_HELP = ("reflex: CMA-ES on the reflex controller | collocation: {what} by direct "
                "collocation (CasADi + IPOPT).")


def _method(method: str) -> str:
    if method not in METHODS:
        raise SpecError(f"unknown method {method!r}", where="--method",
                        hint=" or ".join(METHODS))
    return method


def _csv(values) -> str:
    return ",".join(str(v) for v in values)


def register(app: typer.Typer) -> None:
    @app.command("predict", cls=PanelCommand)
    def predict(
        ctx: typer.Context,
        # -- common ----------------------------------------------------------------------
        out: Path = typer.Option(
            ..., "--out", rich_help_panel=COMMON,
            help="Output folder: the reflex run's checkpoint and best.json, or the collocation "
                 "solve's solution.json."),
        method: str = typer.Option(
            defaults.METHOD, "--method", rich_help_panel=COMMON,
            help=_METHOD_HELP.format(what="one periodic stride")),
        model: str = typer.Option(
            "able", "--model", rich_help_panel=COMMON,
            help="able | amputee | transfemoral (the transfemoral runner: collocation "
                 "only)."),
        blade: str | None = typer.Option(
            None, "--blade", rich_help_panel=COMMON,
            help=f"Blade category of the amputee [default: {defaults.REFLEX_BLADE}; "
                 "collocation: the runner's own blade, Cat4 for the transfemoral runner]."),
        speed: float = typer.Option(
            defaults.SPEED_M_PER_S, "--speed", rich_help_panel=COMMON,
            help="Prescribed mean speed [m/s]."),
        resume: bool = typer.Option(
            False, "--resume", rich_help_panel=COMMON,
            help="Continue from the checkpoint (reflex) or from the folder's solve "
                 "(collocation)."),
        force: bool = typer.Option(
            False, "--force", rich_help_panel=COMMON,
            help="Start over in an --out that holds a run (replacing it)."),
        # -- reflex controller (CMA-ES) ----------------------------------------------------
        init: Path | None = typer.Option(
            None, "--init", rich_help_panel=REFLEX, help="Warm start: parameters JSON."),
        seeds: str = typer.Option(
            str(defaults.SEED), "--seeds", rich_help_panel=REFLEX,
            help="Comma-separated CMA-ES seeds: one run each."),
        generations: int = typer.Option(
            defaults.GENERATIONS, "--generations", rich_help_panel=REFLEX,
            help="CMA-ES generations."),
        popsize: int = typer.Option(
            defaults.POPULATION_SIZE, "--popsize", rich_help_panel=REFLEX,
            help="Candidates per generation."),
        sigma: float = typer.Option(
            defaults.INITIAL_STEP, "--sigma", rich_help_panel=REFLEX,
            help="Initial step [× parameter scale]."),
        jobs: int = typer.Option(1, "--jobs", rich_help_panel=REFLEX,
                                 help="Parallel worker processes."),
        executor: str = typer.Option("local", "--executor", rich_help_panel=REFLEX,
                                     help="local | ray"),
        checkpoint_every: int = typer.Option(
            defaults.CHECKPOINT_EVERY, "--checkpoint-every", rich_help_panel=REFLEX,
            help="Generations between two checkpoints."),
        duration: float = typer.Option(
            defaults.DURATION_S, "--duration", rich_help_panel=REFLEX,
            help="Simulated time [s]."),
        dt: float = typer.Option(
            defaults.TIME_STEP_S, "--dt", rich_help_panel=REFLEX,
            help="Time step [s]; 5e-4 only for quick exploratory runs."),
        robust_samples: int = typer.Option(
            defaults.ROBUST_SAMPLES, "--robust-samples", rich_help_panel=REFLEX,
            help="Simulations per candidate (nominal + jittered copies)."),
        robust_jitter: float = typer.Option(
            defaults.ROBUST_JITTER, "--robust-jitter", rich_help_panel=REFLEX,
            help="Relative parameter jitter of the copies [-]."),
        robust_directions: str = typer.Option(
            defaults.ROBUST_DIRECTIONS, "--robust-directions", rich_help_panel=REFLEX,
            help="fixed (the copies' jitter directions drawn once per run) | per-generation "
                 "(drawn anew every generation; the best so far is simulated on each "
                 "generation's copies too)."),
        robust_speed_change: float = typer.Option(
            0.0, "--robust-speed-change", rich_help_panel=REFLEX,
            help="Start the copies at (1 + s), (1 - s), ... × the initial speed (relative "
                 "[-]; 0.05: the ±5 % acceptance test inside the objective)."),
        robust_push: float = typer.Option(
            0.0, "--robust-push", rich_help_panel=REFLEX,
            help="Push each copy once in mid-run: its forward speed times (1 + p), (1 - p), "
                 "... at a seeded time (relative [-]; tests the gait's basin)."),
        robust_half_step: bool = typer.Option(
            False, "--robust-half-step", rich_help_panel=REFLEX,
            help="Run the last copy at half the time step (a gait must not live on the "
                 "discretisation; needs --robust-samples 2 or more)."),
        initial_speed: float | None = typer.Option(
            None, "--initial-speed", rich_help_panel=REFLEX,
            help="Forward speed of the initial state [m/s]; default --speed."),
        strike_limit: float = typer.Option(
            defaults.STRIKE_LIMIT_BW, "--strike-limit", rich_help_panel=REFLEX,
            help="A step whose swinging foot strikes the ground earns max(0, 1 - peak/limit) "
                 "of its credit [body weights]; the stable-gait acceptance allows at most "
                 "0.2 body weights."),
        lean_weight: float = typer.Option(
            defaults.LEAN_WEIGHT_PER_DEG, "--lean-weight", rich_help_panel=REFLEX,
            help="Weight of the pelvis tilt outside -16...-2 deg [1/deg], averaged over the "
                 "run (seed 001's)."),
        run_up: bool = typer.Option(
            False, "--run-up", rich_help_panel=REFLEX,
            help="The reflexes on the mean forward speed act from the start, as if the "
                 "runner had moved at the initial speed before it (else they wait for a full "
                 "window of the run)."),
        integrator: str | None = typer.Option(
            None, "--integrator", rich_help_panel=REFLEX, show_default=False,
            help="explicit (the 0.25 ms scheme; the default on seed 001's and the toes body, "
                 "whose joint dampers it integrates) | newmark "
                 "(stiff forces linearly implicit, second-order rule, at --dt 1e-3 more "
                 "accurate than explicit at 0.25 ms and 4x cheaper; the default on the human "
                 "body, whose toes' dampers the explicit scheme cannot integrate) | implicit "
                 "(its first-order predecessor, for runs made with it)."),
        track: Path | None = typer.Option(
            None, "--track", rich_help_panel=REFLEX,
            help="Add a term that pulls the gait towards this collocation stride of the same "
                 "runner (solution.json; its joint angles and stride time, stride by stride); "
                 "then run again with --init OUT/best.json and no --track."),
        track_weight: float = typer.Option(
            defaults.TRACK_WEIGHT_PER_RAD2, "--track-weight", rich_help_panel=REFLEX,
            help="Weight of the tracking term [1/rad²] (with --track)."),
        start_stride: Path | None = typer.Option(
            None, "--start-stride", rich_help_panel=REFLEX, show_default=False,
            help="Start every simulation from this collocation stride's state at its first "
                 "leg's touch-down (solution.json of the same runner), moving at "
                 "--initial-speed or --speed, instead of SCONE's gait state."),
        hold: str | None = typer.Option(
            None, "--hold", rich_help_panel=REFLEX, show_default=False,
            help="Keep the parameters whose names match these comma-separated patterns at "
                 "their start values (names as in a parameter file; * and ? match), e.g. "
                 "'*-pelvis_tx.*' (the foot placement) or 'S11100.iliopsoas_?-hamstrings.*'."),
        # -- collocation -------------------------------------------------------------------
        max_speed: bool = typer.Option(
            False, "--max-speed", rich_help_panel=COLLOCATION,
            help="Maximise the mean speed instead of prescribing --speed."),
        mesh: int = typer.Option(
            defaults.MESH_INTERVALS, "--mesh", rich_help_panel=COLLOCATION,
            help="Mesh intervals of the stride."),
        guess: str = typer.Option(
            defaults.GUESS, "--guess", rich_help_panel=COLLOCATION,
            help="Initial guess: stored (the shipped stride of the model on the human body; "
                 "else the trial) | trial (the Fukuchi 3.5 m/s trial) | template | FILE "
                 "(solution.json, best_iterate.json or reflex JSON)."),
        max_iter: int = typer.Option(
            defaults.MAX_ITER, "--max-iter", rich_help_panel=COLLOCATION,
            help="IPOPT iterations per stage."),
        as_json: bool = typer.Option(
            False, "--json", rich_help_panel=COLLOCATION,
            help="Print the summary as one JSON object."),
        body: str | None = typer.Option(
            None, "--body", rich_help_panel=COMMON, show_default=False,
            help="human (H0918's segments and muscles, compliant Achilles, toes, soft heel "
                 "pad) | seed001 (seed 001's model) | toes (seed 001's with a toe segment and "
                 f"compliant Achilles tendons); docs/runner-model.md. Default: {defaults.BODY} "
                 f"for collocation, {defaults.REFLEX_BODY} for the reflex controller (its "
                 "parameters and reflex starts are that body's)."),
        swing_clearance: float = typer.Option(
            0.0, "--swing-clearance", rich_help_panel=COLLOCATION,
            help="Keep every swinging foot or blade this high above the ground [m] (0: no "
                 "constraint)."),
        knee_moment_min: float | None = typer.Option(
            None, "--knee-moment-min", rich_help_panel=COLLOCATION,
            help="Transfemoral runner: keep the ground force's extension moment about the "
                 "prosthetic knee at or above this [N·m] (<= 0; 0: the knee never buckles)."),
        knee_flexion_max: float | None = typer.Option(
            None, "--knee-flexion-max", rich_help_panel=COLLOCATION,
            help="Transfemoral runner: keep the prosthetic knee within this flexion [deg] "
                 "while its blade is loaded (the straight stance)."),
        tilt_range: str | None = typer.Option(
            None, "--tilt-range", rich_help_panel=COLLOCATION,
            help="Keep the pelvis tilt within LO,HI [deg] at every node (forward lean "
                 "negative), e.g. --tilt-range=-16,-2 (seed 001's window)."),
        stride_time: str | None = typer.Option(
            None, "--stride-time", rich_help_panel=COLLOCATION, show_default=False,
            help="Keep the stride time within LO,HI [s], or at T [s] (an athlete's measured "
                 "cadence: imposed, not predicted, and the report says so), e.g. "
                 "--stride-time 0.64,0.78; or 'people': within measured runners' band at "
                 "the speed (0.62-0.76 s at 4 m/s). Default: free (0.4-1.2 s)."),
        alternating_steps: float | None = alternating_steps_option(),
        symmetric: bool = typer.Option(
            False, "--symmetric", rich_help_panel=COLLOCATION,
            help="Able runner: each leg does what the other did half a stride earlier "
                 "(bilateral symmetry, as PredSim imposes it; an even --mesh)."),
        prosthetic_load_max: float | None = typer.Option(
            None, "--prosthetic-load-max", rich_help_panel=COLLOCATION, show_default=False,
            help="Keep the prosthetic leg's vertical ground force at or below this many body "
                 "weights (the load the residual limb takes in its socket; default: no "
                 "limit)."),
        people_weight: float | None = people_weight_option(),
        swing_knee: float | None = swing_knee_option(),
        body_mass: float | None = athlete_option("body_mass_kg"),
        height: float | None = athlete_option("height_m"),
        muscle_strength: float | None = athlete_option("muscle_strength"),
        max_shortening_velocity: float | None = athlete_option("max_shortening_velocity"),
        residual_limb: float | None = athlete_option("residual_limb_length_m"),
        thigh_length: float | None = athlete_option("thigh_length_m"),
        shank_length: float | None = athlete_option("shank_length_m"),
        prosthesis_extra_length: float | None = athlete_option("prosthesis_extra_length_m"),
        static: Path | None = static_option(),
        starts: int | None = typer.Option(
            None, "--starts", rich_help_panel=COLLOCATION, show_default=False,
            help="Solve the stride from up to K starts (the guess, the guess with the "
                 "barrier started at 1e-4, the template, the guess's primal values with "
                 "IPOPT's default barrier) and keep the best; each start's "
                 f"solve in OUT/starts/. Default: {defaults.ATHLETE_STARTS} for an athlete "
                 "scaled by --body-mass, --height, --muscle-strength, "
                 "--max-shortening-velocity, --residual-limb, --thigh-length, "
                 "--shank-length, --prosthesis-extra-length or --static (one start can land "
                 f"17 % too high there), else {defaults.STARTS}."),
        mesh_check: bool = typer.Option(
            False, "--mesh-check", rich_help_panel=COLLOCATION,
            help="After the solve, solve the same problem on twice the mesh intervals from "
                 "the stride and say what it moved (objective, stride time, cost of "
                 "transport, contacts, peaks; settled: objective and stride time within 1 %); "
                 "kept in OUT/mesh-check/, shown in the report. About 2-5 times the solve's "
                 "time."),
    ) -> None:
        """Predict a running gait: solve one periodic stride of the human body by direct
        collocation (writes DIR/solution.json; exit status 2 and DIR/best_iterate.json if
        IPOPT does not converge), or with --method reflex optimise seed 001's reflex
        controller with CMA-ES (seed 001 eq. 2.4). An option of the other method is
        refused."""
        method = _method(method)
        refuse_other_methods(ctx, method, PREDICT_PANELS, labels=LABELS, hints=PREDICT_HINTS)
        if method == "collocation":
            # deferred: keeps bladelab --help fast
            from bladelab.cli.collocation import run_collocation

            raise typer.Exit(run_collocation(
                out=out, model=model, blade=blade, speed=speed, max_speed=max_speed, mesh=mesh,
                guess=guess, max_iter=max_iter, resume=resume, force=force, as_json=as_json,
                body=body or defaults.BODY, swing_clearance=swing_clearance,
                knee_moment_min=knee_moment_min,
                knee_flexion_max=knee_flexion_max, tilt_range=tilt_range,
                stride_time=stride_time,
                alternating_steps=alternating_steps, prosthetic_load_max=prosthetic_load_max,
                people_weight=people_weight, swing_knee=swing_knee, symmetric=symmetric,
                athlete=athlete_from_options(static, body_mass_kg=body_mass, height_m=height,
                                 muscle_strength=muscle_strength,
                                 max_shortening_velocity=max_shortening_velocity,
                                 residual_limb_length_m=residual_limb,
                                 thigh_length_m=thigh_length, shank_length_m=shank_length,
                                 prosthesis_extra_length_m=prosthesis_extra_length),
                starts=starts, mesh_check=mesh_check))
        from bladelab.cli.reflex import run_reflex  # deferred: keeps bladelab --help fast

        body = body or defaults.REFLEX_BODY
        run_reflex(
            out=out, model=model, blade=blade, body=body, speed=speed,
            init=init, seeds=seeds,
            generations=generations, popsize=popsize, sigma=sigma, jobs=jobs,
            executor=executor, resume=resume, force=force, checkpoint_every=checkpoint_every,
            duration=duration, dt=dt, robust_samples=robust_samples,
            robust_jitter=robust_jitter, robust_directions=robust_directions,
            robust_speed_change=robust_speed_change, robust_push=robust_push,
            robust_half_step=robust_half_step, initial_speed=initial_speed,
            strike_limit=strike_limit, lean_weight=lean_weight, run_up=run_up,
            integrator=integrator, track=track,
            track_weight=track_weight,
            start_stride=start_stride, hold=hold)

    @app.command("sweep", cls=PanelCommand)
    def sweep(
        ctx: typer.Context,
        # -- common ----------------------------------------------------------------------
        out: Path = typer.Option(..., "--out", rich_help_panel=COMMON,
                                 help="Output folder (re-run to continue)."),
        method: str = typer.Option(
            "reflex", "--method", rich_help_panel=COMMON,
            help=_METHOD_HELP.format(what="speed continuation and maximum speed")),
        categories: str = typer.Option(
            _csv(defaults.SWEEP_CATEGORIES), "--categories", rich_help_panel=COMMON,
            help="Blade categories, comma-separated."),
        speeds: str = typer.Option(
            _csv(defaults.SWEEP_SPEEDS_M_PER_S), "--speeds", rich_help_panel=COMMON,
            help="Speeds [m/s], rising, comma-separated (not used by a recipe, which raises "
                 "the speed by continuation)."),
        jobs: int = typer.Option(1, "--jobs", rich_help_panel=COMMON,
                                 help="Parallel worker processes."),
        executor: str = typer.Option("local", "--executor", rich_help_panel=COMMON,
                                     help="local | ray"),
        # -- reflex controller (CMA-ES), grid and recipe -----------------------------------
        init: Path | None = typer.Option(
            None, "--init", rich_help_panel=REFLEX, help="Amputee parameters JSON."),
        checkpoint_every: int = typer.Option(
            defaults.CHECKPOINT_EVERY, "--checkpoint-every", rich_help_panel=REFLEX,
            help="Generations between two checkpoints."),
        # -- reflex speed grid -------------------------------------------------------------
        generations: int = typer.Option(
            defaults.GENERATIONS, "--generations", rich_help_panel=GRID,
            help="CMA-ES generations."),
        popsize: int = typer.Option(
            defaults.POPULATION_SIZE, "--popsize", rich_help_panel=GRID,
            help="Candidates per generation."),
        sigma: float = typer.Option(
            defaults.INITIAL_STEP, "--sigma", rich_help_panel=GRID,
            help="Initial step [× parameter scale]; 0.05–0.2 from a solution."),
        seed: int = typer.Option(defaults.SEED, "--seed", rich_help_panel=GRID,
                                 help="CMA-ES seed."),
        duration: float = typer.Option(
            defaults.DURATION_S, "--duration", rich_help_panel=GRID,
            help="Simulated time [s]."),
        dt: float = typer.Option(defaults.TIME_STEP_S, "--dt", rich_help_panel=GRID,
                                 help="Time step [s]."),
        robust_samples: int = typer.Option(
            defaults.ROBUST_SAMPLES, "--robust-samples", rich_help_panel=GRID,
            help="Simulations per candidate (nominal + jittered copies)."),
        robust_jitter: float = typer.Option(
            defaults.ROBUST_JITTER, "--robust-jitter", rich_help_panel=GRID,
            help="Relative parameter jitter of the copies [-]."),
        initial_speed: float | None = typer.Option(
            None, "--initial-speed", rich_help_panel=GRID,
            help="Forward speed of every cell's initial state [m/s]; default the first "
                 "speed."),
        chain_from: str | None = typer.Option(
            None, "--chain-from", rich_help_panel=GRID,
            help="Warm-start categories outwards from this one (e.g. Cat6)."),
        # -- reflex recipe -----------------------------------------------------------------
        recipe: str | None = typer.Option(
            None, "--recipe", rich_help_panel=REFLEX,
            help="Run a recipe of stages per category and seed instead of the speed grid: "
                 "stable-gait (stages that track a collocation stride, then make the gait "
                 "survive a long horizon, pushes, other starts, and penalise swing strikes "
                 "and lean; then speed continuation on the speed reached) | FILE (a recipe "
                 "JSON); 'able' among --categories adds the able-bodied runner."),
        seeds: str = typer.Option(
            _csv(defaults.RECIPE_SEEDS), "--seeds", rich_help_panel=RECIPE,
            help="CMA-ES seeds per category, comma-separated."),
        track_study: Path | None = typer.Option(
            None, "--track-study", rich_help_panel=RECIPE,
            help="The collocation study whose strides the tracking stages follow "
                 "(amputee-<category>/speed-<v>.json)."),
        # -- collocation -------------------------------------------------------------------
        able: bool = typer.Option(False, "--able", rich_help_panel=COLLOCATION,
                                  help="Sweep the able model too (first); with "
                                       "--categories '' the able model alone."),
        mesh: int = typer.Option(defaults.MESH_INTERVALS, "--mesh", rich_help_panel=COLLOCATION,
                                 help="Mesh intervals of the stride."),
        guess: str = typer.Option(
            defaults.GUESS, "--guess", rich_help_panel=COLLOCATION,
            help="Initial guess of each model's first speed: stored | trial | template | "
                 "FILE."),
        max_iter: int = typer.Option(defaults.MAX_ITER, "--max-iter",
                                     rich_help_panel=COLLOCATION,
                                     help="IPOPT iterations per stage."),
        resume: bool = typer.Option(
            False, "--resume", rich_help_panel=COLLOCATION,
            help="Continue the sweep in --out (done solves are read back)."),
        force: bool = typer.Option(False, "--force", rich_help_panel=COLLOCATION,
                                   help="Start over in an --out that holds a sweep."),
        as_json: bool = typer.Option(False, "--json", rich_help_panel=COLLOCATION,
                                     help="Print the table as one JSON object."),
        starts: int = typer.Option(
            defaults.STARTS, "--starts", rich_help_panel=COLLOCATION,
            help="Solve each problem from up to K starts (warm start, barrier start 1e-4, "
                 "template, previous-but-one solution, restart with IPOPT's default barrier) "
                 "and keep the best."),
        body: str = typer.Option(
            defaults.BODY, "--body", rich_help_panel=COLLOCATION,
            help="human (H0918's segments and muscles, compliant Achilles, toes, soft heel "
                 "pad) | seed001 (seed 001's model) | toes (seed 001's with a toe segment and "
                 "compliant Achilles tendons)."),
        people_weight: float | None = people_weight_option(),
        swing_knee: float | None = swing_knee_option(),
        alternating_steps: float | None = alternating_steps_option(),
        stride_time: str | None = typer.Option(
            None, "--stride-time", rich_help_panel=COLLOCATION, show_default=False,
            help="'people': keep every prescribed speed's stride time within measured "
                 "runners' band at that speed (0.62-0.76 s at 4 m/s; imposed, not predicted, "
                 "and each report says so); the maximum speed stays free. Default: free."),
        body_mass: float | None = athlete_option("body_mass_kg"),
        height: float | None = athlete_option("height_m"),
        muscle_strength: float | None = athlete_option("muscle_strength"),
        max_shortening_velocity: float | None = athlete_option("max_shortening_velocity"),
        residual_limb: float | None = athlete_option("residual_limb_length_m"),
        thigh_length: float | None = athlete_option("thigh_length_m"),
        shank_length: float | None = athlete_option("shank_length_m"),
        prosthesis_extra_length: float | None = athlete_option("prosthesis_extra_length_m"),
        static: Path | None = static_option(),
        mesh_check: bool = typer.Option(
            False, "--mesh-check", rich_help_panel=COLLOCATION,
            help="Solve every converged problem again on twice the mesh intervals from its "
                 "stride (DIR/<model>/mesh-check/) and add each one's changes and whether it "
                 "settled (objective and stride time within 1 %) to the table and the "
                 "report. About 2-5 times the sweep's time."),
        settle: bool = typer.Option(
            False, "--settle", rich_help_panel=COLLOCATION,
            help="After every model, solve each amputee problem again from the kept strides "
                 "of the two nearest categories (by stiffness) at the same problem, and each "
                 "of the able runner's problems from two of its own other strides (else its "
                 "shipped stride); keep the lowest (files speed-<v>.from-<category>.json, "
                 "speed-<v>.from-max-speed.json, speed-<v>.from-stored.json; "
                 "the spread in the table): starts that converge on the human body, where "
                 "the template's does not."),
    ) -> None:
        """Category × speed grid: warm-started optimisations, maximum speed, cost at 4 m/s,
        200 m and 400 m times, contact times (seed 001 §2.2.2 B–C, Table 3.1). Running it again
        with the same --out continues: finished cells are read back, interrupted ones resumed.

        With --recipe: per category and seed (--seeds), the recipe's stages, each warm-started
        from the one before, then the speed raised by continuation on the speed reached;
        DIR/<category>/seed-<n>/ (one folder per level, levels.json), DIR/levels.csv and
        DIR/summary.csv (whether each category's seeds agree, maximum speeds). The recipe sets
        its own speeds, generations, population, steps, durations, time steps and copies (the
        grid's options are refused). Running it again with the same --out continues.

        With --method collocation: per model (--able, and the amputee with each category), the
        speed continuation over --speeds (each speed warm-started from the previous solution)
        and the maximum speed; DIR/<model>/speed-<v>.json, max-speed.json and the table
        DIR/collocation-sweep.csv. A used --out needs --resume or --force; exit status 2 when a
        model failed (after the others). --starts K solves each problem from up to K starts
        and keeps the best; --settle adds the two nearest categories' strides as starts
        (the able runner's: its own other strides'); --mesh-check adds the settling evidence
        of every solve.

        An option of another method (or of the grid with --recipe) is refused."""
        method = _method(method)
        mode = "recipe" if method == "reflex" and recipe is not None else method
        refuse_other_methods(ctx, mode, SWEEP_PANELS, labels=LABELS, hints=SWEEP_HINTS)
        if mode == "collocation":
            # deferred: keeps bladelab --help fast
            from bladelab.cli.collocation_sweep import run_collocation_sweep

            raise typer.Exit(run_collocation_sweep(
                out=out, categories=categories, able=able, speeds=speeds, mesh=mesh,
                guess=guess, max_iter=max_iter, jobs=jobs, executor=executor, resume=resume,
                force=force, as_json=as_json, starts=starts, body=body,
                people_weight=people_weight, swing_knee=swing_knee,
                alternating_steps=alternating_steps,
                stride_time=stride_time,
                athlete=athlete_from_options(static, body_mass_kg=body_mass, height_m=height,
                                 muscle_strength=muscle_strength,
                                 max_shortening_velocity=max_shortening_velocity,
                                 residual_limb_length_m=residual_limb,
                                 thigh_length_m=thigh_length, shank_length_m=shank_length,
                                 prosthesis_extra_length_m=prosthesis_extra_length),
                mesh_check=mesh_check, settle=settle))
        from bladelab.cli import reflex  # deferred: keeps bladelab --help fast

        if mode == "recipe":
            reflex.run_recipe_sweep(out=out, categories=categories, recipe=recipe, seeds=seeds,
                                    track_study=track_study, init=init, jobs=jobs,
                                    executor=executor, checkpoint_every=checkpoint_every)
            return
        reflex.run_reflex_sweep(
            out=out, categories=categories, speeds=speeds, init=init, generations=generations,
            popsize=popsize, sigma=sigma, seed=seed, jobs=jobs, executor=executor,
            duration=duration, dt=dt, robust_samples=robust_samples,
            robust_jitter=robust_jitter, initial_speed=initial_speed,
            checkpoint_every=checkpoint_every, chain_from=chain_from)
