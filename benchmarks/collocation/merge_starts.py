"""Merge collocation sweeps of the same problems solved along different paths: keep, per model
and problem, the converged solve with the lowest objective (one without gait warnings if there
is one: :func:`bladelab.predict.collocation.starts.pick`, the rule of ``bladelab sweep
--starts K``).

    python benchmarks/collocation/merge_starts.py OUT LABEL_A=SWEEP_A LABEL_B=SWEEP_B ...

Each SWEEP is a ``bladelab sweep --method collocation`` folder (``collocation-sweep.csv`` and
its files); LABEL names the path (e.g. ``ipopt-defaults``, ``warm-mu-1e-4``). OUT receives the
kept solution files (``<model>/<file>``) and a ``collocation-sweep.csv`` in the sweep's format
plus the columns of :func:`bladelab.predict.collocation.starts.start_columns` (the same as a
``--starts`` sweep's): ``start`` (the label kept), ``starts`` (how many paths converged),
``objective``, ``objective_<label>`` for every path (NaN where that path did not converge) and
``spread_pct`` (largest minus lowest objective among the converged paths without gait
warnings, in % of the lowest). ``bladelab report OUT`` renders it.

Why (docs/collocation.md, "Local optima along a continuation"): the stride's landscape has
local optima 15–25 % apart, and which one a warm-started solve reaches depends on the path and
on IPOPT's barrier start; two paths per problem and the better one kept is the cheapest
multi-start. ``bladelab sweep --method collocation --starts K`` now does this inside the sweep,
continuing each model from the kept solution; this script merges whole paths.
"""

from __future__ import annotations

import math
import shutil
import sys
from pathlib import Path

import pandas as pd


def _candidate(label: str, folder: Path, file: str, converged: bool):
    """The start of one path's solve (objective and gait warnings from its file)."""
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.predict.collocation.starts import Candidate, candidate

    if not converged:
        return Candidate(label, False, math.nan)
    return candidate(label, CollocationSolution.read(folder / file))


def merge(out: Path, sweeps: dict[str, Path]) -> pd.DataFrame:
    """Write OUT (module docstring) and return its table."""
    from bladelab.predict.collocation.starts import pick, start_columns
    from bladelab.predict.collocation.sweep import SWEEP_TABLE, write_table

    tables = {}
    for label, folder in sweeps.items():
        t = pd.read_csv(folder / SWEEP_TABLE)
        t["converged"] = t.converged.astype(str).str.lower() == "true"
        t["candidate"] = [_candidate(label, folder, f, ok)
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
        kept = pick([r.candidate for r in cands.values()])
        label, best = kept.label, cands[kept.label]
        row = best.drop(labels=["key", "candidate"]).to_dict()
        row.update(start_columns([r.candidate for r in cands.values()], label, labels=list(tables)))
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
    cols = ["model", "problem", "prescribed_speed_mps", "converged", "start", "starts", "objective",
            *[f"objective_{lab}" for lab in sweeps], "spread_pct"]
    print(table[cols].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
