"""The shape of ``bladelab predict``, ``sweep`` and ``design``: options grouped by method in
``--help``, an option of another method refused by one table-driven check, and the library
functions the commands call (settings, guesses, settling) given the same values as before."""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys
import types

import pytest

from bladelab.cli import main


# -- an option of another method --------------------------------------------------------------
@pytest.mark.parametrize(("args", "option", "belongs"), [
    (["predict", "--method", "collocation", "--generations", "5"], "--generations",
     "--method reflex"),
    (["predict", "--method", "collocation", "--integrator", "newmark"], "--integrator",
     "--method reflex"),
    (["predict", "--method", "collocation", "--seeds", "1,2"], "--seeds", "--method reflex"),
    (["predict", "--method", "reflex", "--mesh", "30"], "--mesh", "--method collocation"),
    (["predict", "--method", "reflex", "--json"], "--json", "--method collocation"),
    (["predict", "--method", "reflex", "--max-speed"], "--max-speed", "--method collocation"),
    (["sweep", "--method", "collocation", "--sigma", "0.1"], "--sigma", "--method reflex"),
    (["sweep", "--method", "collocation", "--chain-from", "Cat6"], "--chain-from",
     "--method reflex"),
    (["sweep", "--guess", "trial"], "--guess", "--method collocation"),
    (["sweep", "--recipe", "stable-gait", "--generations", "5"], "--generations",
     "--method reflex"),
    (["sweep", "--track-study", "x"], "--track-study", "--recipe"),
    (["design", "--evaluator", "blade", "--settle", "2"], "--settle", "--evaluator collocation"),
    (["design", "--evaluator", "collocation", "--dt", "1e-5"], "--dt", "--evaluator blade"),
    (["design", "--evaluator", "blade", "--gait", "x.csv"], "--gait", "--evaluator runner"),
])
def test_an_option_of_another_method_is_refused_naming_it_and_its_method(
        args, option, belongs, tmp_path, capsys):
    out = tmp_path / "out"
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {option}: only with ") and belongs in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_an_option_of_the_chosen_method_given_its_default_is_accepted(tmp_path, monkeypatch):
    """The check is about where an option belongs, not its value: the reflex method's own
    options pass it (the run itself is replaced here)."""
    import bladelab.cli.reflex as reflex

    seen = {}
    monkeypatch.setattr(reflex, "run_reflex", lambda **kw: seen.update(kw))
    assert main(["predict", "--method", "reflex",
                 "--integrator", "explicit", "--seeds", "1", "--out",
                 str(tmp_path)]) == 0
    assert seen["integrator"] == "explicit" and seen["seeds"] == "1"


# -- --help ---------------------------------------------------------------------------------
def _sections(text: str) -> dict[str, list[str]]:
    """Option names per help section ('Common options:' ...)."""
    sections, current = {}, None
    for line in text.splitlines():
        if line.endswith("options:") and not line.startswith(" "):
            current = line[:-len(" options:")]
            sections[current] = []
        elif current and line.startswith("  --"):
            sections[current].append(line.split()[0])
    return sections


@pytest.mark.parametrize(("command", "groups"), [
    ("predict", {"Common": "--speed", "Reflex controller (CMA-ES)": "--track",
                 "Collocation": "--mesh"}),
    ("sweep", {"Common": "--speeds", "Reflex controller (CMA-ES)": "--recipe",
               "Reflex speed grid (without --recipe)": "--chain-from",
               "Reflex recipe (with --recipe)": "--track-study", "Collocation": "--starts"}),
    ("design", {"Study": "--body-mass", "Blade and runner evaluator": "--dt",
                "Runner evaluator": "--motion", "Collocation evaluator": "--settle"}),
])
def test_help_shows_the_options_by_method(command, groups, capsys):
    assert main([command, "--help"]) == 0
    sections = _sections(capsys.readouterr().out)
    assert list(sections) == list(groups)
    for title, option in groups.items():
        assert option in sections[title], (title, sections[title])


