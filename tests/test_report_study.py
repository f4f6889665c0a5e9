"""A reduced example study end to end: generate C3D trials -> identify -> ``bladelab report``.

Also the report's clear errors, and a headless-Chromium check of the study page with the harness
of ``browser.py``.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest

from bladelab.cli import main
from bladelab.errors import DataError, InputFileError
from bladelab.example.study import make_example_study, read_ground_truth
from bladelab.report.study import build_study_report
from bladelab.study import run_study

N_TRIALS = 4
# GRF, distance, K*/D* bars, 3 mechanics panels, cost landscape, sensitivity to noise and
# marker rate, recovered vs true
FIGURES = 9


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    folder = tmp_path_factory.mktemp("e2e") / "sprint"
    make_example_study(folder, seed=1, n_trials=N_TRIALS, jobs=1, progress=False)
    run = run_study(folder, settings={"max_evals": 200}, jobs=1, executor="serial",
                    progress=False)
    assert run.finished + len(run.failures) == N_TRIALS
    return folder


@pytest.fixture(scope="module")
def report(study):
    return build_study_report(study, landscape_points=7, progress=False)


def test_the_report_has_every_section_and_its_tables(study, report):
    html = report.index.read_text(encoding="utf-8")
    for heading in ("nRMSE of the GRF (Table 1)", "nRMSE of the characteristic distance (Table 2)",
                    "GRF and distance vs time", "K* and D* per group and speed band",
                    "Blade mechanics", "Statistics", "Identifiability",
                    "How far to trust K* and D*", "Recovered vs true parameters", "Settings, versions and seed"):
        assert heading in html, heading
    assert "SYNTHETIC" in html
    # one athlete per amputation level: the tests describe these athletes' trials
    assert "Unit of analysis: the trial" in html and "not a population" in html
    assert len(re.findall(r'<img src="data:image/png;base64,', html)) == FIGURES
    assert report.n_trials + report.n_failed == N_TRIALS and report.n_trials >= 3
    tables = report.index.parent / "tables"
    grf = pd.read_csv(tables / "nrmse-grf.csv")
    # both amputation levels and every category group of the reduced study are rows
    assert {"TF", "TT"} <= set(grf["group"])
    # a richer generating model: the fit is good but not exact (seed 000: 10–17 % for GRF)
    assert (grf["nrmse_trials_mean_pct"] > 1.0).all() and (grf["nrmse_trials_mean_pct"] < 60).all()
    dist = pd.read_csv(tables / "nrmse-distance.csv")
    assert (dist["nrmse_trials_mean_pct"] < 30).all()


def test_recovered_parameters_are_compared_with_the_generators_truth(study, report):
    per_trial = pd.read_csv(report.index.parent / "tables"
                            / "recovered-vs-true-parameters-per-trial.csv")
    truth = read_ground_truth(study).set_index("trial_id")
    assert len(per_trial) == report.n_trials
    for row in per_trial.itertuples():
        assert row.K_true == pytest.approx(truth.loc[row.trial_id, "K_Nm_per_deg"])
        assert row.K_error_pct == pytest.approx(100 * (row.K_Nm_per_deg / row.K_true - 1))
    # the seed's formulation on degraded data is biased, but lands in the right region
    assert np.all(np.abs(per_trial["K_error_pct"]) < 50)


def test_no_results_yet_is_a_clear_error(tmp_path, study, capsys):
    empty = tmp_path / "fresh"
    make_example_study(empty, seed=1, n_trials=2, jobs=1, progress=False)
    with pytest.raises(InputFileError, match="no identification results"):
        build_study_report(empty, progress=False)
    assert main(["report", str(empty)]) == 2
    err = capsys.readouterr().err
    assert "run `bladelab identify" in err and "Traceback" not in err
    assert not (empty / "report").exists()
    with pytest.raises(DataError, match="no identification result"):
        build_study_report(study, trial="nope", progress=False)


def test_the_cli_writes_the_report_with_a_chosen_landscape_trial(study, tmp_path, capsys):
    trial_id = sorted(p.stem for p in (study / "trials").glob("*.c3d"))[-1]
    out = tmp_path / "rep"
    assert main(["report", str(study), "--trial", trial_id, "--out", str(out), "--json"]) == 0
    assert f'"landscape_trial": "{trial_id}"' in capsys.readouterr().out
    assert (out / "index.html").is_file()


def test_the_study_report_opens_in_headlesschromium(tmp_path, report):
    from browser import LAYOUT, chromium, figure_ok, inspect_page

    binary = chromium()
    figures, errors, layout = inspect_page(binary, report.index, tmp_path / "study.png",
                                           tmp_path / "profile", probe=LAYOUT)
    print(f"\nstudy report screenshot: {tmp_path / 'study.png'}")
    assert errors == [], f"console errors: {errors}"
    assert len(figures) == FIGURES
    for fig in figures:
        assert figure_ok(fig), fig
    # no clipped table: the page never overflows sideways, every table scrolls in its own box
    # and says so when it is wider than the page
    assert layout["pageOverflowX"] <= 0, layout["pageOverflowX"]
    assert layout["tables"] and all(t["scrolls"] for t in layout["tables"])
    assert all(t["hintShown"] == t["overflows"] for t in layout["tables"])
    assert any("Flagged trials" in h for h in layout["headings"])


def _flag_only(study, trial_id, *, reason="test: marked by hand"):
    """Mark exactly one trial flagged in the study's results (others not flagged)."""
    import sqlite3

    con = sqlite3.connect(study / "results.sqlite")
    with con:
        con.execute("UPDATE results SET flagged = 0, flags = ''")
        con.execute("UPDATE results SET flagged = 1, flags = ? WHERE trial_id = ?",
                    (reason, trial_id))
    con.close()


