"""Blade-category sweeps (seed 001 §2.2.2 B–C, Fig. 3.7, Table 3.1).

Each category is one independent task (run on an executor of :mod:`bladelab.executors`:
in-process, local process pool or Ray): the amputee with that blade is optimised at the first
prescribed speed, warm-started from ``init`` (or the controller's initial guess), then at each
higher speed warm-started from the previous speed's best, until the model falls (it "can no
longer run"). Per category (``summary.csv``):

- ``max_speed``: the highest mean speed [m/s] of a solution that ran the whole simulation;
- ``cot_4``: metabolic cost of transport [J/(kg·m)] of the 4 m/s solution (if it ran);
- ``t200``, ``t400``: 200 m and 400 m times [s] at the maximum speed (distance / speed);
- ``contact_time_intact``, ``contact_time_prosthetic``: mean contact time [s] of each leg in the
  maximum-speed solution (re-simulated when its cell finished; :func:`spatiotemporal`).

Results: ``out/results.csv`` (tidy: category, speed, cost, fell, mean_speed, j_cot, ...,
generations, evaluations, wall_time_s, contact times) and ``out/summary.csv``, both rewritten
(atomically) after every finished cell; each cell's optimisation under
``out/<category>/<speed>/`` with a ``cell.json`` (its settings, then its result).

Resuming: running the same sweep again with the same ``out`` continues it. A cell whose
optimisation finished is read back from its ``cell.json`` and ``best.json`` (no evaluation); an
interrupted cell continues from its ``checkpoint.pkl`` (``optimize_controller(resume=True)``,
the same result as not stopping). A cell run with other settings (generations, popsize, seed,
duration, time step, robust sampling, objective) or from another initial guess is an error that
names the cell and the setting.
"""

from __future__ import annotations

import json
import math
import threading
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from bladelab._io import atomic_open, read_json, write_json
from bladelab.errors import InputFileError, OptimizationError, SpecError
from bladelab.executors import make_executor
from bladelab.predict import defaults
from bladelab.predict.reflex.controller import parameter_digest, read_parameters
from bladelab.predict.reflex.objective import ObjectiveSettings, simulate_controlled
from bladelab.predict.reflex.optimize import CHECKPOINT_NAME, optimize_controller, runner_and_layout
from bladelab.runner.analyses import spatiotemporal
from bladelab.runner.blade_categories import blade_catalogue, blade_category

CELL_NAME = "cell.json"
CELL_FORMAT = 1

# CLI option of each checked setting (for the error message)
_OPTION = {
    "generations": "--generations",
    "popsize": "--popsize",
    "sigma": "--sigma",
    "seed": "--seed",
    "duration": "--duration",
    "dt": "--dt",
    "robust_samples": "--robust-samples",
    "robust_jitter": "--robust-jitter",
    "initial_speed": "--initial-speed",
}


def cell_dir(out: str | Path, category: str, speed: float) -> Path:
    """The folder of one (category, speed) optimisation: ``out/<category>/<speed:g>``."""
    return Path(out) / category / f"{float(speed):g}"


def _plain(obj):
    """JSON round trip (tuples become lists) so stored and wanted settings compare equal."""
    return json.loads(json.dumps(obj))


def _wanted(payload: dict) -> dict:
    """The settings a cell must have been run with (the objective's speed is the cell's)."""
    obj = {k: v for k, v in payload["settings"].items() if k != "speed"}
    return _plain(
        {
            "generations": payload["generations"],
            "popsize": payload["popsize"],
            "sigma": payload["sigma"],
            "seed": payload["seed"],
            **obj,
        }
    )