def test_help_is_the_same_with_and_without_rich():
    """The app's help is plain text: typer's rich formatting (TYPER_USE_RICH) and rich
    itself change nothing."""
    code = "from bladelab.cli import main; main(['predict', '--help'])"
    runs = [
        {},
        {"TYPER_USE_RICH": "0"},
    ]
    texts = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            env={**os.environ, **extra}, check=False, timeout=120).stdout
             for extra in runs]
    no_rich = subprocess.run(
        [sys.executable, "-c", "import sys; sys.modules['rich'] = None; " + code],
        capture_output=True, text=True, check=False, timeout=120).stdout
    assert "Reflex controller (CMA-ES) options:" in texts[0]
    assert texts[0] == texts[1] == no_rich


@pytest.mark.parametrize("command", [["predict"], ["sweep"], ["design"]])
def test_every_option_has_a_panel_of_the_table(command):
    """Each option is tagged once, by its panel; every panel is in the command's table."""
    import typer.main

    from bladelab.cli import app, design, predict

    tables = {"predict": predict.PREDICT_PANELS, "sweep": predict.SWEEP_PANELS,
              "design": design.DESIGN_PANELS}
    titles = {p.title for p in tables[command[0]]}
    cmd = typer.main.get_command(app).commands[command[0]]
    options = [p for p in cmd.params if p.param_type_name == "option"]
    assert options and all(p.rich_help_panel in titles for p in options)


def test_help_names_no_work_sitting(capsys):
    import re

    for command in ("predict", "sweep", "design"):
        assert main([command, "--help"]) == 0
        text = capsys.readouterr().out
        assert not re.search(r"\b(issue|session)s? ?\d", text, re.IGNORECASE), command


# -- the same calls with the same values ----------------------------------------------------
class _Called(Exception):
    """Raised by a replaced library function once it has recorded its call."""


def test_predict_reflex_passes_the_same_settings(tmp_path, monkeypatch, capsys):
    import bladelab.predict.reflex.named_runs as named
    from bladelab.predict.reflex.objective import ObjectiveSettings

    seen = {}

    def optimize_seeds(model, **kw):
        seen.update(model=model, **kw)
        return [types.SimpleNamespace(best_cost=1.0, to_dict=lambda: {"best_cost": 1.0})]

    monkeypatch.setattr(named, "optimize_seeds", optimize_seeds)
    assert main(["predict", "--method", "reflex",
                 "--model", "amputee", "--blade", "Cat5", "--speed", "4",
                 "--generations", "3", "--popsize", "6", "--sigma", "0.5", "--seeds", "1,2",
                 "--duration", "4", "--dt", "5e-4", "--robust-samples", "3",
                 "--robust-jitter", "1e-5", "--robust-speed-change", "0.05",
                 "--lean-weight", "2", "--strike-limit", "0.5", "--run-up", "--integrator",
                 "newmark", "--jobs", "2", "--checkpoint-every", "7", "--force",
                 "--out", str(tmp_path)]) == 0
    assert json.loads(capsys.readouterr().out) == {"best_cost": 1.0}
    progress = seen.pop("progress")
    assert callable(progress)
    assert seen == dict(
        model="amputee", seeds=[1, 2], out=tmp_path, blade="Cat5", body="seed001",
        speed=4.0, x0=None,
        generations=3, popsize=6, sigma=0.5, jobs=2, executor="local", resume=False,
        force=True, checkpoint_every=7,
        settings=ObjectiveSettings(
            speed=4.0, duration=4.0, dt=5e-4, robust_samples=3, robust_jitter=1e-5,
            robust_directions="fixed", robust_speed_change=0.05, robust_push=0.0,
            robust_half_step=False, initial_speed=None, strike_limit_bw=0.5, w_lean=2.0,
            run_up=True, integrator="newmark", track=None, w_track=0.0))


