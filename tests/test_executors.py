"""Executors: results in any order, a failing task named, and an interrupted pool that stops
its workers at once."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from bladelab.executors import LocalExecutor, SerialExecutor, make_executor
from processes import alive, descendants


def _square_or_fail(payload: dict) -> dict:
    if payload["x"] < 0:
        raise ValueError("negative input")
    return {"y": payload["x"] ** 2}


@pytest.mark.parametrize("executor", [SerialExecutor(), LocalExecutor(2)],
                         ids=["serial", "local"])
def test_every_task_reports_once_and_a_failure_does_not_stop_the_others(executor):
    results = {i: (status, value) for i, status, value in
               executor.run(_square_or_fail, [{"x": 3}, {"x": -1}, {"x": 5}])}
    assert results[0] == ("ok", {"y": 9}) and results[2] == ("ok", {"y": 25})
    assert results[1][0] == "failed" and "ValueError: negative input" in results[1][1]


@pytest.mark.parametrize("executor", [SerialExecutor(), LocalExecutor(2)],
                         ids=["serial", "local"])
def test_payloads_appended_while_results_are_read_are_run(executor):
    """A caller hands out work as earlier tasks finish: each result of x < 4 appends x + 1."""
    payloads = [{"x": 0}, {"x": 10}]
    seen = {}
    for i, status, value in executor.run(_square_or_fail, payloads):
        assert status == "ok"
        seen[i] = value["y"]
        x = payloads[i]["x"]
        if x < 4:
            payloads.append({"x": x + 1})
    assert len(payloads) == 6
    assert seen == {i: p["x"] ** 2 for i, p in enumerate(payloads)}


def test_make_executor_is_in_process_for_one_job():
    assert isinstance(make_executor("local", 1), SerialExecutor)
    assert isinstance(make_executor("local", 2), LocalExecutor)


#: A task that waits inside the collocation solve's interrupt guard (which turns SIGTERM into
#: a KeyboardInterrupt), and the parent that runs four of them on two workers.
_TASK = '''
import os, time
from bladelab.predict.collocation.solve import _interrupts_recorded

def guarded_wait(payload):
    open(os.path.join(payload["dir"], "started-%d" % payload["i"]), "w").close()
    with _interrupts_recorded():
        time.sleep(60)
    return {}
'''
_PARENT = '''
import signal, sys
from guarded_task import guarded_wait
from bladelab.executors import LocalExecutor

def stop(signum, frame):
    raise KeyboardInterrupt

if __name__ == "__main__":
    signal.signal(signal.SIGTERM, stop)
    payloads = [{"dir": sys.argv[1], "i": i} for i in range(4)]
    for _ in LocalExecutor(2).run(guarded_wait, payloads):
        pass
'''


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_sigterm_stops_busy_workers_and_starts_no_queued_task(tmp_path):
    # a worker inside a collocation solve turns SIGTERM into a KeyboardInterrupt, which
    # concurrent.futures used to send back as a result before starting the next queued task:
    # the killed parent then waited for whole solves, and they wrote into its output folder
    (tmp_path / "guarded_task.py").write_text(textwrap.dedent(_TASK))
    (tmp_path / "parent.py").write_text(textwrap.dedent(_PARENT))
    out = tmp_path / "out"
    out.mkdir()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}
    proc = subprocess.Popen([sys.executable, str(tmp_path / "parent.py"), str(out)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    workers: set[int] = set()
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and len(list(out.glob("started-*"))) < 2:
            time.sleep(0.1)
        assert proc.poll() is None, proc.communicate()
        workers = descendants(proc.pid)
        time.sleep(0.5)  # both workers are inside the guard
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=20)  # not the 60 s of a queued task
        assert "Exception in thread" not in err  # the pool's manager thread ended quietly
        time.sleep(0.5)
        assert not [p for p in workers if alive(p)]
        assert sorted(f.name for f in out.iterdir()) == ["started-0", "started-1"]
    finally:  # never leave a process behind, even when the test fails
        for pid in [proc.pid, *workers]:
            if alive(pid):
                os.kill(pid, signal.SIGKILL)
        proc.communicate()
