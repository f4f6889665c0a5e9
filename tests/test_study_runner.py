"""Study folder: study.yaml validation, results store, executors, skip/force, failures, seeds."""

from __future__ import annotations

import sqlite3
import textwrap

import numpy as np
import pytest

from bladelab.errors import BladelabError, InputFileError, SpecError
from bladelab.executors import make_executor
from bladelab.identify.optimizers import minimize
from bladelab.study import ResultsStore, load_study, run_study, trial_seed


def fake_task(payload: dict) -> dict:
    """A cheap stand-in for the identification: a seeded PSO on a quadratic from the file."""
    values = np.loadtxt(payload["file"], delimiter=",")
    target = np.array([values.mean(), values.std()])
    res = minimize(lambda X: np.sum((X - target) ** 2, axis=1), [(-10, 10), (0, 10)],
                   seed=payload["seed"], max_evals=60, n_particles=6)
    return {"K_Nm_per_deg": float(res.x[0]), "D_Nms_per_deg": float(res.x[1]),
            "cost": float(res.fun), "evaluations": res.evaluations}


def failing_task(payload: dict) -> dict:
    if payload["trial_id"] == "t2":
        raise ValueError("boom")
    return fake_task(payload)


STUDY = """
name: test study
seed: 7
athletes:
  - {id: TF1, mass_kg: 65, amputation: transfemoral, height_m: 1.80, side: left}
  - {id: TT1, mass_kg: 76, amputation: transtibial}
blades:
  - {id: xceed, blade: xceed-cat2, category: 2}
  - {id: xtreme5, blade: xtreme-cat5, category: 5}
configurations:
  - {id: A, pylon_height_m: 0.75}
  - {id: B, pylon_height_m: 0.95}
trials:
"""


def make_study(tmp_path, n=4, missing=()):
    lines = [STUDY]
    for i in range(n):
        tid = f"t{i}"
        lines.append(f"  - {{id: {tid}, file: trials/{tid}.csv, athlete: TF1, blade: xceed, "
                     f"configuration: A, speed_pct_pb: {60 + 10 * i}}}\n")
        if tid not in missing:
            (tmp_path / "trials").mkdir(exist_ok=True)
            np.savetxt(tmp_path / "trials" / f"{tid}.csv", np.arange(5.0) * (i + 1), delimiter=",")
    (tmp_path / "study.yaml").write_text("".join(lines))
    return tmp_path


def test_load_and_validate(tmp_path):
    study, folder = load_study(make_study(tmp_path))
    assert folder == tmp_path and len(study.trials) == 4
    assert study.athlete("TF1").amputation == "transfemoral"
    bad = (tmp_path / "study.yaml").read_text().replace("athlete: TF1, blade: xceed, configuration: A, speed_pct_pb: 70",
                                                        "athlete: TT9, blade: xceed, configuration: A, speed_pct_pb: 70")
    (tmp_path / "study.yaml").write_text(bad)
    with pytest.raises(SpecError, match=r"trials\[1\]\.athlete: 'TT9' is not one of the athletes"):
        load_study(tmp_path)


def test_field_paths_in_errors(tmp_path):
    text = STUDY.replace("mass_kg: 76", "mass_kg: -3") + \
        "  - {id: a, file: x.csv, athlete: TF1, blade: xceed, speed_pct_pb: 300}\n"
    (tmp_path / "study.yaml").write_text(text)
    with pytest.raises(SpecError) as err:
        load_study(tmp_path)
    msg = str(err.value)
    assert "athletes[1].mass_kg" in msg and "trials[0].speed_pct_pb" in msg
    with pytest.raises(InputFileError, match="no study.yaml"):
        load_study(tmp_path / "nowhere")
    (tmp_path / "study.yaml").write_text(STUDY + "  - {id: a, file: x.csv, athlete: TF1, blade: xceed, colour: red}\n")
    with pytest.raises(SpecError, match=r"trials\[0\]\.colour"):
        load_study(tmp_path)


def test_trial_seeds_are_deterministic_and_distinct():
    assert trial_seed(7, "t1") == trial_seed(7, "t1")
    assert len({trial_seed(7, f"t{i}") for i in range(100)}) == 100
    assert trial_seed(7, "t1") != trial_seed(8, "t1")


