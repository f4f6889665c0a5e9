"""One stride from several starts into an output folder (``bladelab predict --starts K``).

The stride's landscape has local optima (docs/collocation.md, "Local optima along a
continuation"), and which one a solve reaches depends on its start and on IPOPT's barrier
start. Measured 2026-11-30: the amputee with Cat6 on the human body scaled to a 68 kg, 1.75 m
athlete at 4 m/s reached an objective 17 % above the settled one from the shipped stride with
IPOPT's default barrier start, and within 0.08 % of it from the same stride with the barrier
started at 1e-4 (``benchmarks/human_body/athlete-68kg-1.75m``).

:func:`predict_stride_from_starts` solves the problem from the first K starts of
:func:`~bladelab.predict.collocation.starts.plan_starts` that apply: ``warm`` (the guess
itself), the barrier start (``warm-mu-1e-4``: its primal values with the barrier started at
1e-4, when the guess is a collocation solution), ``template`` (the template guess through
the tracking stage, when the guess is not itself the template) and the restart
(``warm-restart``: the guess's primal values with IPOPT's default barrier start, as the barrier
start applies), and keeps the lowest objective
among the converged solves without gait warnings
(:func:`~bladelab.predict.collocation.starts.pick`).

Folder: every start's solve in ``OUT/starts/`` (``solution.json`` for ``warm``,
``solution.<label>.json`` for the others, ``.best_iterate.json`` where a start did not
converge), ``OUT/starts/starts.json`` (the kept start, each start's objective and their spread
[%]); the kept one copied to ``OUT/solution.json`` (``OUT/best_iterate.json`` if no start
converged). ``--resume`` reads back the starts that converged and warm-starts the others from
their best iterates.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from pathlib import Path

from bladelab._io import write_json
from bladelab.errors import SpecError
from bladelab.predict.collocation.output_folder import (
    BEST_ITERATE_FILE,
    SOLUTION_FILE,
    STARTS_DIR,
    FolderResult,
    check_output_folder,
    read_stored,
    write_solve,
)
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solve import SolveProgress, predict_stride
from bladelab.predict.collocation.starts import (
    START_ORDER,
    Start,
    candidate,
    plan_starts,
    solve_starts,
    start_columns,
    start_files,
)
from bladelab.predict.collocation.stored import check_model_spec

__all__ = ["MAX_STRIDE_STARTS", "STARTS_FILE", "check_stride_starts",
           "predict_stride_from_starts"]

#: The starts' record in ``OUT/starts/``.
STARTS_FILE = "starts.json"
#: The most starts of one stride: the guess, its barrier start, the template, the restart.
MAX_STRIDE_STARTS = 4


def check_stride_starts(starts, where: str = "starts") -> int:
    """The number of starts of one stride as an int in 1..:data:`MAX_STRIDE_STARTS`;
    SpecError naming ``where``."""
    if isinstance(starts, bool) or not isinstance(starts, int) or not (
            1 <= starts <= MAX_STRIDE_STARTS):
        raise SpecError(f"need 1 to {MAX_STRIDE_STARTS} starts, got {starts!r}", where=where,
                        hint="1: the guess; 2: + the guess with the barrier started at 1e-4; "
                             "3: + the template; 4: + the guess's primal values with IPOPT's "
                             "default barrier")
    return starts


def predict_stride_from_starts(
    out: str | Path,
    runner,
    settings: CollocationSettings,
    make_guess: Callable[[], object],
    template_guess: Callable[[], object],
    *,
    starts: int,
    model_spec: dict,
    resume: bool = False,
    force: bool = False,
    progress: Callable[[SolveProgress], None] | None = None,
    say: Callable[[str], None] | None = None,
) -> FolderResult:
    """:func:`~bladelab.predict.collocation.output_folder.predict_stride_in_folder` from up to
    ``starts`` starts (module docstring): ``make_guess`` gives the warm start's guess,
    ``template_guess`` the template's; ``resume``, ``force`` and ``progress`` as there (each
    start's stages named ``start <label>: <stage>``); ``say(line)`` gets a line as each start
    begins or is read back, and one naming the kept start with every start's objective.
    Returns the kept start's :class:`~bladelab.predict.collocation.output_folder.FolderResult` (its
    path the copy in ``out``).

    Raises
    ------
    InputFileError
        As :func:`~bladelab.predict.collocation.output_folder.predict_stride_in_folder`.
    """
    out = Path(out)
    spec = check_model_spec(model_spec)
    check_output_folder(out, resume=resume, force=force)
    ok, best = out / SOLUTION_FILE, out / BEST_ITERATE_FILE
    warm_guess = functools.cache(make_guess)  # built once: its source plans the starts
    warm = Start(START_ORDER[0], settings, warm_guess)
    template = Start("template", settings, template_guess, "from the template guess")
    plan = plan_starts(starts, warm, warm_source=str(warm_guess().source), template=template,
                       previous=None, restart_start=starts == MAX_STRIDE_STARTS)
    folder = out / STARTS_DIR
    folder.mkdir(parents=True, exist_ok=True)
    files = (folder / SOLUTION_FILE, folder / BEST_ITERATE_FILE)
    label_of = {start_files(*files, s.label)[0]: s.label for s in plan}

    def read(o: Path, b: Path, s: CollocationSettings):
        return (None, None) if force else read_stored(o, b, spec, s)

    def solve(s: CollocationSettings, guess, o: Path, b: Path, said):
        label = label_of[o]

        def relay(p: SolveProgress) -> None:
            if progress is not None:
                progress(dataclasses.replace(p, stage=f"start {label}: {p.stage}"))

        sol = predict_stride(runner, s, guess, model_spec=spec, progress=relay)
        return sol, write_solve(sol, o, b)

    def report(event: str, *, path=None, message: str = "", solve=None) -> None:
        if say is not None and message:
            say(message)

    kept, outcomes = solve_starts(plan, ok=files[0], best=files[1], read=read, solve=solve,
                                  report=report, retry=True, several=True)
    cands = [candidate(x.label, x.solution) for x in outcomes]
    write_json(folder / STARTS_FILE, {
        **start_columns(cands, kept.label, [s.label for s in plan]),
        "files": {x.label: x.path.name for x in outcomes}})
    target = write_solve(kept.solution, ok, best)
    return FolderResult(kept.solution, target, any(x.solved for x in outcomes))

