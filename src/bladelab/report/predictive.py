"""The HTML report of predictive-running results (``bladelab report PATH``).

``PATH`` is one of (:func:`predictive_kind`):

- ``"run"``: a ``bladelab predict`` folder (``best.json`` and ``history.csv``);
- ``"runs"``: a ``bladelab predict --seeds ...`` folder (``summary.json`` and ``seed-<n>/``);
- ``"sweep"``: a ``bladelab sweep`` folder (``results.csv``, ``summary.csv``,
  ``<category>/<speed>/best.json``);
- ``"parameters"``: one parameter JSON file (keys ``model``, ``blade``, ``speed_m_per_s``,
  ``settings`` {``dt``, ...}, ``parameters``);
- ``"collocation"``: a collocation solution (``"kind": "collocation-solution"``, the
  ``solution.json`` of ``bladelab predict --method collocation``, or its folder): its stride
  repeated, not re-simulated (:mod:`bladelab.report.collocation`);
- ``"recipe-sweep"``: a ``bladelab sweep --recipe`` folder (``levels.csv``,
  ``<category>/seed-<n>/levels.json``): every level re-simulated and judged, the category
  table with the seeds' agreement, and each category's fastest gait
  (:mod:`bladelab.report.recipe_sweep`);
- ``"collocation-sweep"``: a ``bladelab sweep --method collocation`` folder
  (``collocation-sweep.csv``): cost, contact times and GRF against speed per model, the
  category table beside seed 001, and the maximum-speed solutions' strides
  (:mod:`bladelab.report.collocation_sweep`).

Nothing is taken from a stored evaluation: every reflex solution is simulated again from its parameters
(:func:`bladelab.predict.reflex.objective.simulate_controlled` with the file's time step). The sections
shown (:func:`bladelab.report.predictive_sections.add_predictive_sections`) come from a
``duration`` (10 s) re-simulation recorded every 2nd step. A run's cost terms are recomputed with
the run's own objective settings (its duration, robust sampling) and set beside the stored best
cost; a sweep's category summary is recomputed from every cell the same way.

Each solution shown is also animated in the page, and with ``export=True`` written for OpenSim
and other tools (:func:`bladelab.runner.export.write_opensim`) into ``export/<solution>/`` of
the report folder.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from bladelab._io import read_json
from bladelab.errors import InputFileError
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.reflex.agreement import seed_agreement
from bladelab.predict.reflex.controller import read_parameters
from bladelab.predict.reflex.objective import simulate_controlled
from bladelab.predict.reflex.optimize import runner_and_layout, stored_body, stored_settings
from bladelab.predict.reflex.robust import robust_evaluation
from bladelab.predict.reflex.sweep import finished_cell, summarise
from bladelab.report.builder import Report
from bladelab.report.collocation import collocation_sections, collocation_solution_file
from bladelab.report.collocation_sweep import collocation_sweep_sections, is_collocation_sweep
from bladelab.report.predictive_robustness import robustness_runs, robustness_section
from bladelab.report.predictive_sections import add_predictive_sections
from bladelab.report.recipe_sweep import is_recipe_sweep, recipe_sweep_sections
from bladelab.runner.analyses import power_balance_residual_pct, spatiotemporal, swing_contacts
from bladelab.runner.export import write_opensim

__all__ = ["PredictiveReport", "build_predictive_report", "default_report_dir", "predictive_kind"]

_KINDS_HINT = (
    "give a 'bladelab predict' folder (best.json + history.csv, or summary.json + seed-N/), "
    "a 'bladelab sweep' folder (results.csv + summary.csv, or collocation-sweep.csv), a "
    "parameter JSON file or a collocation solution.json"
)


@dataclasses.dataclass(frozen=True)
class PredictiveReport:
    """What :func:`build_predictive_report` wrote."""

    index: str
    kind: str
    solutions: tuple[str, ...]
    simulations: int

    def to_dict(self) -> dict:
        return dataclasses.asdict(self) | {"solutions": list(self.solutions)}


def predictive_kind(path: str | Path) -> str | None:
    """``"run"``, ``"runs"``, ``"sweep"``, ``"recipe-sweep"``, ``"parameters"``,
    ``"collocation"``, ``"collocation-sweep"`` or None (see
    module docstring); a collocation best iterate raises InputFileError (not a solution)."""
    p = Path(path)
    if collocation_solution_file(p) is not None:
        return "collocation"
    if p.is_file():
        if p.suffix.lower() != ".json":
            return None
        try:
            data = json.loads(p.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        ok = isinstance(data, dict) and isinstance(data.get("parameters"), dict)
        return "parameters" if ok else None
    if not p.is_dir():
        return None
    if is_collocation_sweep(p):
        return "collocation-sweep"
    if is_recipe_sweep(p):
        return "recipe-sweep"
    if (p / "results.csv").is_file() and (p / "summary.csv").is_file():
        if any(p.glob("*/*/best.json")):
            return "sweep"
    if (p / "best.json").is_file() and (p / "history.csv").is_file():
        return "run"
    if (p / "summary.json").is_file() and any(p.glob("seed-*/best.json")):
        return "runs"
    return None


def _read_json(path: Path) -> dict:
    data = read_json(path, what="parameter file")
    if not isinstance(data, dict) or not isinstance(data.get("parameters"), dict):
        raise InputFileError("expected a parameter file with a 'parameters' mapping", file=path)
    return data


@dataclasses.dataclass
class _Solution:
    """A parameter file, its model and settings, and its simulations (cached)."""

    path: Path
    data: dict
    model: object = None
    layout: object = None
    x: np.ndarray | None = None
    body: str = "seed001"

    def __post_init__(self) -> None:
        kind = self.data.get("model", "able")
        if kind not in ("able", "amputee"):
            raise InputFileError(f"unknown model {kind!r}", file=self.path, where="model")
        blade = self.data.get("blade") or ("Cat6" if kind == "amputee" else None)
        self.body = stored_body(self.data, self.path)
        self.model, self.layout = runner_and_layout(kind, blade, self.body)
        self.x = read_parameters(self.path, self.layout, body=self.body)

    @property
    def kind(self) -> str:
        return self.data.get("model", "able")

    @property
    def blade(self) -> str | None:
        return self.data.get("blade") if self.kind == "amputee" else None

    @property
    def speed(self) -> float:
        s = self.data.get("speed_m_per_s", self.data.get("settings", {}).get("speed", 3.5))
        return float(s)

    def settings(self, duration: float | None = None, *, nominal: bool = False):
        """The run's objective settings (unknown keys dropped), optionally another duration."""
        return stored_settings(self.data, speed=self.speed, duration=duration, nominal=nominal)

    def simulate(self, duration: float | None = None):
        """(Evaluation, RunnerResult) of a nominal simulation recorded every 2nd step."""
        s = self.settings(duration, nominal=True)
        return simulate_controlled(self.model, self.x, layout=self.layout, settings=s,
                                   record_every=2)

    def evaluate(self, nominal_ev):
        """The evaluation as the optimiser computed it (robust mean where the run used it)."""
        s = self.settings()
        if s.robust_samples > 1:
            return robust_evaluation(nominal_ev, self.model, self.x, self.layout, s)
        return nominal_ev

    def label(self) -> str:
        who = "able-bodied" if self.kind == "able" else f"amputee {self.blade}"
        on = "" if self.body == "seed001" else f" ({self.body} body)"
        return f"{who} {self.speed:g} m/s{on}"