def test_run_skip_force_and_store(tmp_path):
    make_study(tmp_path)
    run = run_study(tmp_path, task=fake_task, progress=False)
    assert (run.total, run.finished, run.skipped, run.failures) == (4, 4, 0, ())
    again = run_study(tmp_path, task=fake_task, progress=False)
    assert (again.finished, again.skipped) == (0, 4)
    forced = run_study(tmp_path, task=fake_task, progress=False, force=True)
    assert forced.finished == 4
    # another seed changes the input hash: everything re-runs
    assert run_study(tmp_path, task=fake_task, progress=False, seed=99).finished == 4
    assert run_study(tmp_path, task=fake_task, progress=False, force=True).finished == 4
    with ResultsStore(tmp_path / "results.sqlite") as store:
        df = store.table()
    assert len(df) == 4 and set(df["status"]) == {"ok"}
    assert list(df["speed_pct_pb"]) == [60, 70, 80, 90] and set(df["category"]) == {"2"}
    assert df["input_hash"].notna().all() and (df["package_version"] == "0.1.0").all()
    con = sqlite3.connect(tmp_path / "results.sqlite")
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    con.close()
    # changed input -> re-run that trial only
    np.savetxt(tmp_path / "trials" / "t0.csv", np.arange(6.0), delimiter=",")
    changed = run_study(tmp_path, task=fake_task, progress=False)
    assert (changed.finished, changed.skipped) == (1, 3)


def test_missing_file_is_reported_others_run(tmp_path):
    make_study(tmp_path, missing=("t1",))
    run = run_study(tmp_path, task=fake_task, progress=False)
    assert run.finished == 3 and [t for t, _ in run.failures] == ["t1"]
    assert "file not found" in run.failures[0][1] and "t1.csv" in run.failures[0][1]
    with ResultsStore(tmp_path / "results.sqlite") as store:
        df = store.table()
    assert dict(zip(df["trial_id"], df["status"], strict=True)) == {
        "t0": "ok", "t1": "failed", "t2": "ok", "t3": "ok"}
    # the file appears: the failed row is replaced on the next run
    np.savetxt(tmp_path / "trials" / "t1.csv", np.arange(5.0), delimiter=",")
    assert run_study(tmp_path, task=fake_task, progress=False).finished == 1


def test_task_exception_does_not_stop_others(tmp_path):
    make_study(tmp_path)
    run = run_study(tmp_path, task=failing_task, progress=False)
    assert run.finished == 3 and run.failures[0][0] == "t2" and "ValueError: boom" in run.failures[0][1]


def test_store_never_writes_a_row_twice(tmp_path):
    with ResultsStore(tmp_path / "r.sqlite") as store:
        row = {"trial_id": "a", "variant": "linear", "status": "ok", "K_Nm_per_deg": 1.0, "input_hash": "h"}
        assert store.write(row)
        assert not store.write({**row, "K_Nm_per_deg": 2.0})  # same inputs: kept
        assert store.table()["K_Nm_per_deg"].tolist() == [1.0]
        assert store.write({**row, "K_Nm_per_deg": 3.0}, force=True)
        assert not store.write({**row, "status": "failed", "input_hash": None})  # ok row kept
        assert store.table()["K_Nm_per_deg"].tolist() == [3.0]
        with pytest.raises(KeyError, match="unknown result column"):
            store.write({**row, "colour": "red"})


def _k_by_trial(tmp_path):
    with ResultsStore(tmp_path / "results.sqlite") as store:
        df = store.table(status=["ok"])
    return dict(zip(df["trial_id"], zip(df["K_Nm_per_deg"], df["D_Nms_per_deg"], strict=True), strict=True))


