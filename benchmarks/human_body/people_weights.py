"""The category study at several weights of people's joint angles, side by side.

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/people_weights.py W=DIR [W=DIR ...]

Each ``DIR`` is a ``bladelab sweep --method collocation`` folder solved at the weight ``W``
[1/rad²] (``--people-weight``). Prints one markdown row per model: cost of transport at
4 m/s [J/(kg·m)], the maximum speed [m/s], the 4 m/s stride time [s], peaks [BW] and peak
swing knee flexion [deg] per leg, and the criteria of people's running met at 4 m/s, each
as ``w0 / w1 / ...`` in the order given.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.solution import CollocationSolution


def _rows(folder: Path) -> dict[tuple[str, str], dict]:
    with open(folder / "collocation-sweep.csv", newline="", encoding="utf-8") as f:
        return {(r["model"], r["problem"] + r["prescribed_speed_mps"]): r for r in csv.DictReader(f)}


def _criteria(folder: Path, row: dict) -> dict:
    sol = CollocationSolution.read(folder / row["file"])
    return {c.name: c for c in human_running_criteria(sol)}


def main() -> None:
    studies = [(w, Path(d)) for w, d in (a.split("=", 1) for a in sys.argv[1:])]
    tables = [(w, folder, _rows(folder)) for w, folder in studies]
    models = list(dict.fromkeys(m for _, _, rows in tables for m, _ in rows))
    print("weights: " + " / ".join(w for w, _ in studies))
    print("| model | CoT 4 m/s [J/(kg·m)] | maximum speed [m/s] | stride 4 m/s [s] | "
          "peaks 4 m/s [BW] | swing knees 4 m/s [deg] | criteria met at 4 m/s |")
    print("|---|---|---|---|---|---|---|")
    for model in models:
        cells = {k: [] for k in ("cot", "vmax", "stride", "peaks", "knees", "met")}
        for _, folder, rows in tables:
            r4 = rows.get((model, "speed4.0"))
            rmax = next((r for (m, p), r in rows.items() if m == model and p.startswith("max")),
                        None)
            if r4 is None or r4["converged"] != "True":
                for k in cells:
                    cells[k].append("–")
            else:
                crit = _criteria(folder, r4)
                legs = [n.split(", ")[1] for n in crit if n.startswith("peak vertical")]
                cells["cot"].append(f"{float(r4['cost_of_transport_J_per_kg_m']):.2f}")
                cells["stride"].append(f"{float(r4['stride_time_s']):.3f}")
                cells["peaks"].append(", ".join(
                    f"{crit['peak vertical ground force, ' + leg].value:.2f}" for leg in legs))
                cells["knees"].append(", ".join(
                    f"{crit['peak swing knee flexion, ' + leg].value:.0f}" for leg in legs))
                cells["met"].append(f"{sum(c.met for c in crit.values())}/{len(crit)}")
            ok = rmax is not None and rmax["converged"] == "True"
            cells["vmax"].append(f"{float(rmax['mean_speed_mps']):.2f}" if ok else "–")
        print(f"| {model} | " + " | ".join(" / ".join(v) for v in cells.values()) + " |")


if __name__ == "__main__":
    main()
