"""``bladelab design``, ``bladelab blade test`` and the design report section."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bladelab.cli import main
from bladelab.design import generate_blade


@pytest.fixture(scope="module")
def blade_yaml(tmp_path_factory):
    path = tmp_path_factory.mktemp("blade") / "gen.yaml"
    path.write_text(generate_blade({"stiffness_kN_per_m": 25.0}).spec.to_yaml())
    return path


def test_blade_test_hits_target_stiffness(blade_yaml, capsys, tmp_path):
    """The generated blade was scaled to 25 kN/m at 0°: the command reports that at 0°."""
    fig = tmp_path / "ct.png"
    assert main(["blade", "test", str(blade_yaml), "--alignment", "0,-8,8", "--json",
                 "--plot", str(fig)]) == 0
    data = json.loads(capsys.readouterr().out)
    tests = {t["alignment_deg"]: t for t in data["tests"]}
    assert tests[0.0]["stiffness_linear_N_per_m"] == pytest.approx(25e3, rel=1e-6)
    assert data["load_N"] == pytest.approx(76 * 9.80665)
    # secant stiffness at body weight: load / displacement there
    t0 = tests[0.0]
    assert t0["stiffness_at_load_N_per_m"] == pytest.approx(t0["load_N"] / t0["displacement_at_load_m"])
    assert fig.stat().st_size > 0


def test_blade_test_single_joint_falls_back_to_free(capsys):
    assert main(["blade", "test", "xtreme", "--alignment", "0"]) == 0
    out = capsys.readouterr()
    assert "tip free" in out.out and "cannot compress" in out.err


def test_blade_test_load_not_reached_is_null(capsys):
    assert main(["blade", "test", "xtreme", "--alignment", "0", "--max-displacement", "0.01",
                 "--json"]) == 0
    t = json.loads(capsys.readouterr().out)["tests"][0]
    assert t["stiffness_at_load_N_per_m"] is None and t["stiffness_linear_N_per_m"] > 0


def test_blade_test_bad_input(blade_yaml, capsys):
    assert main(["blade", "test", str(blade_yaml), "--alignment", "0,x"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and "--alignment" in err and "Traceback" not in err
    assert main(["blade", "test", "no-such-blade"]) == 2


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study") / "ds"
    args = ["design", "--factors", "stiffness_kN_per_m=18:32,toe_length_m=0.19:0.25",
            "--runs", "ccd", "--evaluator", "blade", "--out", str(out),
            "--constraint", "swing_clearance_m=0.07", "--no-figures"]
    assert main(args) == 0
    return out, args


def test_design_writes_study(study):
    out, _ = study
    for name in ("study.json", "results.csv", "surfaces.json", "anova.csv", "optimum.json",
                 "evaluator.json"):
        assert (out / name).is_file(), name
    table = pd.read_csv(out / "results.csv")
    assert len(table) == 9  # 2-factor face-centred CCD: 4 + 4 + 1
    # the clearance proxy is pure geometry of the toe: the surface fits it almost exactly
    surf = json.loads((out / "surfaces.json").read_text())
    assert surf["swing_clearance_m"]["r2"] > 0.999
    opt = json.loads((out / "optimum.json").read_text())
    assert opt["constraints"]["swing_clearance_m"]["slack"] >= -1e-6
    # the sitting's wall time, recorded by the study itself
    from bladelab.design.timing import RUNS_STAGE, stage_walls
    runs = stage_walls(out)[RUNS_STAGE]
    assert runs["designs"] == 9 and runs["sittings"] == 1 and runs["wall_s"] > 0


def test_design_resumes_and_draws(study, capsys):
    out, args = study
    args = [a for a in args if a != "--no-figures"]
    assert main(args) == 0
    assert "(0 evaluated, 9 resumed)" in capsys.readouterr().out
    from bladelab.design.timing import read_segments
    assert len(read_segments(out)) == 1  # a sitting that evaluated nothing is not a segment
    assert (out / "figures" / "main_effects.png").is_file()
    assert any((out / "figures").glob("contour_*.png"))


def test_design_report(study, tmp_path):
    from bladelab.report.design import build_design_report, design_report_sections

    out, _ = study
    sections = design_report_sections(out)
    titles = [s["title"] for s in sections]
    assert any("ANOVA" in t for t in titles) and any("optimum" in t for t in titles)
    index = build_design_report(out, tmp_path / "rep")
    html = index.read_text()
    assert "ANOVA of delta_vx_m_per_s" in html and "<img" in html


def test_design_jobs_match_serial(study, tmp_path, capsys):
    """Runs evaluated by 2 worker processes give the serial study's results exactly, and a
    fresh folder says so ("9 evaluated, 0 resumed", not "0 evaluated, 9 resumed")."""
    out, args = study
    par = tmp_path / "par"
    i = args.index("--out")
    capsys.readouterr()
    assert main([*args[:i], "--out", str(par), *args[i + 2:], "--jobs", "2"]) == 0
    n_runs = len(pd.read_csv(out / "results.csv"))
    assert f"({n_runs} evaluated, 0 resumed)" in capsys.readouterr().out
    pd.testing.assert_frame_equal(pd.read_csv(par / "results.csv"),
                                  pd.read_csv(out / "results.csv"))


def test_bladelab_report_dispatches_design_folder(study, tmp_path, capsys):
    out, _ = study
    assert main(["report", str(out), "--out", str(tmp_path / "r")]) == 0
    assert "report written" in capsys.readouterr().out
    assert (tmp_path / "r" / "index.html").is_file()


def test_design_caps_a_response_from_the_command_line(study, tmp_path):
    """``response<=maximum``: stored as {"max": v}; the optimum (the long toe, whose blade is
    the heaviest, 0.67 kg) moves to a shorter toe to stay under a 0.65 kg cap, on it; the
    report rebuilds it."""
    out, args = study
    capped = tmp_path / "capped"
    shutil.copytree(out, capped)
    limit = 0.65
    argv = [a for a in args if a not in ("--constraint", "swing_clearance_m=0.07")]
    argv[argv.index("--out") + 1] = str(capped)
    assert main([*argv, "--constraint", f"blade_mass_kg<={limit}"]) == 0
    meta = json.loads((capped / "study.json").read_text())
    assert meta["constraints"] == {"blade_mass_kg": {"max": limit}}
    optimum = json.loads((capped / "optimum.json").read_text())
    opt = optimum["constraints"]["blade_mass_kg"]
    assert opt["maximum"] == limit and opt["predicted"] == pytest.approx(limit, abs=1e-5)
    assert optimum["coded"]["toe_length_m"] < 0.9
    assert main(["report", str(capped), "--out", str(tmp_path / "r")]) == 0


def test_design_bad_input(tmp_path, capsys):
    assert main(["design", "--out", str(tmp_path / "x"), "--constraint", "nonsense"]) == 2
    assert "--constraint" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "x"), "--constraint", "a<=b"]) == 2
    assert "response<=maximum" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "y"), "--evaluator", "fem"]) == 2
    assert main(["design", "--out", str(tmp_path / "w"), "--evaluator", "runner", "--gait",
                 str(tmp_path / "missing.csv")]) == 2
    assert "no such gait-cycle file" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "z"), "--runs", "bbd", "--factors",
                 "stiffness_kN_per_m=18:32,width_m=0.05:0.08"]) == 2  # BBD needs k >= 3
    assert main(["design", "--out", str(tmp_path / "c"), "--start", str(tmp_path)]) == 2
    assert "--start: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--settle", "1"]) == 2
    assert "--settle: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--knee-moment-min", "0"]) == 2
    assert "--knee-moment-min: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--knee-moment-min", "10"]) == 2
    assert "knee moment minimum must be <= 0" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--knee-flexion-max", "5"]) == 2
    assert "--knee-flexion-max: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--knee-flexion-max", "120"]) == 2
    assert "loaded knee's flexion limit" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--reference-weight", "10"]) == 2
    assert "--reference-weight: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--reference-weight", "-1"]) == 2
    assert "reference weight must be >= 0" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--amputation", "transtibial", "--body-mass", "-70"]) == 2
    assert "--body-mass: body_mass_kg must be a number > 0 [kg]" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--muscle-strength", "1.5"]) == 2
    assert "--muscle-strength: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--amputation", "transtibial", "--max-shortening-velocity", "99"]) == 2
    assert "--max-shortening-velocity: the maximum shortening velocity" in (
        capsys.readouterr().err)
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--prosthesis-extra-length", "0.5"]) == 2
    assert "--prosthesis-extra-length:" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--mesh", "100"]) == 2
    assert "--mesh: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--mesh", "3"]) == 2
    assert "--mesh: need an integer of at least 4 mesh intervals" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--start", str(tmp_path / "none.json")]) == 2
    assert "none.json" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--body", "human"]) == 2
    assert "--body: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--body", "human"]) == 2
    err = capsys.readouterr().err
    assert "--body: no built-in start stride of the transfemoral runner on the human body" in err
    assert "Traceback" not in err
    assert main(["design", "--out", str(tmp_path / "c"), "--amputation", "transtibial"]) == 2
    assert "--amputation: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--amputation", "ankle"]) == 2
    assert "--amputation: unknown amputation 'ankle'" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--amputation", "transtibial", "--knee-moment-min", "0"]) == 2
    assert "--knee-moment-min: a setting of the prosthetic knee" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--reference-weight", "10", "--people-weight", "10"]) == 2
    assert "--people-weight: people's joint angles and the start stride's technique" in (
        capsys.readouterr().err)
    assert main(["design", "--out", str(tmp_path / "c"), "--alternating-steps", "0.1"]) == 2
    assert "--alternating-steps: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--alternating-steps", "0.6"]) == 2
    assert "--alternating-steps:" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--prosthetic-load-max", "3"]) == 2
    assert "--prosthetic-load-max: only with --evaluator collocation" in (
        capsys.readouterr().err)
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--prosthetic-load-max", "0"]) == 2
    assert "--prosthetic-load-max: the prosthetic load limit" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--stride-time", "people"]) == 2
    assert "--stride-time: only with --evaluator collocation" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--stride-time", "fast"]) == 2
    assert "--stride-time:" in capsys.readouterr().err
    assert main(["design", "--out", str(tmp_path / "c"), "--evaluator", "collocation",
                 "--stride-time", "0.6,9"]) == 2
    assert "--stride-time: the stride time range" in capsys.readouterr().err
    assert not (tmp_path / "c").exists()  # refused before any output


def test_an_interrupted_settling_pass_is_recorded_and_resumed(tmp_path, monkeypatch):
    # a settling pass takes hours: each design is recorded as it finishes, and the next
    # --settle resumes the pass with the designs it had not reached
    import types

    import numpy as np

    from bladelab.design import settling
    from bladelab.design.settling import RECORD_NAME, settle_study
    from bladelab.design.space import default_design_space
    from bladelab.design.study import run_file

    space = default_design_space()
    coded = np.array([[0, 0, 0, 0], [1, 0, 0, 0], [-1, 0, 0, 0], [0, 1, 0, 0]], float)
    result = types.SimpleNamespace(space=space, design=types.SimpleNamespace(coded=coded),
                                   out_dir=tmp_path, failed={})
    for i in range(4):
        run_file(tmp_path, i).parent.mkdir(exist_ok=True)
        run_file(tmp_path, i).write_text("{}")
    seen, knowns = [], []

    def settle(evaluator, points, *, skip=(), on_design=None, stop_after=None, cheapest=None,
               known=None, **_):
        todo = [i for i in range(len(points)) if i not in set(skip)]
        seen.append(todo)
        knowns.append(known)
        assert cheapest is True  # a new pass also starts from the study's cheapest stride
        for n, i in enumerate(todo):
            if stop_after is not None and n == stop_after:
                raise KeyboardInterrupt
            improved = i % 2 == 1  # designs 2 and 4 get a better stride (10 % lower)
            on_design(i, {"point": points[i], "before": 1.0, "after": 0.9 if improved else 1.0,
                          "from": "nb.json" if improved else None,
                          "tries": [{"from": "nb.json", "start": f"id {len(knowns)}"}]})

    monkeypatch.setattr(settling, "settle_strides", lambda *a, **k: settle(*a, stop_after=2, **k))
    with pytest.raises(KeyboardInterrupt):
        settle_study(None, result, passes=1, jobs=1)
    record = json.loads((tmp_path / RECORD_NAME).read_text())["passes"]
    assert [r["run"] for r in record[0]["designs"]] == [1, 2] and not record[0]["complete"]
    assert record[0]["from_cheapest"] is True
    assert run_file(tmp_path, 0).is_file() and not run_file(tmp_path, 1).exists()

    monkeypatch.setattr(settling, "settle_strides", settle)
    outcome = settle_study(None, result, passes=1, jobs=1)
    assert outcome.changed and outcome.passes == 1  # design 4 changed
    assert seen[-1] == [2, 3]  # resumed: only the designs the pass had not reached
    record = json.loads((tmp_path / RECORD_NAME).read_text())["passes"]
    assert len(record) == 1 and record[0]["complete"] and record[0]["improved"] == 2
    assert record[0]["largest_objective_drop"] == pytest.approx(0.1)
    assert [run_file(tmp_path, i).exists() for i in range(4)] == [True, False, True, False]
    # both sittings of the pass are timed, the stopped one too
    from bladelab.design.timing import settling_stage, stage_walls
    first = stage_walls(tmp_path)[settling_stage(1)]
    assert first["designs"] == 4 and first["sittings"] == 2
    (tmp_path / "timing.json").write_text('{"note": "written by hand", "segments": []}')
    settle_study(None, result, passes=1, jobs=1)  # a new pass: every design again
    assert knowns[0] == knowns[1] == [{}, {}, {}, {}]  # the first pass knew no start
    # the new pass knows each design's starts of the first (the resumed sitting's identity)
    assert knowns[2] == [{"nb.json": "id 1"}] * 2 + [{"nb.json": "id 2"}] * 2
    walls = stage_walls(tmp_path)
    assert list(walls) == [settling_stage(2)] and walls[settling_stage(2)]["designs"] == 4
    assert json.loads((tmp_path / "timing.json").read_text())["note"] == "written by hand"
    (tmp_path / "timing.json").unlink()
    assert seen[-1] == [0, 1, 2, 3]
    assert len(json.loads((tmp_path / RECORD_NAME).read_text())["passes"]) == 2
    # that pass lowered design 4 by 10 %: not settled, so a further pass runs; once a pass
    # lowers nothing by more than 1 %, the study is settled and --settle runs no more
    monkeypatch.setattr(settling, "settle_strides", lambda evaluator, points, *, skip=(),
                        on_design=None, **_: [
                            on_design(i, {"point": points[i], "before": 1.0, "after": 0.995,
                                          "from": "nb.json"}) for i in range(len(points))])
    assert settle_study(None, result, passes=3, jobs=1).passes == 1
    again = settle_study(None, result, passes=3, jobs=1)
    assert again.settled and again.passes == 0 and not again.changed
    assert len(json.loads((tmp_path / RECORD_NAME).read_text())["passes"]) == 3

    other = types.SimpleNamespace(space=space, design=types.SimpleNamespace(coded=coded[::-1]),
                                  out_dir=tmp_path, failed={})
    from bladelab.errors import InputFileError
    with pytest.raises(InputFileError, match="is not run"):
        settle_study(None, other, passes=1, jobs=1)


def _collocation_copy(study, tmp_path, residuals: dict[int, float], missing=()):
    """The blade study's folder as if its runs were collocation strides: every run's stride is
    the built-in clean transfemoral stride, run ``i``'s dynamics residual set to
    ``residuals[i]`` [%]."""

    from bladelab.design.collocation_evaluator import DEFAULT_START, point_file_stem

    out, _ = study
    copy = tmp_path / "coll"
    shutil.copytree(out, copy)
    (copy / "evaluator.json").write_text(json.dumps(
        {"evaluator": "collocation", "solutions_dir": "elsewhere/strides"}))
    stride = json.loads(DEFAULT_START.read_text())
    table = pd.read_csv(copy / "results.csv")
    names = ["stiffness_kN_per_m", "toe_length_m"]
    (copy / "strides").mkdir()
    for _, row in table.iterrows():
        run = int(row["run"])
        if run in missing:
            continue
        data = json.loads(json.dumps(stride))
        data["consistency"]["dynamics_residual_pct"] = residuals.get(run, 1.0)
        (copy / "strides" / f"{point_file_stem({n: row[n] for n in names})}.json").write_text(
            json.dumps(data))
    return copy, table


def test_design_report_leaves_out_flagged_strides(study, tmp_path):
    """A collocation study's run whose stride fails today's checks (a 12 % residual) is named
    in the report and left out of its surfaces; a run whose stride file is missing is kept and
    said to be unchecked."""
    from bladelab.report.design import _load, design_report_sections

    copy, table = _collocation_copy(study, tmp_path, {3: 12.0}, missing=(5,))
    meta, _, _, surfaces = _load(copy)  # the strides found inside the moved study's folder
    checks = meta["_strides"]
    assert checks.loc[checks["run"] == 3, "excluded"].item()
    assert "12.0 %" in checks.loc[checks["run"] == 3, "warnings"].item()
    assert checks.loc[checks["run"] == 5, "warnings"].item() == "stride file not found"
    assert not checks.loc[checks["run"] != 3, "excluded"].any()
    fitted = next(iter(surfaces.values()))
    assert len(fitted.y) == len(table) - 1
    sections = {s["title"]: s for s in design_report_sections(copy)}
    strides = sections["Design study: predicted strides"]
    assert "1 carry warnings" in strides["text"] and "1 stride files were not found" in \
        strides["text"]
    runs = dict(sections["Design study: response surfaces"]["tables"])["Runs"]
    assert runs.loc[runs["run"] == 3, "stride"].item() == "left out (warnings)"
    assert "the gait predicted freely" in strides["text"]


def test_design_report_says_how_many_strides_gallop(study, tmp_path):
    """The built-in transfemoral stride gallops (both legs land within a fifth of a stride);
    one run given the shipped alternating amputee stride: the report's first section and its
    strides section say 8 of 9 gallop, and the strides table gives each run's step phase."""
    from bladelab.design.collocation_evaluator import point_file_stem
    from bladelab.report.design import design_report_sections

    copy, table = _collocation_copy(study, tmp_path, {})
    row = table.iloc[1]
    stem = point_file_stem({n: row[n] for n in ["stiffness_kN_per_m", "toe_length_m"]})
    alternating = Path(__file__).parents[1] / "src/bladelab/data/runner/collocation/" \
        "amputee-Cat6-4-human.json"
    shutil.copyfile(alternating, copy / "strides" / f"{stem}.json")
    sections = {s["title"]: s for s in design_report_sections(copy)}
    assert "8 of 9 strides gallop" in sections["Design study: response surfaces"]["text"]
    strides = sections["Design study: predicted strides"]
    assert "8 of 9 strides gallop" in strides["text"] and "40–60 %" in strides["text"]
    shown = dict(strides["tables"])[
        "Strides (files in the study's strides folder, named by the design point)"]
    phases = shown.set_index("run")["step phase (% of the stride)"]
    assert 40.0 < phases[int(row["run"])] < 60.0
    assert ((phases.drop(int(row["run"])) < 25.0) | (phases.drop(int(row["run"])) > 75.0)).all()


