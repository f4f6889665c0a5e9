"""Predictive simulation: optimise the reflex controller with CMA-ES (seed 001 §2.2).

:func:`optimize_controller` runs ``cma``'s ask/tell loop; the candidates of a generation are
evaluated in parallel (a persistent local process pool, or Ray), each one a closed-loop
simulation (:func:`bladelab.predict.reflex.objective.simulate_controlled`) stopped early once the model
has fallen. Sampling uses a seeded ``numpy.random.Generator`` (never NumPy's global one) and
``cma`` writes no log files.

Output folder (``out``):

- ``checkpoint.pkl`` (:mod:`~bladelab.predict.reflex.checkpoint`): the full optimiser state
  (pickled ``cma.CMAEvolutionStrategy`` including its random generator, generation, history,
  best), written atomically every ``checkpoint_every``
  generations and at the end; ``resume=True`` continues from it to the same result as an
  uninterrupted run (same settings, same seed);
- ``best.json``: the best parameters so far (``--init`` file of a warm start), with the run's
  settings and the best evaluation;
- ``history.csv``: generation, evaluations, best, median, sigma and ``elapsed_s`` (wall time
  [s] since the run started, accumulated across resumes) per generation.

``best.json`` also holds ``wall_time_s``: the wall time [s] the run has taken so far, summed over
resumes (the checkpoint stores the elapsed time; generations recomputed after an interruption
count once, the lost ones not at all). Wall time is kept apart from
:attr:`OptimizationResult.history`, which depends only on the seed and settings.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from bladelab._io import write_json
from bladelab.errors import InputFileError, OptimizationError
from bladelab.executors import ProcessPool, RayExecutor
from bladelab.predict import defaults
from bladelab.predict.reflex.checkpoint import (
    CHECKPOINT_NAME,
    RUN_FILES,
    load_checkpoint,
    write_checkpoint,
)
from bladelab.predict.reflex.controller import ControllerLayout, controller_layout
from bladelab.predict.reflex.objective import Evaluation, ObjectiveSettings, simulate_controlled
from bladelab.predict.reflex.robust import (
    OBJECTIVE_JITTER_SEED,
    generation_jitter_seed,
    robust_evaluation,
)
from bladelab.runner.model import RunnerModel, build_runner
from bladelab.runner.params import BODIES

# per-process cache of built models: (kind, blade) -> (model, layout)
_MODELS: dict[tuple[str, str | None], tuple[RunnerModel, ControllerLayout]] = {}


def runner_and_layout(kind: str, blade: str | None,
                      body: str = defaults.REFLEX_BODY) -> tuple[RunnerModel, ControllerLayout]:
    """The runner ``kind`` (``"able"``/``"amputee"``; ``blade`` category of the amputee) on
    ``body`` (:data:`bladelab.runner.params.BODIES`) and its controller layout, built once per
    process (workers evaluate many candidates of one model)."""
    key = (kind, blade if kind == "amputee" else None, body)
    if key not in _MODELS:
        model = build_runner(kind, blade=key[1], body=body)
        _MODELS[key] = (model, controller_layout(model))
    return _MODELS[key]


def stored_body(data: dict, path: str | Path) -> str:
    """The body of a parameter file's runner (``"body"``; seed 001's where the file names
    none: every file written before the reflex route ran another body)."""
    body = data.get("body", defaults.REFLEX_BODY)
    if body not in BODIES:
        raise InputFileError(f"unknown body {body!r}", file=path, where="body",
                             hint=" or ".join(BODIES))
    return body


def evaluate_candidates(payload: dict) -> list[dict]:
    """Evaluate a batch of parameter vectors (a top-level function for worker processes).

    ``payload``: ``model``, ``blade``, ``settings`` (ObjectiveSettings as a dict), ``xs`` (list
    of vectors). Returns one :meth:`Evaluation.to_dict` per vector.
    """
    model, layout = runner_and_layout(payload["model"], payload.get("blade"),
                                      payload.get("body", defaults.REFLEX_BODY))
    settings = ObjectiveSettings.from_dict(payload["settings"])
    seed = payload.get("jitter_seed", OBJECTIVE_JITTER_SEED)
    out = []
    for x in payload["xs"]:
        x = np.asarray(x, float)
        ev, _ = simulate_controlled(model, x, layout=layout, settings=settings)
        if settings.robust_samples > 1:
            ev = robust_evaluation(ev, model, x, layout, settings, seed=seed)
        out.append(ev.to_dict())
    return out


def stored_settings(
    data: dict, *, speed: float, duration: float | None = None, nominal: bool = False
) -> ObjectiveSettings:
    """The objective settings a parameter file was optimised with (its ``settings``; keys this
    version does not know are dropped), at ``speed`` [m/s], optionally another ``duration`` [s];
    ``nominal`` drops robust sampling (one simulation of the parameters as they are)."""
    known = {f.name for f in fields(ObjectiveSettings)}
    d = {k: v for k, v in (data.get("settings") or {}).items() if k in known}
    d["speed"] = float(speed)
    if duration is not None:
        d["duration"] = float(duration)
    if nominal:  # one simulation: no copies, so none of their starts, pushes or steps either
        d.update(robust_samples=1, robust_speed_change=0.0, robust_push=0.0,
                 robust_half_step=False)
    return ObjectiveSettings.from_dict(d)


class _Randn:
    """``randn(*shape)`` for ``cma`` drawn from a seeded Generator (picklable)."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def __call__(self, *shape: int) -> np.ndarray:
        return self.rng.standard_normal(shape)


