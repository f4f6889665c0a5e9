"""The notice before a numba kernel's first compilation: printed on a cold cache, not on a warm
one, and asked for by every large kernel's caller (blade kernel, runner loop, reflex loop)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

NOTICE = "compiling the tiny kernel (first run after install or update"


class _Stop(Exception):
    """Raised by the recording stand-in so that no kernel is compiled or run."""


@pytest.fixture
def announced(monkeypatch):
    """Replace ``announce_compilation`` where the kernels' callers imported it; records
    (function name, what) and stops the call before the kernel runs."""
    calls: list[tuple[str, str]] = []

    def record(dispatcher, what):
        calls.append((dispatcher.py_func.__name__, what))
        raise _Stop

    import bladelab.predict.reflex.objective as objective
    import bladelab.runner.simulate as runner_simulate
    import bladelab.sim.api as sim_api

    for module in (sim_api, runner_simulate, objective):
        monkeypatch.setattr(module, "announce_compilation", record)
    return calls


def test_notice_on_a_cold_cache_and_not_on_a_warm_one(tmp_path):
    (tmp_path / "tiny.py").write_text(textwrap.dedent("""
        from numba import njit

        @njit(cache=True)
        def add_one(x):
            return x + 1.0
    """))
    script = textwrap.dedent("""
        from bladelab.sim.compilation import announce_compilation
        import tiny
        announce_compilation(tiny.add_one, "the tiny kernel")
        announce_compilation(tiny.add_one, "the tiny kernel")  # once per process
        assert tiny.add_one(1.0) == 2.0
        announce_compilation(tiny.add_one, "the tiny kernel")  # compiled now: silent
    """)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}

    def stderr() -> str:
        return subprocess.run([sys.executable, "-c", script], env=env, cwd=tmp_path,
                              capture_output=True, text=True, check=True, timeout=300).stderr

    cold = stderr()
    assert cold.count(NOTICE) == 1 and cold.strip().endswith("cached afterwards)…")
    assert NOTICE not in stderr()  # the cache written by the first run is loaded


def test_a_stale_cache_is_cold(tmp_path):
    (tmp_path / "tiny2.py").write_text("from numba import njit\n\n\n@njit(cache=True)\n"
                                       "def f(x):\n    return x * 2.0\n")
    script = ("import os, tiny2\nfrom bladelab.sim.compilation import cache_is_cold\n"
              "print(cache_is_cold(tiny2.f))\ntiny2.f(1.0)\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}

    def cold() -> str:
        return subprocess.run([sys.executable, "-c", script], env=env, cwd=tmp_path,
                              capture_output=True, text=True, check=True, timeout=300).stdout
    assert cold().strip() == "True"
    assert cold().strip() == "False"
    # an edited source file (new stamp) makes the cached code stale: numba compiles again
    source = tmp_path / "tiny2.py"
    source.write_text(source.read_text().replace("2.0", "3.0"))
    os.utime(source, (1e9, 1e9))
    assert cold().strip() == "True"


def test_the_blade_kernel_announces_its_compilation(announced):
    from bladelab.blade import load_blade
    from bladelab.sim import prepare, simulate
    from bladelab.sim.synthetic import generate_stance

    blade = load_blade("xtreme").build()
    stance, _ = generate_stance(blade, speed_mps=7.0, body_mass_kg=76.0, sample_rate=1000.0)
    with pytest.raises(_Stop):
        simulate(prepare(blade, stance))
    assert announced == [("simulate_batch_serial", "the blade simulation kernel")]


def test_the_runner_loops_announce_their_compilation(announced):
    from bladelab.predict.reflex.controller import controller_layout
    from bladelab.predict.reflex.objective import simulate_controlled
    from bladelab.runner import build_runner, simulate_runner

    model = build_runner("able")
    with pytest.raises(_Stop):
        simulate_runner(model, duration=0.01)
    with pytest.raises(_Stop):
        simulate_runner(model, duration=0.01, controller=lambda t, state: np.full(len(model.muscle_names), 0.05))
    layout = controller_layout(model)
    with pytest.raises(_Stop):
        simulate_controlled(model, layout.x0, layout=layout)
    assert announced == [
        ("run_loop", "the runner's simulation loop"),
        ("step_forces", "the runner's force functions"),
        ("run_closed_loop", "the reflex controller's simulation loop"),
    ]
