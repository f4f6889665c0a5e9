"""``bladelab design``: a response-surface design study; ``bladelab design gait-cycle``: the mean
gait cycle of a measured trial; ``bladelab blade test``: compression test.

``bladelab blade test`` is added to the ``blade`` group of :mod:`bladelab.cli.blade` from here
(this module is registered after it).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from bladelab.errors import SpecError

__all__ = ["register"]


def _parse_floats(text: str, what: str) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise SpecError(f"cannot read {text!r} as comma-separated numbers", where=what,
                        hint="e.g. --alignment 0,-8,8") from None
    if not vals or not all(math.isfinite(v) for v in vals):
        raise SpecError(f"no finite numbers in {text!r}", where=what)
    return vals


def _blade_test(
    blade: str = typer.Argument(..., help="Built-in blade name or blade spec file."),
    category: str | None = typer.Option(None, "--category", help="Stiffness category, e.g. cat5."),
    alignment: str = typer.Option("0,-8,8", "--alignment",
                                  help="Alignment angles [deg], comma-separated."),
    body_mass: float = typer.Option(76.0, "--body-mass", help="Body mass [kg] (load = m·g)."),
    max_displacement: float = typer.Option(0.08, "--max-displacement",
                                           help="Largest clamp displacement [m]."),
    tip: str = typer.Option("held", "--tip", help="held (seed 002's fixture) or free."),
    plot: Path | None = typer.Option(None, "--plot", help="Draw the force–displacement curves."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON (curves included)."),
) -> None:
    """Virtual compression test: force–displacement curve and stiffness at body-weight load."""
    from bladelab.blade import load_blade
    from bladelab.design.compression import compression_test
    from bladelab.units import body_weight

    if plot is not None:
        from bladelab._io import figure_format

        figure_format(plot)  # refuse an unknown image format before any work
    if not (body_mass > 0 and math.isfinite(body_mass)):
        raise SpecError(f"body mass must be > 0 kg, got {body_mass}", where="--body-mass")
    angles = _parse_floats(alignment, "--alignment")
    spec = load_blade(blade, category=category)
    model = spec.build()
    load = body_weight(body_mass)
    results = []
    from bladelab.design.compression import vertical_stiffness
    from bladelab.errors import ModelError

    if tip == "held":
        try:
            vertical_stiffness(model, alignment_deg=angles[0], tip="held")
        except ModelError:
            tip = "free"
            typer.echo("note: this blade cannot compress with its support held (fewer than two "
                       "compliant joints between clamp and support); testing with tip free",
                       err=True)
    for a in angles:
        try:
            r = compression_test(model, max_displacement=max_displacement, n_steps=40, load=load,
                                 alignment_deg=a, tip=tip)
        except SpecError as err:
            if err.where != "load":
                raise
            r = compression_test(model, max_displacement=max_displacement, n_steps=40,
                                 alignment_deg=a, tip=tip)
        results.append(r)
    if as_json:
        def _clean(v):
            if isinstance(v, float) and not math.isfinite(v):
                return None
            if isinstance(v, dict):
                return {k: _clean(x) for k, x in v.items()}
            if isinstance(v, list):
                return [_clean(x) for x in v]
            return v

        typer.echo(json.dumps(_clean({"blade": model.name, "body_mass_kg": body_mass,
                                      "load_N": load, "tests": [r.to_dict() for r in results]}),
                              indent=2))
    else:
        typer.echo(f"{model.name}: virtual compression test (tip {tip}), load m·g = {load:.0f} N")
        typer.echo(" alignment_deg  k_linear_kN_per_m  k_at_bw_kN_per_m  displacement_at_bw_mm")
        for r in results:
            at = ("not reached" if math.isnan(r.stiffness_at_load) else
                  f"{r.stiffness_at_load / 1e3:16.2f}  {r.displacement_at_load * 1e3:21.1f}")
            typer.echo(f"{r.alignment_deg:14.1f}  {r.stiffness_linear / 1e3:17.2f}  {at}")
    if plot is not None:
        _plot_compression(results, model.name, load, plot)
        typer.echo(f"wrote {plot}", err=True)


def _plot_compression(results, name: str, load: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bladelab.design.plots import save_figure

    fig, ax = plt.subplots(figsize=(5, 4))
    for r in results:
        ax.plot(r.displacement * 1e3, r.force, label=f"{r.alignment_deg:+g}°")
    ax.axhline(load, color="0.5", ls="--", lw=0.8, label="body weight")
    ax.set_xlabel("clamp displacement [mm]")
    ax.set_ylabel("vertical force [N]")
    ax.set_title(f"{name}: virtual compression test")
    ax.legend(title="alignment")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def _design(
    ctx: typer.Context,
    factors: str | None = typer.Option(
        None, "--factors",
        help="name=low:high,... (default: stiffness_kN_per_m=18:32,width_m=0.05:0.08,"
             "height_m=0.40:0.48,toe_length_m=0.19:0.25)."),
    runs: str = typer.Option("ccd", "--runs", help="ccd, bbd, dopt or a CSV file of runs."),
    evaluator: str = typer.Option(
        "blade", "--evaluator",
        help="blade (one passive stance), runner (a template gait cycle) or collocation (a "
             "predicted transfemoral stride per design, docs/design.md)."),
    out: Path | None = typer.Option(None, "--out",
                                    help="Output folder (resumes an interrupted study); required."),
    seed: int = typer.Option(0, "--seed", help="Seed (D-optimal design, optimiser starts)."),
    jobs: int = typer.Option(1, "--jobs", help="Worker processes for the runs."),
    n_runs: int | None = typer.Option(None, "--n-runs", help="Runs of a D-optimal design."),
    model: str = typer.Option("quadratic", "--model",
                              help="Surface model: quadratic, linear, interaction, or terms."),
    objective: str = typer.Option("delta_vx_m_per_s", "--objective", help="Response to maximise."),
    sense: str = typer.Option("max", "--sense", help="max or min."),
    constraint: list[str] = typer.Option(
        [], "--constraint",
        help="response=minimum (repeatable), e.g. knee_moment_min_Nm=0 swing_clearance_m=0.02."),
    speed: float | None = typer.Option(
        None, "--speed",
        help="Touch-down speed [m/s] (default 8 blade, 7 runner); the stride's mean speed "
             "(collocation, default 4)."),
    body_mass: float | None = typer.Option(
        None, "--body-mass", help="Body mass [kg] (blade and runner evaluators; default 76)."),
    knee_moment_min: float | None = typer.Option(
        None, "--knee-moment-min",
        help="Collocation evaluator: keep the prosthetic knee's extension moment at or above "
             "this [N·m] in every design's stride (<= 0; default: reported, not imposed)."),
    knee_flexion_max: float | None = typer.Option(
        None, "--knee-flexion-max",
        help="Collocation evaluator: keep the prosthetic knee within this flexion [deg] while "
             "its blade is loaded (the straight stance; default: free)."),
    reference_weight: float | None = typer.Option(
        None, "--reference-weight",
        help="Collocation evaluator: keep the athlete's own joints (trunk, intact leg, "
             "residual hip) near the start stride's, this weight [1/rad²] × their mean "
             "squared deviation added to the objective: every blade run with the same "
             "technique (docs/design.md; default 0: the gait predicted freely)."),
    settle: int = typer.Option(
        0, "--settle",
        help="Collocation evaluator: after the runs, up to this many settling passes (each "
             "design solved again from its 2 nearest neighbours' strides, the lowest objective "
             "kept; stops when no objective drops by more than 1 %). Recorded design by design "
             "in settling.json: a stopped pass resumes where it stopped."),
    skip_failed: bool = typer.Option(
        False, "--skip-failed",
        help="Record runs whose evaluation fails (runs/run_NNNN.failed.json, failed.csv), do "
             "not evaluate runs recorded as failed again, and fit the surfaces to the runs that "
             "finished (default: a failed run stops the study)."),
    start: Path | None = typer.Option(
        None, "--start",
        help="Collocation solution of the transfemoral runner that the first design starts "
             "from (collocation evaluator; default: the built-in centre stride)."),
    base: str = typer.Option("xtreme", "--base", help="Base blade of the generator."),
    gait: Path | None = typer.Option(None, "--gait",
                                     help="Gait-cycle CSV (runner evaluator; default built-in)."),
    motion: Path | None = typer.Option(
        None, "--motion",
        help="Motion file (YAML/CSV: gait cycles with their blades): each design runs the "
             "cycle predicted by seed 002's motion model (runner evaluator; not with --gait)."),
    motion_model: str | None = typer.Option(
        None, "--motion-model",
        help="Motion model: auto (quadratic if the cycles can estimate it, else linear), "
             "quadratic, linear, or terms (default: the file's model:, else auto)."),
    dt: float | None = typer.Option(None, "--dt", help="Simulation step [s] of the evaluator."),
    figures: bool = typer.Option(True, "--figures/--no-figures", help="Write figures."),
) -> None:
    """Run a design study: DOE -> evaluator per run -> surfaces, ANOVA, optimum, figures.

    ``bladelab design gait-cycle TRIAL.c3d ...`` makes a gait-cycle CSV for ``--gait``; a motion
    file of several such cycles (one per blade or trial) adapts the motion per design.
    """
    if ctx.invoked_subcommand is not None:
        return
    if out is None:
        raise typer.BadParameter("missing option '--out' (the study's output folder)",
                                 param_hint="--out")
    from bladelab.design import DesignSpace, default_design_space, make_design, run_design
    from bladelab.design.evaluators import make_evaluator
    from bladelab.design.terms import parse_terms

    space = DesignSpace.parse(factors) if factors else default_design_space()
    if jobs < 1:
        raise SpecError(f"--jobs must be >= 1, got {jobs}", where="--jobs")
    cons: dict[str, float] = {}
    for c in constraint:
        name, sep, value = c.partition("=")
        try:
            cons[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep or not name.strip():
            raise SpecError(f"cannot read constraint {c!r}", where="--constraint",
                            hint="write response=minimum, e.g. knee_moment_min_Nm=0")
    options: dict = {"generator": {"base": base}}
    if evaluator == "collocation":
        if body_mass is not None or dt is not None:
            raise SpecError(f"--{'body-mass' if body_mass is not None else 'dt'} does not apply "
                            "to the collocation evaluator", where="--evaluator collocation",
                            hint="its runner is the transfemoral parameter set "
                                 "(docs/runner-model.md); collocation has no time step")
        options["solutions_dir"] = str(out / "strides")
        options["factor_ranges"] = {f.name: (f.low, f.high) for f in space.factors}
        if start is not None:
            options["start"] = str(start)
        if knee_moment_min is not None:
            options["knee_moment_min_Nm"] = knee_moment_min
        if knee_flexion_max is not None:
            options["knee_flexion_max_loaded_deg"] = knee_flexion_max
        if reference_weight is not None:
            options["reference_weight"] = reference_weight
    else:
        options["body_mass_kg"] = 76.0 if body_mass is None else body_mass
        if settle:
            raise SpecError("--settle needs --evaluator collocation", where="--settle")
        for name, given in (("--start", start), ("--knee-moment-min", knee_moment_min),
                            ("--knee-flexion-max", knee_flexion_max),
                            ("--reference-weight", reference_weight)):
            if given is not None:
                raise SpecError(f"{name} needs --evaluator collocation", where=name)
    if speed is not None:
        options["speed_mps"] = speed
    if dt is not None:
        if not (dt > 0 and math.isfinite(dt)):
            raise SpecError(f"--dt must be > 0 s, got {dt}", where="--dt")
        options["dt"] = dt
    if gait is not None and motion is not None:
        raise SpecError("--gait (one cycle for every design) and --motion (a predicted cycle per "
                        "design) exclude each other", where="--gait/--motion",
                        hint="give one of them")
    if evaluator != "runner" and (gait is not None or motion is not None):
        raise SpecError(f"--{'gait' if gait is not None else 'motion'} needs --evaluator runner",
                        where="--evaluator")
    if motion_model is not None and motion is None:
        raise SpecError("--motion-model needs --motion", where="--motion-model")
    from bladelab.errors import InputFileError

    if gait is not None:
        if not gait.is_file():
            raise InputFileError("no such gait-cycle file", file=gait,
                                 hint="a CSV with time_s and the joint angles (docs/design.md)")
        options["gait"] = str(gait)
    design = make_design(runs, space, n_runs=n_runs, model=model, seed=seed)
    from bladelab.design.doe import require_estimable

    require_estimable(design, parse_terms(model, space.names), space.names)
    if motion is not None:
        from bladelab.design.motion import load_motion_model

        options["motion"] = load_motion_model(motion, space=space, model=motion_model,
                                              progress=True)
        _echo_motion(options["motion"])
    if settle < 0:
        raise SpecError(f"--settle must be >= 0, got {settle}", where="--settle")
    ev = make_evaluator(evaluator, **options)

    def study():
        return run_design(space, runs=design, evaluator=ev, out_dir=out, seed=seed, model=model,
                          objective=objective, sense=sense, constraints=cons, units=ev.units,
                          jobs=jobs, skip_failed=skip_failed)

    result = study()
    if settle:
        from bladelab.cli.design_settle import settle_study

        if settle_study(ev, result, passes=settle, jobs=jobs):
            result = study()  # the settled strides' responses (read back, not solved)
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
    if figures:
        from bladelab.design.plots import write_design_figures

        for p in write_design_figures(result, out, objective=objective, constraints=cons):
            typer.echo(f"wrote {p}", err=True)


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
    import numpy as np

    from bladelab._io import atomic_path
    from bladelab.design.gait_cycle import average_gait_cycle, gait_cycles_from_trial
    from bladelab.errors import InputFileError
    from bladelab.trial import read_c3d
    from bladelab.trial.joint_angles import load_joint_marker_map

    if samples < 8:
        raise SpecError(f"--samples must be >= 8, got {samples}", where="--samples")
    for f in (trial_file, static):
        if f is not None and not f.is_file():
            raise InputFileError("no such file", file=f)
    mmap = load_joint_marker_map(markers) if markers is not None else None
    trial = read_c3d(trial_file, forward=forward, up=up)
    ax = trial.metadata.get("axes", {})
    st = None
    if static is not None:
        st = read_c3d(static, forward=ax.get("forward", forward), up=ax.get("up", up))
    cycles = gait_cycles_from_trial(trial, leg=leg, markers=mmap, static=st,
                                    cutoff_hz=cutoff if cutoff > 0 else None, n=samples)
    mean = average_gait_cycle(cycles, source=f"{trial_file}: mean of {len(cycles)} {leg}-leg "
                                             "cycles")
    with atomic_path(out) as tmp:
        mean.to_frame().to_csv(tmp, index=False, float_format="%.6g")
    periods = np.array([c.period for c in cycles])
    a = {k: np.degrees(v) for k, v in mean.angles.items()}
    sd = {k: float(np.mean(np.degrees(np.std([c.angles[k] for c in cycles], axis=0))))
          for k in mean.angles}
    typer.echo(f"{len(cycles)} cycles of the {leg} leg: period {periods.mean():.4f} ± "
               f"{periods.std():.4f} s")
    for k in a:
        typer.echo(f"  {k:16s} {a[k].min():7.1f} .. {a[k].max():7.1f} deg  "
                   f"(between-cycle SD {sd[k]:.1f} deg)")
    typer.echo(f"wrote {out}")
    if st is None:
        typer.echo("note: no --static trial: the angles are those of the marker axes, not zero "
                   "at standing", err=True)


def register(app: typer.Typer) -> None:
    """Add ``bladelab design`` (with ``design gait-cycle``) and ``bladelab blade test``."""
    from bladelab.cli.blade import blade_app

    blade_app.command("test")(_blade_test)
    design_app = typer.Typer()
    design_app.callback(invoke_without_command=True)(_design)
    design_app.command("gait-cycle")(_gait_cycle)
    app.add_typer(design_app, name="design")