def _read_cell(folder: Path, category: str, speed: float, wanted: dict) -> dict | None:
    """The cell's ``cell.json`` (None if it has none); an error if its settings differ."""
    path = folder / CELL_NAME
    where = f"{category} at {speed:g} m/s"
    if not path.is_file():
        if (folder / CHECKPOINT_NAME).exists():
            raise InputFileError(
                f"sweep cell {where} holds a checkpoint but no {CELL_NAME} "
                "(not written by this version of 'bladelab sweep')",
                file=folder,
                hint="use another --out, or remove that folder to recompute the cell",
            )
        return None
    hint = "remove that folder to recompute the cell"
    data = read_json(path, what=f"sweep cell {where}", hint=hint)
    try:
        stored = {"sigma": 1.0, **data["settings"]}  # cells written before --sigma existed
    except (KeyError, TypeError) as err:
        raise InputFileError(
            f"sweep cell {where} has no settings ({type(err).__name__}: {err})",
            file=path,
            hint=hint,
        ) from None
    if data.get("format") != CELL_FORMAT:
        raise InputFileError(f"sweep cell {where}: unknown format", file=path)
    diff = [k for k in sorted(set(wanted) | set(stored)) if stored.get(k) != wanted.get(k)]
    if diff:
        parts = [
            f"{_OPTION.get(k, k)} {stored.get(k)!r} there, {wanted.get(k)!r} now" for k in diff
        ]
        raise SpecError(
            f"sweep cell {where} was run with other settings: " + "; ".join(parts),
            file=path,
            where=_OPTION.get(diff[0], diff[0]),
            hint="re-run with the settings of the first run, or use another --out",
        )
    return data


def _contact_times(category: str, x: np.ndarray, settings: ObjectiveSettings) -> dict:
    """Mean contact time [s] per leg of the solution ``x``, re-simulated with ``settings``."""
    model, layout = runner_and_layout("amputee", category)
    _, res = simulate_controlled(model, x, layout=layout, settings=settings, record_every=2)
    st = spatiotemporal(res)
    out = {}
    for leg in ("intact", "prosthetic"):
        v = st.value[(st.leg == leg) & (st.variable == "contact_time")]
        out[f"contact_time_{leg}"] = float(v.iloc[0]) if len(v) else math.nan
    return out


