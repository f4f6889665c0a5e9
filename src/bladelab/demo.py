"""``python -m bladelab.demo`` (``make demo``): the characterise workflow on the example study.

Everything is written under ``examples/`` in the current working directory (:func:`examples_dir`;
``make demo`` runs it from the project root), never inside the installation.

1. Generates (or reuses) the **synthetic** example study in ``examples/sprint-study/``
   (``bladelab example make``; see ``docs/example-study.md``): 50 C3D trials of seed 000's cohort.
2. Identifies K* and D* of every trial with 2 worker processes (``bladelab identify --jobs 2``).
3. Writes the study report ``examples/sprint-study/report/index.html`` (``bladelab report``).
4. Runs the trial pipeline on one real recording shipped with bladelab
   (:func:`bladelab.datasets.measured_running_trial`, Fukuchi et al. 2017: a recreational runner,
   62 kg, treadmill at 3.5 m/s): its stances with peak forces in body weights.

5. Runs the design example (seed 002, ``docs/design.md``): a 25-run face-centred CCD over the
   default design space with the blade evaluator into ``examples/design-study/`` and its report
   ``examples/design-study/report/index.html`` (surfaces, optimum; the blade evaluator has no
   runner, so seed 002's trends about running are not tested by it); and, in a repository
   checkout, the report of the committed predicted-gait design study
   (:data:`PREDICTED_DESIGN_STUDY`: a transtibial runner's predicted stride per blade), rebuilt
   from its files without a solve into ``examples/design-predicted/report/index.html``.

A complete example study and finished identifications (and design runs) are reused, so a second
``make demo`` only rewrites the reports.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd

from bladelab.datasets import MEASURED_SUBJECT_MASS_KG, measured_running_trial
from bladelab.design import BladeEvaluator, default_design_space, run_design
from bladelab.design.plots import write_design_figures
from bladelab.errors import BladelabError
from bladelab.example.study import default_example_dir, make_example_study
from bladelab.predict import defaults
from bladelab.predict.collocation.human_running import human_running_criteria
from bladelab.predict.collocation.named_runs import solve_named_stride
from bladelab.predict.collocation.output_folder import SOLUTION_FILE
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.report.design import build_design_report
from bladelab.report.predictive import build_predictive_report
from bladelab.report.study import build_study_report
from bladelab.runner.params import RUNNER_DATA_DIR
from bladelab.study import run_study
from bladelab.trial import detect_stances, read_c3d
from bladelab.units import body_weight

#: Mass [kg] of the runner of the demo's real trial (subject RBDS001, ``RBDSinfo.txt``).
DEMO_MASS_KG = MEASURED_SUBJECT_MASS_KG


def examples_dir() -> Path:
    """The folder the demo writes into: ``examples/`` under the current working directory (read
    when called), so that ``make demo`` from the project root fills ``examples/`` there and an
    installed bladelab writes beside the user, never into the installation."""
    return Path.cwd() / "examples"


def run(path: str | Path | None = None, *, rows: int = 5) -> str:
    """Run the trial pipeline on the real trial ``path`` (default: the shipped
    :func:`~bladelab.datasets.measured_running_trial`, a 62 kg runner) and return the printed
    summary.

    The first ``rows`` stances are listed (numbered from 1, as ``bladelab trial stances``); the
    ranges cover all of them.
    """
    path = measured_running_trial() if path is None else Path(path)
    trial = read_c3d(path)
    stances = detect_stances(trial)
    bw = body_weight(DEMO_MASS_KG)
    axes = trial.metadata["axes"]
    lines = [
        f"real trial {path.name} ({trial.duration:.1f} s, {len(trial.markers)} markers at "
        f"{trial.marker_rate:g} Hz, {len(trial.platforms)} force platform(s) at "
        f"{trial.platforms[0].rate:g} Hz; file axes forward {axes['forward']}, up {axes['up']})",
        f"{len(stances)} complete stances (threshold 20 N), runner {DEMO_MASS_KG:g} kg:",
        f"{'index':>5} {'start_s':>8} {'end_s':>8} {'contact_s':>9} {'peak_fz_N':>9} {'peak_BW':>7} "
        f"{'impulse_z_Ns':>12}",
    ]
    for s in stances[:rows]:
        lines.append(
            f"{s.index + 1:>5} {s.start_s:>8.3f} {s.end_s:>8.3f} {s.contact_time_s:>9.3f} "
            f"{s.peak_fz_N:>9.1f} {s.peak_fz_N / bw:>7.2f} {s.impulse_z_Ns:>12.2f}"
        )
    if len(stances) > rows:
        lines.append(f"  ... {len(stances) - rows} more (bladelab trial stances {path})")
    ct = [s.contact_time_s for s in stances]
    pk = [s.peak_fz_N / bw for s in stances]
    lines.append(
        f"contact time {min(ct):.3f}–{max(ct):.3f} s, peak vertical force {min(pk):.2f}–{max(pk):.2f} BW"
    )
    return "\n".join(lines)


#: Illustrative constraint thresholds of the design example (blade-evaluator proxies).
DESIGN_CONSTRAINTS = {"knee_moment_min_Nm": -30.0, "swing_clearance_m": 0.07}


def design_example(out_dir: str | Path | None = None, *, seed: int = 0) -> tuple[Path, list[str]]:
    """Run (or resume) the design example in ``out_dir`` (default ``examples/design-study`` under
    the current folder, :func:`examples_dir`) and write its report; returns (report, summary
    lines).

    A 25-run face-centred central composite design over :func:`default_design_space` with the
    blade evaluator (8 m/s, 76 kg), objective Δv_x, constraints :data:`DESIGN_CONSTRAINTS`.
    """
    import matplotlib

    matplotlib.use("Agg")

    out_dir = examples_dir() / "design-study" if out_dir is None else Path(out_dir)
    ev = BladeEvaluator()
    res = run_design(default_design_space(), runs="ccd", evaluator=ev, out_dir=out_dir, seed=seed,
                     objective="delta_vx_m_per_s", constraints=DESIGN_CONSTRAINTS, units=ev.units)
    write_design_figures(res, Path(out_dir), objective="delta_vx_m_per_s",
                         constraints=DESIGN_CONSTRAINTS)
    report = build_design_report(out_dir)
    lines = [f"design example: {res.design.n_runs} runs ({res.n_evaluated} evaluated, "
             f"{res.n_resumed} reused), blade evaluator, default space -> {out_dir}"]
    if res.optimum is not None:
        o = res.optimum
        pt = ", ".join(f"{k}={v:.4g}" for k, v in o.point.items())
        lines.append(f"  optimum Δv_x {o.predicted:+.3f} m/s (PI {o.pi[0]:+.3f} .. {o.pi[1]:+.3f})"
                     f" at {pt}")
    lines.append("  the blade evaluator has no runner: the blade under one prescribed passive "
                 f"stance (a {ev.body_mass_kg:g} kg point mass on a rigid pylon lands at "
                 f"{ev.speed_mps:g} m/s); its numbers "
                 "describe the blade, and seed 002's trends about running are not tested by it "
                 "(docs/guide-design.md)")
    return report, lines


#: The committed predicted-gait design study the demo renders (no solve), relative to the
#: folder the demo runs in (``make demo``: the repository root). A wheel does not carry it
#: (25 strides, several MB); the demo then says so and goes on.
PREDICTED_DESIGN_STUDY = (Path("benchmarks") / "design"
                          / "transtibial-people-stride-soleus-2026-12-07")


def predicted_design_example(out_dir: str | Path | None = None,
                             study: str | Path | None = None) -> tuple[Path | None, list[str]]:
    """The report of the committed predicted-gait design study ``study`` (default
    :data:`PREDICTED_DESIGN_STUDY` under the current folder), rebuilt from its files into
    ``out_dir`` (default ``examples/design-predicted/report``); returns (report or None when the
    study is not there, summary lines)."""
    study = Path.cwd() / PREDICTED_DESIGN_STUDY if study is None else Path(study)
    if not (study / "results.csv").is_file():
        return None, [f"predicted-gait design study: {study} not found (a repository checkout "
                      "has it; `bladelab report` rebuilds its report there)"]
    out_dir = examples_dir() / "design-predicted" / "report" if out_dir is None else Path(out_dir)
    report = build_design_report(study, out_dir=out_dir)
    results = pd.read_csv(study / "results.csv")
    cot = results["cost_of_transport_J_per_kg_m"]
    lines = [f"predicted-gait design study (committed, report rebuilt without a solve): "
             f"{len(results)} blades, each on the transtibial runner's predicted stride at "
             f"4 m/s and people's stride time -> {report}",
             f"  cost of transport {cot.min():.2f}–{cot.max():.2f} J/(kg·m) across the blades "
             "(the report: surfaces, optimum, seed 002's trends, every flagged stride)"]
    if "socket_moment_max_Nm" in results:
        socket = results["socket_moment_max_Nm"]
        lines.append(f"  peak socket moment {socket.min():.0f}–{socket.max():.0f} N·m "
                     f"(the cheapest blade: {socket[cot.idxmin()]:.0f} N·m)")
    return report, lines


#: The shipped stride the predict example starts from: the amputee runner on the human body
#: wearing a Cat6 blade at 4 m/s (benchmarks/human_body/README.md). It carries its multipliers,
#: so the solve starts from its primal and dual values and ends at once (docs/collocation.md,
#: "Warm starts"); from its primal values alone IPOPT's default barrier start wandered for
#: 946 iterations (measured).
PREDICT_EXAMPLE_STRIDE = RUNNER_DATA_DIR / "collocation" / "amputee-Cat6-4-human.json"


def predict_example(out_dir: str | Path | None = None) -> tuple[Path, list[str]]:
    """Solve (or read back) one amputee stride at 4 m/s on the human body in ``out_dir``
    (default ``examples/predict-amputee-Cat6-4`` under the current folder), warm-started from
    :data:`PREDICT_EXAMPLE_STRIDE`, and write its report; returns (report, summary lines), the
    lines saying criterion by criterion where the stride lies against people."""
    import matplotlib

    matplotlib.use("Agg")

    out_dir = examples_dir() / "predict-amputee-Cat6-4" if out_dir is None else Path(out_dir)
    t0 = time.perf_counter()
    res = solve_named_stride(
        out_dir, model="amputee", blade="Cat6", body="human",
        settings=CollocationSettings(speed_m_per_s=4.0,
                                     **people_settings("human", kind="amputee")),
        guess=str(PREDICT_EXAMPLE_STRIDE),
        resume=(out_dir / SOLUTION_FILE).is_file())
    sol = res.solution
    report = build_predictive_report(res.path, out_dir / "report", progress=False,
                                     robustness=False)
    s = sol.summary()
    how = "solved" if res.solved else "read back"
    lines = [f"predict example: amputee Cat6, human body, 4 m/s, {how} in "
             f"{time.perf_counter() - t0:.0f} s ({s['iterations']} IPOPT iterations, warm start "
             f"from the shipped stride; people's measured joint angles in the objective at "
             f"{defaults.PEOPLE_WEIGHT_PER_RAD2:g} 1/rad² and their swing knee, at least "
             f"{defaults.SWING_KNEE_MIN_DEG:g}°, imposed: docs/collocation.md) -> {out_dir}",
             f"  converged {s['converged']}, stride {s['stride_time_s']:.3f} s, cost of "
             f"transport {s['cost_of_transport_J_per_kg_m']:.2f} J/(kg·m), dynamics residual "
             f"{s['dynamics_residual_pct']:.2f} %"]
    crit = human_running_criteria(sol)
    lines.append(f"  against people running at 4 m/s: {sum(c.met for c in crit)} of {len(crit)} "
                 "gait criteria met (the report adds the joint angles against the measured "
                 "3.5 m/s trial)")
    lines += [f"    {c.line()}" for c in crit if not c.met]
    return Path(report.index), lines


@dataclasses.dataclass(frozen=True)
class PipelineResult:
    """What :func:`run_example_pipeline` did (times in seconds).

    Attributes
    ----------
    folder, report
        The study folder and its ``report/index.html``.
    generated
        False when a complete study was reused.
    n_trials, n_identified, n_failed
        Trials in the study, identified now or before, and failed.
    generate_s, identify_s, report_s
        Wall-clock time of each step [s].
    """

    folder: Path
    report: Path
    generated: bool
    n_trials: int
    n_identified: int
    n_failed: int
    generate_s: float
    identify_s: float
    report_s: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        d = dataclasses.asdict(self)
        d["folder"], d["report"] = str(self.folder), str(self.report)
        return d


def run_example_pipeline(
    folder: str | Path | None = None,
    *,
    seed: int = 0,
    jobs: int = 2,
    n_trials: int | None = None,
    progress: bool = True,
    echo: Callable[[str], None] = print,
) -> PipelineResult:
    """Generate (or reuse) the example study, identify all its trials, write its report.

    Parameters
    ----------
    folder
        Study folder (default ``examples/sprint-study`` under the current folder,
        :func:`~bladelab.example.study.default_example_dir`).
    seed
        Study seed.
    jobs
        Worker processes for generation and identification.
    n_trials
        A reduced study (tests); None: all 50 trials.
    progress
        Progress bars.
    echo
        Where the step lines go.
    """
    t0 = time.perf_counter()
    folder = default_example_dir() if folder is None else Path(folder)
    made = make_example_study(folder, seed=seed, jobs=jobs, n_trials=n_trials, progress=progress)
    t1 = time.perf_counter()
    echo(f"[1/3] example study {'generated' if made.generated else 'reused'}: {made.folder} "
         f"({made.n_trials} synthetic trials, {t1 - t0:.1f} s)")
    run = run_study(made.folder, jobs=jobs, progress=progress)
    t2 = time.perf_counter()
    echo(f"[2/3] identified K*, D*: {run.finished} trials now, {run.skipped} already done, "
         f"{len(run.failures)} failed ({t2 - t1:.1f} s, {jobs} jobs)")
    for tid, msg in run.failures:
        echo(f"      failed: {tid}: {msg[:160]}")
    rep = build_study_report(made.folder, progress=progress)
    t3 = time.perf_counter()
    flagged = (f", {rep.n_flagged} flagged and left out of the group statistics (listed in "
               "the report)" if rep.n_flagged else "")
    echo(f"[3/3] report of {rep.n_trials} trials{flagged} ({t3 - t2:.1f} s)")
    return PipelineResult(
        folder=made.folder, report=rep.index, generated=made.generated, n_trials=made.n_trials,
        n_identified=run.finished + run.skipped, n_failed=len(run.failures),
        generate_s=t1 - t0, identify_s=t2 - t1, report_s=t3 - t2,
    )


def _summary(report: Path) -> list[str]:
    """Headline numbers from the report's CSV tables."""
    tables = report.parent / "tables"
    out = []
    grf = tables / "nrmse-grf.csv"
    dist = tables / "nrmse-distance.csv"
    if grf.is_file() and dist.is_file():
        g = pd.read_csv(grf).set_index("group")
        d = pd.read_csv(dist).set_index("group")
        for level in ("TF", "TT"):
            if level in g.index and level in d.index:
                out.append(f"  {level}: nRMSE GRF {g.loc[level, 'nrmse_trials_mean_pct']:.1f} ± "
                           f"{g.loc[level, 'nrmse_trials_sd_pct']:.1f} %, distance "
                           f"{d.loc[level, 'nrmse_trials_mean_pct']:.1f} ± "
                           f"{d.loc[level, 'nrmse_trials_sd_pct']:.1f} % (individual trials)")
    truth = tables / "recovered-vs-true-parameters-per-trial.csv"
    if truth.is_file():
        t = pd.read_csv(truth)
        out.append(f"  identified vs true (synthetic ground truth, {len(t)} trials): median K error "
                   f"{t['K_error_pct'].median():+.1f} % against the hinge's nominal K")
        if "K_vs_secant_error_pct" in t.columns:
            out.append(f"    and {t['K_vs_secant_error_pct'].median():+.1f} % against its secant "
                       "stiffness at peak deflection (the generator's spring stiffens)")
        out.append(f"    median D error {t['D_error_pct'].median():+.1f} %")
    return out


def main() -> int:
    """Run the demo; a :class:`BladelabError` prints one line and returns 2."""
    t0 = time.perf_counter()
    try:
        print("bladelab demo: the characterise workflow on the SYNTHETIC example study "
              "(docs/example-study.md)", flush=True)
        res = run_example_pipeline(jobs=2, echo=lambda s: print(s, flush=True))
        print("\n".join(_summary(res.report)))
        print("\n" + run())
        print("\nbladelab demo: the design workflow (seed 002, docs/design.md)", flush=True)
        design_report, design_lines = design_example()
        print("\n".join(design_lines))
        predicted_report, predicted_lines = predicted_design_example()
        print("\n".join(predicted_lines))
        print("\nbladelab demo: the predict workflow (docs/guide-predict.md)", flush=True)
        predict_report, predict_lines = predict_example()
        print("\n".join(predict_lines))
    except BladelabError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(f"\ndemo finished in {time.perf_counter() - t0:.0f} s")
    print(f"report: {res.report}")
    print(f"design report: {design_report}")
    if predicted_report is not None:
        print(f"predicted-gait design report: {predicted_report}")
    print(f"predict report: {predict_report}")
    print(f"open them with: xdg-open {res.report}   (or any browser; they work offline)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
