"""Merge collocation sweeps of the same problems solved along different paths: keep, per model
and problem, the converged solve with the lowest objective.

    python benchmarks/collocation/merge_starts.py OUT LABEL_A=SWEEP_A LABEL_B=SWEEP_B ...

Each SWEEP is a ``bladelab sweep --method collocation`` folder (``collocation-sweep.csv`` and
its files); LABEL names the path (e.g. ``ipopt-defaults``, ``warm-mu-1e-4``). OUT receives the
kept solution files (``<model>/<file>``) and a ``collocation-sweep.csv`` in the sweep's format
plus the columns ``objective``, ``start`` (the label kept), ``objective_<label>`` for every
path (NaN where that path did not converge) and ``spread_pct`` (largest minus lowest
converged objective, in % of the lowest). ``bladelab report OUT`` renders it.

Why (docs/collocation.md, "Local optima along a continuation"): the stride's landscape has
local optima 15–25 % apart, and which one a warm-started solve reaches depends on the path and
on IPOPT's barrier start; two paths per problem and the better one kept is the cheapest
multi-start.
"""

from __future__ import annotations

import math
import shutil
import sys
from pathlib import Path

import pandas as pd


def _objective(folder: Path, file: str) -> float:
    from bladelab.predict.collocation.solution import CollocationSolution

    return float(CollocationSolution.read(folder / file).nlp.objective)


def merge(out: Path, sweeps: dict[str, Path]) -> pd.DataFrame:
    """Write OUT (module docstring) and return its table."""
    from bladelab.predict.collocation.sweep import SWEEP_TABLE, write_table

    tables = {}
    for label, folder in sweeps.items():
        t = pd.read_csv(folder / SWEEP_TABLE)
        t["converged"] = t.converged.astype(str).str.lower() == "true"
        t["objective"] = [_objective(folder, f) if ok else math.nan
                          for f, ok in zip(t.file, t.converged, strict=True)]
        t["key"] = list(zip(t.model, t.problem, t.prescribed_speed_mps.fillna(-1.0),
                            strict=True))
        tables[label] = t
    keys = []
    for t in tables.values():
        keys.extend(k for k in t.key if k not in keys)
    rows = []
    for key in keys:
        cands = {lab: t[t.key == key].iloc[0] for lab, t in tables.items() if (t.key == key).any()}
        ok = {lab: r for lab, r in cands.items() if r.converged}
        label, best = (min(ok.items(), key=lambda kv: kv[1].objective) if ok
                       else next(iter(cands.items())))
        row = best.drop(labels=["key"]).to_dict()
        row["start"] = label
        objs = {lab: r.objective for lab, r in ok.items()}
        for lab in tables:
            row[f"objective_{lab}"] = objs.get(lab, math.nan)
        lo = min(objs.values()) if objs else math.nan
        row["spread_pct"] = (100.0 * (max(objs.values()) - lo) / abs(lo)
                             if len(objs) > 1 else math.nan)
        src = sweeps[label] / best.file
        dst = out / best.file
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, dst)
        rows.append(row)
    write_table(out / SWEEP_TABLE, rows)
    return pd.DataFrame(rows)


def main(argv: list[str]) -> int:
    if len(argv) < 3 or any("=" not in a for a in argv[1:]):
        print(__doc__, file=sys.stderr)
        return 2
    out = Path(argv[0])
    sweeps = {a.split("=", 1)[0]: Path(a.split("=", 1)[1]) for a in argv[1:]}
    table = merge(out, sweeps)
    cols = ["model", "problem", "prescribed_speed_mps", "converged", "start", "objective",
            *[f"objective_{lab}" for lab in sweeps], "spread_pct"]
    print(table[cols].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
