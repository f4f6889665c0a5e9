"""The node function compiled to C: the same numbers, the cache's keys and files, two processes
at once, and the fallback when no compiler works."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.compiled import (
    CACHE_ENV,
    CompileWarning,
    cache_dir,
    compiled_node,
)
from bladelab.predict.collocation.dynamics import stride_dynamics
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.transcription import StrideNLP
from bladelab.runner import build_runner


@pytest.fixture()
def cache(tmp_path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv(CACHE_ENV, str(folder))
    return folder


def _tiny(scale: float = 2.0) -> ca.Function:
    """A small SX function (compiles in a fraction of a second)."""
    x, u = ca.SX.sym("x", 3), ca.SX.sym("u", 2)
    return ca.Function("node", [x, u], [ca.sin(x) * scale + ca.vertcat(u, u[0] * u[1]),
                                        ca.sumsqr(x) * u[1]])


def _libraries(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_a_node_is_compiled_once_and_a_changed_one_again(cache):
    first = compiled_node(_tiny())
    assert first is not None
    (lib,) = _libraries(cache)
    stamp = (cache / lib).stat().st_mtime_ns
    assert compiled_node(_tiny()) is not None  # the same graph: read from the cache
    assert _libraries(cache) == [lib] and (cache / lib).stat().st_mtime_ns == stamp
    assert compiled_node(_tiny(3.0)) is not None  # another graph: another library
    assert len(_libraries(cache)) == 2
    x, u = np.array([0.1, -0.4, 0.7]), np.array([0.3, -1.2])
    for got, want in zip(first(x, u), _tiny()(x, u), strict=True):
        np.testing.assert_array_equal(np.asarray(got), np.asarray(want))


def test_a_damaged_library_in_the_cache_is_compiled_again(cache):
    assert compiled_node(_tiny()) is not None
    (lib,) = _libraries(cache)
    (cache / lib).write_bytes(b"not a shared library")
    again = compiled_node(_tiny())
    assert again is not None and _libraries(cache) == [lib]
    x, u = np.array([0.2, 0.1, -0.3]), np.array([1.0, 2.0])
    np.testing.assert_array_equal(np.asarray(again(x, u)[1]), np.asarray(_tiny()(x, u)[1]))


def test_two_processes_compiling_the_same_node_leave_one_valid_library(cache):
    script = textwrap.dedent("""
        import casadi as ca, numpy as np, sys
        from bladelab.predict.collocation.compiled import compiled_node
        x, u = ca.SX.sym("x", 3), ca.SX.sym("u", 2)
        node = ca.Function("node", [x, u], [ca.sin(x) * 2.0 + ca.vertcat(u, u[0] * u[1]),
                                            ca.sumsqr(x) * u[1]])
        f = compiled_node(node)
        out = f(np.array([0.1, -0.4, 0.7]), np.array([0.3, -1.2]))
        want = node(np.array([0.1, -0.4, 0.7]), np.array([0.3, -1.2]))
        sys.exit(0 if all(np.array_equal(np.asarray(a), np.asarray(b))
                          for a, b in zip(out, want)) else 3)
    """)
    env = {**os.environ, CACHE_ENV: str(cache)}
    procs = [subprocess.Popen([sys.executable, "-c", script], env=env) for _ in range(2)]
    assert [p.wait(timeout=300) for p in procs] == [0, 0]
    (lib,) = _libraries(cache)  # one library, no temporary files left
    assert lib.endswith(".so") and not lib.startswith(".")


def test_no_compiler_or_a_failing_one_warns_and_gives_the_interpreted_function(
        tmp_path, cache, monkeypatch):
    empty = tmp_path / "bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))
    with pytest.warns(CompileWarning, match="no C compiler"):
        assert compiled_node(_tiny()) is None
    broken = empty / "cc"  # answers --version, fails on every file
    broken.write_text("#!/bin/sh\n[ \"$1\" = --version ] && echo 'cc 0' && exit 0\n"
                      "echo 'cc: internal error' >&2\nexit 1\n")
    broken.chmod(0o755)
    with pytest.warns(CompileWarning, match="internal error"):
        assert compiled_node(_tiny()) is None
    assert not cache.exists() or _libraries(cache) == []


def test_an_unwritable_cache_folder_falls_back_to_a_temporary_one(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv(CACHE_ENV, str(blocked / "cache"))
    folder = cache_dir()
    assert folder.is_dir() and blocked not in folder.parents


@pytest.fixture(scope="module")
def nlps(tmp_path_factory):
    """The able runner's stride NLP on 6 intervals, interpreted and compiled (one compile of
    the real node function, about 15 s), and a point near the template."""
    folder = tmp_path_factory.mktemp("cache")
    old = os.environ.get(CACHE_ENV)
    os.environ[CACHE_ENV] = str(folder)
    try:
        runner = build_runner("able", body="human")
        dyn = stride_dynamics(build_collocation_model(runner))
        plain = StrideNLP(dyn, n=6, speed=3.5, compiled=False)
        with warnings.catch_warnings():
            warnings.simplefilter("error", CompileWarning)
            fast = StrideNLP(dyn, n=6, speed=3.5, compiled=True)
    finally:
        if old is None:
            os.environ.pop(CACHE_ENV, None)
        else:
            os.environ[CACHE_ENV] = old
    x0 = plain.initial_vector(template_guess(runner, speed=3.5, n=6))
    return plain, fast, x0


def test_the_compiled_nlp_is_the_interpreted_one_to_round_off(nlps):
    plain, fast, x0 = nlps
    assert fast.compiled and not plain.compiled
    assert fast.interpreted() is not fast and not fast.interpreted().compiled
    rng = np.random.default_rng(4)
    for x in (x0, x0 * (1 + 0.01 * rng.standard_normal(x0.size))):
        values = []
        for nlp in (plain, fast):
            f = ca.Function("fg", [nlp.nlp["x"], nlp.nlp["p"]], [nlp.nlp["f"], nlp.nlp["g"],
                                                             ca.jacobian(nlp.nlp["g"],
                                                                         nlp.nlp["x"])])
            values.append([np.asarray(ca.DM(v).full()) for v in f(x, 3.5)])
        for a, b in zip(*values, strict=True):
            scale = np.maximum(np.abs(a), 1.0)
            assert np.max(np.abs(a - b) / scale) <= 1e-12


def test_the_exact_hessian_is_refused_on_the_compiled_nlp(nlps):
    from bladelab.errors import SpecError

    _, fast, x0 = nlps
    with pytest.raises(SpecError, match="interpreted node function"):
        fast.solve(x0, hessian="exact", max_iter=1)