class _Subspace:
    """The free parameters of a run that holds others fixed: CMA-ES sees ``reduce(x)``, the
    simulations ``expand(z)`` (the held values in place; picklable for the checkpoint)."""

    def __init__(self, start: np.ndarray, fixed: Sequence[int],
                 free: Sequence[int] | None = None) -> None:
        self.held = np.asarray(start, float).copy()
        self.free = (np.setdiff1d(np.arange(self.held.size), np.asarray(fixed, int))
                     if free is None else np.asarray(free, int))

    def reduce(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x, float)[self.free]

    def expand(self, z) -> np.ndarray:
        x = self.held.copy()
        x[self.free] = z
        return x


class _Evaluator:
    """Evaluates a list of vectors: in-process, on a persistent local process pool, or Ray
    (:mod:`bladelab.executors`)."""

    def __init__(self, executor: str, jobs: int, base: dict) -> None:
        self.executor, self.jobs, self.base = executor, max(1, int(jobs)), base
        self._pool = None
        self._ray = None
        if executor not in ("local", "ray"):
            raise OptimizationError(
                f"unknown executor {executor!r}", where="executor", hint="use 'local' or 'ray'"
            )
        if executor == "ray":
            self._ray = RayExecutor(self.jobs)
        elif self.jobs > 1:
            self._pool = ProcessPool(self.jobs)

    def __call__(self, xs: Sequence[np.ndarray],
                 jitter_seed: int | Sequence[int] = OBJECTIVE_JITTER_SEED) -> list[dict]:
        xs = [np.asarray(x, float).tolist() for x in xs]
        base = {**self.base, "jitter_seed": jitter_seed}
        if self._pool is None and self._ray is None:
            return evaluate_candidates({**base, "xs": xs})
        n = self.jobs
        chunks = [xs[i::n] for i in range(n)]
        payloads = [{**base, "xs": c} for c in chunks if c]
        if self._pool is not None:
            results = self._pool.map(evaluate_candidates, payloads)
        else:
            results = [None] * len(payloads)
            for i, status, value in self._ray.run(evaluate_candidates, payloads):
                if status != "ok":
                    raise OptimizationError(f"evaluation failed on Ray: {value}")
                results[i] = value
        out: list[dict] = [{}] * len(xs)
        for i, res in enumerate(results):
            for j, ev in enumerate(res):
                out[i + j * n] = ev
        return out

    def close(self, *, abort: bool = False) -> None:
        """Shut the pool down; ``abort`` stops busy workers at once (an interrupted run)."""
        if self._pool is not None:
            self._pool.close(abort=abort)
            self._pool = None


