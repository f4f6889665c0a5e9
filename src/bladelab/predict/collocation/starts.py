"""Several starts per problem, the best kept (``bladelab sweep --method collocation --starts K``).

The stride's landscape has local optima 15–25 % apart (docs/collocation.md, "Local optima
along a continuation"): which one a solve reaches depends on its start and on IPOPT's barrier
start. With K > 1 the speed continuation and the maximum speed
(:mod:`bladelab.predict.collocation.continuation`) solve each problem from up to K starts and
keep one. The starts, in this fixed order (:data:`START_ORDER`), the first K that apply (the
restart only with K = 5, so that K = 4 solves what it solved before the restart existed):

1. ``warm``: the continuation's own warm start (the previous speed's kept solution, the first
   guess at the first speed, the fastest kept speed for the maximum speed), with the
   settings' :attr:`~bladelab.predict.collocation.settings.CollocationSettings.warm_start_mu`
   (the only start of K = 1: today's sweep);
2. ``warm-mu-1e-4`` (the barrier start): the same warm start from its primal values alone
   (its multipliers dropped) with ``warm_start_mu`` 1e-4 (:data:`BARRIER_MU`);
   ``warm-mu-default`` (IPOPT's defaults) when the settings already use 1e-4. The warm start
   itself starts from the solution's multipliers where it carries them
   (docs/collocation.md, "Warm starts"), which stays on its branch; this one leaves it. Only when the warm start is a collocation solution (a template or trial guess goes
   through the tracking stage, where the barrier start does not apply);
3. ``template``: the template guess at the problem's speed (at the warm start's speed for the
   maximum speed), through the tracking stage: a start that no path of the continuation
   biases. Not when the warm start is itself a template guess;
4. ``previous-but-one``: the kept solution of the problem before the previous one (the
   second-fastest kept speed for the maximum speed), when there is one;
5. ``warm-restart`` (the restart): the warm start's primal values with IPOPT's default
   barrier start, which may leave the warm start's branch altogether. Measured at sprint
   speed: a continuation with dual warm starts stays on a running branch well past the speed
   where a bounding stride is cheaper (7.75 m/s: 6.49 against 8.50), and the barrier start at
   1e-4 stays on it too; the restart found the bound. Only when the warm start is a
   collocation solution and the barrier start is not already IPOPT's default.

So K = 3 gives, at every speed after the first, the warm start, the barrier start and the
template; K = 4 adds the previous-but-one solution from the third speed on; K = 5 adds the
restart at every speed after the first.

Kept (:func:`pick`): the lowest objective among the converged solves without
:meth:`~bladelab.predict.collocation.solution.CollocationSolution.gait_warnings`; if every
converged solve has some, the lowest converged one (its ``warnings`` column of the table says
why); if none converged, the first start's best iterate. Ties go to the earlier start.

Files (:func:`start_files`): the ``warm`` start keeps the names of a one-start sweep
(``speed-4.json``, ``speed-4.best_iterate.json``, ``max-speed.json``), so a sweep run with
K = 1 can be resumed with a larger K; the others insert their label (``speed-4.template.json``,
``max-speed.warm-mu-1e-4.best_iterate.json``). Every start's file stays.

Table columns (:func:`start_columns`, shared with ``benchmarks/collocation/merge_starts.py``):
``start`` (the label kept), ``starts`` (how many converged), ``objective`` (the kept one's;
empty if it did not converge), ``objective_<label>`` for each start (empty where it did not
converge or did not run) and ``spread_pct`` (largest minus lowest objective among the solves
:func:`pick` chooses from: the converged starts without gait warnings, or every converged one
if each has some; in % of the lowest; empty with fewer than two).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from bladelab.errors import SpecError
from bladelab.predict.collocation.stride_guess import COLLOCATION_SOURCE

__all__ = [
    "BARRIER_MU",
    "MAX_STARTS",
    "START_COLUMNS",
    "START_ORDER",
    "Candidate",
    "Start",
    "StartOutcome",
    "barrier_start",
    "candidate",
    "restart",
    "check_starts",
    "kept_message",
    "pick",
    "plan_starts",
    "solve_starts",
    "start_columns",
    "start_files",
    "warm_guess",
]

#: The starts in the order they are tried (module docstring); ``barrier`` is labelled
#: ``warm-mu-1e-4`` (or ``warm-mu-default``).
START_ORDER = ("warm", "barrier", "template", "previous-but-one", "restart")
#: The most starts per problem.
MAX_STARTS = len(START_ORDER)
#: IPOPT's initial barrier parameter of the barrier start.
BARRIER_MU = 1e-4
#: Table columns of a several-start problem, in order (``objective_<label>`` after
#: ``objective``).
START_COLUMNS = ("start", "starts", "objective", "spread_pct")

WARM = "warm"


def check_starts(starts, where: str = "starts") -> int:
    """The number of starts K as an int in 1..:data:`MAX_STARTS`; SpecError naming ``where``."""
    if isinstance(starts, bool) or not isinstance(starts, int) or not (
            1 <= starts <= MAX_STARTS):
        raise SpecError(f"need 1 to {MAX_STARTS} starts, got {starts!r}", where=where,
                        hint="1: the continuation's warm start only; " + ", ".join(
                            f"{i + 1}: + {s}" for i, s in enumerate(START_ORDER) if i))
    return starts


@dataclass(frozen=True)
class Start:
    """One start of a problem.

    Attributes
    ----------
    label
        Its name in file names and table columns (module docstring).
    settings
        The problem's :class:`~bladelab.predict.collocation.settings.CollocationSettings` (the
        barrier start changes ``warm_start_mu`` only).
    guess
        ``guess() -> StrideGuess``, called only when the start is solved.
    text
        How the progress line names the start (empty: ``from <guess source>``).
    speed_floor
        Of a maximum-speed problem, the speed [m/s] its stride is held at or above, where it
        is not the start stride's own (another model's stride: its speed would pin this
        model's to it); None: the solver's rule.
    """

    label: str
    settings: object
    guess: Callable[[], object]
    text: str = ""
    speed_floor: float | None = None


def barrier_start(warm: Start) -> Start:
    """The barrier start of a warm start (module docstring, start 2): its primal values alone
    (the multipliers dropped, which would start it where the warm start starts)."""
    mu = None if warm.settings.warm_start_mu == BARRIER_MU else BARRIER_MU
    label = "warm-mu-default" if mu is None else "warm-mu-1e-4"
    text = (warm.text or "the same warm start") + ", primal values" + (
        ", IPOPT's default barrier start" if mu is None else ", barrier start 1e-4")

    def guess():
        return dataclasses.replace(warm.guess(), multipliers=None)

    return Start(label, dataclasses.replace(warm.settings, warm_start_mu=mu), guess, text)


def restart(warm: Start) -> Start:
    """The restart of a warm start (module docstring, start 5): its primal values with
    IPOPT's default barrier start."""
    def guess():
        return dataclasses.replace(warm.guess(), multipliers=None)

    return Start("warm-restart", dataclasses.replace(warm.settings, warm_start_mu=None), guess,
                 (warm.text or "the same warm start")
                 + ", primal values, IPOPT's default barrier start")


