"""The report of a collocation sweep folder (bladelab.report.collocation_sweep), on the committed
first-pass category study (benchmarks/collocation/study-4mps)."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import pandas as pd
import pytest

from bladelab.errors import InputFileError
from bladelab.report.collocation_sweep import read_sweep_table, sweep_summary
from bladelab.report.predictive import build_predictive_report, predictive_kind

STUDY = Path(__file__).resolve().parents[1] / "benchmarks" / "collocation" / "study-4mps"


def _subset(tmp_path: Path, blades: list[str]) -> Path:
    """A sweep folder with only the given categories (their files and table rows)."""
    out = tmp_path / "sweep"
    out.mkdir()
    table = pd.read_csv(STUDY / "collocation-sweep.csv")
    table = table[table.blade.isin(blades)]
    for b in blades:
        shutil.copytree(STUDY / f"amputee-{b}", out / f"amputee-{b}")
    table.to_csv(out / "collocation-sweep.csv", index=False)
    return out


def test_a_collocation_sweep_folder_is_recognised():
    assert predictive_kind(STUDY) == "collocation-sweep"


def test_category_summary_reads_the_max_speed_and_the_4_mps_solves():
    raw = pd.read_csv(STUDY / "collocation-sweep.csv")
    summary = sweep_summary(read_sweep_table(STUDY)).set_index("category")
    assert sorted(summary.index) == sorted(raw.blade.unique())
    for blade, rows in raw.groupby("blade"):
        fastest = rows[rows.problem == "max-speed"].iloc[0]
        at4 = rows[(rows.problem == "speed") & (rows.prescribed_speed_mps == 4.0)].iloc[0]
        s = summary.loc[blade]
        assert s.max_speed == pytest.approx(fastest.mean_speed_mps)
        assert s.max_speed > 4.0
        assert s.cot_4 == pytest.approx(at4.cost_of_transport_J_per_kg_m)
        assert s.t200 * s.max_speed == pytest.approx(200.0)
        assert s.contact_time_prosthetic == pytest.approx(fastest.contact_time_prosthetic_s)


def test_the_speed_figure_draws_each_model_s_first_leg_solid_and_the_second_dashed():
    import matplotlib

    matplotlib.use("Agg")
    from bladelab.report import collocation_sweep as cs

    table = read_sweep_table(STUDY)
    fig = cs._speed_figure(table)
    contact = fig.axes[1]
    styles = {ln.get_label(): ln.get_linestyle() for ln in contact.lines
              if not ln.get_label().startswith("_")}
    n_models = table.model.nunique()
    assert len(styles) == 2 * n_models  # intact and prosthetic per model, no third 'leg'
    assert all(v == "-" for k, v in styles.items() if k.endswith(" intact"))
    assert all(v == "--" for k, v in styles.items() if k.endswith(" prosthetic"))


def test_a_solve_that_did_not_converge_is_left_out_of_the_summary(tmp_path):
    folder = _subset(tmp_path, ["Cat5"])
    table = pd.read_csv(folder / "collocation-sweep.csv")
    table.loc[table.problem == "max-speed", "converged"] = False
    table.to_csv(folder / "collocation-sweep.csv", index=False)
    s = sweep_summary(read_sweep_table(folder)).iloc[0]
    assert math.isnan(s.max_speed) and math.isnan(s.t200)
    assert math.isfinite(s.cot_4)


def test_a_maximum_speed_on_its_floor_is_said_to_be_there(tmp_path):
    """The summary compares the maximum speed with its floor: the recorded one, else (an older
    table) the model's fastest prescribed speed; the section text names the models on it."""
    from bladelab.report.collocation_sweep import _floor_text

    folder = _subset(tmp_path, ["Cat5", "Cat6"])
    table = pd.read_csv(folder / "collocation-sweep.csv")
    top = table.problem == "max-speed"
    fastest = table.loc[~top, "prescribed_speed_mps"].max()
    table.loc[top & (table.blade == "Cat5"), "mean_speed_mps"] = fastest + 2e-4
    table.to_csv(folder / "collocation-sweep.csv", index=False)
    read = read_sweep_table(folder)
    summary = sweep_summary(read).set_index("category")
    assert summary.loc["Cat5", "max_speed_floor"] == f"on it ({fastest:g} m/s)"
    assert summary.loc["Cat6", "max_speed_floor"] == f"above it ({fastest:g} m/s)"
    text = _floor_text(read)
    assert "Cat5" in text and "Cat6" not in text
    # a recorded floor is the one compared with
    table["speed_floor_mps"] = math.nan
    table.loc[top, "speed_floor_mps"] = 3.0
    table.to_csv(folder / "collocation-sweep.csv", index=False)
    summary = sweep_summary(read_sweep_table(folder)).set_index("category")
    assert summary.loc["Cat5", "max_speed_floor"] == "above it (3 m/s)"


