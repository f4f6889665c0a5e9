"""The loads each category's best 4 m/s stride puts on the socket (``collocation.loads``), from
``speed-4/CAT-best.json``; prints a Markdown table. Usage (repository root):
``.venv/bin/python benchmarks/collocation/study-human-swing-knee-2026-12-03/socket_loads.py``
"""

from __future__ import annotations

from pathlib import Path

from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.loads import peak_loads
from bladelab.predict.collocation.nodes import evaluate_nodes
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.runner.layout import CP_LEG

HERE = Path(__file__).resolve().parent
CATEGORIES = ("Cat4", "Cat5", "Cat6", "Cat6High", "Cat7")


def main() -> None:
    print("| category | peak socket force [N] | [BW] | peak socket moment [N·m] |")
    print("|---|---|---|---|")
    for cat in CATEGORIES:
        sol = CollocationSolution.read(HERE / "speed-4" / f"{cat}-best.json")
        runner = runner_from_spec(sol.model_spec)
        nodes = evaluate_nodes(build_collocation_model(runner), sol.nlp.q, sol.nlp.qd,
                               sol.nlp.tendon_force, sol.nlp.tendon_force_rate)
        loads = peak_loads(runner, sol.nlp, nodes["forces"], nodes["passive"],
                           runner.contact_params[:, CP_LEG] == 1)
        weight = runner.total_mass * runner.gravity
        print(f"| {cat} | {loads['socket_force_max_N']:.0f} | "
              f"{loads['socket_force_max_N'] / weight:.2f} | {loads['socket_moment_max_Nm']:.1f} |")


if __name__ == "__main__":
    main()
