"""Predictive report: sections and tables, `bladelab report` on predict/sweep folders and
parameter files (everything re-simulated), seed 001's packaged values, bad paths."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import bladelab.report.predictive_sections as pr
from bladelab.cli import main
from bladelab.predict.reflex.controller import controller_layout
from bladelab.predict.reflex.objective import ObjectiveSettings, simulate_controlled
from bladelab.predict.reflex.optimize import optimize_controller
from bladelab.predict.reflex.sweep import run_sweep
from bladelab.report import Report
from bladelab.report.predictive import build_predictive_report, predictive_kind
from bladelab.runner import build_runner

SOLUTIONS = Path(pr.__file__).resolve().parents[1] / "data" / "runner" / "reflex-starts"


class _FakeModel:
    kind = "able"
    total_mass = 80.0


class _FakeResult:
    model = _FakeModel()


def test_power_table_by_hand(monkeypatch):
    t = np.linspace(0.0, 2.0, 2001)
    # hip_l: +160 W for the first half of each 0.5 s stride, -80 W in the second half
    p = np.where((t % 0.5) < 0.25, 160.0, -80.0)
    pw = pd.DataFrame({"time": t, "joint": "hip_flexion_l", "power": p})
    ev = pd.DataFrame({"leg": "left", "event": "touchdown", "time": [0.0, 0.5, 1.0, 1.5, 2.0]})
    monkeypatch.setattr(pr, "joint_powers", lambda r: pw)
    monkeypatch.setattr(pr, "gait_events", lambda r: ev)
    tab = pr.power_table(_FakeResult())
    row = tab[(tab.leg == "left") & (tab.joint == "hip_flexion_l")].iloc[0]
    # mean positive power: 160 W half the time / 80 kg = 1.0 W/kg; negative -0.5 W/kg
    assert row.P_pos == pytest.approx(1.0, rel=2e-3)
    assert row.P_neg == pytest.approx(-0.5, rel=2e-3)
    tot = tab[(tab.leg == "left") & (tab.joint == "total")].iloc[0]
    assert tot.P_pos == pytest.approx(row.P_pos)
    wide = pr.power_table_wide(_FakeResult())
    assert wide["left hip P+ (W/kg)"].iloc[0] == pytest.approx(1.0, rel=2e-3)
    assert wide["TOTAL P− (W/kg)"].iloc[0] == pytest.approx(-0.5, rel=2e-3)


def test_report_sections_are_written(tmp_path):
    model = build_runner("amputee", blade="Cat6")
    layout = controller_layout(model)
    _, res = simulate_controlled(
        model, layout.x0, layout=layout, settings=ObjectiveSettings(duration=0.6), record_every=4
    )
    report = Report("Predictive running")
    summary = pd.DataFrame(
        {
            "category": ["Cat5", "Cat6"],
            "max_speed": [4.3, 4.6],
            "cot_4": [7.2, 6.9],
            "t200": [200 / 4.3, 200 / 4.6],
            "t400": [400 / 4.3, 400 / 4.6],
        }
    )
    pr.add_predictive_sections(report, {"amputee Cat6": res}, sweep_summary=summary)
    index = report.write(tmp_path / "report")
    html = index.read_text()
    assert "Predictive simulation: amputee Cat6" in html
    assert "Table 3.1" in html and "Joint powers" in html


def test_seed001_values_are_those_of_the_seed():
    seed = pr.seed001_results()
    assert set(seed.category) == {"Cat4", "Cat5", "Cat6", "Cat6High", "Cat7"}
    assert seed.source.str.len().min() > 5  # every row cites where it comes from

    def v(cat, q):
        return float(seed[(seed.category == cat) & (seed.quantity == q)].value.iloc[0])

    # seed 001 §3.2 A and Table 3.1 (typed again here from the seed's text)
    assert v("Cat6High", "max_speed") == 4.675 and v("Cat4", "max_speed") == 4.27
    assert v("Cat6", "cot_4") == 6.91 and v("Cat5", "cot_4") == 7.29
    assert v("Cat6High", "t200") == 42.8 and v("Cat4", "t400") == 93.7
    assert v("Cat7", "contact_time_prosthetic") == 0.138
    # Table 3.1's times are distance / maximum speed of the text, to its rounding
    for cat in set(seed.category):
        vmax = v(cat, "max_speed")
        assert abs(v(cat, "t200") - 200 / vmax) < 0.1
        assert abs(v(cat, "t400") - 400 / vmax) < 0.2
    # the comparison: differences relative to the seed, verdicts only where meaningful
    ours = pd.DataFrame({"category": ["Cat6"], "max_speed": [4.62 * 1.1], "cot_4": [6.95],
                         "t200": [200 / (4.62 * 1.1)], "t400": [400 / (4.62 * 1.1)],
                         "contact_time_intact": [0.2], "contact_time_prosthetic": [0.15]})
    cmp = pr.seed_comparison(ours).set_index("quantity")
    assert cmp.loc["maximum speed (m/s)", "difference (%)"] == pytest.approx(10.0)
    assert cmp.loc["maximum speed (m/s)", "within seed range"] == "no"
    assert cmp.loc["metabolic cost at 4 m/s (J/(kg·m))", "within seed range"] == "yes"
    assert cmp.loc["intact contact time at maximum speed (s)", "within seed range"] == "no"
    assert cmp.loc["200 m time (s)", "within seed range"] == ""


def _tables(index: Path) -> dict[str, pd.DataFrame]:
    return {p.stem: pd.read_csv(p) for p in (index.parent / "tables").glob("*.csv")}


def _table(tables: dict, part: str) -> pd.DataFrame:
    hits = [k for k in tables if part in k]
    assert len(hits) >= 1, (part, sorted(tables))
    return tables[hits[0]]


def _units_everywhere(df: pd.DataFrame, unitless=("run", "solution", "category", "leg",
                                                   "variable", "joint", "quantity")) -> None:
    for col in df.columns:
        assert col in unitless or re.search(r"\(.+\)$", col), col


def test_report_of_predict_folders(tmp_path, capsys):
    # one run (API) and a two-seed run (CLI), 3 generations of 1 s simulations
    run = tmp_path / "run"
    optimize_controller("able", generations=3, popsize=4, seed=2,
                        settings=ObjectiveSettings(duration=1.0), out=run)
    assert predictive_kind(run) == "run"
    assert main(["report", str(run), "--export"]) == 0
    assert list((run / "report" / "export").glob("*/coordinates.mot"))
    index = run / "report" / "index.html"
    html = index.read_text(encoding="utf-8")
    for title in ("Optimisation: convergence and run summary", "Joint angles per leg",
                  "Ground reaction force in body weights", "Spatiotemporal variables",
                  "Joint powers", "Table 3.2", "Table 3.3", "Re-simulation of the solutions"):
        assert title in html, title
    tables = _tables(index)
    summary = _table(tables, "run-summary")
    _units_everywhere(summary)
    row = summary.iloc[0]
    assert row["generations (count)"] == 3 and row["evaluations (count)"] == 12
    assert row["wall time (s)"] > 0
    # the stored best cost is reproduced by an independent re-simulation of best.json
    assert bool(row["stored cost reproduced (yes/no)"])
    hist = pd.read_csv(run / "history.csv")
    assert row["recomputed cost (–)"] == pytest.approx(hist.best.iloc[-1], rel=1e-9)
    resim = _table(tables, "re-simulations")
    _units_everywhere(resim)
    assert 0 < resim["simulated (s)"].iloc[0] <= 10.0 + 1e-9
    assert resim["time step (s)"].iloc[0] == ObjectiveSettings().dt
    for part in ("table-3-2", "table-3-3", "spatiotemporal"):
        _units_everywhere(_table(tables, part))
    capsys.readouterr()
    seeds = tmp_path / "seeds"
    assert main(["predict", "--method", "reflex",
                 "--generations", "2", "--popsize", "4", "--duration", "0.5",
                 "--seeds", "1,2", "--out", str(seeds)]) == 0
    assert predictive_kind(seeds) == "runs"
    capsys.readouterr()
    assert main(["report", str(seeds), "--out", str(tmp_path / "r2"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["kind"] == "runs" and len(out["solutions"]) == 1
    assert "best of seed-" in out["solutions"][0]
    runs = _table(_tables(Path(out["index"])), "run-summary")
    assert sorted(runs.run) == ["seed-1", "seed-2"]
    # the best seed agrees with itself; two seeds never settle a cell (it needs 3)
    best = runs["recomputed cost (–)"].idxmin()
    assert runs["agrees with the best seed (yes/no)"][best]
    html = Path(out["index"]).read_text(encoding="utf-8")
    assert "of 2 seeds reach the best seed" in html and "not settled" in html


@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("sweep")
    run_sweep(["Cat4", "Cat6"], [3.5, 4.0], out=out, generations=2, popsize=4, duration=0.3,
              progress=False)
    return out


@pytest.fixture(scope="module")
def sweep_report(sweep_dir, tmp_path_factory) -> Path:
    """``bladelab report SWEEP`` (CLI defaults), written once: checked for its content and
    opened in the browser."""
    assert predictive_kind(sweep_dir) == "sweep"
    out = tmp_path_factory.mktemp("sweep-report") / "r"
    assert main(["report", str(sweep_dir), "--out", str(out)]) == 0
    return out / "index.html"


def test_report_of_a_sweep(sweep_dir, sweep_report):
    index = sweep_report
    html = index.read_text(encoding="utf-8")
    results = pd.read_csv(sweep_dir / "results.csv")
    for cat in ("Cat4", "Cat6"):
        assert f"Predictive simulation: {cat} 3.5 m/s" in html
        ran = results[(results.category == cat) & ~results.fell]
        if len(ran):
            top = ran.loc[ran.mean_speed.idxmax()]
            assert f"{cat} {top.speed:g} m/s (highest speed that ran)" in html
    assert "Blade categories: maximum speed and metabolic cost" in html
    tables = _tables(index)
    check = _table(tables, "recomputed-summary")
    assert check["as in summary.csv (yes/no)"].all()  # re-simulation reproduces the sweep
    cats = _table(tables, "per-category")
    _units_everywhere(cats)
    stored = pd.read_csv(sweep_dir / "summary.csv")
    np.testing.assert_allclose(cats["maximum speed (m/s)"], stored.max_speed, rtol=1e-9)
    cmp = _table(tables, "beside-seed-001")
    six = cmp[(cmp.category == "Cat6") & (cmp.quantity == "maximum speed (m/s)")].iloc[0]
    assert six["seed 001"] == 4.62 and six["source"].startswith("§3.2 A")
    assert six["difference (%)"] == pytest.approx(
        100 * (stored.set_index("category").max_speed["Cat6"] - 4.62) / 4.62)


def test_sweep_report_leaves_out_unfinished_cells(sweep_dir, tmp_path):
    # a cell still optimising (status "running") holds an interim best.json: not a result
    import shutil

    copy = tmp_path / "sweep"
    shutil.copytree(sweep_dir, copy)
    cell = copy / "Cat6" / "4" / "cell.json"
    data = json.loads(cell.read_text())
    data["status"] = "running"
    cell.write_text(json.dumps(data))
    rep = build_predictive_report(copy, tmp_path / "r", duration=0.3, progress=False)
    html = Path(rep.index).read_text(encoding="utf-8")
    assert "Unfinished cells, left out (their best is an interim one): Cat6 at 4 m/s." in html
    cells = _table(_tables(Path(rep.index)), "re-evaluated-with-their-own-settings")
    shown = set(zip(cells.category, cells["prescribed speed (m/s)"], strict=True))
    assert ("Cat6", 4.0) not in shown and ("Cat6", 3.5) in shown and ("Cat4", 4.0) in shown


def test_sweep_report_opens_in_a_browser(sweep_report, tmp_path):
    from browser import chromium, figure_ok, inspect_page

    binary = chromium()
    figures, errors = inspect_page(binary, sweep_report, tmp_path / "shot.png",
                                   tmp_path / "profile")
    assert errors == []
    # the gait figures overlay every solution (12) + the category figure
    assert len(figures) == 12 + 1
    assert all(figure_ok(f) for f in figures)


def test_report_of_a_parameter_file(tmp_path):
    src = SOLUTIONS / "able-3.5.json"  # a reflex start
    rep = build_predictive_report(src, tmp_path / "r", duration=2.0, progress=False)
    # the re-simulation, then the acceptance's robustness runs: the nominal (judged at the speed it
    # reaches), 4 copies and 2 other starts (2 s has no room for a push)
    assert rep.kind == "parameters" and rep.simulations == 1 + (1 + 4 + 2)
    tables = _tables(Path(rep.index))
    resim = _table(tables, "re-simulations").iloc[0]
    judged = _table(tables, "judged-runs")
    _units_everywhere(judged)
    assert len(judged) == 7 and not any("pushed-runs" in k for k in tables)
    nominal = judged.iloc[0]  # the same simulation as the re-simulation's
    for column in ("mean speed (m/s)", "power-balance residual (%)", "swing contacts (count)"):
        assert nominal[column] == pytest.approx(resim[column], rel=1e-9), column
    # a run that falls never meets the acceptance; the text's verdict follows the table
    assert not (judged["meets the acceptance (yes/no)"] & ~judged["runs the whole time (yes/no)"]).any()
    html = Path(rep.index).read_text(encoding="utf-8")
    met = judged["meets the acceptance (yes/no)"].all()
    assert ("Stable-gait acceptance: met" in html) == met
    assert "No pushes" in html
    # a running solution: 2 s without a fall near its 3.5 m/s, energy conserved (power balance)
    assert not resim["fell (yes/no)"] and resim["simulated (s)"] == pytest.approx(2.0)
    assert abs(resim["mean speed (m/s)"] - 3.5) < 0.3
    assert resim["power-balance residual (%)"] < 2.0
    st = _table(tables, "spatiotemporal")
    _units_everywhere(st)
    contact = st["contact time (s)"]
    assert ((contact > 0.1) & (contact < 0.35)).all()  # running contact times (seed 001 §3.1)


def test_a_parameter_file_of_the_human_body_is_shown_on_that_body(tmp_path):
    """A reflex file of the human body is re-simulated on it (its toe joints: the re-simulated
    cost is the human runner's, not seed 001's) and labelled with its body."""
    from bladelab.predict.reflex.controller import write_parameters
    from bladelab.predict.reflex.objective import ObjectiveSettings, simulate_controlled
    from bladelab.predict.reflex.optimize import runner_and_layout

    human, layout = runner_and_layout("able", None, "human")
    settings = ObjectiveSettings(speed=3.5, duration=1.0, integrator="newmark")
    path = write_parameters(tmp_path / "human.json", layout, layout.x0, body="human",
                            speed_m_per_s=3.5, settings=settings.to_dict())
    rep = build_predictive_report(path, tmp_path / "r", duration=1.0, progress=False)
    resim = _table(_tables(Path(rep.index)), "re-simulations").iloc[0]
    assert resim["solution"] == "able-bodied 3.5 m/s (human body)"
    want = {body: simulate_controlled(runner_and_layout("able", None, body)[0], layout.x0,
                                      settings=settings)[0].cost for body in ("human", "seed001")}
    assert resim["cost (–)"] == pytest.approx(want["human"], rel=1e-6)
    assert want["seed001"] != pytest.approx(want["human"], rel=1e-3)


class _Sections:
    """Collects what a section function adds (a stand-in for the report builder)."""

    def __init__(self) -> None:
        self.sections = []

    def add_section(self, title, text="", tables=(), figures=()):
        self.sections.append((title, text, dict(tables)))


def _check(fell=False, ok=True, peak_bw=0.1, tilt=-10.0, **extra) -> dict:
    return {"fell": fell, "ok": ok, "duration_s": 5.0 if fell else 10.0,
            "mean_speed_m_per_s": 4.0, "strides": 12, "strides_with_flight": 12,
            "same_leg_steps": 0, "power_balance_residual_pct": 0.5, "swing_contacts": 1,
            "swing_contact_peak_N": 80.0 * 9.81 * peak_bw, "swing_contact_peak_bw": peak_bw,
            "pelvis_tilt_mean_deg": tilt, "pelvis_tilt_min_deg": tilt - 5,
            "pelvis_tilt_max_deg": tilt + 5, **extra}


def test_robustness_section_judges_the_acceptance_by_hand():
    from bladelab.report.predictive_robustness import robustness_section

    # as verify_solution returns it: "ok" is every run's verdict, "nominal_ok" the nominal's
    out = {**_check(ok=False), "nominal_ok": True, "judged_at_m_per_s": 3.5,
           "judged_at_reached_speed": False,
           "jittered": [_check(), _check(peak_bw=0.25), _check(fell=True, ok=False), _check()],
           "initial_speed": [_check(tilt=-17.0, initial_speed_m_per_s=3.675),
                             _check(initial_speed_m_per_s=3.325)],
           "pushed": [_check(push_time_s=2.0, push_change=0.02),
                      _check(fell=True, ok=False, push_time_s=2.0, push_change=-0.02)]}
    rep = _Sections()
    robustness_section(rep, out, 10.0)
    (title, text, tables), = rep.sections
    judged = tables["Judged runs (the stable-gait acceptance)"]
    # strike above 0.2 BW (copy 2), a fall (copy 3), mean tilt outside -16...-2 deg (+5 %)
    assert judged["meets the acceptance (yes/no)"].tolist() == [
        True, True, False, False, True, False, True]
    assert judged.run.tolist()[5] == "start 3.675 m/s"
    assert "not met by 3 of 7 judged runs" in text
    assert "speed within 0.1 m/s of 3.50 m/s, the prescribed speed" in text
    pushed = tables["Pushed runs (the gait's basin; not judged)"]
    assert pushed["runs the whole time (yes/no)"].tolist() == [True, False]
    assert "1 of 2 pushed runs keep running" in text
    out["jittered"] = [_check()] * 4
    out["initial_speed"] = [_check(initial_speed_m_per_s=v) for v in (3.675, 3.325)]
    out["ok"] = True
    out["judged_at_m_per_s"], out["judged_at_reached_speed"] = 3.35, True
    rep = _Sections()
    robustness_section(rep, out, 10.0)
    assert "acceptance: met by every judged run" in rep.sections[0][1]
    assert "within 0.1 m/s of 3.35 m/s, the speed the nominal run reaches" in rep.sections[0][1]


def test_a_shipped_file_reports_into_the_current_folder(tmp_path, monkeypatch):
    from bladelab.report.predictive import default_report_dir

    monkeypatch.chdir(tmp_path)
    shipped = SOLUTIONS / "able-3.5.json"
    assert default_report_dir(shipped, "parameters") == tmp_path / "able-3.5-report"
    mine = tmp_path / "sub" / "mine.json"
    assert default_report_dir(mine, "parameters") == tmp_path / "sub" / "mine-report"
    assert default_report_dir(tmp_path / "run", "run") == tmp_path / "run" / "report"


def test_bad_paths_exit_2_and_write_nothing(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("hello")
    (tmp_path / "other.json").write_text(json.dumps({"model": "able"}))
    (tmp_path / "broken.json").write_text("{not json")
    (tmp_path / "empty").mkdir()
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    for name in ("missing", "notes.txt", "other.json", "broken.json", "empty"):
        capsys.readouterr()
        assert main(["report", str(tmp_path / name)]) == 2, name
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error:"), err
        assert name in err[0]
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before
    from bladelab.errors import InputFileError

    with pytest.raises(InputFileError, match="not a predictive result"):
        build_predictive_report(tmp_path / "empty")


def test_report_of_the_amputee_reflex_start(shipped_amputee_report):
    from bladelab.runner.export import read_mot

    rep = shipped_amputee_report  # 3 s re-simulated, exported (conftest.py)
    assert rep.kind == "parameters" and rep.simulations == 1 + (1 + 4 + 2)  # the re-simulation, the nominal, copies, starts
    index = Path(rep.index)
    html = index.read_text(encoding="utf-8")
    assert 'class="runner-animation"' in html and "Table D.1" in html
    tables = _tables(index)
    energy = _table(tables, "table-3-3")
    _units_everywhere(energy)
    # Table 3.3 from real stances only: as many as the spatiotemporal contacts
    st = _table(tables, "spatiotemporal")
    assert set(st["strides (count)"]) <= {3, 4}
    blade = _table(tables, "table-d-1").iloc[0]
    _units_everywhere(_table(tables, "table-d-1"))
    # the sphere with seed 001's c = 0.2 s/m returns about half; the seed's bookkeeping ~100 %
    assert 45.0 < blade["recoil (%)"] < 62.0
    assert blade["recoil, compression from eq. 2.3 (%)"] > 99.9
    k = _table(tables, "leg-stiffness")
    _units_everywhere(k)
    assert ((k["K_leg (kN/m)"] > 15) & (k["K_leg (kN/m)"] < 35)).all()
    folder = index.parent / "export" / "amputee-cat6-3.5-m-s"
    for name in ("coordinates.mot", "grf.mot", "external_loads.xml", "states.csv"):
        assert (folder / name).is_file(), name
    header, coords = read_mot(folder / "coordinates.mot")
    assert header["inDegrees"] == "yes" and coords.time.iloc[-1] == pytest.approx(3.0)
    assert "export/amputee-cat6-3.5-m-s/grf.mot" in html


def test_mean_and_sd_cells_show_the_sd_to_the_mean_s_decimal_place():
    """The repeated stances of one periodic stride differ by round-off: their SD reads 0 at
    the mean's precision, not 1.8e-15; a real SD keeps its digits there."""
    assert pr._pm(9.5213, 1.8e-15) == "9.52 ± 0.00"
    assert pr._pm(9.5213, 0.234) == "9.52 ± 0.23"
    assert pr._pm(0.17634, 2e-17) == "0.176 ± 0.000"
    assert pr._pm(123.4, 5.67) == "123 ± 6"
    assert pr._pm(0.26, 1e-17) == "0.260 ± 0.000"
    assert pr._pm(1234.5, 12.0) == "1234 ± 12"
    assert pr._pm(2.4, float("nan")) == "2.40"
    assert pr._pm(float("nan"), 1.0) == "–"
