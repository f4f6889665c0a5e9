"""``bladelab report PATH``: the HTML report of a study, design study or predictive result."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from bladelab.errors import InputFileError

__all__ = ["register"]


def _report(
    study_dir: Path = typer.Argument(..., metavar="PATH", help="Study folder (study.yaml + results.sqlite), "
                                     "design folder, 'bladelab predict' or 'bladelab sweep' "
                                     "folder, a runner parameter JSON file, or a collocation "
                                     "solution.json."),
    trial: str | None = typer.Option(None, "--trial", help="Trial of the cost landscape "
                                     "(default: the first identified trial)."),
    variant: str | None = typer.Option(None, "--variant", help="Model variant to report "
                                       "(default: linear)."),
    out: Path | None = typer.Option(None, "--out", help="Report folder (default PATH/report)."),
    export: bool = typer.Option(False, "--export", help="Predictive results: also write each "
                                "solution as OpenSim .mot files and a states CSV (report/export/)."),
    include_flagged: bool = typer.Option(False, "--include-flagged", help="Study: keep flagged "
                                         "trials (poorly determined or poorly fitted) in the group "
                                         "statistics; by default they are left out, listed and "
                                         "marked."),
    window: str = typer.Option("contact", "--window", help="Study: normalise the GRF and "
                               "distance curves (and nRMSE tables) over the contact (touch-down to "
                               "toe-off, seed 000) or over the stance window (flight included)."),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON."),
) -> None:
    """Write PATH/report/index.html: fits, K*/D*, mechanics, statistics, identifiability (a
    study); surfaces and optimum (a design study); or the re-simulated predictive solutions."""

    # deferred: keeps bladelab --help fast
    from bladelab.report.predictive import build_predictive_report, predictive_kind
    from bladelab.report.study import build_study_report  # deferred: keeps bladelab --help fast

    if study_dir.is_file() or (study_dir.is_dir() and predictive_kind(study_dir) is not None
                               and not (study_dir / "study.yaml").is_file()):
        if predictive_kind(study_dir) is None:
            raise InputFileError("not a runner parameter file (no 'parameters' mapping) nor a "
                                 "collocation solution", file=study_dir,
                                 hint="a file must be a parameter JSON file or a collocation "
                                 "solution.json; otherwise give a study, design, predict or "
                                 "sweep folder")
        pres = build_predictive_report(study_dir, out, progress=not as_json, export=export)
        typer.echo(json.dumps(pres.to_dict(), indent=2) if as_json
                   else f"report written: {pres.index} ({len(pres.solutions)} solutions)")
        return
    if not study_dir.is_dir():
        raise InputFileError("no such study folder, predictive result or parameter file",
                             file=study_dir, hint="give the folder that holds study.yaml, a "
                             "'bladelab predict'/'sweep' folder or a parameter JSON file")
    # deferred: keeps bladelab --help fast
    from bladelab.report.design import build_design_report, is_design_folder

    if is_design_folder(study_dir):  # a 'bladelab design' folder (study.json from run_design)
        index = build_design_report(study_dir, out)
        typer.echo(json.dumps({"index": str(index)}) if as_json else f"report written: {index}")
        return
    if (study_dir / "study.json").is_file() and (study_dir / "runs").is_dir():
        done = len([f for f in (study_dir / "runs").glob("run_*.json")
                    if not f.name.endswith(".failed.json")])
        raise InputFileError(
            f"this design study is not finished ({done} runs done, no results.csv yet)",
            file=study_dir, hint="run the same 'bladelab design ... --out' command again to "
            "finish it (finished runs are read back), or add --skip-failed if runs fail")
    res = build_study_report(study_dir, trial=trial, variant=variant, out_dir=out,
                             progress=not as_json, include_flagged=include_flagged,
                             window=window)
    if as_json:
        typer.echo(json.dumps(res.to_dict(), indent=2))
        return
    extra = f", {res.n_failed} not reported" if res.n_failed else ""
    if res.n_flagged:
        extra += (f", {res.n_flagged} flagged " +
                  ("kept in" if include_flagged else "left out of") + " group statistics")
    typer.echo(f"report written: {res.index} ({res.n_trials} trials{extra})")


def register(app: typer.Typer) -> None:
    """Add ``report`` to the root app."""
    app.command("report")(_report)