def test_a_merged_folder_says_so_with_its_spread(tmp_path):
    from bladelab.report.builder import Report
    from bladelab.report.collocation_sweep import collocation_sweep_sections

    folder = _subset(tmp_path, ["Cat6"])
    table = pd.read_csv(folder / "collocation-sweep.csv")
    table = table[table.problem == "speed"]  # no gait section needed
    table["start"] = "defaults"
    table["spread_pct"] = 37.0
    table.to_csv(folder / "collocation-sweep.csv", index=False)
    rep = Report("t")
    results, summary = collocation_sweep_sections(rep, folder)
    assert results == {} and summary.iloc[0].cot_4 > 0
    text = " ".join(rep.sections[0].text)
    assert "solved from several starts" in text and "37 %" in text
    assert "warm-started from the previous converged speed;" not in text
    # a spread below 1 % is not rounded away
    table["spread_pct"] = [0.47] + [0.05] * (len(table) - 1)
    table.to_csv(folder / "collocation-sweep.csv", index=False)
    rep = Report("t")
    collocation_sweep_sections(rep, folder)
    assert "the largest spread between starts is 0.47 % of" in " ".join(rep.sections[0].text)


def test_a_several_start_folder_shows_the_spread_of_each_problem(tmp_path):
    """The columns of 'bladelab sweep --starts K' (bladelab.predict.collocation.starts)."""
    from bladelab.report.builder import Report
    from bladelab.report.collocation_sweep import collocation_sweep_sections, starts_table

    folder = _subset(tmp_path, ["Cat6"])
    table = pd.read_csv(folder / "collocation-sweep.csv")
    table = table[table.problem == "speed"].reset_index(drop=True)
    n = len(table)
    table["start"] = ["warm-mu-1e-4"] + ["warm"] * (n - 1)
    table["starts"] = [3] + [1] * (n - 1)
    table["objective"] = 2.0
    table["objective_warm"] = [2.5] + [2.0] * (n - 1)
    table["objective_warm-mu-1e-4"] = [2.0] + [math.nan] * (n - 1)
    table["spread_pct"] = [25.0] + [math.nan] * (n - 1)
    table.to_csv(folder / "collocation-sweep.csv", index=False)
    assert starts_table(read_sweep_table(STUDY)) is None  # one start: no such table
    shown = starts_table(read_sweep_table(folder))
    assert list(shown.columns) == [
        "model", "problem", "prescribed_speed_mps", "converged", "start", "starts", "objective",
        "objective_warm", "objective_warm-mu-1e-4", "spread_pct"]
    assert shown.spread_pct.iloc[0] == 25.0 and shown.spread_pct.iloc[1:].isna().all()
    rep = Report("t")
    collocation_sweep_sections(rep, folder)
    section = rep.sections[0]
    assert "25 %" in " ".join(section.text)
    (per_problem,) = [t for t in section.tables if t.title.startswith("Starts per problem")]
    assert len(per_problem.frame) == n
    assert per_problem.frame.spread_pct.iloc[0] == 25.0
    # objectives to five digits (starts differ by tenths of a per cent), counts as integers
    assert per_problem.frame.objective_warm.iloc[0] == "2.5"
    assert per_problem.frame["objective_warm-mu-1e-4"].iloc[0] == "2"
    assert per_problem.frame.starts.iloc[0] == "3"


