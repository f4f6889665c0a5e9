"""``bladelab identify`` (one stance or a whole study) and ``bladelab results``."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from bladelab.errors import InputFileError, SpecError
from bladelab.parameters import JOINT_PARAMETERS

__all__ = ["register"]


def _identify(
    path: Path = typer.Argument(..., help="A stance CSV, or a study folder holding study.yaml."),
    blade: str | None = typer.Option(
        None, "--blade", help="Built-in blade name or blade spec file (required for a stance; "
        "for a study it replaces the study's blades)."),
    optimizer: str = typer.Option("pso", "--optimizer", help="pso (20 × 30, seed 000) or cmaes."),
    seed: int | None = typer.Option(None, "--seed", help="Seed (stance: default 0; study: "
                                    "replaces study.yaml's seed)."),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON."),
    jobs: int = typer.Option(1, "--jobs", "-j", help="Parallel workers for a study."),
    executor: str = typer.Option("local", "--executor", help="local (process pool) or ray."),
    force: bool = typer.Option(False, "--force", help="Re-run trials that are already done."),
    polish: bool = typer.Option(False, "--polish", help="Refine the optimum with L-BFGS-B "
                                "(always on with --nonlinear)."),
    nonlinear: bool = typer.Option(False, "--nonlinear", help="Also identify K2 (stiffening spring)."),
    joint: int | None = typer.Option(None, "--joint", help="Hinge position (blade point index)."),
    grf: str = typer.Option("z", "--grf", help="GRF components in the cost: z or zx."),
    max_evals: int = typer.Option(600, "--max-evals", help="Evaluation budget of the search."),
    no_ci: bool = typer.Option(False, "--no-ci", help="Skip confidence intervals."),
    formulation: str | None = typer.Option(
        None, "--formulation", help="How the stance drives the model: utilised-friction (default; "
        "friction = measured Fx/Fz × normal force, robust to motion-capture noise) or seed "
        "(seed 000 exactly: prescribed clamp, stick-slip friction) or grf-driven (measured GRF "
        "drives the model, distance-only cost). For a study: replaces "
        "study.yaml's setting."),
) -> None:
    """Identify K* [N·m/deg] and D* [N·m·s/deg] of a stance, or of every trial of a study."""
    if optimizer not in ("pso", "cmaes"):
        raise SpecError(f"unknown optimizer {optimizer!r}", where="--optimizer", hint="pso or cmaes")
    if grf not in ("z", "zx", "xz"):
        raise SpecError(f"unknown GRF components {grf!r}", where="--grf", hint="z or zx")
    components = ("z",) if grf == "z" else ("z", "x")
    # deferred: keeps bladelab --help fast
    from bladelab.identify.formulations import DEFAULT_FORMULATION, FORMULATIONS

    if formulation is not None and formulation not in FORMULATIONS:
        raise SpecError(f"unknown formulation {formulation!r}", where="--formulation",
                        hint="one of " + ", ".join(FORMULATIONS))
    if path.is_dir():
        _identify_study(path, blade=blade, seed=seed, as_json=as_json, jobs=jobs, executor=executor,
                        force=force, settings={
                            "optimizer": optimizer, "polish": True if polish else None,
                            "nonlinear": nonlinear,
                            "joint": joint, "grf_components": list(components),
                            "max_evals": max_evals, "identifiability": not no_ci,
                            **({} if formulation is None else {"formulation": formulation})})
        return
    if not path.is_file():
        raise InputFileError("no such stance file or study folder", file=path)
    if blade is None:
        raise SpecError("--blade is required to identify a stance", where="--blade",
                        hint="a built-in name (bladelab blade list) or a blade spec file")
    from bladelab.identify.identify import identify_stance  # deferred: keeps bladelab --help fast
    from bladelab.trial import read_stance_csv  # deferred: keeps bladelab --help fast

    stance = read_stance_csv(path)
    ident = identify_stance(stance, blade, optimizer=optimizer, seed=0 if seed is None else seed,
                            grf_components=components, joint=joint, nonlinear=nonlinear,
                            polish=True if polish else None, max_evals=max_evals,
                            identifiability=not no_ci,
                            formulation=DEFAULT_FORMULATION if formulation is None else formulation)
    d = ident.to_dict()
    if as_json:
        typer.echo(json.dumps(d, indent=2))
        return
    k, dd, k2 = (JOINT_PARAMETERS[n] for n in ("K", "D", "K2"))
    lines = [f"K* = {d[k.edge_key]:.3f} {k.edge_unit}", f"D* = {d[dd.edge_key]:.4f} {dd.edge_unit}"]
    if k2.edge_key in d:
        lines.append(f"K2 = {d[k2.edge_key]:.4g} {k2.edge_unit}")
    if k.ci_key in d:
        k_ci, d_ci = d[k.ci_key], d[dd.ci_key]
        lines.append(f"95 % CI: K [{k_ci[0]:.3f}, {k_ci[1]:.3f}], D [{d_ci[0]:.4f}, {d_ci[1]:.4f}]; "
                     f"K–D correlation {d['KD_correlation']:.2f}")
    lines.append(f"nRMSE GRF {d['nrmse_grf_pct']:.2f} %, distance {d['nrmse_distance_pct']:.2f} %, "
                 f"cost {d['cost']:.4g}")
    lines.append(f"{d['evaluations']} simulations ({d['optimizer']}, seed {d['seed']}, "
                 f"formulation {d['formulation']}), "
                 f"{d['wall_s']:.2f} s")
    for note in d.get("notes", []):
        lines.append(f"note: {note}")
    for name, why in d["poorly_determined"].items():
        lines.append(f"warning: {name} is poorly determined: {why}")
    quality = d.get("quality") or {}
    if quality.get("flagged"):
        lines.append("flagged (left out of group statistics in a study report): "
                     + "; ".join(quality["flags"]))
    typer.echo("\n".join(lines))


def _identify_study(path: Path, *, blade, seed, as_json, jobs, executor, force, settings) -> None:
    from bladelab.study.runner import run_study  # deferred: keeps bladelab --help fast

    run = run_study(path, blade=blade, settings=settings, jobs=jobs, executor=executor, force=force,
                    progress=not as_json, seed=seed)
    if as_json:
        typer.echo(json.dumps(run.to_dict(), indent=2))
    else:
        typer.echo(f"{run.finished} identified, {run.skipped} already done, {len(run.failures)} "
                   f"failed, of {run.total} ({run.wall_s:.1f} s, {run.executor}, {run.jobs} job(s))")
        if run.flagged:
            typer.echo(f"{len(run.flagged)} flagged (poorly determined or poorly fitted; left out "
                       "of the report's group statistics unless --include-flagged): "
                       + ", ".join(run.flagged[:10]) + (" ..." if len(run.flagged) > 10 else ""))
        for trial, msg in run.failures:
            typer.echo(f"failed: {trial}: {msg}", err=True)
    if run.failures:
        raise typer.Exit(1)


_SHOWN = ["trial_id", "variant", "status", "athlete", "blade", "category", "configuration",
          "speed_pct_pb", "K_Nm_per_deg", "D_Nms_per_deg", "K_ci_low_Nm_per_deg",
          "K_ci_high_Nm_per_deg", "nrmse_grf_pct", "nrmse_distance_pct", "flags", "error"]


def _results(
    study_dir: Path = typer.Argument(..., help="Study folder (with results.sqlite)."),
    as_csv: bool = typer.Option(False, "--csv", help="Print all columns as CSV."),
    output: Path | None = typer.Option(None, "--output", "-o", help="Write the CSV to this file."),
) -> None:
    """Print (or export as CSV) the results table of a study."""
    # deferred: keeps bladelab --help fast
    from bladelab.study.store import export_results_csv, open_results

    if output is not None:
        rows = export_results_csv(study_dir, output)
        typer.echo(f"wrote {output} ({rows} rows)", err=True)
        return
    df = open_results(study_dir)
    if as_csv:
        typer.echo(df.to_csv(index=False), nl=False)
        return
    if df.empty:
        typer.echo("no results yet")
        return
    cols = [c for c in _SHOWN if c in df.columns and df[c].notna().any()]
    typer.echo(df[cols].to_string(index=False, float_format=lambda v: f"{v:.4g}"))


def register(app: typer.Typer) -> None:
    """Add ``identify`` and ``results`` to the root app."""
    app.command("identify")(_identify)
    app.command("results")(_results)