def test_predict_reflex_hold_keeps_the_matching_parameters(tmp_path, monkeypatch, capsys):
    """--hold turns name patterns into the indices CMA-ES leaves at their start values; a
    pattern that matches nothing is refused, naming the option."""
    import bladelab.predict.reflex.named_runs as named
    from bladelab.predict.reflex.optimize import runner_and_layout

    seen = {}
    monkeypatch.setattr(named, "optimize_seeds", lambda model, **kw: seen.update(kw) or [
        types.SimpleNamespace(best_cost=1.0, to_dict=dict)])
    assert main(["predict", "--method", "reflex", "--model", "able",
                 "--hold", "*-pelvis_tx.*, S11100.iliopsoas_l-hamstrings.KL",
                 "--out", str(tmp_path)]) == 0
    names = runner_and_layout("able", None, "seed001")[1].names
    held = [names[i] for i in seen["fixed"]]
    # both legs' placement rows: a gain and an offset each, in stance and swing
    placement = [n for n in names if n.count(".") == 2 and n.split(".")[1].endswith("-pelvis_tx")]
    assert len(placement) == 24 and set(placement) < set(held)
    assert sorted(set(held) - set(placement)) == ["S11100.iliopsoas_l-hamstrings.KL"]
    seen.clear()
    assert main(["predict", "--method", "reflex", "--out", str(tmp_path)]) == 0
    assert "fixed" not in seen  # nothing held unless asked
    capsys.readouterr()
    assert main(["predict", "--method", "reflex", "--hold", "*-pelvis_ty.*",
                 "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "--hold" in err and "'*-pelvis_ty.*'" in err


def test_predict_reflex_defaults_are_the_settings_defaults(tmp_path, monkeypatch, capsys):
    import bladelab.predict.reflex.named_runs as named
    from bladelab.predict.reflex.objective import ObjectiveSettings

    seen = {}
    monkeypatch.setattr(named, "optimize_seeds", lambda model, **kw: seen.update(kw) or [
        types.SimpleNamespace(best_cost=1.0, to_dict=dict)])
    assert main(["predict", "--method", "reflex", "--out", str(tmp_path)]) == 0
    assert seen["settings"] == ObjectiveSettings()
    assert (seen["generations"], seen["popsize"], seen["sigma"], seen["checkpoint_every"],
            seen["blade"], seen["seeds"]) == (100, 16, 1.0, 5, "Cat6", [1])


def test_predict_collocation_passes_the_same_settings(tmp_path, monkeypatch, capsys):
    import bladelab.predict.collocation.named_runs as named
    from bladelab.predict.collocation.settings import CollocationSettings
    from bladelab.predict.defaults import ATHLETE_STARTS, SWING_KNEE_MIN_DEG

    seen = {}

    def solve(out, runner, settings, make_guess, **kw):
        seen.update(out=out, runner=runner, settings=settings, **kw)
        raise _Called

    monkeypatch.setattr(named, "runner_from_spec", lambda spec: ("runner", spec))
    monkeypatch.setattr(named, "predict_stride_in_folder", solve)
    with pytest.raises(_Called):
        main(["predict", "--method", "collocation", "--model", "transfemoral", "--speed", "4",
              "--mesh", "8", "--max-iter", "7", "--swing-clearance", "0.02",
              "--knee-moment-min", "0", "--knee-flexion-max", "10", "--tilt-range=-16,-2",
              "--alternating-steps", "0.1", "--prosthetic-load-max", "3", "--resume",
              "--out", str(tmp_path)])
    # the human body's default: people's angles; no swing knee on the transfemoral runner
    people = {"reference": "people", "reference_weight": 10.0}
    assert seen["settings"] == CollocationSettings(
        mesh_intervals=8, speed_m_per_s=4.0, max_iter=7, swing_clearance_m=0.02,
        knee_moment_min_nm=0.0, knee_flexion_max_loaded_deg=10.0,
        pelvis_tilt_range_deg=(-16.0, -2.0), step_phase_tolerance=0.1,
        prosthetic_load_max_bw=3.0, **people)
    assert seen["model_spec"] == {"model": "transfemoral", "blade": "Cat4", "body": "human"}
    assert seen["runner"] == ("runner", seen["model_spec"])
    assert (seen["out"], seen["resume"], seen["force"]) == (tmp_path, True, False)
    seen.clear()
    # the able runner: people's angles and people's swing knee
    people |= {"swing_knee_min_deg": SWING_KNEE_MIN_DEG}
    with pytest.raises(_Called):
        main(["predict", "--method", "collocation", "--max-speed", "--out", str(tmp_path)])
    assert seen["settings"] == CollocationSettings(speed_m_per_s=None, **people)
    assert seen["model_spec"] == {"model": "able", "blade": None, "body": "human"}
    seen.clear()
    with pytest.raises(_Called):  # without --method: collocation on the human body
        main(["predict", "--out", str(tmp_path)])
    assert seen["settings"] == CollocationSettings(**people)
    assert seen["model_spec"] == {"model": "able", "blade": None, "body": "human"}
    free_knee = {"reference": "people", "reference_weight": 10.0}
    for args, term in ((["--people-weight", "0", "--swing-knee", "0"], {}),  # free
                       (["--people-weight", "20"], {**people, "reference_weight": 20.0}),
                       (["--swing-knee", "0"], free_knee),
                       (["--swing-knee", "95"], {**people, "swing_knee_min_deg": 95.0}),
                       (["--body", "seed001"], {})):  # the seed's body: as the seed solved it
        seen.clear()
        with pytest.raises(_Called):
            main(["predict", "--out", str(tmp_path), *args])
        assert seen["settings"] == CollocationSettings(**term), args
    seen.clear()

    def from_starts(out, runner, settings, make_guess, template_guess, **kw):
        seen.update(out=out, settings=settings, **kw)
        raise _Called

    monkeypatch.setattr(named, "predict_stride_from_starts", from_starts)
    with pytest.raises(_Called):  # the athlete is part of the model; two starts by default
        main(["predict", "--out", str(tmp_path), "--model", "amputee", "--body-mass", "68",
              "--height", "1.75", "--muscle-strength", "1.3", "--max-shortening-velocity",
              "12.5", "--residual-limb", "0.2", "--prosthesis-extra-length", "0.05"])
    assert seen["model_spec"]["athlete"] == {"body_mass_kg": 68.0, "height_m": 1.75,
                                             "muscle_strength": 1.3,
                                             "max_shortening_velocity": 12.5,
                                             "residual_limb_length_m": 0.2,
                                             "prosthesis_extra_length_m": 0.05}
    assert seen["starts"] == ATHLETE_STARTS == 2
    # a static trial gives the thighs and shanks (both sides' mean); an option wins over it
    from bladelab.datasets import measured_static_trial

    seen.clear()
    with pytest.raises(_Called):
        main(["predict", "--out", str(tmp_path), "--static", str(measured_static_trial()),
              "--shank-length", "0.44"])
    athlete = seen["model_spec"]["athlete"]
    assert athlete["shank_length_m"] == 0.44
    assert athlete["thigh_length_m"] == pytest.approx((0.4653 + 0.4574) / 2, abs=2e-4)
    for args, starts in ((["--body-mass", "68", "--starts", "1"], None),
                         (["--starts", "3"], 3)):
        seen.clear()
        with pytest.raises(_Called):
            main(["predict", "--out", str(tmp_path), "--model", "amputee", *args])
        assert seen.get("starts") == starts, args  # None: the one-start folder solve
    assert main(["predict", "--out", str(tmp_path), "--starts", "9"]) == 2
    assert "--starts: need 1 to 4 starts" in capsys.readouterr().err


def test_sweep_collocation_passes_the_same_settings(tmp_path, monkeypatch, capsys):
    import bladelab.predict.collocation.named_runs as named
    from bladelab.predict.collocation.settings import CollocationSettings
    from bladelab.predict.collocation.starting_guess import make_guess
    from bladelab.predict.defaults import SWING_KNEE_MIN_DEG

    seen = {}

    def sweep(models, speeds, settings, guess, **kw):
        seen.update(models=models, speeds=speeds, settings=settings, guess=guess, **kw)
        raise _Called

    monkeypatch.setattr(named, "collocation_sweep", sweep)
    with pytest.raises(_Called):
        main(["sweep", "--method", "collocation", "--able", "--categories", "Cat5,Cat6",
              "--speeds", "3.5,4", "--mesh", "12", "--max-iter", "9", "--starts", "2",
              "--jobs", "2", "--out", str(tmp_path)])
    assert [m.get("blade") for m in seen["models"]] == [None, "Cat5", "Cat6"]
    assert seen["speeds"] == [3.5, 4.0]
    assert seen["settings"] == CollocationSettings(mesh_intervals=12, speed_m_per_s=3.5,
                                                   max_iter=9, reference="people",
                                                   reference_weight=10.0,
                                                   swing_knee_min_deg=SWING_KNEE_MIN_DEG)
    assert isinstance(seen["guess"], functools.partial) and seen["guess"].func is make_guess
    assert seen["guess"].keywords == {"guess": "stored"}  # the default guess
    assert (seen["jobs"], seen["executor"], seen["starts"], seen["resume"], seen["force"]) == (
        2, "local", 2, False, False)
    seen.clear()
    with pytest.raises(_Called):
        main(["sweep", "--method", "collocation", "--able", "--categories", "",
              "--people-weight", "0", "--swing-knee", "0", "--out", str(tmp_path)])
    assert seen["settings"].reference_weight == 0.0 and seen["settings"].reference is None
    assert seen["settings"].swing_knee_min_deg is None
    assert "athlete" not in seen["models"][0]
    seen.clear()
    with pytest.raises(_Called):
        main(["sweep", "--method", "collocation", "--able", "--categories", "Cat6",
              "--muscle-strength", "1.5", "--out", str(tmp_path)])
    assert [m["athlete"] for m in seen["models"]] == [{"muscle_strength": 1.5}] * 2
    assert seen["settings"].step_phase_tolerance is None  # free unless asked
    seen.clear()
    with pytest.raises(_Called):
        main(["sweep", "--method", "collocation", "--categories", "Cat6",
              "--alternating-steps", "0.1", "--out", str(tmp_path)])
    assert seen["settings"].step_phase_tolerance == 0.1
    assert not seen["settings"].stride_time_people  # free unless asked
    seen.clear()
    with pytest.raises(_Called):
        main(["sweep", "--method", "collocation", "--categories", "Cat6", "--speeds", "4,5",
              "--stride-time", "people", "--out", str(tmp_path)])
    assert seen["settings"].stride_time_people
    assert seen["settings"].period_bounds_s == pytest.approx((0.6182, 0.7591), abs=1e-4)
    capsys.readouterr()
    assert main(["sweep", "--method", "collocation", "--categories", "Cat6",
                 "--alternating-steps", "0.5", "--out", str(tmp_path)]) == 2
    assert "--alternating-steps" in capsys.readouterr().err


def test_sweep_reflex_grid_passes_the_same_values(tmp_path, monkeypatch, capsys):
    import bladelab.cli.reflex as reflex

    seen = {}

    def run_sweep(categories, speeds, **kw):
        seen.update(categories=categories, speeds=speeds, **kw)
        return types.SimpleNamespace(to_string=lambda index: "table")

    monkeypatch.setattr(reflex, "run_sweep", run_sweep)
    assert main(["sweep", "--categories", "Cat6", "--speeds", "3.5,4", "--generations", "2",
                 "--seed", "3", "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.strip() == "table"
    assert seen == dict(categories=["Cat6"], speeds=[3.5, 4.0], out=tmp_path, init=None,
                        generations=2, popsize=16, sigma=1.0, seed=3, jobs=1,
                        executor="local", duration=10.0, dt=2.5e-4, robust_samples=1,
                        robust_jitter=1e-6, initial_speed=None, checkpoint_every=5,
                        chain_from=None)


# -- the moved library functions --------------------------------------------------------------
def test_evaluator_settings_give_the_evaluators_options(tmp_path):
    from bladelab.design import make_evaluator
    from bladelab.design.settings import EvaluatorSettings, build_evaluator
    from bladelab.design.space import default_design_space
    from bladelab.errors import SpecError

    space = default_design_space()
    blade = EvaluatorSettings()
    assert blade.options(space, tmp_path) == {"generator": {"base": "xtreme"}}
    # the blade evaluator's own 76 kg: the same evaluator.json as with the mass given
    assert (build_evaluator(blade, space, tmp_path).to_dict()
            == make_evaluator("blade", generator={"base": "xtreme"},
                              body_mass_kg=76.0).to_dict())
    runner = EvaluatorSettings(kind="runner", body_mass_kg=70.0, dt_s=4e-5, speed_mps=6.0)
    assert runner.options(space, tmp_path) == {"generator": {"base": "xtreme"},
                                               "body_mass_kg": 70.0, "dt": 4e-5,
                                               "speed_mps": 6.0}
    coll = EvaluatorSettings(kind="collocation", knee_moment_min_Nm=0.0, reference_weight=10.0)
    opts = coll.options(space, tmp_path)
    assert opts["solutions_dir"] == str(tmp_path / "strides")
    assert opts["factor_ranges"]["stiffness_kN_per_m"] == (18.0, 32.0)
    assert opts["knee_moment_min_Nm"] == 0.0 and opts["reference_weight"] == 10.0
    assert "athlete" not in opts and "start" not in opts and "mesh_intervals" not in opts
    # the athlete: the body mass joins the other fields; the mesh of every design's stride
    athlete = EvaluatorSettings(kind="collocation", body_mass_kg=70.0,
                                athlete={"height_m": 1.75}, mesh_intervals=100)
    opts = athlete.options(space, tmp_path)
    assert opts["athlete"] == {"height_m": 1.75, "body_mass_kg": 70.0}
    assert opts["mesh_intervals"] == 100 and "body_mass_kg" not in opts
    for kind, field, value in (("blade", "athlete", {"height_m": 1.75}),
                               ("runner", "mesh_intervals", 100),
                               ("blade", "start", "x.json"), ("blade", "gait", "x.csv")):
        with pytest.raises(SpecError) as err:
            EvaluatorSettings(kind=kind, **{field: value})
        assert err.value.where == field
    with pytest.raises(SpecError, match="unknown evaluator"):
        EvaluatorSettings(kind="fem")


def test_starting_guess_names(tmp_path, monkeypatch):
    from bladelab.errors import InputFileError, SpecError
    from bladelab.predict.collocation.starting_guess import guess_file_kind, resolve_guess

    assert resolve_guess("template") == "template" and resolve_guess("trial") == "trial"
    with pytest.raises(SpecError) as err:
        resolve_guess(str(tmp_path / "none.json"), where="--guess")
    assert err.value.where == "--guess"
    reflex = tmp_path / "best.json"
    reflex.write_text(json.dumps({"parameters": {"a": 1.0}}))
    monkeypatch.chdir(tmp_path)
    assert resolve_guess("best.json") == str(reflex.resolve())  # workers may start elsewhere
    assert guess_file_kind(reflex) == "reflex"
    stride = tmp_path / "solution.json"
    stride.write_text(json.dumps({"kind": "collocation-solution"}))
    assert guess_file_kind(stride) == "collocation"
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"kind": "something"}))
    with pytest.raises(InputFileError, match="not a collocation solution"):
        guess_file_kind(other)


def test_a_runner_without_a_prosthetic_knee_refuses_knee_settings(tmp_path):
    from bladelab.errors import SpecError
    from bladelab.predict.collocation.named_runs import solve_named_stride, sweep_named_models
    from bladelab.predict.collocation.settings import CollocationSettings

    with pytest.raises(SpecError) as err:
        solve_named_stride(tmp_path / "x", model="amputee",
                           settings=CollocationSettings(knee_flexion_max_loaded_deg=5.0))
    assert err.value.where == "knee_flexion_max_loaded_deg"
    with pytest.raises(SpecError) as err:
        solve_named_stride(tmp_path / "x", model="robot")
    assert err.value.where == "model"
    with pytest.raises(SpecError) as err:
        sweep_named_models(tmp_path / "x", categories=["Cat6"], speeds=[])
    assert err.value.where == "speeds"
    assert not (tmp_path / "x").exists()


def test_reflex_run_checks_and_recipes():
    from bladelab.errors import SpecError
    from bladelab.predict.reflex.named_runs import (
        check_run_settings,
        named_recipe,
        optimize_named,
    )
    from bladelab.predict.reflex.recipe import STABLE_GAIT_RECIPE

    for field, value in (("dt", 3e-3), ("robust_samples", 0), ("robust_jitter", 0.2),
                         ("integrator", "rk4"), ("w_lean", -1.0), ("strike_limit_bw", -0.1),
                         ("duration", 0.0), ("speed", -1.0)):
        with pytest.raises(SpecError) as err:
            check_run_settings(**{field: value})
        assert err.value.where == field
    check_run_settings(dt=1e-3, integrator="newmark")
    assert named_recipe("stable-gait") is STABLE_GAIT_RECIPE
    with pytest.raises(SpecError) as err:
        named_recipe("fastest")
    assert err.value.where == "recipe"
    with pytest.raises(SpecError) as err:
        optimize_named("transfemoral", out="x")
    assert err.value.where == "model"


def test_a_design_study_is_run_again_only_when_a_stride_changed(monkeypatch):
    import bladelab.design.settling as settling

    runs, outcomes = [], iter([True, False])
    monkeypatch.setattr(settling, "run_design", lambda space, **kw: runs.append(kw) or len(runs))

    def settle(evaluator, result, *, passes, jobs, progress):
        progress(f"pass over result {result}")
        changed = next(outcomes)
        return settling.SettlingOutcome(changed, not changed, 1, 0.0)

    monkeypatch.setattr(settling, "settle_study", settle)
    lines = []
    result, outcome = settling.run_settled_design("space", evaluator="ev", out_dir="o",
                                                  settle_passes=1, progress=lines.append,
                                                  seed=3)
    assert result == 2 and outcome.changed and lines == ["pass over result 1"]
    assert runs == [dict(evaluator="ev", out_dir="o", jobs=1, seed=3)] * 2
    result, outcome = settling.run_settled_design("space", evaluator="ev", out_dir="o",
                                                  settle_passes=1, progress=lines.append)
    assert result == 3 and not outcome.changed and len(runs) == 3
    assert settling.run_settled_design("space", evaluator="ev", out_dir="o")[1] is None


def test_the_blade_test_result_is_json_ready():
    from bladelab.design.blade_test import virtual_blade_test
    from bladelab.errors import SpecError

    result = virtual_blade_test("xtreme", alignments_deg=(0.0,), max_displacement_m=0.01)
    assert result.tip == "free" and result.tip_freed  # one compliant joint: the tip is freed
    data = result.to_dict()
    assert data["tests"][0]["stiffness_at_load_N_per_m"] is None  # load not reached
    assert data["body_mass_kg"] == 76.0
    with pytest.raises(SpecError) as err:
        virtual_blade_test("xtreme", body_mass_kg=0.0)
    assert err.value.where == "body_mass_kg"


def test_the_defaults_modules_load_nothing_heavy():
    code = ("import sys, bladelab.predict.defaults, bladelab.design.defaults; "
            "print([m for m in ('numpy', 'pandas', 'scipy', 'numba', 'mujoco', 'casadi') "
            "if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120).stdout
    assert out.strip() == "[]"