def test_design_report_says_the_technique_was_kept(study, tmp_path):
    """A study solved with a reference weight says so, with the weight and the knee bound."""
    from bladelab.report.design import design_report_sections

    copy, _ = _collocation_copy(study, tmp_path, {})
    (copy / "evaluator.json").write_text(json.dumps(
        {"evaluator": "collocation", "solutions_dir": "strides", "speed_mps": 4.0,
         "reference_weight": 10.0, "knee_moment_min_Nm": 0.0}))
    text = {s["title"]: s for s in design_report_sections(copy)}[
        "Design study: predicted strides"]["text"]
    assert "at 4 m/s" in text and "10 /rad²" in text and "intact leg" in text
    assert "held at or above 0 N·m" in text and "predicted freely" not in text


def test_design_report_refuses_too_few_clean_strides(study, tmp_path):
    from bladelab.errors import InputFileError
    from bladelab.report.design import _load

    copy, _ = _collocation_copy(study, tmp_path, {1: 9.0, 2: 9.0, 3: 9.0, 4: 9.0})
    with pytest.raises(InputFileError, match="only 5 of 9 runs have clean strides"):
        _load(copy)


def test_report_of_an_unfinished_design_study_says_so(study, tmp_path, capsys):

    out, _ = study
    partial = tmp_path / "partial"
    shutil.copytree(out, partial)
    (partial / "results.csv").unlink()
    assert main(["report", str(partial), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "not finished (9 runs done" in err and "Traceback" not in err


def test_design_report_shows_what_the_start_decides(study, tmp_path):
    """A settling record with two clean strides of the same designs: the report gives each
    response's start spread and R² ceiling beside the fits, and names the responses whose
    ceiling is below 0.8."""
    from bladelab.report.design import design_report_sections

    copy, table = _collocation_copy(study, tmp_path, {})
    y = table["delta_vx_m_per_s"].to_numpy(float)
    big = 3.0 * float(np.std(y, ddof=1))  # the start moves it more than the designs do
    z = table["impulse_z_Ns"].to_numpy(float)
    small = 0.2 * float(np.std(z, ddof=1))  # ... and this one less
    designs = [{"run": r, "before": 1.0,
                "responses_before": {"delta_vx_m_per_s": y[r - 1], "max_speed_m_per_s": 5.0,
                                     "impulse_z_Ns": z[r - 1]},
                "tries": [{"from": "n.json", "converged": True, "objective": 1.01,
                           "responses": {"delta_vx_m_per_s": y[r - 1] + big,
                                         "max_speed_m_per_s": 5.1,
                                         "impulse_z_Ns": z[r - 1] + small}}]}
               for r in (1, 2)]
    (copy / "settling.json").write_text(json.dumps({"passes": [{"pass": 1,
                                                                "designs": designs}]}))
    sections = {s["title"]: s for s in design_report_sections(copy)}
    spread = sections["Design study: what the solver's start decides"]
    table_ = dict(spread["tables"])["Start spread of the responses"].set_index("response")
    assert table_.loc["delta_vx_m_per_s", "within_sd"] == pytest.approx(big / np.sqrt(2))
    assert table_.loc["delta_vx_m_per_s", "r2_ceiling"] == 0.0
    assert "delta_vx_m_per_s" in spread["text"] and "below 0.8" in spread["text"]
    assert "With 2 designs the spread is a rough estimate" in spread["text"]
    fits = dict(sections["Design study: response surfaces"]["tables"])["Surface fits"]
    fitted = fits.set_index("response")
    assert fitted.loc["delta_vx_m_per_s", "R2 ceiling (start spread)"] == 0.0
    assert fitted.loc["delta_vx_m_per_s", "R2_pred ceiling (start spread)"] == 0.0
    # a response the start moves less: the leverages put its predicted-R² ceiling below
    # its R² ceiling
    r2_ceiling, r2_pred_ceiling = fitted.loc["impulse_z_Ns", ["R2 ceiling (start spread)",
                                                              "R2_pred ceiling (start spread)"]]
    assert 0.0 < r2_pred_ceiling < r2_ceiling < 1.0
    assert "stride_objective" not in spread["text"]  # a study without it as a response
    # with the objective a response of the study, the section says what its spread means
    table.assign(stride_objective=np.linspace(1.0, 2.0, len(table)),
                 max_speed_m_per_s=np.linspace(4.8, 5.2, len(table))).to_csv(
        copy / "results.csv", index=False)
    spread = {s["title"]: s for s in design_report_sections(copy)}[
        "Design study: what the solver's start decides"]
    rows = dict(spread["tables"])["Start spread of the responses"].set_index("response")
    assert "stride_objective" in rows.index
    assert rows.loc["max_speed_m_per_s", "unit"] == "m/s"  # the maximum-speed problem's
    assert "stride_objective is the value each solve minimised" in spread["text"]
