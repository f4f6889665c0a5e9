"""Batch runner: every trial of a study as an independent task, results into ``results.sqlite``.

Per-trial seeds are derived deterministically from the study seed and the trial id
(:func:`trial_seed`), so results do not depend on the executor, the number of jobs or the order in
which tasks finish. Each finished task is written (and committed) at once by the driver process;
already finished (trial, variant) rows with the same input hash are skipped unless ``force``.
A trial that fails (missing file, bad data, ...) is written as a ``failed`` row with its message and
reported; the other trials still run.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import json
import time
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bladelab import __version__
from bladelab.executors import make_executor, run_task_safely
from bladelab.identify.formulations import DEFAULT_FORMULATION
from bladelab.study.spec import RESULTS_FILE, IdentificationSettings, Study, load_study
from bladelab.study.store import ResultsStore

DEFAULT_TASK = "bladelab.study.tasks:identify_trial"


def trial_seed(study_seed: int, trial_id: str) -> int:
    """A 32-bit seed from the study seed and the trial id (stable across runs and machines)."""
    words = np.frombuffer(hashlib.sha256(trial_id.encode("utf-8")).digest()[:16], dtype=np.uint32)
    return int(np.random.SeedSequence([int(study_seed), *words.tolist()]).generate_state(1)[0])


def variant_name(settings: dict) -> str:
    """The model variant of a settings dict: ``linear`` or ``nonlinear``, ``@j<point>`` if a joint
    is forced, ``+<formulation>`` for a formulation other than the default (e.g. ``linear+seed``)."""
    name = "nonlinear" if settings.get("nonlinear") else "linear"
    if settings.get("joint") is not None:
        name += f"@j{settings['joint']}"
    formulation = settings.get("formulation", DEFAULT_FORMULATION)
    if formulation != DEFAULT_FORMULATION:
        name += f"+{formulation}"
    return name


def _hash_inputs(files: list[Path], settings: dict, seed: int) -> str:
    h = hashlib.sha256()
    for f in files:
        h.update(f.read_bytes())
    h.update(json.dumps(settings, sort_keys=True).encode())
    h.update(str(seed).encode())
    return h.hexdigest()[:16]


def _resolve_task(task: Callable | str) -> Callable:
    if callable(task):
        return task
    module, _, name = task.partition(":")
    return getattr(importlib.import_module(module), name)


@dataclasses.dataclass(frozen=True)
class StudyRun:
    """What a study run did.

    Attributes
    ----------
    total
        Trials × variants in the study.
    finished
        Tasks run and written successfully now.
    skipped
        Already done (same input) and not forced.
    claimed
        Left to another run on the same study that had claimed them (running concurrently).
    failures
        (trial id, message) of every failed trial.
    wall_s
        Wall-clock time [s].
    executor, jobs
        How it ran.
    flagged
        Trials identified now whose quality is flagged (:mod:`bladelab.identify.quality`).
    """

    total: int
    finished: int
    skipped: int
    failures: tuple[tuple[str, str], ...]
    wall_s: float
    executor: str
    jobs: int
    claimed: int = 0
    flagged: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready dictionary."""
        d = dataclasses.asdict(self)
        d["failures"] = [{"trial": t, "error": m} for t, m in self.failures]
        return d


def plan(study: Study, folder: Path, *, settings: dict, blade: str | None = None) -> list[dict]:
    """One payload per trial (missing inputs become payloads with an ``error``)."""
    payloads = []
    for trial in study.trials:
        entry = study.blade(trial.blade)
        blade_ref = blade if blade is not None else entry.blade
        blade_path = Path(blade_ref) if Path(blade_ref).suffix in (".yaml", ".yml") else None
        if blade_path is not None and not blade_path.is_absolute():
            blade_path = folder / blade_path
        seed = trial_seed(study.seed, trial.id)
        file = folder / trial.file
        meta = {
            "athlete": trial.athlete,
            "blade": trial.blade,
            "category": None if entry.category is None else str(entry.category),
            "configuration": trial.configuration,
            "speed_pct_pb": trial.speed_pct_pb,
        }
        payload: dict[str, Any] = {
            "trial_id": trial.id, "variant": variant_name(settings), "file": str(file),
            "stance": trial.stance, "blade": str(blade_path) if blade_path else blade_ref,
            "settings": settings, "seed": seed, "meta": meta,
            "athlete_mass_kg": study.athlete(trial.athlete).mass_kg,
        }
        missing = [p for p in (file, blade_path) if p is not None and not p.is_file()]
        if missing:
            payload["error"] = f"{missing[0]}: file not found"
            payload["input_hash"] = None
        else:
            payload["input_hash"] = _hash_inputs([p for p in (file, blade_path) if p], settings, seed)
        payloads.append(payload)
    return payloads


