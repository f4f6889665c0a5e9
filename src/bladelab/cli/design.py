"""``bladelab design``: a response-surface design study; ``bladelab design gait-cycle``: the mean
gait cycle of a measured trial; ``bladelab blade test``: compression test.

``bladelab design``'s options sit in help panels by the evaluator they belong to
(:data:`DESIGN_PANELS`): an option given for another evaluator is refused, naming it and its
evaluator (:func:`~bladelab.cli.panels.refuse_other_methods`). The evaluator itself is built by
:func:`bladelab.design.settings.build_evaluator` from
:class:`~bladelab.design.settings.EvaluatorSettings`, the study run (and settled) by
:func:`bladelab.design.settling.run_settled_design`; the option defaults are the library's
(:mod:`bladelab.design.defaults`, which imports nothing: ``--help`` stays fast).

``bladelab blade test`` is added to the ``blade`` group of :mod:`bladelab.cli.blade` from here
(this module is registered after it).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import typer

from bladelab._io import figure_format
from bladelab.cli.blade import blade_app
from bladelab.cli.collocation_options import (
    ATHLETE_OPTIONS,
    athlete_from_options,
    athlete_option,
    static_option,
)
from bladelab.cli.panels import Panel, PanelGroup, refuse_other_methods, renamed
from bladelab.cli.values import parse_list
from bladelab.design import defaults
from bladelab.errors import BladelabError, SpecError

__all__ = ["DESIGN_PANELS", "OPTIONS", "register"]

STUDY = "Study"
BLADE_RUNNER = "Blade and runner evaluator"
RUNNER = "Runner evaluator"
COLLOCATION = "Collocation evaluator"
#: ``bladelab design``: its panels and the evaluators their options belong to.
DESIGN_PANELS = (Panel(STUDY), Panel(BLADE_RUNNER, ("blade", "runner")),
                 Panel(RUNNER, ("runner",)), Panel(COLLOCATION, ("collocation",)))
#: ``EvaluatorSettings`` field -> the option that sets it.
OPTIONS = {
    "kind": "--evaluator", "speed_mps": "--speed", "body_mass_kg": "--body-mass",
    "dt_s": "--dt", "base": "--base", "gait": "--gait", "motion": "--motion",
    "motion_model": "--motion-model", "start": "--start",
    "knee_moment_min_Nm": "--knee-moment-min",
    "knee_flexion_max_loaded_deg": "--knee-flexion-max",
    "reference_weight": "--reference-weight", "body": "--body", "amputation": "--amputation",
    "people_weight": "--people-weight", "step_phase_tolerance": "--alternating-steps",
    "prosthetic_load_max_bw": "--prosthetic-load-max",
    "stride_time_range_s": "--stride-time", "stride_time_people": "--stride-time",
    "max_speed": "--max-speed", "start_strides": "--start-strides", "mesh_intervals": "--mesh",
    "athlete.body_mass_kg": "--body-mass",
    **{f"athlete.{name}": flag for name, (flag, _) in ATHLETE_OPTIONS.items()},
}
_FACTORS = ",".join(f"{name}={low:g}:{high:g}" for name, low, high, *_ in defaults.DESIGN_FACTORS)


def _parse_floats(text: str, what: str) -> list[float]:
    vals = parse_list(text, what, float, hint="comma-separated numbers, e.g. --alignment 0,-8,8")
    if not all(math.isfinite(v) for v in vals):
        raise SpecError(f"no finite numbers in {text!r}", where=what)
    return vals


def _constraints(given: list[str]) -> dict[str, float | dict[str, float]]:
    """``--constraint`` (repeatable): ``response=minimum`` or ``response>=minimum`` as
    {response: minimum}, ``response<=maximum`` as {response: {"max": maximum}}."""
    cons: dict[str, float | dict[str, float]] = {}
    for c in given:
        match = re.fullmatch(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*(<=|>=|=)\s*(\S+)\s*", c)
        value = None
        if match:
            try:
                value = float(match.group(3))
            except ValueError:
                value = None
        if value is None or not math.isfinite(value):
            raise SpecError(f"cannot read constraint {c!r}", where="--constraint",
                            hint="write response=minimum or response<=maximum, e.g. "
                                 "knee_moment_min_Nm=0 or socket_moment_max_Nm<=150")
        name, relation = match.group(1), match.group(2)
        cons[name] = {"max": value} if relation == "<=" else value
    return cons


def _blade_test(
    blade: str = typer.Argument(..., help="Built-in blade name or blade spec file."),
    category: str | None = typer.Option(None, "--category", help="Stiffness category, e.g. cat5."),
    alignment: str = typer.Option(
        ",".join(f"{a:g}" for a in defaults.COMPRESSION_ALIGNMENTS_DEG), "--alignment",
        help="Alignment angles [deg], comma-separated."),
    body_mass: float = typer.Option(defaults.BODY_MASS_KG, "--body-mass",
                                    help="Body mass [kg] (load = m·g)."),
    max_displacement: float = typer.Option(defaults.COMPRESSION_MAX_DISPLACEMENT_M,
                                           "--max-displacement",
                                           help="Largest clamp displacement [m]."),
    tip: str = typer.Option("held", "--tip", help="held (seed 002's fixture) or free."),
    plot: Path | None = typer.Option(None, "--plot", help="Draw the force–displacement curves."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON (curves included)."),
) -> None:
    """Virtual compression test: force–displacement curve and stiffness at body-weight load."""
    if plot is not None:
        figure_format(plot)  # refuse an unknown image format before any work
    if not (body_mass > 0 and math.isfinite(body_mass)):
        raise SpecError(f"body mass must be > 0 kg, got {body_mass}", where="--body-mass")
    angles = _parse_floats(alignment, "--alignment")
    # deferred: keeps bladelab --help fast
    from bladelab.design.blade_test import plot_blade_test, virtual_blade_test

    result = virtual_blade_test(blade, category=category, alignments_deg=angles,
                                body_mass_kg=body_mass, max_displacement_m=max_displacement,
                                tip=tip)
    if result.tip_freed:
        typer.echo("note: this blade cannot compress with its support held (fewer than two "
                   "compliant joints between clamp and support); testing with tip free", err=True)
    if as_json:
        import json  # deferred: keeps bladelab --help fast

        typer.echo(json.dumps(result.to_dict(), indent=2))
    else:
        typer.echo(f"{result.blade}: virtual compression test (tip {result.tip}), load m·g = "
                   f"{result.load_N:.0f} N")
        typer.echo(" alignment_deg  k_linear_kN_per_m  k_at_bw_kN_per_m  displacement_at_bw_mm")
        for r in result.tests:
            at = ("not reached" if math.isnan(r.stiffness_at_load) else
                  f"{r.stiffness_at_load / 1e3:16.2f}  {r.displacement_at_load * 1e3:21.1f}")
            typer.echo(f"{r.alignment_deg:14.1f}  {r.stiffness_linear / 1e3:17.2f}  {at}")
    if plot is not None:
        plot_blade_test(result, plot)
        typer.echo(f"wrote {plot}", err=True)


def _design(
    ctx: typer.Context,
    # -- the study (every evaluator) -----------------------------------------------------
    factors: str | None = typer.Option(
        None, "--factors", rich_help_panel=STUDY,
        help=f"name=low:high,... in each factor's unit (default: {_FACTORS})."),
    runs: str = typer.Option(defaults.RUNS, "--runs", rich_help_panel=STUDY,
                             help="ccd, bbd, dopt or a CSV file of runs."),
    evaluator: str = typer.Option(
        "blade", "--evaluator", rich_help_panel=STUDY,
        help="blade (one passive stance), runner (a template gait cycle) or collocation (a "
             "predicted amputee stride per design, docs/design.md)."),
    out: Path | None = typer.Option(None, "--out", rich_help_panel=STUDY,
                                    help="Output folder (resumes an interrupted study); required."),
    seed: int = typer.Option(defaults.SEED, "--seed", rich_help_panel=STUDY,
                             help="Seed (D-optimal design, optimiser starts)."),
    jobs: int = typer.Option(1, "--jobs", rich_help_panel=STUDY,
                             help="Worker processes for the runs."),
    n_runs: int | None = typer.Option(None, "--n-runs", rich_help_panel=STUDY,
                                      help="Runs of a D-optimal design."),
    model: str = typer.Option(defaults.SURFACE_MODEL, "--model", rich_help_panel=STUDY,
                              help="Surface model: quadratic, linear, interaction, or terms."),
    objective: str = typer.Option(defaults.OBJECTIVE, "--objective", rich_help_panel=STUDY,
                                  help="Response to optimise."),
    sense: str = typer.Option(defaults.SENSE, "--sense", rich_help_panel=STUDY,
                              help="max or min."),
    constraint: list[str] = typer.Option(
        [], "--constraint", rich_help_panel=STUDY,
        help="response=minimum (or >=) or response<=maximum in the response's unit "
             "(repeatable), e.g. knee_moment_min_Nm=0 swing_clearance_m=0.02 "
             "socket_moment_max_Nm<=150."),
    speed: float | None = typer.Option(
        None, "--speed", rich_help_panel=STUDY,
        help=f"Touch-down speed [m/s] (default {defaults.BLADE_SPEED_MPS:g} blade, "
             f"{defaults.RUNNER_SPEED_MPS:g} runner); the stride's mean speed (collocation, "
             f"default {defaults.COLLOCATION_SPEED_MPS:g})."),
    base: str = typer.Option(defaults.BASE_BLADE, "--base", rich_help_panel=STUDY,
                             help="Base blade of the generator."),
    skip_failed: bool = typer.Option(
        False, "--skip-failed", rich_help_panel=STUDY,
        help="Record runs whose evaluation fails (runs/run_NNNN.failed.json, failed.csv), do "
             "not evaluate runs recorded as failed again, and fit the surfaces to the runs that "
             "finished (default: a failed run stops the study)."),
    figures: bool = typer.Option(True, "--figures/--no-figures", rich_help_panel=STUDY,
                                 help="Write figures."),
    body_mass: float | None = typer.Option(
        None, "--body-mass", rich_help_panel=STUDY,
        help=f"Body mass [kg]: blade and runner evaluators (default "
             f"{defaults.BODY_MASS_KG:g}); collocation: the athlete's (with the prosthesis; "
             "default the runner body's)."),
    # -- blade and runner evaluators -------------------------------------------------------
    dt: float | None = typer.Option(None, "--dt", rich_help_panel=BLADE_RUNNER,
                                    help="Simulation step [s] of the evaluator."),
    # -- runner evaluator ------------------------------------------------------------------
    gait: Path | None = typer.Option(None, "--gait", rich_help_panel=RUNNER,
                                     help="Gait-cycle CSV (default built-in)."),
    motion: Path | None = typer.Option(
        None, "--motion", rich_help_panel=RUNNER,
        help="Motion file (YAML/CSV: gait cycles with their blades): each design runs the "
             "cycle predicted by seed 002's motion model (not with --gait)."),
    motion_model: str | None = typer.Option(
        None, "--motion-model", rich_help_panel=RUNNER,
        help="Motion model: auto (quadratic if the cycles can estimate it, else linear), "
             "quadratic, linear, or terms (default: the file's model:, else auto)."),
    # -- collocation evaluator -------------------------------------------------------------
    start: Path | None = typer.Option(
        None, "--start", rich_help_panel=COLLOCATION,
        help="Collocation solution of the runner that the first design starts from "
             "(default: the built-in centre stride of the runner, where there is one); "
             "carried to a --speed more than 0.5 m/s from its own in 0.5 m/s steps first "
             "(strides/continuation/)."),
    start_strides: Path | None = typer.Option(
        None, "--start-strides", rich_help_panel=COLLOCATION, show_default=False,
        help="A folder of strides of the same designs (another study's strides/): each design "
             "starts from its own stride there first, e.g. the maximum-speed study from the "
             "4 m/s study's strides."),
    max_speed: bool = typer.Option(
        False, "--max-speed", rich_help_panel=COLLOCATION,
        help="Predict each design's maximum-speed stride (the speed free) instead of one at "
             "--speed; response max_speed_m_per_s [m/s]; with --stride-time people the stride "
             "time is held in people's band at the stride's own speed."),
    amputation: str | None = typer.Option(
        None, "--amputation", rich_help_panel=COLLOCATION, show_default=False,
        help="The runner's amputation: transfemoral (the default: seed 002's athlete, a passive "
             "prosthetic knee) or transtibial (the residual knee, the blade below it)."),
    knee_moment_min: float | None = typer.Option(
        None, "--knee-moment-min", rich_help_panel=COLLOCATION,
        help="Transfemoral: keep the prosthetic knee's extension moment at or above this "
             "[N·m] in every design's stride (<= 0; default: reported, not imposed)."),
    knee_flexion_max: float | None = typer.Option(
        None, "--knee-flexion-max", rich_help_panel=COLLOCATION,
        help="Transfemoral: keep the prosthetic knee within this flexion [deg] while loaded "
             "(the straight stance; default: free)."),
    reference_weight: float | None = typer.Option(
        None, "--reference-weight", rich_help_panel=COLLOCATION,
        help="Keep the athlete's own joints (trunk, intact leg, residual hip) near the start "
             "stride's, this weight [1/rad²] × their mean squared deviation added to the "
             "objective: every blade run with the same technique (docs/design.md; default 0: "
             "the gait predicted freely)."),
    body: str | None = typer.Option(
        None, "--body", rich_help_panel=COLLOCATION, show_default=False,
        help="The runner body: seed001 or human (predict's default body). Default: seed001 "
             "for the transfemoral runner, human for the transtibial one (the transfemoral "
             "runner on the human body needs --start: no clean stride of it is built in)."),
    people_weight: float | None = typer.Option(
        None, "--people-weight", rich_help_panel=COLLOCATION, show_default=False,
        help="Weight [1/rad²] of people's measured hip, knee and ankle angles in every "
             "design's objective (the intact leg and the residual hip; a tracking term of "
             "measured running, docs/collocation.md). Default: 10 on the human body, 0 on "
             "seed001 and with --reference-weight; 0: the gait predicted freely."),
    alternating_steps: float | None = typer.Option(
        None, "--alternating-steps", rich_help_panel=COLLOCATION, show_default=False,
        help="Keep every design's steps alternating: the prosthetic leg's stance half a "
             "stride +- this fraction of the stride after the intact leg's, e.g. 0.1 "
             "(default: free; free transfemoral strides gallop, docs/design.md)."),
    prosthetic_load_max: float | None = typer.Option(
        None, "--prosthetic-load-max", rich_help_panel=COLLOCATION, show_default=False,
        help="Keep every design's prosthetic leg's vertical ground force at or below this "
             "many body weights (the residual limb's load in its socket; default: no limit)."),
    stride_time: str | None = typer.Option(
        None, "--stride-time", rich_help_panel=COLLOCATION, show_default=False,
        help="Keep every design's stride time at people's: 'people' (measured runners' band "
             "at the speed), LO,HI or T [s]; imposed, not predicted (default: free)."),
    settle: int = typer.Option(
        0, "--settle", rich_help_panel=COLLOCATION,
        help="After the runs, up to this many settling passes (each design solved again from "
             "its 2 nearest neighbours' strides and the study's cheapest one, the lowest objective "
             "kept; stops when no "
             f"objective drops by more than {100 * defaults.SETTLED_REL:g} %). Recorded design "
             "by design in settling.json: a stopped pass resumes where it stopped."),
    mesh: int | None = typer.Option(
        None, "--mesh", rich_help_panel=COLLOCATION, show_default=False,
        help="Mesh intervals of every design's stride (default 50; a stride above 5 m/s wants "
             "100, docs/collocation.md)."),
    height: float | None = athlete_option("height_m", COLLOCATION),
    muscle_strength: float | None = athlete_option("muscle_strength", COLLOCATION),
    max_shortening_velocity: float | None = athlete_option("max_shortening_velocity",
                                                           COLLOCATION),
    residual_limb: float | None = athlete_option("residual_limb_length_m", COLLOCATION),
    thigh_length: float | None = athlete_option("thigh_length_m", COLLOCATION),
    shank_length: float | None = athlete_option("shank_length_m", COLLOCATION),
    prosthesis_extra_length: float | None = athlete_option("prosthesis_extra_length_m",
                                                           COLLOCATION),
    static: Path | None = static_option(COLLOCATION),
    confirm: bool = typer.Option(
        False, "--confirm", rich_help_panel=COLLOCATION,
        help="After the study, solve its optimum's blade as one more design (from its nearest "
             "strides, settled from its two nearest and the cheapest) and set it beside the "
             "surfaces' prediction: confirmation.json, the report's confirmation section."),
) -> None:
    """Run a design study: DOE -> evaluator per run -> surfaces, ANOVA, optimum, figures.

    ``bladelab design gait-cycle TRIAL.c3d ...`` makes a gait-cycle CSV for ``--gait``; a motion
    file of several such cycles (one per blade or trial) adapts the motion per design. An
    option of another evaluator is refused.
    """
    if ctx.invoked_subcommand is not None:
        return
    if out is None:
        raise typer.BadParameter("missing option '--out' (the study's output folder)",
                                 param_hint="--out")
    # deferred: keeps bladelab --help fast
    from bladelab.cli.collocation import stride_time_settings

    # deferred: keeps bladelab --help fast
    from bladelab.design import doe, settling, terms

    # deferred: keeps bladelab --help fast
    from bladelab.design.settings import EVALUATORS, EvaluatorSettings, build_evaluator

    # deferred: keeps bladelab --help fast
    from bladelab.design.space import DesignSpace, default_design_space

    if evaluator not in EVALUATORS:
        raise SpecError(f"unknown evaluator {evaluator!r}", where="--evaluator",
                        hint=", ".join(EVALUATORS))
    refuse_other_methods(ctx, evaluator, DESIGN_PANELS,
                         labels={e: f"--evaluator {e}" for e in EVALUATORS})
    space = DesignSpace.parse(factors) if factors else default_design_space()
    if jobs < 1:
        raise SpecError(f"--jobs must be >= 1, got {jobs}", where="--jobs")
    cons = _constraints(constraint)
    if gait is not None and motion is not None:
        raise SpecError("--gait (one cycle for every design) and --motion (a predicted cycle per "
                        "design) exclude each other", where="--gait/--motion",
                        hint="give one of them")
    if motion_model is not None and motion is None:
        raise SpecError("--motion-model needs --motion", where="--motion-model")
    if settle < 0:
        raise SpecError(f"--settle must be >= 0, got {settle}", where="--settle")
    if confirm and (evaluator != "collocation" or not objective):
        raise SpecError("--confirm solves the optimum of a study of predicted strides",
                        where="--confirm", hint="with --evaluator collocation and --objective")
    try:
        athlete = athlete_from_options(
            static, height_m=height, muscle_strength=muscle_strength,
            max_shortening_velocity=max_shortening_velocity,
            residual_limb_length_m=residual_limb, thigh_length_m=thigh_length,
            shank_length_m=shank_length, prosthesis_extra_length_m=prosthesis_extra_length)
        ev_settings = EvaluatorSettings(
            kind=evaluator, speed_mps=speed, body_mass_kg=body_mass, dt_s=dt, base=base,
            gait=gait, motion=motion, motion_model=motion_model, start=start,
            knee_moment_min_Nm=knee_moment_min, knee_flexion_max_loaded_deg=knee_flexion_max,
            reference_weight=reference_weight, body=body, amputation=amputation,
            people_weight=people_weight,
            step_phase_tolerance=alternating_steps,
            prosthetic_load_max_bw=prosthetic_load_max,
            max_speed=max_speed or None, start_strides=start_strides, athlete=athlete,
            mesh_intervals=mesh,
            **(stride_time_settings(stride_time) if stride_time is not None else {}))
    except BladelabError as err:
        raise renamed(err, OPTIONS) from None
    design = doe.make_design(runs, space, n_runs=n_runs, model=model, seed=seed)
    doe.require_estimable(design, terms.parse_terms(model, space.names), space.names)
    try:
        ev = build_evaluator(ev_settings, space, out, progress=True)
    except BladelabError as err:
        raise renamed(err, OPTIONS) from None
    if motion is not None:
        _echo_motion(ev.motion)
    result, settled = settling.run_settled_design(
        space, evaluator=ev, out_dir=out, settle_passes=settle, jobs=jobs, progress=typer.echo,
        runs=design, seed=seed, model=model, objective=objective, sense=sense,
        constraints=cons, units=ev.units, skip_failed=skip_failed)
    if settled is not None and not settled.settled:
        typer.echo(f"not settled after {settled.passes} passes (largest drop above "
                   f"{100 * settling.SETTLED_REL:g} %)", err=True)
    typer.echo(f"{design.n_runs} runs ({result.n_evaluated} evaluated, {result.n_resumed} "
               f"resumed) -> {out}")
    if result.failed:
        typer.echo(f"{len(result.failed)} runs failed and are left out of the surfaces "
                   f"(failed.csv): " + "; ".join(f"run {k}: {v[:120]}"
                                                  for k, v in result.failed.items()), err=True)
    for name, s in result.surfaces.items():
        typer.echo(f"  {name:22s} R² {s.r2:6.3f}  R²adj {s.r2_adj:6.3f}  R²pred {s.r2_pred:6.3f}")
    if result.optimum is not None:
        o = result.optimum
        pt = ", ".join(f"{k}={v:.4g}" for k, v in (o.point or o.coded).items())
        typer.echo(f"optimum ({o.sense} {objective}): {pt}; predicted {o.predicted:.4g} "
                   f"(PI {o.pi[0]:.4g} .. {o.pi[1]:.4g})")
    elif result.optimum_error:
        typer.echo(f"no optimum: {result.optimum_error}")
    if confirm:
        _confirm(ev, result)
    if figures:
        # deferred: matplotlib loads only when figures are written
        from bladelab.design.plots import write_design_figures

        for p in write_design_figures(result, out, objective=objective, constraints=cons):
            typer.echo(f"wrote {p}", err=True)


def _confirm(evaluator, result) -> None:
    """``--confirm``: the optimum solved (:func:`bladelab.design.confirmation.confirm_optimum`)
    and a line per response, predicted beside solved."""
    # deferred: keeps bladelab --help fast
    from bladelab.design.confirmation import CONFIRMATION_FILE, confirm_optimum

    try:
        record = confirm_optimum(evaluator, result, say=typer.echo)
    except BladelabError as err:
        raise renamed(err, {"confirmation": "--confirm"}) from None
    inside = sum(r["inside"] for r in record["responses"].values())
    typer.echo(f"confirmation run ({record['wall_s']:.0f} s): {inside} of "
               f"{len(record['responses'])} responses inside their 95 % prediction interval "
               f"-> {Path(result.out_dir) / CONFIRMATION_FILE}")
    for name, r in record["responses"].items():
        typer.echo(f"  {name:28s} predicted {r['predicted']:.4g} (PI {r['pi'][0]:.4g} .. "
                   f"{r['pi'][1]:.4g}), solved {r['solved']:.4g}"
                   + ("" if r["inside"] else "  outside"))
    for name, c in record["constraints"].items():
        typer.echo(f"  constraint {name} {'<=' if c['upper'] else '>='} {c['bound']:g}: "
                   f"solved {c['solved']:.4g}, {'met' if c['met'] else 'NOT met'}")


def _echo_motion(mm) -> None:
    """One summary line of the motion model, and its leave-one-blade-out errors."""
    def fmt(v: float, scale: float = 1.0, digits: int = 2) -> str:
        return "n/a" if not math.isfinite(v) else f"{v * scale:.{digits}f}"

    typer.echo(f"motion model: {mm.model} ({len(mm.terms)} terms: {', '.join(mm.term_names)}) "
               f"from {mm.n_cycles} cycles at {mm.n_blades} blades")
    typer.echo(f"  leave-one-blade-out error: period {fmt(mm.loo_period_s, 1e3, 1)} ms; "
               + ", ".join(f"{k} {fmt(v)}°" for k, v in mm.loo_angles_deg.items()))


def _gait_cycle(
    trial_file: Path = typer.Argument(..., help="C3D trial with markers and force platforms."),
    out: Path = typer.Option(..., "--out", help="Gait-cycle CSV to write (for --gait)."),
    leg: str = typer.Option("right", "--leg",
                            help="left or right: the leg whose touch-down starts the cycle "
                                 "(the prosthetic leg)."),
    static: Path | None = typer.Option(None, "--static",
                                       help="Standing trial: its angles become zero."),
    markers: Path | None = typer.Option(None, "--markers",
                                        help="YAML joint marker map (default: Fukuchi set)."),
    samples: int = typer.Option(100, "--samples", help="Samples per cycle."),
    cutoff: float = typer.Option(20.0, "--cutoff", help="Marker low-pass [Hz] (0: none)."),
    forward: str = typer.Option("auto", "--forward", help="File axis that is forward (+x, -y...)."),
    up: str = typer.Option("auto", "--up", help="File axis that is up."),
) -> None:
    """Mean gait cycle of a measured trial (joint angles from markers) as a gait-cycle CSV."""
    from bladelab.design.gait_cycle import measured_gait_cycle  # deferred: keeps --help fast

    if samples < 8:
        raise SpecError(f"--samples must be >= 8, got {samples}", where="--samples")
    res = measured_gait_cycle(trial_file, leg=leg, static_file=static, markers_file=markers,
                              n=samples, cutoff_hz=cutoff if cutoff > 0 else None,
                              forward=forward, up=up, out=out)
    periods = res.periods_s
    typer.echo(f"{len(res.cycles)} cycles of the {leg} leg: period {periods.mean():.4f} ± "
               f"{periods.std():.4f} s")
    for k, (lo, hi, sd) in res.angle_ranges_deg().items():
        typer.echo(f"  {k:16s} {lo:7.1f} .. {hi:7.1f} deg  (between-cycle SD {sd:.1f} deg)")
    typer.echo(f"wrote {res.path}")
    if not res.zeroed_at_standing:
        typer.echo("note: no --static trial: the angles are those of the marker axes, not zero "
                   "at standing", err=True)


def register(app: typer.Typer) -> None:
    """Add ``bladelab design`` (with ``design gait-cycle``) and ``bladelab blade test``."""
    blade_app.command("test")(_blade_test)
    design_app = typer.Typer(cls=PanelGroup)
    design_app.callback(invoke_without_command=True)(_design)
    design_app.command("gait-cycle")(_gait_cycle)
    app.add_typer(design_app, name="design")
