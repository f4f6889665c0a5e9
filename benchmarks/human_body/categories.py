"""The amputee on the human body at 4 m/s with each blade category, from several starts.

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/categories.py [OUT] [--jobs 2] [--speed 4]
        [--people-weight W]

Per category (Cat4, Cat5, Cat6, Cat6High, Cat7), up to five starts: ``trial`` (with
``--trial``: the measured 3.5 m/s stride scaled to the speed, through the tracking stage),
``shipped`` (the packaged Cat6 stride at 4 m/s,
``data/runner/collocation/amputee-Cat6-4-human.json``, with IPOPT's barrier started at 1e-4),
``fast`` (the category's own 5 m/s stride of the committed category study, :data:`FAST`, its
primal values), ``neighbour`` (the kept stride of the next stiffer category, or of Cat6 for
Cat7, barrier 1e-4) once the first starts have run everywhere, and ``best`` (the kept stride of
the category whose kept objective is the lowest, barrier 1e-4) once the neighbours have run,
for every other category.
Each start writes ``OUT/<category>.<start>.json`` (``.best_iterate.json`` if IPOPT did not
converge); a file already there is kept (re-run to continue). ``OUT/categories.csv`` has one
row per category: the kept start (the lowest objective among converged solves), every start's
objective and their spread [%], the kept stride's summary, its criteria against people's running
and its stride analyses (K_leg, joint powers). Default OUT: ``benchmarks/human_body/categories``.
The objective is the human body's default (people's joint angles at weight 10 1/rad²) unless
``--people-weight`` says otherwise (0: the free problem).
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

CATEGORIES = ("Cat4", "Cat5", "Cat6", "Cat6High", "Cat7")
STARTS = ("trial", "shipped", "fast", "neighbour", "best")
SHIPPED = "amputee-Cat6-4-human.json"
#: The category's own 5 m/s stride of the committed category study, the ``fast`` start
FAST = "benchmarks/collocation/study-human-people10-2026-11-29/amputee-{}-human/speed-5.json"
# the next stiffer category's kept stride starts the neighbour solve
NEIGHBOUR = {"Cat4": "Cat5", "Cat5": "Cat6", "Cat6": "Cat6High", "Cat6High": "Cat7",
             "Cat7": "Cat6"}


def _path(out: Path, category: str, start: str) -> Path | None:
    for suffix in (".json", ".best_iterate.json"):
        p = out / f"{category}.{start}{suffix}"
        if p.is_file():
            return p
    return None


def _solve(out: str, category: str, start: str, guess: str, speed: float,
           people_weight: float) -> str:
    from bladelab.predict import defaults
    from bladelab.predict.collocation.settings import CollocationSettings, people_term
    from bladelab.predict.collocation.solve import predict_stride
    from bladelab.predict.collocation.starting_guess import make_guess
    from bladelab.runner import build_runner

    runner = build_runner("amputee", blade=category, body="human")
    settings = CollocationSettings(speed_m_per_s=speed,
                                   warm_start_mu=None if start in ("trial", "fast") else 1e-4,
                                   **people_term(defaults.people_weight_for("human",
                                                                            people_weight)))
    t0 = time.perf_counter()
    sol = predict_stride(runner, settings,
                         make_guess(runner, guess, n=settings.mesh_intervals, speed=speed),
                         model_spec={"model": "amputee", "blade": category, "body": "human"})
    name = f"{category}.{start}" + (".json" if sol.converged else ".best_iterate.json")
    sol.write(Path(out) / name)
    return (f"{name}: converged {sol.converged}, objective {sol.nlp.objective:.4f}, "
            f"{time.perf_counter() - t0:.0f} s")


def _converged(out: Path, category: str) -> dict:
    """The converged solves of ``category`` by start (a best iterate is not one)."""
    from bladelab.predict.collocation.solution import CollocationSolution

    return {start: CollocationSolution.read(p) for start in STARTS
            if (p := _path(out, category, start)) is not None
            and p.name.endswith(f"{start}.json")}


def _kept(out: Path, category: str, solves: dict | None = None):
    """(start, solution) of the lowest objective among ``category``'s converged solves."""
    solves = _converged(out, category) if solves is None else solves
    if not solves:
        return None
    start = min(solves, key=lambda s: solves[s].nlp.objective)
    return start, solves[start]