class _Counter:
    """A progress bar that also counts (a disabled tqdm does not)."""

    def __init__(self, bar) -> None:
        self.bar, self.count = bar, 0

    def update(self) -> None:
        self.count += 1
        self.bar.update()

    def __enter__(self) -> _Counter:
        return self

    def __exit__(self, *exc) -> None:
        self.bar.close()


def _close(a: float, b: float) -> bool:
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.isnan(a) and math.isnan(b)
    return bool(np.isclose(a, b, rtol=1e-9, atol=1e-12))


def _resim_row(label: str, sol: _Solution, ev, res) -> dict:
    swings = swing_contacts(res)
    return {
        "solution": label,
        "time step (s)": sol.settings().dt,
        "simulated (s)": ev.duration,
        "fell (yes/no)": bool(ev.fell),
        "prescribed speed (m/s)": sol.speed,
        "mean speed (m/s)": ev.mean_speed,
        "cost (–)": ev.cost,
        "J_cot (J/(kg·m))": ev.j_cot,
        "power-balance residual (%)": power_balance_residual_pct(res),
        "swing contacts (count)": len(swings),
        "largest swing contact (N)": float(swings.peak_N.max()) if len(swings) else 0.0,
    }


def _convergence_figure(histories: dict[str, pd.DataFrame]):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 3.5))
    positive = True
    for name, h in histories.items():
        tag = f"{name}: " if len(histories) > 1 else ""
        ax.plot(h.generation, h.best, label=f"{tag}best")
        ax.plot(h.generation, h["median"], "--", alpha=0.7, label=f"{tag}generation median")
        positive = positive and bool((h[["best", "median"]].to_numpy() > 0).all())
    if positive:
        ax.set_yscale("log")
    else:
        ax.set_yscale("symlog")
    ax.set_xlabel("generation")
    ax.set_ylabel("cost J (–)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _read_history(folder: Path) -> pd.DataFrame:
    path = folder / "history.csv"
    try:
        h = pd.read_csv(path)
    except (OSError, ValueError) as err:
        raise InputFileError(f"cannot read the history ({err})", file=path) from None
    missing = {"generation", "evaluations", "best", "median"} - set(h.columns)
    if missing:
        raise InputFileError(f"history lacks column(s) {', '.join(sorted(missing))}", file=path)
    return h


def _run_sections(report, folders: dict[str, Path], duration: float,
                  bar) -> tuple[dict, list, Path]:
    """Convergence + run summary sections; returns ({label: result}, re-simulation rows, the
    parameter file shown)."""
    histories, rows, sols = {}, [], {}
    for name, folder in folders.items():
        histories[name] = _read_history(folder)
        sol = _Solution(folder / "best.json", _read_json(folder / "best.json"))
        ev0, _ = sol.simulate()  # the run's own settings (duration, dt)
        bar.update()
        ev = sol.evaluate(ev0)
        stored = (sol.data.get("evaluation") or {}).get("cost", math.nan)
        wall = sol.data.get("wall_time_s")
        rows.append({
            "run": name,
            "seed (–)": sol.data.get("seed"),
            "generations (count)": sol.data.get("generation"),
            "evaluations (count)": sol.data.get("evaluations"),
            "wall time (s)": math.nan if wall is None else float(wall),
            "stored best cost (–)": float(stored),
            "recomputed cost (–)": ev.cost,
            "stored cost reproduced (yes/no)": _close(ev.cost, float(stored)),
            "J_cot (J/(kg·m))": ev.j_cot,
            "J_gait (–)": ev.j_gait,
            "J_inj (N·m)": ev.j_inj,
            "J_lean (deg)": ev.j_lean,
            **({"J_track (rad²)": ev.j_track, "tracked strides (count)": ev.track_strides}
               if (sol.data.get("settings") or {}).get("track") else {}),
            "fell, nominal or a robust copy (yes/no)": bool(ev.fell),
            "simulated (s)": ev.duration,
            "mean speed (m/s)": ev.mean_speed,
        })
        sols[name] = (sol, ev.cost)
    table = pd.DataFrame(rows)
    agreement = ""
    if len(rows) > 1:
        agree = seed_agreement(table["recomputed cost (–)"].tolist(),
                               table["mean speed (m/s)"].tolist())
        table["agrees with the best seed (yes/no)"] = list(agree.agreeing)
        agreement = " Seeds, on the same copies: " + agree.describe()
    import matplotlib.pyplot as plt

    fig = _convergence_figure(histories)
    report.add_section(
        "Optimisation: convergence and run summary",
        figures=[("Best and generation-median cost per generation (log scale)", fig)],
        tables=[("Run summary: the best solution re-evaluated with the run's own settings",
                 table)],
        text=("Every cost term is recomputed from best.json's parameters with the run's objective "
              "settings (simulated time, time step, robust sampling) and set beside the cost the "
              "optimiser stored (a run whose copies changed every generation stored its best's "
              "cost on its last generation's copies; the recomputed cost uses the fixed copies "
              "every run shares, so the two differ). Wall time: elapsed time of the "
              "optimisation summed over resumes (blank for runs written before it was "
              f"recorded).{agreement}"),
    )
    plt.close(fig)
    name = min(sols, key=lambda n: sols[n][1])
    sol = sols[name][0]
    ev, res = sol.simulate(duration)
    bar.update()
    label = f"{sol.label()} (best of {name})" if len(folders) > 1 else sol.label()
    return {label: res}, [_resim_row(label, sol, ev, res)], sol.path


def _sweep_cells(folder: Path) -> tuple[list[tuple[str, float, Path]], list[str]]:
    """The sweep's finished cells (category, prescribed speed [m/s], folder), in results.csv's
    category order, and the names of the unfinished ones (still optimising or stopped: their
    best.json is an interim best, so they are left out)."""
    try:
        res = pd.read_csv(folder / "results.csv")
        order = list(dict.fromkeys(res.category.astype(str)))
    except (OSError, ValueError, AttributeError) as err:
        raise InputFileError(f"cannot read the sweep results ({err})",
                             file=folder / "results.csv") from None
    cells, unfinished = [], []
    for cat_dir in sorted(p for p in folder.iterdir() if p.is_dir()):
        for cell in cat_dir.iterdir():
            if not (cell / "best.json").is_file():
                continue
            try:
                speed = float(cell.name)
            except ValueError:
                continue
            if finished_cell(cell) is not None:
                cells.append((cat_dir.name, speed, cell))
            else:
                unfinished.append(f"{cat_dir.name} at {speed:g} m/s")
    rank = {c: i for i, c in enumerate(order)}
    cells.sort(key=lambda c: (rank.get(c[0], len(rank)), c[0], c[1]))
    return cells, sorted(unfinished)


def _sweep_sections(
    report, folder: Path, duration: float, bar
) -> tuple[dict, list, pd.DataFrame, list[tuple[str, float, Path]]]:
    """Add the sweep's sections; return the solutions shown, their re-simulation rows, the
    recomputed category summary and the finished cells (:func:`_sweep_cells`)."""
    cells, unfinished = _sweep_cells(folder)
    rows, sims = [], {}
    for cat, speed, cell in cells:
        sol = _Solution(cell / "best.json", _read_json(cell / "best.json"))
        ev0, res = sol.simulate()
        bar.update()
        ev = sol.evaluate(ev0)
        st = spatiotemporal(res)
        ct = {f"contact_time_{leg}": st.value[(st.leg == leg)
                                             & (st.variable == "contact_time")].iloc[0]
              for leg in ("intact", "prosthetic")}
        rows.append({"category": cat, "speed": speed, **ev.to_dict(tracking=False), **ct})
        sims[(cat, speed)] = (sol, ev0, res)
    results = pd.DataFrame(rows)
    summary = summarise(results)
    try:
        stored = pd.read_csv(folder / "summary.csv").set_index("category")
    except (OSError, ValueError, KeyError):
        stored = pd.DataFrame()
    same = []
    for r in summary.itertuples(index=False):
        ok = r.category in stored.index and all(
            _close(float(getattr(r, q)), float(stored.loc[r.category, q]))
            for q in ("max_speed", "cot_4", "contact_time_intact", "contact_time_prosthetic")
            if q in stored.columns)
        same.append(bool(ok))
    check = summary[["category"]].assign(**{"as in summary.csv (yes/no)": same})
    report.add_section(
        "Sweep: recomputed cells",
        text=("Every cell's best.json is simulated again with the cell's own settings; the "
              "category summary below comes from these simulations, not from results.csv. "
              "'as in summary.csv' checks its maximum speed, cost at 4 m/s and contact times "
              "against the sweep's own table."
              + (" Unfinished cells, left out (their best is an interim one): "
                 + ", ".join(unfinished) + "." if unfinished else "")),
        tables=[("Cells re-evaluated with their own settings",
                 results.rename(columns={
                     "speed": "prescribed speed (m/s)", "cost": "cost (–)",
                     "j_cot": "J_cot (J/(kg·m))", "j_gait": "J_gait (–)", "j_inj": "J_inj (N·m)",
                     "j_lean": "J_lean (deg)", "fell": "fell (yes/no)",
                     "duration": "simulated (s)", "distance": "distance (m)",
                     "mean_speed": "mean speed (m/s)", "metabolic_energy": "metabolic energy (J)",
                     "n_steps": "steps (count)",
                     "contact_time_intact": "intact contact time (s)",
                     "contact_time_prosthetic": "prosthetic contact time (s)"})),
                ("Recomputed summary against the stored one", check)],
    )
    shown, resim = {}, []
    for cat in dict.fromkeys(c for c, _, _ in cells):
        mine = results[results.category == cat]
        ran = mine[~mine.fell.astype(bool)]
        picks = []
        if len(ran):
            top = ran.loc[ran.mean_speed.idxmax()]
            picks.append((float(top.speed), "highest speed that ran"))
        at35 = mine[np.isclose(mine.speed, 3.5)]
        if len(at35) and not any(np.isclose(p[0], 3.5) for p in picks):
            picks.append((3.5, ""))
        for speed, note in picks:
            sol, ev0, res0 = sims[(cat, speed)]
            if math.isclose(sol.settings().duration, duration):
                ev, res = ev0, res0
            else:
                ev, res = sol.simulate(duration)
                bar.update()
            label = f"{cat} {speed:g} m/s" + (f" ({note})" if note else "")
            shown[label] = res
            resim.append(_resim_row(label, sol, ev, res))
    return shown, resim, summary, cells


def _export_section(report, results: dict) -> None:
    """Attach each solution's OpenSim files to the report and list them in a section."""
    rows = []
    for label, res in results.items():
        folder = "export/" + (re.sub(r"[^a-z0-9.]+", "-", label.lower()).strip("-") or "solution")
        report.add_file(folder, lambda path, r=res: write_opensim(r, path, every=2))
        for name, what in (("coordinates.mot", "coordinates, OpenSim names, rotations in deg"),
                           ("grf.mot", "ground reaction forces per leg, OpenSim external loads"),
                           ("external_loads.xml", "OpenSim ExternalLoads applying grf.mot"),
                           ("states.csv", "every recorded state, units in the column names")):
            rows.append({"solution": label, "file": f"{folder}/{name}", "content": what})
    report.add_section(
        "Export for OpenSim and other tools",
        text=("Each solution shown, every 2nd recorded sample (1 kHz at the 0.25 ms step), in the "
              "report folder. OpenSim conventions: ground frame x forward, y up, z to the right; "
              "pelvis_tx/pelvis_ty locate the pelvis frame origin of SCONE's H0918 OpenSim model "
              "(docs/runner-model.md, 'Export')."),
        tables=[("Exported files (paths relative to this report)", pd.DataFrame(rows))],
    )


def default_report_dir(path: Path, kind: str) -> Path:
    """Where a report goes without ``out_dir``: ``path/report`` for a folder; ``<stem>-report``
    beside a parameter or collocation solution file, or in the current folder for a file
    shipped inside bladelab (never into the installed package)."""
    if kind not in ("parameters", "collocation") or path.is_dir():
        return path / "report"
    package = Path(__file__).resolve().parents[1]
    folder = Path.cwd() if path.resolve().is_relative_to(package) else path.parent
    return folder / f"{path.stem}-report"


def build_predictive_report(
    path: str | Path,
    out_dir: str | Path | None = None,
    *,
    duration: float = 10.0,
    progress: bool = True,
    export: bool = False,
    animate: bool = True,
    robustness: bool = True,
) -> PredictiveReport:
    """Write the HTML report of a predictive result (see the module docstring).

    Parameters
    ----------
    path
        A ``bladelab predict`` or ``bladelab sweep`` folder, a parameter JSON file, or a
        collocation solution (``solution.json`` or its folder).
    out_dir
        Report folder; default :func:`default_report_dir`.
    duration
        Simulated time [s] of the re-simulations shown in the sections.
    progress
        Show a progress bar while simulating.
    export
        Also write each solution shown for OpenSim and other tools into
        ``export/<solution>/`` (``coordinates.mot``, ``grf.mot``, ``external_loads.xml``,
        ``states.csv``; every 2nd recorded sample, i.e. 1 kHz at the default 0.25 ms step).
    animate
        Animate each solution shown in the page.
    robustness
        For one solution or run: re-simulate it as copies, from other initial speeds and
        pushed, and judge the stable-gait acceptance
        (:mod:`bladelab.report.predictive_robustness`).

    Raises
    ------
    InputFileError
        ``path`` is none of the kinds above, or one of its files cannot be read. Nothing is
        written then.
    """
    import matplotlib

    matplotlib.use("Agg")
    path = Path(path)
    kind = predictive_kind(path)
    if kind is None:
        raise InputFileError("not a predictive result", file=path, hint=_KINDS_HINT)
    if out_dir is None:
        out_dir = default_report_dir(path, kind)
    titles = {"run": "Predictive running: optimisation", "runs": "Predictive running: runs",
              "sweep": "Predictive running: blade-category sweep",
              "recipe-sweep": "Predictive running: blade-category sweep by recipes",
              "parameters": "Predictive running: solution",
              "collocation": "Predictive running: collocation solution",
              "collocation-sweep": "Predictive running: collocation sweep"}
    rep = Report(titles[kind], subtitle=str(path))
    sweep_summary = None
    resim = checked = None
    # a collocation solution is not re-simulated: no progress bar for it
    with _Counter(tqdm(desc="re-simulating", unit="sim",
                       disable=not progress or kind.startswith("collocation"))) as bar:
        if kind == "collocation":
            results, csol = collocation_sections(rep, path)
            settings, seed = csol.settings.to_dict(), None
        elif kind == "collocation-sweep":
            results, sweep_summary = collocation_sweep_sections(rep, path)
            settings, seed = {}, None
        elif kind == "parameters":
            sol = _Solution(path, _read_json(path))
            ev, res = sol.simulate(duration)
            bar.update()
            results = {sol.label(): res}
            resim = [_resim_row(sol.label(), sol, ev, res)]
            shown = path
            settings = sol.data.get("settings") or {}
            seed = sol.data.get("seed")
        elif kind in ("run", "runs"):
            if kind == "run":
                folders = {path.name: path}
            else:
                folders = {p.name: p for p in sorted(path.glob("seed-*"))
                           if (p / "best.json").is_file()}
            results, resim, shown = _run_sections(rep, folders, duration, bar)
            first = _read_json(next(iter(folders.values())) / "best.json")
            settings, seed = first.get("settings") or {}, first.get("seed")
        elif kind == "recipe-sweep":
            _, files = recipe_sweep_sections(rep, path, bar)
            results, resim = {}, []
            for label, file in files.items():
                sol = _Solution(file, _read_json(file))
                ev, res = sol.simulate(duration)
                bar.update()
                results[label] = res
                resim.append(_resim_row(label, sol, ev, res))
            first = _read_json(next(iter(files.values()))) if files else {}
            settings, seed = first.get("settings") or {}, None
        else:
            results, resim, sweep_summary, cells = _sweep_sections(rep, path, duration, bar)
            first = _read_json(cells[0][2] / "best.json") if cells else {}
            settings, seed = first.get("settings") or {}, first.get("seed")
        if robustness and kind in ("parameters", "run", "runs"):
            checked = robustness_runs(shown, duration, speed="reached")
            for _ in range(checked["simulations"]):
                bar.update()
    if resim is not None:
        _resim_section(rep, resim, duration)
    if checked is not None:
        robustness_section(rep, checked, duration)
    if kind in ("parameters", "run", "runs"):
        results = _with_tracked_stride(results, settings)
    add_predictive_sections(rep, results, sweep_summary=sweep_summary, animate=animate)
    if export:
        _export_section(rep, results)
    rep.settings = {"source": str(path), "kind": kind,
                    "resimulated_s": None if resim is None else duration,
                    "objective": settings}
    rep.seed = seed
    index = rep.write(Path(out_dir))
    return PredictiveReport(str(index), kind, tuple(results), bar.count)


def _with_tracked_stride(results: dict, settings: dict) -> dict:
    """``results`` and, for a run that tracked a collocation stride (``settings["track"]``,
    ``bladelab predict --track``), that stride beside it in every figure and table."""
    track = settings.get("track")
    if not track:
        return results
    stride = CollocationSolution.read(track).to_runner_result()
    return {**results, f"tracked collocation stride ({Path(track).name})": stride}


def _resim_section(rep, resim: list, duration: float) -> None:
    rep.add_section(
        "Re-simulation of the solutions shown",
        text=(f"Each solution below is simulated again from its parameters for {duration:g} s "
              "with the time step it was optimised with; nothing is taken from a stored "
              "evaluation. Power-balance residual: RMS of external minus kinetic power in % of "
              "the peak kinetic power. Swing contacts: a swinging foot striking the ground "
              "(contacts in which no step starts; left out of the gait events and "
              "spatiotemporal variables below)."),
        tables=[("Re-simulations", pd.DataFrame(resim))],
    )