def finished_cell(folder: Path) -> dict | None:
    """The ``cell.json`` of a finished sweep cell in ``folder``; None while it has none, cannot
    be read, or is not done (its ``best.json`` is then an interim best)."""
    try:
        data = json.loads((Path(folder) / CELL_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get("status") == "done" else None


def _cells_done(out: Path, categories: list[str], speeds: list[float]) -> list[dict]:
    rows = []
    for cat in categories:
        for speed in speeds:
            data = finished_cell(cell_dir(out, cat, speed))
            if data is not None:
                rows.append(data["result"])
    return rows


def _cells_settled(done: list[dict], speeds: list[float]) -> int:
    """Cells finished or no longer needed: the finished ``done`` rows, plus each category's
    speeds above its first fall (its chain ends there)."""
    n = len(done)
    for cat in {r["category"] for r in done}:
        fell = [r["speed"] for r in done if r["category"] == cat and r["fell"]]
        if fell:
            n += sum(1 for v in speeds if v > min(fell))
    return n


def _write_tables(out: Path, rows: list[dict], categories: list[str]) -> pd.DataFrame:
    """Write results.csv and summary.csv (atomically); return the summary."""
    order = {c: i for i, c in enumerate(categories)}
    results = pd.DataFrame(rows)
    if len(results):
        results = results.sort_values(
            ["category", "speed"], key=lambda s: s.map(order) if s.name == "category" else s
        ).reset_index(drop=True)
    summary = summarise(results)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_open(out / "results.csv", "w", newline="") as fh:
        results.to_csv(fh, index=False)
    with atomic_open(out / "summary.csv", "w", newline="") as fh:
        summary.to_csv(fh, index=False)
    return summary


def category_task(payload: dict) -> dict:
    """Run one category's speed chain (a top-level function for executors).

    Finished cells are read back, interrupted ones resumed from their checkpoint; after each
    newly finished cell, ``results.csv`` and ``summary.csv`` are rewritten from every finished
    cell of the sweep on disk.
    """
    cat = payload["category"]
    out = Path(payload["out"])
    _, layout = runner_and_layout("amputee", cat)
    if payload.get("init"):
        x = read_parameters(payload["init"], layout, transfer=True)
    else:
        x = layout.x0.copy()
    wanted = _wanted(payload)
    rows = []
    for speed in payload["speeds"]:
        folder = cell_dir(out, cat, speed)
        data = _read_cell(folder, cat, speed, wanted)
        digest = parameter_digest(x, layout)
        if data is not None and data.get("x0_sha256") != digest:
            raise SpecError(
                f"sweep cell {cat} at {speed:g} m/s was started from another initial guess",
                file=folder / CELL_NAME,
                where="--init",
                hint="use the --init (and --chain-from) of the first run, or another --out",
            )
        if data is not None and data.get("status") == "done":
            row = data["result"]
            x = read_parameters(folder / "best.json", layout)
        else:
            resume = data is not None and (folder / CHECKPOINT_NAME).is_file()
            if data is None:
                write_json(
                    folder / CELL_NAME,
                    {
                        "format": CELL_FORMAT,
                        "category": cat,
                        "speed_m_per_s": speed,
                        "status": "running",
                        "settings": wanted,
                        "x0_sha256": digest,
                    },
                )
            settings = ObjectiveSettings.from_dict({**payload["settings"], "speed": float(speed)})
            res = optimize_controller(
                "amputee",
                blade=cat,
                speed=speed,
                x0=x,
                generations=payload["generations"],
                popsize=payload["popsize"],
                sigma=payload["sigma"],
                seed=payload["seed"],
                jobs=1,
                out=folder,
                resume=resume,
                force=not resume,  # the cell's folder is the sweep's own
                checkpoint_every=payload.get("checkpoint_every", 5),
                settings=settings,
            )
            row = {
                "category": cat,
                "speed": float(speed),
                **res.best.to_dict(tracking=False),  # a sweep tracks nothing
                "generations": res.generations,
                "evaluations": res.evaluations,
                "wall_time_s": res.wall_time_s,
                **_contact_times(cat, res.x, settings),
            }
            write_json(
                folder / CELL_NAME,
                {
                    "format": CELL_FORMAT,
                    "category": cat,
                    "speed_m_per_s": speed,
                    "status": "done",
                    "settings": wanted,
                    "x0_sha256": digest,
                    "result": row,
                },
            )
            x = res.x
            done = _cells_done(out, payload["categories"], payload["all_speeds"])
            _write_tables(out, done, payload["categories"])
        rows.append(row)
        if row["fell"]:
            break
    return {"category": cat, "rows": rows}


class _CellProgress:
    """A progress bar of finished cells, counted from their ``cell.json`` on disk (the cells
    finish inside worker processes); a background thread refreshes it every ``every`` s."""

    def __init__(self, out: Path, categories: list[str], speeds: list[float], *,
                 enabled: bool, every: float = 2.0) -> None:
        self.out, self.categories, self.speeds = out, categories, speeds
        self.bar = tqdm(total=len(categories) * len(speeds), desc="sweep cells",
                        unit="cell", disable=not enabled)
        self._stop = threading.Event()
        self._thread = None
        if enabled:
            self.refresh_count()
            self._thread = threading.Thread(target=self._loop, args=(every,), daemon=True)
            self._thread.start()

    def _loop(self, every: float) -> None:
        while not self._stop.wait(every):
            self.refresh_count()

    def refresh_count(self) -> None:
        if self.bar.disable:
            return
        n = _cells_settled(_cells_done(self.out, self.categories, self.speeds), self.speeds)
        if n != self.bar.n:
            self.bar.n = n
            self.bar.refresh()

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        self.refresh_count()
        self.bar.close()


def _run_wave(ex, payloads: list[dict], bar) -> list[dict]:
    rows, failed = [], []
    for i, status, value in ex.run(category_task, payloads):
        if status != "ok":
            failed.append(f"{payloads[i]['category']}: {value}")
            continue
        rows.extend(value["rows"])
        bar.refresh_count()
    if failed:
        raise OptimizationError("sweep task(s) failed: " + "; ".join(failed))
    return rows


def _chain(ex, base, categories, speeds, init, chain_from, bar) -> list[dict]:
    """Waves of first-speed optimisations outwards from ``chain_from``, then speed chains."""
    stiff = {name: c.stiffness_n_per_m for name, c in blade_catalogue().items()}
    ordered = sorted(categories, key=lambda c: stiff[blade_category(c).name])
    names = [blade_category(c).name for c in ordered]
    start = blade_category(chain_from).name
    if start not in names:
        raise OptimizationError(
            f"--chain-from {chain_from} is not among the categories", where="chain_from"
        )
    i0 = names.index(start)
    first = speeds[0]

    def best(cat: str) -> str:
        return str(cell_dir(base["out"], cat, first) / "best.json")

    rows: list[dict] = []
    for dist in range(max(i0, len(ordered) - 1 - i0) + 1):
        wave = []
        for i in {i0 - dist, i0 + dist}:
            if 0 <= i < len(ordered):
                parent = None if dist == 0 else (i + 1 if i < i0 else i - 1)
                src = (str(init) if init else None) if parent is None else best(ordered[parent])
                wave.append({**base, "category": ordered[i], "speeds": [first], "init": src})
        rows.extend(_run_wave(ex, wave, bar))
    ran = {r["category"] for r in rows if not r["fell"]}
    rest = [
        {**base, "category": c, "speeds": speeds[1:], "init": best(c)}
        for c in ordered
        if c in ran and len(speeds) > 1
    ]
    if rest:
        rows.extend(_run_wave(ex, rest, bar))
    return rows


def summarise(results: pd.DataFrame) -> pd.DataFrame:
    """One row per category: max_speed [m/s], cot_4 [J/(kg·m)], t200 and t400 [s], and the
    mean contact times [s] of the intact and prosthetic leg at the maximum speed."""
    cols = [
        "category",
        "max_speed",
        "cot_4",
        "t200",
        "t400",
        "contact_time_intact",
        "contact_time_prosthetic",
    ]
    out = []
    if not len(results):
        return pd.DataFrame(columns=cols)
    for cat, df in results.groupby("category", sort=False):
        ran = df[~df.fell.astype(bool)]
        vmax = float(ran.mean_speed.max()) if len(ran) else math.nan
        at4 = ran[np.isclose(ran.speed, 4.0)]
        contact = {"contact_time_intact": math.nan, "contact_time_prosthetic": math.nan}
        if len(ran):
            top = ran.loc[ran.mean_speed.idxmax()]
            for key in contact:
                if key in top.index:
                    contact[key] = float(top[key])
        out.append(
            {
                "category": cat,
                "max_speed": vmax,
                "cot_4": float(at4.j_cot.iloc[0]) if len(at4) else math.nan,
                "t200": 200.0 / vmax if vmax > 0 else math.nan,
                "t400": 400.0 / vmax if vmax > 0 else math.nan,
                **contact,
            }
        )
    return pd.DataFrame(out, columns=cols)


def run_sweep(
    categories: list[str],
    speeds: list[float],
    *,
    out: str | Path,
    init: str | Path | None = None,
    generations: int = defaults.GENERATIONS,
    popsize: int = defaults.POPULATION_SIZE,
    sigma: float = defaults.INITIAL_STEP,
    seed: int = defaults.SEED,
    jobs: int = 1,
    executor: str = "local",
    duration: float = defaults.DURATION_S,
    dt: float | None = None,
    robust_samples: int = defaults.ROBUST_SAMPLES,
    robust_jitter: float = defaults.ROBUST_JITTER,
    initial_speed: float | None = None,
    checkpoint_every: int = defaults.CHECKPOINT_EVERY,
    chain_from: str | None = None,
    progress: bool = True,
) -> pd.DataFrame:
    """Run (or continue) the category × speed sweep; returns the per-category summary (see
    the module docstring).

    Parameters
    ----------
    categories
        Blade categories (``Cat4`` ... ``Cat7``).
    speeds
        Prescribed speeds [m/s], raised in this order.
    out
        Output folder. Running again with the same folder continues the sweep: finished cells
        are read back, interrupted ones resumed from their checkpoint.
    init
        Warm start for the first speed of every category (parameters JSON).
    generations, popsize, sigma, seed
        CMA-ES settings of every cell (``sigma``: initial step × parameter scale; from a warm
        start a small one, 0.05–0.2, keeps the gait: 1 scatters the first candidates so far
        that nearly all fall).
    jobs, executor
        Categories run in parallel on ``executor`` (``local``/``ray``) with ``jobs`` workers.
    duration
        Simulated time [s] of each evaluation.
    dt
        Time step [s] (default the objective's, :data:`bladelab.runner.model.DEFAULT_DT`).
    robust_samples, robust_jitter
        Robust evaluation: simulations per candidate (nominal + jittered copies) and their
        relative parameter jitter (:class:`ObjectiveSettings`).
    initial_speed
        Forward speed [m/s] of every cell's initial state; None: the first (lowest) speed. One
        initial state for all, as seed 001 §2.2.2: a solution warm-started at the next speed
        keeps running (starting at the new speed, the previous controller falls within a second)
        and the step-speed penalty guides it faster.
    checkpoint_every
        Checkpoint every this many generations in each cell.
    chain_from
        Warm-start categories from each other at the first speed, as seed 001 §2.2.2 B does:
        this category starts from ``init``, its softer and stiffer neighbours (catalogue order)
        from its solution, and so on outwards (each wave in parallel); then every category
        raises its speed independently. None: every category starts from ``init``.
    progress
        Show a progress bar of finished cells (read back ones included).
    """
    for c in categories:
        blade_category(c)
    if not speeds or any(not (s > 0) for s in speeds):
        raise OptimizationError("speeds must be positive", where="speeds")
    if generations < 1 or popsize < 2 or checkpoint_every < 1 or not sigma > 0:
        raise OptimizationError(
            "need generations >= 1, popsize >= 2, sigma > 0 and checkpoint_every >= 1",
            where="generations",
        )
    out = Path(out)
    init = Path(init).resolve() if init else None
    speeds = sorted(float(s) for s in speeds)
    objective = ObjectiveSettings(
        duration=duration,
        robust_samples=int(robust_samples),
        robust_jitter=float(robust_jitter),
        initial_speed=float(speeds[0] if initial_speed is None else initial_speed),
        **({"dt": float(dt)} if dt is not None else {}),
    )
    base = {
        "generations": int(generations),
        "popsize": int(popsize),
        "sigma": float(sigma),
        "seed": int(seed),
        "out": str(out.resolve()),  # workers (Ray) may run in another folder
        "settings": objective.to_dict(),
        "checkpoint_every": int(checkpoint_every),
        "categories": list(categories),
        "all_speeds": speeds,
    }
    # settings of cells already there: checked before anything runs
    wanted = _wanted(base)
    for c in categories:
        for s in speeds:
            _read_cell(cell_dir(out, c, s), c, s, wanted)
    ex = make_executor(executor, jobs)
    bar = _CellProgress(out, list(categories), speeds, enabled=progress)
    rows: list[dict] = []
    try:
        if chain_from is None:
            payloads = [
                {**base, "category": c, "speeds": speeds, "init": str(init) if init else None}
                for c in categories
            ]
            rows.extend(_run_wave(ex, payloads, bar))
        else:
            rows.extend(_chain(ex, base, categories, speeds, init, chain_from, bar))
    finally:
        bar.close()
    return _write_tables(out, rows, categories)


__all__ = ["CELL_NAME", "category_task", "cell_dir", "finished_cell", "run_sweep", "summarise"]
