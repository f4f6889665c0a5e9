"""The example study end to end: generate (or reuse) -> identify every trial -> report.

:func:`run_example_pipeline` is what ``make demo`` (``python -m bladelab.demo``) runs.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["PipelineResult", "run_example_pipeline"]


@dataclasses.dataclass(frozen=True)
class PipelineResult:
    """What :func:`run_example_pipeline` did (times in seconds).

    Attributes
    ----------
    folder, report
        The study folder and its ``report/index.html``.
    generated
        False when a complete study was reused.
    n_trials, n_identified, n_failed
        Trials in the study, identified now or before, and failed.
    generate_s, identify_s, report_s
        Wall-clock time of each step [s].
    """

    folder: Path
    report: Path
    generated: bool
    n_trials: int
    n_identified: int
    n_failed: int
    generate_s: float
    identify_s: float
    report_s: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        d = dataclasses.asdict(self)
        d["folder"], d["report"] = str(self.folder), str(self.report)
        return d


def run_example_pipeline(
    folder: str | Path | None = None,
    *,
    seed: int = 0,
    jobs: int = 2,
    n_trials: int | None = None,
    progress: bool = True,
    echo: Callable[[str], None] = print,
) -> PipelineResult:
    """Generate (or reuse) the example study, identify all its trials, write its report.

    Parameters
    ----------
    folder
        Study folder (default ``examples/sprint-study`` in the project).
    seed
        Study seed.
    jobs
        Worker processes for generation and identification.
    n_trials
        A reduced study (tests); None: all 50 trials.
    progress
        Progress bars.
    echo
        Where the step lines go.
    """
    from bladelab.example.study import make_example_study
    from bladelab.report.study import build_study_report
    from bladelab.study import run_study

    t0 = time.perf_counter()
    made = make_example_study(folder, seed=seed, jobs=jobs, n_trials=n_trials, progress=progress)
    t1 = time.perf_counter()
    echo(f"[1/3] example study {'generated' if made.generated else 'reused'}: {made.folder} "
         f"({made.n_trials} synthetic trials, {t1 - t0:.1f} s)")
    run = run_study(made.folder, jobs=jobs, progress=progress)
    t2 = time.perf_counter()
    echo(f"[2/3] identified K*, D*: {run.finished} trials now, {run.skipped} already done, "
         f"{len(run.failures)} failed ({t2 - t1:.1f} s, {jobs} jobs)")
    for tid, msg in run.failures:
        echo(f"      failed: {tid}: {msg[:160]}")
    rep = build_study_report(made.folder, progress=progress)
    t3 = time.perf_counter()
    echo(f"[3/3] report of {rep.n_trials} trials ({t3 - t2:.1f} s)")
    return PipelineResult(
        folder=made.folder, report=rep.index, generated=made.generated, n_trials=made.n_trials,
        n_identified=run.finished + run.skipped, n_failed=len(run.failures),
        generate_s=t1 - t0, identify_s=t2 - t1, report_s=t3 - t2,
    )