@dataclass(frozen=True)
class OptimizationResult:
    """Outcome of :func:`optimize_controller`."""

    model: str
    blade: str | None
    speed: float
    seed: int
    generations: int
    evaluations: int
    best_cost: float
    best: Evaluation
    x: np.ndarray = field(repr=False)
    history: tuple[tuple[int, int, float, float, float], ...] = field(repr=False)
    out: str | None = None
    wall_time_s: float = math.nan
    body: str = defaults.REFLEX_BODY

    def to_dict(self) -> dict:
        return {
            "model": self.model,
            "blade": self.blade,
            "body": self.body,
            "speed_m_per_s": self.speed,
            "seed": self.seed,
            "generations": self.generations,
            "evaluations": self.evaluations,
            "best_cost": self.best_cost,
            "best": self.best.to_dict(),
            "out": self.out,
            "wall_time_s": self.wall_time_s,
        }


def optimize_controller(
    model: str = "able",
    *,
    blade: str | None = defaults.REFLEX_BLADE,
    body: str = defaults.REFLEX_BODY,
    speed: float = defaults.SPEED_M_PER_S,
    x0: np.ndarray | None = None,
    generations: int = defaults.GENERATIONS,
    popsize: int = defaults.POPULATION_SIZE,
    sigma: float = defaults.INITIAL_STEP,
    seed: int = defaults.SEED,
    jobs: int = 1,
    executor: str = "local",
    out: str | Path | None = None,
    resume: bool = False,
    force: bool = False,
    checkpoint_every: int = defaults.CHECKPOINT_EVERY,
    settings: ObjectiveSettings | None = None,
    progress: Callable[[int, float, float], None] | None = None,
    fixed: Sequence[int] = (),
) -> OptimizationResult:
    """Optimise the reflex controller of a runner with CMA-ES.

    Parameters
    ----------
    model
        ``"able"`` or ``"amputee"``.
    blade
        Blade category of the amputee (ignored for ``able``).
    body
        The runner's body (:data:`bladelab.runner.params.BODIES`; default seed 001's).
    speed
        Prescribed running speed [m/s] (initial speed and the centre of the step-speed band).
    x0
        Initial parameters (warm start; evaluated once before the first generation, so the
        best is never worse than it); default SCONE's (:func:`controller_layout`).
    generations
        Number of CMA-ES generations in total (a resumed run continues up to this number).
    popsize
        Candidates per generation (λ).
    sigma
        Initial step size, in units of each parameter's initial scale (``layout.std``).
    seed
        Seed of the sampling generator.
    jobs, executor
        Parallel workers and ``"local"`` (process pool) or ``"ray"``.
    out
        Output folder (checkpoint, best.json, history.csv); None writes nothing.
    resume
        Continue from ``out/checkpoint.pkl`` (with the checkpoint's seed and objective settings;
        ``x0``, ``popsize``, ``sigma`` and ``settings`` are then ignored). A checkpoint written
        before the controller layout grew resumes with the added parameters held at their
        defaults (they stay switched off in that run).
    force
        Start a new run in an ``out`` that holds one (its files are replaced as the new run
        writes them); without ``force`` or ``resume`` such a folder is refused.
    checkpoint_every
        Write the checkpoint every this many generations.
    settings
        Objective settings (speed is taken from ``speed``).
    progress
        Called after each generation with (generation, best cost, generation median).
    fixed
        Indices of parameters held at their initial values: CMA-ES searches the others only
        (a resumed run keeps its own; the checkpoint's ``subspace``).
    """
    # (simulating, verifying or re-simulating a solution imports this module, never cma)
    # deferred: cma takes ~2 s to import (it loads matplotlib)
    import cma

    base_settings = settings or ObjectiveSettings()
    settings = ObjectiveSettings.from_dict({**base_settings.to_dict(), "speed": float(speed)})
    blade = blade if model == "amputee" else None
    runner, layout = runner_and_layout(model, blade, body)
    del runner
    out_dir = Path(out) if out is not None else None
    if generations < 1 or popsize < 2:
        raise OptimizationError("need generations >= 1 and popsize >= 2", where="generations")
    ckpt = out_dir / CHECKPOINT_NAME if out_dir is not None else None
    state = None
    if out_dir is not None and not (resume or force):
        held = [n for n in RUN_FILES if (out_dir / n).exists()]
        if held:
            raise InputFileError(
                f"the output folder holds a run ({', '.join(held)})",
                file=out_dir,
                hint="--resume continues it, --force starts over in it, or choose another --out",
            )
    if resume:
        if ckpt is None or not ckpt.exists():
            raise InputFileError(
                "no checkpoint to resume from",
                file=ckpt,
                hint="run without --resume first, with the same --out",
            )
        state = load_checkpoint(ckpt)
        own = (state["model"], state["blade"], state.get("body", defaults.REFLEX_BODY),
               state["speed"])
        if own != (model, blade, body, float(speed)):
            raise InputFileError(
                f"checkpoint is for {_run_text(*own)}, not {_run_text(model, blade, body, speed)}",
                file=ckpt,
                hint="resume with the same --model, --blade, --body and --speed",
            )
        if list(state["parameter_names"]) != list(layout.names):
            _resume_in_grown_layout(state, layout, ckpt)
        es = state["es"]
        gen, evals = state["generation"], state["evaluations"]
        history = list(state["history"])
        best_x, best_f, best_ev = state["best_x"], state["best_f"], state["best_eval"]
        # wall time before this call (NaN for a checkpoint written before it was recorded)
        elapsed0 = float(state.get("elapsed_s", math.nan))
        elapsed = list(state.get("elapsed", [math.nan] * len(history)))
        seed = state["seed"]
        settings = ObjectiveSettings.from_dict(state["settings"])  # the run's own objective settings
        subspace = state.get("subspace")
    else:
        start = layout.x0 if x0 is None else np.asarray(x0, float)
        if start.shape != (layout.size,):
            raise OptimizationError(
                f"initial guess has {start.size} values, the {model} controller {layout.size}",
                where="init",
            )
        start = np.clip(start, layout.lower, layout.upper)
        opts = {
            "popsize": int(popsize),
            "CMA_stds": layout.std.tolist(),
            "bounds": [layout.lower.tolist(), layout.upper.tolist()],
            "randn": _Randn(seed),
            "seed": math.nan,
            "verbose": -9,
            "verb_log": 0,
            "verb_disp": 0,
            "verb_filenameprefix": os.devnull + "/",
            "maxiter": math.inf,
            "tolfun": 0.0,
            "tolfunhist": 0.0,
            "tolx": 0.0,
            "tolstagnation": 10**9,
            "tolflatfitness": 10**9,
        }
        subspace = _Subspace(start, fixed) if len(fixed) else None
        if subspace is not None:  # CMA-ES searches the free parameters only
            opts["CMA_stds"] = subspace.reduce(layout.std).tolist()
            opts["bounds"] = [subspace.reduce(layout.lower).tolist(),
                              subspace.reduce(layout.upper).tolist()]
        es = cma.CMAEvolutionStrategy(
            (start if subspace is None else subspace.reduce(start)).tolist(), float(sigma), opts)
        gen, evals, history = 0, 0, []
        best_x, best_f, best_ev = start.copy(), math.inf, None
        elapsed0, elapsed = 0.0, []
    t_start = time.perf_counter()
    evaluator = _Evaluator(
        executor, jobs, {"model": model, "blade": blade, "body": body,
                         "settings": settings.to_dict()}
    )
    try:
        fresh = settings.robust_samples > 1 and settings.robust_directions == "per-generation"
        if state is None and x0 is not None:
            # a warm start is evaluated first: the best is never worse than the start (CMA-ES
            # samples around it and, from a fragile gait, may not find as good a point soon)
            ev0 = evaluator([best_x], generation_jitter_seed(settings, seed, 0))[0]
            best_f, best_ev = float(ev0["cost"]), ev0
            evals += 1
        while gen < generations:
            zs = es.ask()
            xs = zs if subspace is None else [subspace.expand(z) for z in zs]
            jitter_seed = generation_jitter_seed(settings, seed, gen + 1)
            if fresh and best_ev is not None:
                # new copies every generation: the best so far is simulated on this
                # generation's copies too, and a candidate replaces it only if it beats it on
                # the same copies (a best that survived only its own generation's copies falls
                # on the next one's and is replaced)
                *evs, best_ev = evaluator([*xs, best_x], jitter_seed)
                best_f = float(best_ev["cost"])
                evals += 1
            else:
                evs = evaluator(xs, jitter_seed)
            fs = [e["cost"] for e in evs]
            es.tell(zs, fs)
            gen += 1
            evals += len(xs)
            i = int(np.argmin(fs))
            if fs[i] < best_f:
                best_f, best_x, best_ev = float(fs[i]), np.asarray(xs[i], float), evs[i]
            history.append((gen, evals, best_f, float(np.median(fs)), float(es.sigma)))
            elapsed.append(elapsed0 + time.perf_counter() - t_start)
            if progress is not None:
                progress(gen, best_f, float(np.median(fs)))
            if out_dir is not None and (gen % checkpoint_every == 0 or gen == generations):
                write_checkpoint(
                    out_dir,
                    es,
                    gen,
                    evals,
                    history,
                    best_x,
                    best_f,
                    best_ev,
                    layout,
                    model,
                    blade,
                    float(speed),
                    seed,
                    settings,
                    elapsed,
                    elapsed0 if not elapsed else elapsed[-1],
                    subspace,
                    body=body,
                )
    except BaseException:
        evaluator.close(abort=True)
        raise
    evaluator.close()
    best = Evaluation(**best_ev) if best_ev is not None else None
    return OptimizationResult(
        model=model,
        blade=blade,
        body=body,
        speed=float(speed),
        seed=int(seed),
        generations=gen,
        evaluations=evals,
        best_cost=best_f,
        best=best,
        x=best_x,
        history=tuple(history),
        out=str(out_dir) if out_dir is not None else None,
        wall_time_s=elapsed[-1] if elapsed else elapsed0,
    )