def test_a_table_without_a_needed_column_is_refused_by_name(tmp_path):
    folder = _subset(tmp_path, ["Cat4"])
    table = pd.read_csv(folder / "collocation-sweep.csv").drop(columns=["mean_speed_mps"])
    table.to_csv(folder / "collocation-sweep.csv", index=False)
    with pytest.raises(InputFileError, match="mean_speed_mps"):
        read_sweep_table(folder)


def test_the_report_of_a_sweep_folder_has_its_sections(tmp_path, monkeypatch):
    import bladelab.report.predictive_sections as sections

    # the gait-cycle sections are the predictive report's own (tested with it); here only
    # which trajectories reach them
    shown = {}
    monkeypatch.setattr(sections, "_gait_sections",
                        lambda report, results, cycles: shown.update(results))
    folder = _subset(tmp_path, ["Cat4", "Cat6"])
    table = pd.read_csv(folder / "collocation-sweep.csv")
    table.loc[(table.blade == "Cat4") & (table.problem == "max-speed"), "converged"] = False
    table.to_csv(folder / "collocation-sweep.csv", index=False)
    rep = build_predictive_report(folder, tmp_path / "report", progress=False, animate=False)
    assert rep.kind == "collocation-sweep"
    # only the converged maximum-speed solve is shown as a gait
    assert len(rep.solutions) == 1 and "Cat6" in rep.solutions[0]
    assert list(shown) == list(rep.solutions)
    (res,) = shown.values()
    stride = table[(table.blade == "Cat6") & (table.problem == "max-speed")].stride_time_s
    assert res.time[-1] == pytest.approx(3 * float(stride.iloc[0]), rel=1e-6)  # three strides
    html = Path(rep.index).read_text(encoding="utf-8")
    assert "Collocation sweep: speed continuation and maximum speed" in html
    assert "Not converged" in html and "amputee Cat4 max-speed" in html
    assert "Blade categories: maximum speed and metabolic cost" in html
    assert "seed 001" in html
    assert "not the fastest stride the body can run" in html  # what the column means


def _flag(folder: Path, blade: str, problem: str, why: str = "a one-legged hop") -> None:
    table = pd.read_csv(folder / "collocation-sweep.csv")
    table["warnings"] = ""
    table.loc[(table.blade == blade) & (table.problem == problem), "warnings"] = why
    table.to_csv(folder / "collocation-sweep.csv", index=False)


