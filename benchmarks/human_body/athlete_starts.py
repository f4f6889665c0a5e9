"""Several starts for a scaled athlete: the amputee with Cat6 at 4 m/s, 68 kg and 1.75 m.

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/athlete_starts.py OUT [--jobs 1]

The human body scaled to the athlete (``athlete_params``: seed 001's rule), people's joint
angles at the body's weight, mesh 50, from three starts, each scaled to the athlete's height
(the pelvis's translations) with its multipliers dropped, as the ``stored`` guess does:
``stored`` (the shipped amputee Cat6 stride at 4 m/s), ``neighbour`` (the kept Cat5 stride of
the category record ``categories-people10/``), ``fast`` (Cat6's 5 m/s stride of the
committed category study) and ``kept`` (the record's kept Cat6 stride, the lowest of its
starts). Writes ``OUT/<start>.json`` (``.best_iterate.json`` if IPOPT did
not converge; a file already there is kept) and prints each solve's objective and summary and
the spread of the converged objectives [%].
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ATHLETE = {"body_mass_kg": 68.0, "height_m": 1.75}
ROOT = Path(__file__).resolve().parents[2]
STARTS = {
    "stored": "stored",
    "neighbour": str(ROOT / "benchmarks/human_body/categories-people10/Cat5.shipped.json"),
    "fast": str(ROOT / "benchmarks/collocation/study-human-people10-2026-11-29/"
                       "amputee-Cat6-human/speed-5.json"),
    "kept": str(ROOT / "benchmarks/human_body/categories-people10/Cat6.neighbour.json"),
}


def _solve(out: str, name: str, start: str) -> str:
    from bladelab.predict.collocation.settings import CollocationSettings, people_term
    from bladelab.predict.collocation.solve import predict_stride
    from bladelab.predict.collocation.starting_guess import make_guess, scaled_to_athlete
    from bladelab.predict.collocation.stored import check_model_spec, runner_from_spec
    from bladelab.predict.defaults import PEOPLE_WEIGHT_PER_RAD2

    spec = check_model_spec({"model": "amputee", "blade": "Cat6", "body": "human",
                             "athlete": ATHLETE})
    runner = runner_from_spec(spec)
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=4.0,
                                   **people_term(PEOPLE_WEIGHT_PER_RAD2))
    guess = make_guess(runner, start, n=50, speed=4.0)
    if start != "stored":  # the stored guess is scaled by make_guess itself
        guess = scaled_to_athlete(guess, runner)
    sol = predict_stride(runner, settings, guess, model_spec=spec, track=False)
    path = Path(out) / f"{name}{'.json' if sol.converged else '.best_iterate.json'}"
    sol.write(path)
    return json.dumps({"start": name, "converged": sol.converged,
                       "objective": sol.nlp.objective, **sol.summary()})


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--jobs", type=int, default=1)
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    todo = [(n, s) for n, s in STARTS.items()
            if not any((args.out / f"{n}{x}").is_file() for x in (".json", ".best_iterate.json"))]
    with ProcessPoolExecutor(args.jobs) as pool:
        for line in pool.map(_solve, [str(args.out)] * len(todo), *zip(*todo, strict=True)):
            print(line, flush=True)
    from bladelab.predict.collocation.solution import CollocationSolution
    done = {p.stem: CollocationSolution.read(p).nlp.objective for p in args.out.glob("*.json")
            if not p.name.endswith(".best_iterate.json")}
    if done:
        lo = min(done.values())
        print("converged:", {k: round(v, 4) for k, v in done.items()},
              f"spread {100 * (max(done.values()) - lo) / lo:.2f} %")


if __name__ == "__main__":
    main()
