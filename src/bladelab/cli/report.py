"""``bladelab report STUDY_DIR``: the HTML study report."""

from __future__ import annotations

import json
from pathlib import Path

import typer

__all__ = ["register"]


def _report(
    study_dir: Path = typer.Argument(..., help="Study folder (study.yaml + results.sqlite)."),
    trial: str | None = typer.Option(None, "--trial", help="Trial of the cost landscape "
                                     "(default: the first identified trial)."),
    variant: str | None = typer.Option(None, "--variant", help="Model variant to report "
                                       "(default: linear)."),
    out: Path | None = typer.Option(None, "--out", help="Report folder (default STUDY_DIR/report)."),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON."),
) -> None:
    """Write STUDY_DIR/report/index.html: fits, K*/D*, mechanics, statistics, identifiability."""
    from bladelab.errors import InputFileError
    from bladelab.report.study import build_study_report

    if not study_dir.is_dir():
        raise InputFileError("no such study folder", file=study_dir,
                             hint="give the folder that holds study.yaml")
    from bladelab.report.design import build_design_report, is_design_folder

    if is_design_folder(study_dir):  # a 'bladelab design' folder (study.json from run_design)
        index = build_design_report(study_dir, out)
        typer.echo(json.dumps({"index": str(index)}) if as_json else f"report written: {index}")
        return
    res = build_study_report(study_dir, trial=trial, variant=variant, out_dir=out,
                             progress=not as_json)
    if as_json:
        typer.echo(json.dumps(res.to_dict(), indent=2))
        return
    extra = f", {res.n_failed} not reported" if res.n_failed else ""
    typer.echo(f"report written: {res.index} ({res.n_trials} trials{extra})")


def register(app: typer.Typer) -> None:
    """Add ``report`` to the root app."""
    app.command("report")(_report)