def test_process_pool_matches_serial(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    make_study(a)
    make_study(b)
    run_study(a, task=fake_task, progress=False, jobs=1)
    run = run_study(b, task=fake_task, progress=False, jobs=2)
    assert run.finished == 4
    assert _k_by_trial(a) == _k_by_trial(b)


def test_unknown_executor():
    with pytest.raises(BladelabError, match="unknown executor"):
        make_executor("dask", 2)


def test_ray_matches_local(tmp_path, ray_instance):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    make_study(a, missing=("t3",))
    make_study(b, missing=("t3",))
    run_study(a, task=fake_task, progress=False, jobs=2)
    run = run_study(b, task=fake_task, progress=False, jobs=2, executor="ray")
    assert run.finished == 3 and [t for t, _ in run.failures] == ["t3"]
    assert _k_by_trial(a) == _k_by_trial(b)


def test_ray_missing_is_a_clear_error(monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_ray(name, *args, **kwargs):
        if name == "ray":
            raise ImportError("no ray")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_ray)
    with pytest.raises(BladelabError, match=r"bladelab\[ray\]"):
        make_executor("ray", 2)


def test_yaml_example_in_docs_is_valid(tmp_path):
    # the documented minimal example parses
    text = textwrap.dedent("""
        name: minimal
        athletes: [{id: A1, mass_kg: 70, amputation: transtibial}]
        blades: [{id: b, blade: xtreme-cat5, category: 5}]
        trials: [{id: r1, file: r1.csv, athlete: A1, blade: b, speed_pct_pb: 100}]
    """)
    (tmp_path / "study.yaml").write_text(text)
    study, _ = load_study(tmp_path)
    assert study.identification.optimizer == "pso" and study.trials[0].stance == 1


def interrupted_task(payload: dict) -> dict:
    if payload["trial_id"] == "t2":
        raise KeyboardInterrupt  # the user kills the run half-way
    return fake_task(payload)


def test_killed_run_keeps_finished_rows(tmp_path):
    make_study(tmp_path)
    with pytest.raises(KeyboardInterrupt):
        run_study(tmp_path, task=interrupted_task, progress=False)
    with ResultsStore(tmp_path / "results.sqlite") as store:
        assert store.table()["trial_id"].tolist() == ["t0", "t1"]
    resumed = run_study(tmp_path, task=fake_task, progress=False)
    assert (resumed.finished, resumed.skipped) == (2, 2)


def test_concurrent_runs_split_the_trials_by_claims(tmp_path):
    import subprocess
    import sys

    store = ResultsStore(tmp_path / "results.sqlite")
    keys = [("T1", "linear"), ("T2", "linear")]
    assert store.claim(keys[:1], "run-a") == keys[:1]
    assert store.claim(keys, "run-b") == keys[1:]  # T1 is run-a's while its process lives
    store.release("run-a")
    assert store.claim(keys, "run-c") == keys[:1]  # released; T2 still run-b's
    # a claim left by a process that died is taken over
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    with store._con:
        store._con.execute("UPDATE claims SET pid=? WHERE owner='run-b'", (int(dead.stdout),))
    assert store.claim(keys, "run-d") == keys[1:]
    store.close()


def test_a_run_leaves_trials_claimed_by_another_live_run(tmp_path):
    make_study(tmp_path)
    trials = [t.id for t in load_study(tmp_path)[0].trials]
    with ResultsStore(tmp_path / "results.sqlite") as store:  # another run holds two trials
        store.claim([(t, "linear") for t in trials[:2]], "other-run")
    run = run_study(tmp_path, task=fake_task, progress=False)
    assert (run.finished, run.claimed) == (len(trials) - 2, 2)
    with ResultsStore(tmp_path / "results.sqlite") as store:
        assert sorted(store.table().trial_id) == sorted(trials[2:])
        store.release("other-run")
    assert run_study(tmp_path, task=fake_task, progress=False).finished == 2


def test_a_c3d_stance_beyond_the_trial_is_named_from_1(tmp_path):
    # study.yaml's `stance: 9` on a one-stance trial: the message said "no stance 8"
    import trial_synth as synth
    from bladelab.errors import DataError
    from bladelab.study.tasks import read_trial_stance

    path = tmp_path / "one.c3d"
    synth.write_single_plate(path)
    with pytest.raises(DataError, match=r"no stance 9: the trial has 1 stance \(stance 1\)"):
        read_trial_stance(str(path), 9)
    assert read_trial_stance(str(path), 1).metadata["stance"] == 1