def _run(jobs: list[tuple], workers: int, out: Path, speed: float,
         people_weight: float | None) -> None:
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(_solve, str(out), c, s, g, speed, people_weight)
                   for c, s, g in jobs]
        for f in futures:
            print(f.result(), flush=True)


def _table(out: Path) -> None:
    from bladelab.predict.collocation.analyses import stride_analyses
    from bladelab.predict.collocation.human_running import human_running_criteria

    rows = []
    for category in CATEGORIES:
        solves = _converged(out, category)
        kept = _kept(out, category, solves)
        if kept is None:
            continue
        start, sol = kept
        row = {"category": category, "kept_start": start}
        for s in STARTS:
            row[f"objective_{s}"] = solves[s].nlp.objective if s in solves else None
        done = [v.nlp.objective for v in solves.values()]
        row["spread_pct"] = (100 * (max(done) - min(done)) / min(done)) if len(done) > 1 else None
        row.update(sol.summary())
        crit = human_running_criteria(sol)
        row["criteria_met"] = f"{sum(c.met for c in crit)}/{len(crit)}"
        row["criteria_missed"] = "; ".join(f"{c.name} {c.value_text()}" for c in crit
                                           if not c.met)
        row.update(stride_analyses(sol))
        rows.append(row)
    if rows:
        keys = list(dict.fromkeys(k for r in rows for k in r))
        with open(out / "categories.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=keys)
            w.writeheader()
            w.writerows(rows)
        print(json.dumps([{k: r[k] for k in ("category", "kept_start", "spread_pct",
                                            "criteria_met")} for r in rows], indent=1))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", nargs="?", default="benchmarks/human_body/categories", type=Path)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--speed", type=float, default=4.0)
    ap.add_argument("--people-weight", type=float, default=None,
                    help="people's joint-angle term [1/rad²] (default: the body's, 10)")
    ap.add_argument("--trial", action="store_true",
                    help="also start from the measured trial (at weight 10 it lands in far "
                         "dearer basins or fails: Cat4 56.8 after 3000 iterations, 1606 s)")
    ap.add_argument("--table-only", action="store_true")
    args = ap.parse_args(argv)
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    shipped = str(Path(__file__).resolve().parents[2] / "src" / "bladelab" / "data" / "runner"
                  / "collocation" / SHIPPED)
    if not args.table_only:
        root = Path(__file__).resolve().parents[2]
        first = [(c, s, g) for c in CATEGORIES
                 for s, g in (("shipped", shipped), ("fast", str(root / FAST.format(c))))
                 + ((("trial", "trial"),) if args.trial else ())
                 if _path(out, c, s) is None]
        _run(first, args.jobs, out, args.speed, args.people_weight)
        second = []
        for c in CATEGORIES:
            kept = _kept(out, NEIGHBOUR[c])
            if _path(out, c, "neighbour") is None and kept is not None:
                p = _path(out, NEIGHBOUR[c], kept[0])
                second.append((c, "neighbour", str(p)))
        _run(second, args.jobs, out, args.speed, args.people_weight)
        kept = {c: _kept(out, c) for c in CATEGORIES}
        kept = {c: k for c, k in kept.items() if k is not None}
        if kept:
            lowest = min(kept, key=lambda c: kept[c][1].nlp.objective)
            source = str(_path(out, lowest, kept[lowest][0]))
            third = [(c, "best", source) for c in CATEGORIES
                     if c != lowest and _path(out, c, "best") is None]
            _run(third, args.jobs, out, args.speed, args.people_weight)
    _table(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