def plan_starts(k: int, warm: Start, *, warm_source: str, template: Start | None,
                previous: Start | None, restart_start: bool = False) -> list[Start]:
    """The first ``k`` starts that apply, in :data:`START_ORDER` (module docstring):
    ``warm``; its barrier start when ``warm_source`` (the source of the warm start's guess)
    names a collocation solution; ``template`` unless None or the warm start is itself a
    template guess; ``previous`` unless None; the restart when ``restart_start`` (the caller's
    largest K), the barrier start applies and is not itself IPOPT's default."""
    out = [warm]
    solution = warm_source.startswith(COLLOCATION_SOURCE)
    barrier = barrier_start(warm) if solution else None
    if barrier is not None:
        out.append(barrier)
    if warm_source.startswith("template"):
        template = None
    out += [s for s in (template, previous) if s is not None]
    if restart_start and barrier is not None and barrier.settings.warm_start_mu is not None:
        out.append(restart(warm))
    return out[:k]


def start_files(ok: Path, best: Path, label: str) -> tuple[Path, Path]:
    """(solution file, best-iterate file) of start ``label`` of the problem whose one-start
    files are ``ok`` / ``best``: the same for ``warm``, the label inserted otherwise
    (``speed-4.json`` -> ``speed-4.template.json``, ``speed-4.template.best_iterate.json``)."""
    if label == WARM:
        return Path(ok), Path(best)
    ok = Path(ok)
    stem = ok.name.removesuffix(".json")
    return ok.with_name(f"{stem}.{label}.json"), ok.with_name(f"{stem}.{label}.best_iterate.json")