def _row(payload: dict, status: str, value: Any) -> dict:
    row: dict[str, Any] = {
        "trial_id": payload["trial_id"], "variant": payload["variant"], "status": status,
        **payload["meta"], "settings_json": json.dumps(payload["settings"], sort_keys=True),
        "seed": payload["seed"], "package_version": __version__, "input_hash": payload["input_hash"],
    }
    if status == "ok":
        row.update(value)
    else:
        row["error"] = str(value)
    return row


def run_study(
    study_dir: str | Path,
    *,
    blade: str | None = None,
    settings: dict | None = None,
    jobs: int = 1,
    executor: str = "local",
    force: bool = False,
    progress: bool = True,
    task: Callable[[dict], dict] | str = DEFAULT_TASK,
    seed: int | None = None,
) -> StudyRun:
    """Run every trial of a study folder and store the results in its ``results.sqlite``.

    Parameters
    ----------
    study_dir
        Folder with ``study.yaml`` (or the file itself).
    blade
        Use this blade (built-in name or spec file) for every trial instead of the study's own.
    settings
        Overrides of the study's ``identification`` settings (keys of
        :class:`~bladelab.study.spec.IdentificationSettings`).
    jobs
        Parallel workers.
    executor
        ``"local"`` (process pool) or ``"ray"``.
    force
        Re-run and overwrite finished rows.
    progress
        Show a tqdm progress bar.
    task
        ``task(payload) -> dict`` of result columns, top-level importable (or ``"module:function"``).
        The default identifies K and D (:func:`bladelab.study.tasks.identify_trial`).
    seed
        Replaces the study's seed (per-trial seeds are derived from it and the trial ids).
    """
    from tqdm import tqdm

    t0 = time.perf_counter()
    study, folder = load_study(study_dir)
    if seed is not None:
        study = study.model_copy(update={"seed": int(seed)})
    merged = study.identification.model_dump(mode="json")
    if settings:
        merged = IdentificationSettings.model_validate({**merged, **settings}).model_dump(mode="json")
    fn = _resolve_task(task)
    if blade is not None and Path(blade).is_file():
        blade = str(Path(blade).resolve())  # a spec file given on the command line: relative to cwd
    payloads = plan(study, folder, settings=merged, blade=blade)
    store = ResultsStore(folder / RESULTS_FILE)
    owner = uuid.uuid4().hex
    others = 0
    failures: list[tuple[str, str]] = []
    finished = skipped = 0
    flagged: list[str] = []
    try:
        todo = []
        for p in payloads:
            if p.get("error"):
                store.write(_row(p, "failed", p["error"]), force=force)
                failures.append((p["trial_id"], p["error"]))
            elif not force and store.done(p["trial_id"], p["variant"], p["input_hash"]):
                skipped += 1
            else:
                todo.append(p)
        # claim the tasks, so that a second run on the same study does the others
        mine = set(store.claim([(p["trial_id"], p["variant"]) for p in todo], owner))
        others = len(todo) - len(mine)
        todo = [p for p in todo if (p["trial_id"], p["variant"]) in mine]
        if others and progress:
            print(f"{others} trial(s) are being identified by another run on this study; "
                  "leaving them to it", flush=True)
        ex = make_executor(executor, jobs)
        bar = tqdm(total=len(todo), desc="trials", unit="trial", disable=not progress, leave=False)
        try:
            for i, status, value in ex.run(fn, todo):
                p = todo[i]
                store.write(_row(p, status, value), force=force)
                if status == "ok":
                    finished += 1
                    if isinstance(value, dict) and value.get("flagged"):
                        flagged.append(p["trial_id"])
                else:
                    failures.append((p["trial_id"], str(value)))
                    bar.write(f"failed: {p['trial_id']}: {value}")
                bar.update(1)
        finally:
            bar.close()
    finally:
        store.release(owner)
        store.close()
    return StudyRun(total=len(payloads), finished=finished, skipped=skipped, claimed=others,
                    failures=tuple(sorted(failures)), wall_s=time.perf_counter() - t0,
                    executor=executor, jobs=jobs, flagged=tuple(sorted(flagged)))


__all__ = ["StudyRun", "plan", "run_study", "run_task_safely", "trial_seed", "variant_name"]