def test_a_flagged_solve_is_a_cross_off_the_curves_and_out_of_the_summary(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from bladelab.report import collocation_sweep as cs

    folder = _subset(tmp_path, ["Cat5", "Cat6"])
    _flag(folder, "Cat5", "max-speed")
    table = read_sweep_table(folder)
    assert table.flagged.sum() == 1 and not read_sweep_table(STUDY).flagged.any()
    summary = sweep_summary(table).set_index("category")
    assert math.isnan(summary.loc["Cat5", "max_speed"]) and math.isfinite(summary.loc["Cat5", "cot_4"])
    assert math.isfinite(summary.loc["Cat6", "max_speed"])
    flagged_speed = float(table[table.flagged].mean_speed_mps.iloc[0])
    cost = cs._speed_figure(table).axes[0]
    curves = [ln for ln in cost.lines if ln.get_linestyle() == "-"]
    crosses = [ln for ln in cost.lines if ln.get_marker() == "x" and len(ln.get_xdata())]
    assert all(flagged_speed not in ln.get_xdata() for ln in curves)
    assert [list(ln.get_xdata()) for ln in crosses] == [[flagged_speed]]
    assert "flagged (gait warnings)" in [ln.get_label() for ln in cost.lines]


def test_a_flagged_maximum_speed_gait_is_labelled(tmp_path, monkeypatch):
    # the best-of-paths study's Cat4 maximum-speed stride peaks at 8.4 BW (flagged today)
    import bladelab.report.predictive_sections as sections

    shown = {}
    monkeypatch.setattr(sections, "_gait_sections",
                        lambda report, results, cycles: shown.update(results))
    study = STUDY.parent / "study-2026-11-25" / "amputee"
    folder = tmp_path / "sweep"
    shutil.copytree(study / "amputee-Cat4", folder / "amputee-Cat4")
    table = pd.read_csv(study / "collocation-sweep.csv")
    table[table.blade == "Cat4"].to_csv(folder / "collocation-sweep.csv", index=False)
    rep = build_predictive_report(folder, tmp_path / "report", progress=False, animate=False)
    html = Path(rep.index).read_text(encoding="utf-8")
    assert "Converged but flagged by the gait checks" in html
    assert "amputee Cat4 max-speed" in html
    assert list(shown) == list(rep.solutions) and "flagged" in rep.solutions[0]
    assert "A dash: nothing to report" in html  # the category table says why Cat4 has none


def test_an_older_table_is_judged_by_today_s_gait_checks(tmp_path):
    # the best-of-paths study's table predates the gait warnings; its Cat4 5 m/s stride peaks
    # at 11 BW, which today's checks flag from the solution file itself
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.report.builder import Report
    from bladelab.report.collocation_sweep import collocation_sweep_sections

    study = STUDY.parent / "study-2026-11-25" / "amputee"
    out = tmp_path / "sweep"
    shutil.copytree(study / "amputee-Cat4", out / "amputee-Cat4")
    table = pd.read_csv(study / "collocation-sweep.csv")
    table = table[(table.blade == "Cat4") & (table.problem == "speed")]
    table.to_csv(out / "collocation-sweep.csv", index=False)
    assert not read_sweep_table(out).flagged.any()  # nothing recorded
    five = table[table.prescribed_speed_mps == 5.0].iloc[0]
    assert CollocationSolution.read(out / five.file).gait_warnings()
    rep = Report("t")
    _, summary = collocation_sweep_sections(rep, out)
    text = " ".join(rep.sections[0].text)
    assert "flagged by the gait checks" in text and "amputee Cat4 speed 5.0" in text
    assert "amputee Cat4 speed 4.0" not in text
    assert math.isfinite(summary.iloc[0].cot_4)


def test_a_sweep_with_people_s_angles_in_its_objective_says_so(tmp_path, monkeypatch):
    """A study solved with people's joint angles in the objective is no free prediction, and
    its report says so beside the solves; a free study says nothing of it."""
    import bladelab.report.predictive_sections as sections

    monkeypatch.setattr(sections, "_gait_sections", lambda report, results, cycles: None)
    people = STUDY.parent / "study-human-people10-2026-11-29"
    out = tmp_path / "people"
    out.mkdir()
    table = pd.read_csv(people / "collocation-sweep.csv")
    table = table[table.blade == "Cat6"]
    shutil.copytree(people / "amputee-Cat6-human", out / "amputee-Cat6-human")
    table.to_csv(out / "collocation-sweep.csv", index=False)
    rep = build_predictive_report(out, tmp_path / "report", progress=False, animate=False)
    html = Path(rep.index).read_text(encoding="utf-8")
    assert "Not free predictions: every objective held people&#39;s measured hip, knee" in html
    assert "weight 10 1/rad²" in html
    free = build_predictive_report(_subset(tmp_path, ["Cat6"]), tmp_path / "free",
                                   progress=False, animate=False)
    assert "Not free predictions" not in Path(free.index).read_text(encoding="utf-8")


def test_the_sweep_text_counts_the_strides_that_gallop(tmp_path):
    """The committed study alternates its steps (nothing said); with one solve's file swapped
    for the built-in transfemoral stride, which gallops, the text counts it."""
    import types

    from bladelab.design.collocation_evaluator import DEFAULT_START
    from bladelab.report.collocation_sweep import collocation_sweep_sections

    texts = []
    report = types.SimpleNamespace(add_section=lambda title, text="", **kw: texts.append(text))
    folder = _subset(tmp_path, ["Cat4"])
    collocation_sweep_sections(report, folder)
    assert "gallop" not in texts[-1]
    shutil.copyfile(DEFAULT_START, folder / "amputee-Cat4" / "speed-4.json")
    collocation_sweep_sections(report, folder)
    assert "1 of 2 strides gallop" in texts[-1] and "40–60 %" in texts[-1]