def _run_text(model: str, blade: str | None, body: str, speed: float) -> str:
    """``"amputee with Cat6 on the seed001 body at 3.5 m/s"``."""
    return (f"{model}" + (f" with {blade}" if blade else "")
            + f" on the {body} body at {float(speed):g} m/s")


def optimize_seeds(
    model: str = "able",
    *,
    seeds: Sequence[int] = (1,),
    out: str | Path,
    progress: Callable[[int, int, float, float], None] | None = None,
    **options,
) -> list[OptimizationResult]:
    """:func:`optimize_controller` once per seed: into ``out`` (one seed) or ``out/seed-N``
    (several), then ``out/summary.json`` with every run and the best (lowest cost).

    ``progress`` is called with (seed, generation, best cost, generation median); ``options``
    are :func:`optimize_controller`'s keywords.
    """
    out = Path(out)
    results = []
    for seed in seeds:
        folder = out if len(seeds) == 1 else out / f"seed-{seed}"
        show = None if progress is None else (lambda g, b, m, _s=seed: progress(_s, g, b, m))
        results.append(optimize_controller(model, seed=seed, out=folder, progress=show, **options))
    runs = [r.to_dict() for r in results]
    write_json(out / "summary.json", {"runs": runs, "best": min(runs, key=lambda r: r["best_cost"])})
    return results


