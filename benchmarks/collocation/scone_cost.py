"""Seed 001's category table on seed 001's body: the cost of transport at 4 m/s as bladelab
counts it and as SCONE counts it, beside seed 001's.

Usage (repository root)::

    .venv/bin/python benchmarks/collocation/scone_cost.py [STUDY_FOLDER]

``STUDY_FOLDER`` (default ``benchmarks/collocation/study-2026-11-25/amputee``) holds
``amputee-<category>/speed-4.json`` collocation strides on seed 001's body. Prints a markdown
table: per category bladelab's cost (Uchida et al. 2016 with muscle masses from 60 N/cm², basal
1.51 W/kg), SCONE's accounting of the same stride (masses from 0.25 MPa, basal 1.2 W/kg;
``bladelab.predict.collocation.analyses.cost_of_transport``) and seed 001's (its §3.2 A,
reflex controller in SCONE), all in J/(kg·m), with the stride's contact time and peaks.
"""

from __future__ import annotations

import sys
from pathlib import Path

from bladelab.predict.collocation.analyses import (
    SCONE_BASAL_W_PER_KG,
    SCONE_SPECIFIC_TENSION_PA,
    cost_of_transport,
)
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.report.predictive_sections import seed001_results

CATEGORIES = ("Cat4", "Cat5", "Cat6", "Cat6High", "Cat7")


def main() -> None:
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else
                  "benchmarks/collocation/study-2026-11-25/amputee")
    seed = seed001_results()
    seed = seed[seed["quantity"] == "cot_4"].set_index("category")["value"]
    print("| category | bladelab's count | SCONE's count | seed 001 | SCONE's / seed 001 | "
          "contacts intact / prosthetic [s] | peaks [BW] |")
    print("|---|---|---|---|---|---|---|")
    for cat in CATEGORIES:
        sol = CollocationSolution.read(folder / f"amputee-{cat}" / "speed-4.json")
        own = cost_of_transport(sol)
        scone = cost_of_transport(sol, specific_tension_pa=SCONE_SPECIFIC_TENSION_PA,
                                  basal_w_per_kg=SCONE_BASAL_W_PER_KG)
        s = sol.summary()
        print(f"| {cat} | {own:.2f} | {scone:.2f} | {seed[cat]:.2f} | {scone / seed[cat]:.2f} | "
              f"{s['contact_time_intact_s']:.3f} / {s['contact_time_prosthetic_s']:.3f} | "
              f"{s['peak_vertical_grf_intact_bw']:.2f} / "
              f"{s['peak_vertical_grf_prosthetic_bw']:.2f} |")


if __name__ == "__main__":
    main()