@dataclass(frozen=True)
class Candidate:
    """What :func:`pick` and :func:`start_columns` need of one start's solve.

    Attributes
    ----------
    label
        The start.
    converged
        The solve converged.
    objective
        Its objective [-] (NaN where unknown).
    warnings
        Its gait warnings (:meth:`CollocationSolution.gait_warnings`); empty: a running gait.
    """

    label: str
    converged: bool
    objective: float
    warnings: tuple[str, ...] = ()


def candidate(label: str, solution) -> Candidate:
    """The :class:`Candidate` of a :class:`CollocationSolution` (gait warnings are only looked
    for in a converged one)."""
    ok = bool(solution.converged)
    return Candidate(label, ok, float(solution.nlp.objective),
                     tuple(solution.gait_warnings()) if ok else ())


def _choice_pool(candidates: Sequence[Candidate]) -> list[Candidate]:
    """The solves a start is kept from: the converged ones without gait warnings, else every
    converged one (empty if none converged)."""
    done = [c for c in candidates if c.converged and math.isfinite(c.objective)]
    return [c for c in done if not c.warnings] or done


def pick(candidates: Sequence[Candidate]) -> Candidate:
    """The kept start (module docstring): the lowest objective among converged solves without
    gait warnings, else among converged ones, else the first; ties go to the earlier one."""
    if not candidates:
        raise SpecError("no start to choose from", where="starts")
    pool = _choice_pool(candidates)
    return min(pool, key=lambda c: c.objective) if pool else candidates[0]


def start_columns(candidates: Sequence[Candidate], kept: str,
                  labels: Sequence[str] | None = None) -> dict:
    """The table columns of a several-start problem (module docstring): ``start``, ``starts``,
    ``objective``, ``objective_<label>`` for each of ``labels`` (default: the candidates'),
    ``spread_pct``; NaN where a value does not exist."""
    objs: Mapping[str, float] = {c.label: float(c.objective) for c in candidates
                                 if c.converged and math.isfinite(c.objective)}
    row = {"start": kept, "starts": len(objs), "objective": objs.get(kept, math.nan)}
    for lab in (labels if labels is not None else [c.label for c in candidates]):
        row[f"objective_{lab}"] = objs.get(lab, math.nan)
    # the spread among the solves pick() chooses from: a start that ended in a hop is no
    # rival optimum of running gaits (all converged ones when every one has warnings)
    pool = [float(c.objective) for c in _choice_pool(candidates)]
    lo = min(pool, default=math.nan)
    row["spread_pct"] = (100.0 * (max(pool) - lo) / abs(lo)
                         if len(pool) > 1 and lo != 0 else math.nan)
    return row


@dataclass(frozen=True)
class StartOutcome:
    """One start's solve of a problem (solved now or read back).

    Attributes
    ----------
    label
        The start (:class:`Start`).
    solution
        Its :class:`CollocationSolution` (a best iterate when it did not converge).
    path
        The file it is in.
    solved
        False when it was read back.
    """

    label: str
    solution: object
    path: Path
    solved: bool