def _resume_in_grown_layout(state: dict, layout, ckpt: Path) -> None:
    """Carry a checkpoint written before the controller layout grew into ``layout`` (in place):
    the run goes on searching the parameters it searched, the added ones held at their
    defaults (a resumed run continues exactly, the added terms switched off as in older
    parameter files). A layout that lost or reordered parameters is refused."""
    old, new = list(state["parameter_names"]), list(layout.names)
    where = {name: i for i, name in enumerate(new)}
    idx = [where.get(name, -1) for name in old]
    if min(idx) < 0 or idx != sorted(idx):
        raise InputFileError(
            "checkpoint was written for another controller layout",
            file=ckpt,
            hint="warm-start a new run from its best.json with --init instead",
        )
    idx = np.asarray(idx)

    def grown(x: np.ndarray) -> np.ndarray:
        out = layout.x0.copy()
        out[idx] = np.asarray(x, float)
        return out

    sub = state.get("subspace")
    held = grown(sub.held if sub is not None else state["best_x"])
    free = idx[sub.free] if sub is not None else idx
    state["subspace"] = _Subspace(held, (), free=free)
    state["best_x"] = grown(state["best_x"])
    state["parameter_names"] = new


__all__ = [
    "OptimizationResult",
    "runner_and_layout",
    "stored_body",
    "stored_settings",
    "evaluate_candidates",
    "load_checkpoint",
    "optimize_controller",
    "optimize_seeds",
]
