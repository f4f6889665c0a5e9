"""``bladelab example make OUT_DIR``: generate (or reuse) the synthetic example study."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from bladelab.errors import SpecError

__all__ = ["register"]

example_app = typer.Typer(
    help="The synthetic example study (seed 000's cohort, see docs/example-study.md).",
    no_args_is_help=True,
)


@example_app.command("make")
def _make(
    out_dir: Path = typer.Argument(
        None, help="Study folder to write (default: examples/sprint-study in the current folder)."),
    seed: int = typer.Option(0, "--seed", help="Study seed: the same seed gives the same trials."),
    force: bool = typer.Option(False, "--force", help="Regenerate even if a complete study is there."),
    jobs: int = typer.Option(2, "--jobs", "-j", help="Worker processes."),
    trials: int | None = typer.Option(None, "--trials", help="A reduced study with this many "
                                      "trials spread over the groups (default: all 50)."),
    as_json: bool = typer.Option(False, "--json", help="Print the result as JSON."),
) -> None:
    """Generate the example study: C3D trials, study.yaml and ground_truth.csv."""
    from bladelab.example.study import make_example_study  # deferred: keeps bladelab --help fast

    if jobs < 1:
        raise SpecError(f"--jobs must be >= 1, got {jobs}", where="--jobs")
    if trials is not None and trials < 1:
        raise SpecError(f"--trials must be >= 1, got {trials}", where="--trials")
    res = make_example_study(out_dir, seed=seed, force=force, jobs=jobs, n_trials=trials,
                             progress=not as_json)
    if as_json:
        typer.echo(json.dumps(res.to_dict(), indent=2))
        return
    what = "generated" if res.generated else "reused (complete, same seed; --force regenerates)"
    typer.echo(f"example study {what}: {res.folder} ({res.n_trials} trials, {res.wall_s:.1f} s)")
    typer.echo(f"next: bladelab identify {res.folder} --jobs 2 && bladelab report {res.folder}")


def register(app: typer.Typer) -> None:
    """Add the ``example`` sub-command group to the root app."""
    app.add_typer(example_app, name="example")
