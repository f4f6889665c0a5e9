"""Category sweeps: tables, warm-start chain, resuming (read back / checkpoint), settings
checks, wall time of an optimisation, CLI, Ray = local."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import bladelab.predict.reflex.optimize as predict
from bladelab.cli import main
from bladelab.errors import SpecError
from bladelab.predict.reflex.controller import read_parameters
from bladelab.predict.reflex.objective import ObjectiveSettings, simulate_controlled
from bladelab.predict.reflex.optimize import load_checkpoint, optimize_controller, runner_and_layout
from bladelab.predict.reflex.sweep import run_sweep, summarise
from bladelab.runner.analyses import spatiotemporal
from processes import alive, descendants

SHIPPED_AMPUTEE = (Path(__file__).resolve().parents[1] / "src" / "bladelab" / "data" / "runner"
                   / "reflex-starts" / "amputee-Cat6-3.5.json")
TINY = {"generations": 3, "popsize": 4, "duration": 0.3, "checkpoint_every": 1}


def _sweep(out, categories=("Cat6",), speeds=(3.5, 4.0), **kw):
    args = {**TINY, **kw}
    return run_sweep(list(categories), list(speeds), out=out, progress=False, **args)


class _Interrupt(BaseException):
    """Stands for Ctrl-C / a killed job (not an Exception: executors do not catch it)."""


def _counting(monkeypatch, stop_at: int | None = None) -> list[int]:
    """Count calls of the candidate evaluation (one per generation with one job); raise
    _Interrupt on call ``stop_at``."""
    calls = [0]
    real = predict.evaluate_candidates

    def wrapped(payload):
        calls[0] += 1
        if stop_at is not None and calls[0] == stop_at:
            raise _Interrupt
        return real(payload)

    monkeypatch.setattr(predict, "evaluate_candidates", wrapped)
    return calls


def _without_time(df: pd.DataFrame) -> pd.DataFrame:
    return df.drop(columns=[c for c in df.columns if c in ("wall_time_s", "elapsed_s")])


def test_resume_equals_not_stopping_and_finished_cells_are_read_back(tmp_path, monkeypatch):
    # from the amputee reflex start: a gait whose stances complete within the 0.3 s
    init = {"init": SHIPPED_AMPUTEE}
    full = _sweep(tmp_path / "full", **init)
    full_res = pd.read_csv(tmp_path / "full" / "results.csv")
    assert full_res.speed.tolist() == [3.5, 4.0]  # 0.3 s: both cells run, the chain goes on
    # interrupted in the 4 m/s cell's 2nd generation (before it: the 3.5 m/s cell's warm start
    # and 3 generations, the 4 m/s cell's warm start and 1st generation)
    calls = _counting(monkeypatch, stop_at=7)
    with pytest.raises(_Interrupt):
        _sweep(tmp_path / "part", **init)
    # the finished 3.5 m/s cell is already in the tables
    part = pd.read_csv(tmp_path / "part" / "results.csv")
    assert part.speed.tolist() == [3.5]
    assert json.loads((tmp_path / "part" / "Cat6" / "4" / "cell.json").read_text())[
        "status"
    ] == "running"
    calls = _counting(monkeypatch)
    resumed = _sweep(tmp_path / "part", **init)
    # 3.5 m/s read back (0 generations), 4 m/s resumed from its generation-1 checkpoint (2)
    assert calls[0] == 2
    pd.testing.assert_frame_equal(resumed, full)
    got = pd.read_csv(tmp_path / "part" / "results.csv")
    pd.testing.assert_frame_equal(_without_time(got), _without_time(full_res))
    for speed in ("3.5", "4"):
        a = tmp_path / "full" / "Cat6" / speed
        b = tmp_path / "part" / "Cat6" / speed
        pa = json.loads((a / "best.json").read_text())["parameters"]
        pb = json.loads((b / "best.json").read_text())["parameters"]
        assert pa == pb
        ha = pd.read_csv(a / "history.csv")
        hb = pd.read_csv(b / "history.csv")
        pd.testing.assert_frame_equal(_without_time(ha), _without_time(hb))
    # a finished sweep run again evaluates nothing and gives the same tables
    calls = _counting(monkeypatch)
    again = _sweep(tmp_path / "part", **init)
    assert calls[0] == 0
    pd.testing.assert_frame_equal(again, full)
    # the summary's contact times are those of the maximum-speed solution, re-simulated
    top = full_res.loc[full_res.mean_speed.idxmax()]
    cell = tmp_path / "full" / "Cat6" / f"{top.speed:g}"
    model, layout = runner_and_layout("amputee", "Cat6")
    x = read_parameters(cell / "best.json", layout)
    # every cell starts from the first speed's state (seed 001 §2.2.2)
    settings = ObjectiveSettings(speed=top.speed, duration=0.3, initial_speed=3.5)
    _, res = simulate_controlled(model, x, layout=layout, settings=settings, record_every=2)
    st = spatiotemporal(res)
    # both legs' (a leg without a complete stance in the 0.3 s is NaN on both sides), and at
    # least one complete stance
    wanted = []
    for leg in ("intact", "prosthetic"):
        want = st.value[(st.leg == leg) & (st.variable == "contact_time")].iloc[0]
        got = full[f"contact_time_{leg}"].iloc[0]
        assert got == pytest.approx(want, rel=1e-12, nan_ok=True), leg
        wanted.append(want)
    assert any(0.05 < w < 0.4 for w in wanted), wanted


def test_changed_settings_are_refused_naming_cell_and_setting(tmp_path, capsys):
    _sweep(tmp_path / "s", speeds=(3.5,), generations=1)
    for kw, option in (
        ({"generations": 2}, "--generations"),
        ({"generations": 1, "popsize": 6}, "--popsize"),
        ({"generations": 1, "seed": 2}, "--seed"),
        ({"generations": 1, "sigma": 0.2}, "--sigma"),
        ({"generations": 1, "initial_speed": 4.0}, "--initial-speed"),
        ({"generations": 1, "duration": 0.4}, "--duration"),
        ({"generations": 1, "robust_samples": 2}, "--robust-samples"),
    ):
        with pytest.raises(SpecError, match=f"Cat6 at 3.5 m/s.*{option}"):
            _sweep(tmp_path / "s", speeds=(3.5,), **kw)
    # --sigma reaches the cell's CMA-ES (its step after the first generation stays near it)
    _sweep(tmp_path / "small", speeds=(3.5,), generations=1, sigma=0.05)
    steps = [pd.read_csv(tmp_path / f / "Cat6" / "3.5" / "history.csv").sigma.iloc[0]
             for f in ("s", "small")]
    assert 0.5 < steps[0] < 2.0 and 0.025 < steps[1] < 0.1
    # another initial guess
    _, layout = runner_and_layout("amputee", "Cat6")
    init = tmp_path / "init.json"
    init.write_text(json.dumps({"model": "amputee", "parameters": {layout.names[0]: 0.3}}))
    code = main(
        ["sweep", "--categories", "Cat6", "--speeds", "3.5", "--generations", "1",
         "--popsize", "4", "--duration", "0.3", "--checkpoint-every", "1",
         "--init", str(init), "--out", str(tmp_path / "s")]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert "Cat6 at 3.5 m/s" in err and "initial guess" in err
    assert err.count("error:") == 1 and "Traceback" not in err
    code = main(["sweep", "--categories", "Cat6", "--generations", "5", "--out",
                 str(tmp_path / "s")])
    assert code == 2
    assert "--generations 1 there, 5 now" in capsys.readouterr().err


def test_wall_time_is_recorded_and_accumulates_across_resume(tmp_path):
    settings = ObjectiveSettings(duration=0.3)
    args = {"popsize": 4, "seed": 3, "settings": settings, "checkpoint_every": 1}
    part = optimize_controller("able", generations=1, out=tmp_path, **args)
    first = json.loads((tmp_path / "best.json").read_text())["wall_time_s"]
    assert first > 0 and first == pytest.approx(part.wall_time_s)
    resumed = optimize_controller("able", generations=3, out=tmp_path, resume=True, **args)
    hist = pd.read_csv(tmp_path / "history.csv")
    assert list(hist.columns) == ["generation", "evaluations", "best", "median", "sigma",
                                  "elapsed_s"]
    assert hist.elapsed_s.iloc[0] == pytest.approx(first)
    assert np.all(np.diff(hist.elapsed_s) > 0)
    best = json.loads((tmp_path / "best.json").read_text())
    assert best["wall_time_s"] == pytest.approx(hist.elapsed_s.iloc[-1])
    assert resumed.wall_time_s == pytest.approx(best["wall_time_s"]) and resumed.wall_time_s > first
    ckpt = load_checkpoint(tmp_path / "checkpoint.pkl")
    assert ckpt["elapsed_s"] == pytest.approx(best["wall_time_s"])
    assert len(resumed.history[0]) == 5  # history tuples hold no time
    # a checkpoint written before wall time was recorded resumes with unknown (NaN) times
    import pickle

    del ckpt["elapsed"], ckpt["elapsed_s"]
    (tmp_path / "checkpoint.pkl").write_bytes(pickle.dumps(ckpt, protocol=4))
    old = optimize_controller("able", generations=4, out=tmp_path, resume=True, **args)
    assert old.history[:3] == resumed.history and np.isnan(old.wall_time_s)
    assert pd.read_csv(tmp_path / "history.csv").elapsed_s.isna().all()
    assert json.loads((tmp_path / "best.json").read_text())["wall_time_s"] is None


def test_summary_by_hand():
    res = pd.DataFrame(
        {
            "category": ["Cat6"] * 3 + ["Cat4"],
            "speed": [3.5, 4.0, 4.5, 3.5],
            "fell": [False, False, True, True],
            "mean_speed": [3.52, 4.05, 2.0, 1.0],
            "j_cot": [5.0, 6.9, 9.0, 9.0],
            "contact_time_intact": [0.2, 0.17, 0.1, 0.3],
            "contact_time_prosthetic": [0.19, 0.15, 0.1, 0.3],
        }
    )
    s = summarise(res)
    six = s[s.category == "Cat6"].iloc[0]
    assert six.max_speed == pytest.approx(4.05) and six.cot_4 == pytest.approx(6.9)
    assert six.t200 == pytest.approx(200 / 4.05) and six.t400 == pytest.approx(400 / 4.05)
    assert six.contact_time_intact == 0.17 and six.contact_time_prosthetic == 0.15
    four = s[s.category == "Cat4"].iloc[0]  # nothing ran
    assert np.isnan(four.max_speed) and np.isnan(four.t200) and np.isnan(four.cot_4)


def test_progress_counts_the_cells_a_fall_makes_unneeded():
    from bladelab.predict.reflex.sweep import _cells_settled

    speeds = [3.5, 4.0, 4.5, 5.0]
    done = [
        {"category": "Cat7", "speed": 3.5, "fell": True},  # its chain ends: 3 cells unneeded
        {"category": "Cat6", "speed": 3.5, "fell": False},
        {"category": "Cat6", "speed": 4.0, "fell": True},  # 2 unneeded
        {"category": "Cat5", "speed": 3.5, "fell": False},
    ]
    assert _cells_settled(done, speeds) == 4 + 3 + 2
    assert _cells_settled([], speeds) == 0


def test_chain_warm_starts_neighbours(tmp_path):
    _sweep(tmp_path, categories=("Cat4", "Cat5", "Cat6"), speeds=(3.5,), generations=1,
           chain_from="Cat6")
    for child, parent in (("Cat5", "Cat6"), ("Cat4", "Cat5")):
        _, layout = runner_and_layout("amputee", child)
        x_parent = read_parameters(tmp_path / parent / "3.5" / "best.json", layout)
        es = load_checkpoint(tmp_path / child / "3.5" / "checkpoint.pkl")["es"]
        np.testing.assert_allclose(es.x0, x_parent)
    with pytest.raises(Exception, match="chain-from"):
        _sweep(tmp_path / "x", categories=("Cat4",), chain_from="Cat7")


def test_cli_sweep(tmp_path, capsys):
    assert main(["sweep", "--categories", "Cat9", "--out", str(tmp_path / "s")]) == 2
    assert "Cat9" in capsys.readouterr().err
    assert main(["sweep", "--robust-samples", "0", "--out", str(tmp_path / "s")]) == 2
    assert "--robust-samples" in capsys.readouterr().err
    assert not (tmp_path / "s").exists()
    code = main(
        ["sweep", "--categories", "Cat6", "--speeds", "3.5", "--generations", "1",
         "--popsize", "2", "--duration", "0.3", "--robust-samples", "2",
         "--robust-jitter", "1e-5", "--out", str(tmp_path / "sw")]
    )
    assert code == 0
    summary = pd.read_csv(tmp_path / "sw" / "summary.csv")
    assert summary.category.tolist() == ["Cat6"]
    assert "contact_time_prosthetic" in summary.columns
    cell = json.loads((tmp_path / "sw" / "Cat6" / "3.5" / "cell.json").read_text())
    assert cell["settings"]["robust_samples"] == 2
    assert cell["settings"]["robust_jitter"] == 1e-5
    assert cell["result"]["evaluations"] == 1 + 2  # the warm start, then a generation of 2


def test_sweep_on_ray_matches_local(tmp_path, ray_instance):
    kw = {"categories": ("Cat4", "Cat6"), "speeds": (3.5,), "generations": 2}
    local = _sweep(tmp_path / "local", **kw)
    ray = _sweep(tmp_path / "ray", jobs=2, executor="ray", **kw)
    pd.testing.assert_frame_equal(local, ray)
    a = pd.read_csv(tmp_path / "local" / "results.csv")
    b = pd.read_csv(tmp_path / "ray" / "results.csv")
    pd.testing.assert_frame_equal(_without_time(a), _without_time(b))



@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_sigterm_stops_the_sweep_and_its_workers(tmp_path):
    # a killed sweep (SIGTERM, as `kill` or a job scheduler sends) exits 143 and leaves no
    # worker running: orphaned workers used to go on writing into the output folder
    out = tmp_path / "sw"
    cmd = [sys.executable, "-c", "import sys; from bladelab.cli import main; sys.exit(main())",
           "sweep", "--categories", "Cat5,Cat6", "--speeds", "3.5", "--generations", "500",
           "--popsize", "4", "--duration", "3", "--checkpoint-every", "1", "--jobs", "2",
           "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    workers: set[int] = set()
    try:
        deadline = time.monotonic() + 180
        while time.monotonic() < deadline and proc.poll() is None:
            if len(list(out.glob("*/3.5/checkpoint.pkl"))) == 2:
                break  # both category tasks are optimising in their workers
            time.sleep(0.2)
        assert proc.poll() is None, proc.communicate()
        workers = descendants(proc.pid)
        assert len(workers) >= 2
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 143 and "terminated" in err
        time.sleep(1.0)
        assert not [p for p in workers if alive(p)]
    finally:  # never leave a process behind, even when the test fails
        for pid in [proc.pid, *workers]:
            if alive(pid):
                os.kill(pid, signal.SIGKILL)
        proc.communicate()


def test_a_broken_cell_file_is_named_with_its_line_and_a_hint(tmp_path):
    from bladelab.errors import InputFileError
    from bladelab.predict.reflex.sweep import CELL_NAME, _read_cell

    (tmp_path / CELL_NAME).write_text('{"format": 1,\n "settings": {"sigma": }\n}\n')
    with pytest.raises(InputFileError, match=r"not valid JSON: .* line 2") as err:
        _read_cell(tmp_path, "Cat6", 3.5, {})
    assert CELL_NAME in str(err.value) and "recompute the cell" in str(err.value)
    (tmp_path / CELL_NAME).write_text('{"format": 1}\n')
    with pytest.raises(InputFileError, match="sweep cell Cat6 at 3.5 m/s has no settings"):
        _read_cell(tmp_path, "Cat6", 3.5, {})
