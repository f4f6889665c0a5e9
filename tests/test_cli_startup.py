"""The command line starts quickly: ``bladelab --help`` and ``bladelab trial info`` import none of
the heavy libraries (numba, MuJoCo, pandas, matplotlib, scipy.signal, CasADi). Each check runs in
a fresh interpreter, since this test session has imported them all already. Timings are measured
in benchmarks/, not here."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

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


def test_trial_info_imports_no_heavy_library(shared_data):
    result = _run(["trial", "info", str(shared_data / "real/fukuchi2017/RBDS001runT35.c3d")])
    assert result["code"] == 0 and "platform 1: type 4" in result["out"]
    assert result["heavy"] == []


def test_cli_defaults_equal_the_library_defaults():
    from bladelab.cli.defaults import RUNNER_DT
    from bladelab.predict.reflex.objective import DEFAULT_PREDICT_DT
    from bladelab.runner.model import DEFAULT_DT

    assert RUNNER_DT == DEFAULT_DT == DEFAULT_PREDICT_DT


def test_cli_track_weight_equals_the_library_default():
    from bladelab.cli.defaults import TRACK_WEIGHT
    from bladelab.predict.reflex.tracking import DEFAULT_WEIGHT

    assert TRACK_WEIGHT == DEFAULT_WEIGHT


def test_cli_collocation_defaults_equal_the_settings_defaults():
    from bladelab.cli.defaults import COLLOCATION_MAX_ITER, COLLOCATION_MESH
    from bladelab.predict.collocation.solve import CollocationSettings

    settings = CollocationSettings()
    assert (COLLOCATION_MESH, COLLOCATION_MAX_ITER) == (settings.mesh_intervals,
                                                        settings.max_iter)