def _tested(stats: pd.DataFrame) -> int:
    """Trials in the Kruskal–Wallis test across groups (the sum of its group sizes)."""
    kw = stats[stats["test"] == "Kruskal-Wallis H"].iloc[0]
    return sum(int(v) for v in str(kw["n"]).split(" | "))


def test_a_flagged_trial_is_marked_and_left_out_of_group_tests(study, report, tmp_path):
    from bladelab.report.study_quality import FLAG_MARK

    trials = pd.read_csv(report.index.parent / "tables" / "trials.csv")
    largest = trials["group"].value_counts().index[0]  # a group that keeps members
    trial_id = sorted(trials.loc[trials["group"] == largest, "trial_id"])[0]
    _flag_only(study, trial_id)
    out = tmp_path / "flagged"
    res = build_study_report(study, out_dir=out, landscape_points=5, progress=False)
    html = (out / "index.html").read_text(encoding="utf-8")
    assert res.n_flagged == 1 and not res.flagged_in_statistics
    assert "Flagged trials" in html and "test: marked by hand" in html
    # marked in the trials table: its row carries the flag
    row = re.search(rf"<tr><td>{trial_id}</td><td>([^<]*)</td>", html)
    assert row is not None and row.group(1) == FLAG_MARK
    assert "1 of " in html and "LEFT OUT" in html
    stats = pd.read_csv(out / "tables" / "statistics.csv")
    assert _tested(stats) == res.n_trials - 1
    # kept with --include-flagged (the CLI option)
    out2 = tmp_path / "kept"
    assert main(["report", str(study), "--include-flagged", "--out", str(out2), "--json"]) == 0
    stats2 = pd.read_csv(out2 / "tables" / "statistics.csv")
    assert _tested(stats2) == res.n_trials
    html2 = (out2 / "index.html").read_text(encoding="utf-8")
    assert "KEPT in the group statistics" in html2
    assert re.search(rf"<tr><td>{trial_id}</td><td>{FLAG_MARK}</td>", html2)
    # marked in the recovered-vs-true table too
    per = pd.read_csv(out / "tables" / "recovered-vs-true-parameters-per-trial.csv")
    assert per.set_index("trial_id").loc[trial_id, "quality"] == FLAG_MARK
