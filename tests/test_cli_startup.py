"""The command line starts quickly: ``bladelab --help`` and ``bladelab trial info`` import none of
the heavy libraries (numba, MuJoCo, pandas, matplotlib, scipy.signal, CasADi). Each check runs in
a fresh interpreter, since this test session has imported them all already. Timings are measured
in benchmarks/, not here."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from conftest import FUKUCHI_RUN

HEAVY = ("numba", "mujoco", "matplotlib", "pandas", "casadi", "scipy.signal")

_PROBE = """
import contextlib, io, json, sys
from bladelab.cli import main
with contextlib.redirect_stdout(io.StringIO()) as out:
    code = main(json.loads(sys.argv[1]))
print(json.dumps({"code": code, "out": out.getvalue(),
                  "heavy": [m for m in json.loads(sys.argv[2]) if m in sys.modules]}))
"""


def _run(args: list[str]) -> dict:
    """Run ``bladelab ARGS`` in a fresh interpreter; its exit code, stdout and heavy imports."""
    proc = subprocess.run(
        [sys.executable, "-c", _PROBE, json.dumps(args), json.dumps(HEAVY)],
        capture_output=True, text=True, timeout=120, check=True,
    )
    return json.loads(proc.stdout.splitlines()[-1])


@pytest.mark.parametrize("args", [["--help"], ["runner", "simulate", "--help"],
                                  ["predict", "--help"], ["design", "--help"]])
def test_help_imports_no_heavy_library(args):
    result = _run(args)
    assert result["code"] == 0 and "Usage" in result["out"]
    assert result["heavy"] == []


def test_trial_info_imports_no_heavy_library():
    result = _run(["trial", "info", str(FUKUCHI_RUN)])
    assert result["code"] == 0 and "platform 1: type 4" in result["out"]
    assert result["heavy"] == []


def test_the_reflex_time_step_is_the_runner_models():
    from bladelab.predict import defaults
    from bladelab.predict.reflex.objective import DEFAULT_PREDICT_DT, ObjectiveSettings
    from bladelab.runner.model import DEFAULT_DT

    assert defaults.TIME_STEP_S == DEFAULT_DT == DEFAULT_PREDICT_DT == ObjectiveSettings().dt


def test_the_cli_shows_the_library_defaults():
    """The option defaults of predict, sweep, design and blade test are the settings objects'
    (one definition each: bladelab.predict.defaults and bladelab.design.defaults)."""
    import typer.main

    from bladelab.cli import app
    from bladelab.design import defaults as dd
    from bladelab.design.evaluators import BladeEvaluator
    from bladelab.predict import defaults as pd
    from bladelab.predict.collocation.settings import CollocationSettings
    from bladelab.predict.reflex.objective import ObjectiveSettings
    from bladelab.predict.reflex.tracking import DEFAULT_WEIGHT

    group = typer.main.get_command(app)

    def default(command: list[str], option: str):
        cmd = group
        for name in command:
            cmd = cmd.commands[name]
        return next(p.default for p in cmd.params if option in p.opts)

    obj, coll = ObjectiveSettings(), CollocationSettings()
    predict = ["predict"]
    assert default(predict, "--speed") == obj.speed == coll.speed_m_per_s == pd.SPEED_M_PER_S
    assert default(predict, "--dt") == obj.dt
    assert default(predict, "--duration") == obj.duration
    assert default(predict, "--robust-jitter") == obj.robust_jitter
    assert default(predict, "--strike-limit") == obj.strike_limit_bw
    assert default(predict, "--lean-weight") == obj.w_lean
    # None: the body's scheme (the library's explicit default on seed 001's body, newmark on the
    # human body, whose toes' dampers the explicit scheme refuses)
    assert default(predict, "--integrator") is None and obj.integrator == pd.INTEGRATOR
    assert default(predict, "--track-weight") == DEFAULT_WEIGHT
    assert default(predict, "--mesh") == coll.mesh_intervals
    assert default(predict, "--max-iter") == coll.max_iter
    assert default(["sweep"], "--mesh") == coll.mesh_intervals
    assert default(["blade", "test"], "--body-mass") == BladeEvaluator().body_mass_kg
    assert default(["blade", "test"], "--max-displacement") == dd.COMPRESSION_MAX_DISPLACEMENT_M


# (command, option, the library function the command calls, its parameter): the CLI's literal
# default must be the library's own, so that the library owns every default the CLI shows.
_CHARACTERISE_DEFAULTS = [
    (["trial", "stances"], "--threshold", "bladelab.trial.events:detect_stances", "threshold"),
    (["trial", "stances"], "--min-duration", "bladelab.trial.events:detect_stances",
     "min_duration"),
    (["trial", "extract"], "--rate", "bladelab.trial.kinematics:extract_stance", "rate"),
    (["trial", "extract"], "--margin", "bladelab.trial.kinematics:extract_stance", "margin"),
    (["trial", "extract"], "--threshold", "bladelab.trial.kinematics:extract_stance",
     "threshold"),
    (["identify"], "--max-evals", "bladelab.identify:identify_stance", "max_evals"),
    (["simulate"], "--dt", "bladelab.sim:prepare", "dt"),
    (["blade", "segment"], "--max-error", "bladelab.blade.segmentation:segment_profile",
     "max_error_mm2_per_mm"),
    (["example", "make"], "--seed", "bladelab.example.study:make_example_study", "seed"),
    (["example", "make"], "--jobs", "bladelab.example.study:make_example_study", "jobs"),
    (["runner", "simulate"], "--duration", "bladelab.runner:simulate_runner", "duration"),
    (["runner", "simulate"], "--speed", "bladelab.runner:simulate_runner", "initial_speed"),
    (["runner", "simulate"], "--initial-state", "bladelab.runner:simulate_runner",
     "initial_state"),
    (["design", "gait-cycle"], "--samples", "bladelab.design.gait_cycle:gait_cycles_from_trial",
     "n"),
    (["design", "gait-cycle"], "--cutoff", "bladelab.design.gait_cycle:gait_cycles_from_trial",
     "cutoff_hz"),
]


@pytest.mark.parametrize(("command", "option", "function", "parameter"), _CHARACTERISE_DEFAULTS,
                         ids=[" ".join(c) + " " + o for c, o, _, _ in _CHARACTERISE_DEFAULTS])
def test_the_other_commands_show_the_library_defaults(command, option, function, parameter):
    import importlib
    import inspect

    import typer.main

    from bladelab.cli import app

    cmd = typer.main.get_command(app)
    for name in command:
        cmd = cmd.commands[name]
    shown = next(p.default for p in cmd.params if option in p.opts)
    module, name = function.split(":")
    library = inspect.signature(getattr(importlib.import_module(module), name)).parameters
    assert shown == library[parameter].default, (
        f"bladelab {' '.join(command)} {option} defaults to {shown!r}, the library's {name}"
        f"({parameter}=...) to {library[parameter].default!r}")


def test_runner_simulate_leaves_the_integrator_to_the_library_s_choice_per_body():
    import typer.main

    from bladelab.cli import app
    from bladelab.runner import build_runner, integrator_for
    from bladelab.runner.model import DEFAULT_DT

    cmd = typer.main.get_command(app).commands["runner"].commands["simulate"]
    assert next(p.default for p in cmd.params if "--integrator" in p.opts) is None
    assert next(p.default for p in cmd.params if "--dt" in p.opts) is None
    assert integrator_for(build_runner("able", body="seed001")) == ("explicit", DEFAULT_DT)
    assert integrator_for(build_runner("able", body="human"))[0] == "newmark"
    assert integrator_for(build_runner("able", body="toes")) == ("explicit", DEFAULT_DT)