def kept_message(candidates: Sequence[Candidate], kept: Candidate) -> str:
    """The progress line of the kept start: every start's objective, the spread."""
    spread = start_columns(candidates, kept.label)["spread_pct"]
    each = ", ".join(f"{c.label} {c.objective:.5g}" if c.converged else
                     f"{c.label} not converged" for c in candidates)
    why = " (every converged start has gait warnings)" if kept.warnings else ""
    n = len(candidates)
    return (f"kept {kept.label}{why} of {n} start{'s' if n != 1 else ''} ({each})"
            + (f", spread {spread:.1f} %" if math.isfinite(spread) else ""))


def solve_starts(plan: Sequence[Start], *, ok: Path, best: Path, read, solve,
                 report: Callable[..., None], retry: bool = True,
                 several: bool | None = None) -> tuple[StartOutcome, tuple[StartOutcome, ...]]:
    """Solve one problem from each start of ``plan`` and keep one (:func:`pick`).

    ``ok`` / ``best``: the problem's one-start files (:func:`start_files` gives each start's);
    ``read(ok, best, settings)`` -> (converged solution, best iterate) stored there (None if
    absent); ``solve(settings, guess, ok, best, report)`` -> (solution, file written);
    ``report(event, path=, message=, solve=)`` as the continuation's progress (a start's
    messages are led by ``start <label>:`` when there are several, and the kept start is
    reported as event ``"kept"``).

    A start's converged file is read back, not solved again. Its best iterate is read back too
    when another start of the problem converged; otherwise it warm-starts that start again,
    unless ``retry`` is False (the stored iterates are stale: a step was refined). A start
    with a ``speed_floor`` is solved as ``solve(..., speed_floor=floor)``. Returns
    (kept, every start's outcome in order); the outcomes are empty unless ``several`` (default:
    more than one start in ``plan``; a K > 1 sweep passes True where only one start applies,
    so that every row has the columns)."""
    several = len(plan) > 1 if several is None else bool(several)
    files = [start_files(ok, best, s.label) for s in plan]
    stored = [read(o, b, s.settings) for s, (o, b) in zip(plan, files, strict=True)]
    any_done = any(done is not None for done, _ in stored)
    outcomes = []
    for s, (o, b), (done, iterate) in zip(plan, files, stored, strict=True):
        tag = f"start {s.label}: " if several else ""

        def said(event: str, *, path=None, message: str = "", solve=None, _tag=tag) -> None:
            report(event, path=path, message=_tag + message if message else "", solve=solve)

        if done is not None or (iterate is not None and any_done):
            sol, path = (done, o) if done is not None else (iterate, b)
            said("read", path=path,
                 message="read back" if done is not None else "read back (not converged)")
            outcomes.append(StartOutcome(s.label, sol, path, False))
            continue
        if iterate is not None and retry:
            guess = iterate.to_guess()
            said("start", message=f"warm start from the best iterate {b.name}")
        else:
            guess = s.guess()
            said("start", message=s.text or f"from {guess.source}")
        floor = {} if s.speed_floor is None else {"speed_floor": s.speed_floor}
        sol, path = solve(s.settings, guess, o, b, said, **floor)
        outcomes.append(StartOutcome(s.label, sol, path, True))
    if not several:
        return outcomes[0], ()
    cands = [candidate(x.label, x.solution) for x in outcomes]
    chosen = pick(cands)
    kept = outcomes[cands.index(chosen)]
    report("kept", path=kept.path, message=kept_message(cands, chosen))
    return kept, tuple(outcomes)


def warm_guess(solution, note: str = ""):
    """A solution as a warm start, its source naming its speed (``collocation solution at
    4 m/s`` + ``note``); :func:`~bladelab.predict.collocation.solve.predict_stride` scales it to
    the problem's speed unless it starts from the solution's multipliers."""
    v = solution.settings.speed_m_per_s
    return solution.to_guess(f"{COLLOCATION_SOURCE} at "
                             + (f"{v:g} m/s" if v else "maximum speed") + note)
