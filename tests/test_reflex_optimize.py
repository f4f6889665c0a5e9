"""CMA-ES optimisation of the controller: improves, reproducible, resumable; CLI.

Sweeps: tests/test_predict_sweep.py."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from bladelab.cli import main
from bladelab.errors import InputFileError, SpecError
from bladelab.predict.reflex.objective import ObjectiveSettings
from bladelab.predict.reflex.optimize import (
    evaluate_candidates,
    optimize_controller,
    runner_and_layout,
)

SHORT = ObjectiveSettings(duration=1.0)
#: The human body's toe dampers need the Newmark scheme (the explicit one refuses them).
SHORT_HUMAN = ObjectiveSettings(duration=1.0, integrator="newmark")
THREE_S = ObjectiveSettings(duration=3.0)


def _run(**kw):
    args = {"generations": 4, "popsize": 6, "seed": 3, "settings": SHORT}
    args.update(kw)
    return optimize_controller("able", **args)


def test_short_optimisation_improves_and_is_reproducible(tmp_path):
    _, layout = runner_and_layout("able", None)
    start = evaluate_candidates(
        {"model": "able", "settings": SHORT.to_dict(), "xs": [layout.x0.tolist()]}
    )[0]["cost"]
    a = _run(out=tmp_path / "a")
    b = _run()
    assert a.best_cost < start
    assert [h[2] for h in a.history] == sorted((h[2] for h in a.history), reverse=True)
    assert a.best_cost == b.best_cost and np.array_equal(a.x, b.x)
    assert a.history == b.history
    best = json.loads((tmp_path / "a" / "best.json").read_text())
    assert best["evaluation"]["cost"] == pytest.approx(a.best_cost)
    # the stored best re-evaluates to the same cost (nothing trusted from the run)
    x = layout.vector(best["parameters"])
    again = evaluate_candidates({"model": "able", "settings": SHORT.to_dict(), "xs": [x.tolist()]})
    assert again[0]["cost"] == pytest.approx(a.best_cost, rel=1e-12)
    c = _run(seed=4, generations=2)
    assert not np.array_equal(c.x, a.x)


def test_resume_equals_no_stop(tmp_path):
    full = _run(out=tmp_path / "full")
    part = _run(out=tmp_path / "part", generations=2, checkpoint_every=1)
    assert part.generations == 2
    resumed = _run(out=tmp_path / "part", resume=True)
    assert resumed.generations == 4 and resumed.evaluations == full.evaluations
    assert resumed.history == full.history
    np.testing.assert_array_equal(resumed.x, full.x)


def _as_if_older(ckpt: Path, drop: int, held: list[int]) -> None:
    """Rewrite a checkpoint as the layout without parameter ``drop`` would have written it (a
    run that held ``drop`` fixed searched exactly that layout's parameters); ``held``: what the
    older run itself held fixed (indices below ``drop``)."""
    import pickle

    from bladelab.predict.reflex.optimize import _Subspace

    state = pickle.loads(ckpt.read_bytes())
    keep = np.delete(np.arange(len(state["parameter_names"])), drop)
    state["parameter_names"] = [state["parameter_names"][i] for i in keep]
    state["best_x"] = state["best_x"][keep]
    state["subspace"] = _Subspace(state["subspace"].held[keep], held) if held else None
    ckpt.write_bytes(pickle.dumps(state, protocol=4))


@pytest.mark.parametrize("subspace", [False, True])
def test_a_checkpoint_resumes_after_the_layout_grew(tmp_path, subspace):
    # a run written before a parameter was added goes on searching what it searched, the new
    # parameter held at its default: the same as a run that held it fixed from the start
    _, layout = runner_and_layout("able", None)
    new, also = 7, [3] if subspace else []  # the added parameter; one the old run held
    full = _run(out=tmp_path / "full", fixed=[*also, new])
    _run(out=tmp_path / "part", generations=2, checkpoint_every=1, fixed=[*also, new])
    _as_if_older(tmp_path / "part" / "checkpoint.pkl", new, also)
    resumed = _run(out=tmp_path / "part", resume=True)
    assert resumed.history == full.history
    np.testing.assert_array_equal(resumed.x, full.x)
    assert resumed.x[new] == layout.x0[new]
    best = json.loads((tmp_path / "part" / "best.json").read_text())["parameters"]
    assert list(best) == list(layout.names)


def test_a_checkpoint_of_a_layout_that_lost_parameters_is_refused(tmp_path):
    import pickle

    _run(out=tmp_path / "r", generations=1)
    ckpt = tmp_path / "r" / "checkpoint.pkl"
    state = pickle.loads(ckpt.read_bytes())
    state["parameter_names"] = [*state["parameter_names"][:-1], "S00011.gone_l.KF"]
    ckpt.write_bytes(pickle.dumps(state, protocol=4))
    with pytest.raises(InputFileError, match="another controller layout"):
        _run(out=tmp_path / "r", resume=True)


def test_parallel_workers_give_the_serial_result():
    a = _run(generations=2, popsize=4)
    b = _run(generations=2, popsize=4, jobs=2)
    assert a.history == b.history and np.array_equal(a.x, b.x)


def test_resume_errors(tmp_path):
    with pytest.raises(InputFileError, match="no checkpoint"):
        _run(out=tmp_path / "none", resume=True)
    _run(out=tmp_path / "r", generations=1)
    with pytest.raises(InputFileError, match="3.5 m/s"):
        optimize_controller(
            "able",
            speed=4.0,
            generations=2,
            popsize=6,
            out=tmp_path / "r",
            resume=True,
            settings=SHORT,
        )
    (tmp_path / "junk").mkdir()
    (tmp_path / "junk" / "checkpoint.pkl").write_bytes(b"not a pickle")
    with pytest.raises(InputFileError, match="best.json"):
        _run(out=tmp_path / "junk", resume=True)


def test_cli_predict_and_errors(tmp_path, capsys):
    code = main(
        [
            "predict",
            "--method",
            "reflex",
            "--model",
            "able",
            "--generations",
            "2",
            "--popsize",
            "4",
            "--duration",
            "0.5",
            "--strike-limit",
            "0.3",
            "--lean-weight",
            "2",
            "--run-up",
            "--out",
            str(tmp_path / "p"),
        ]
    )
    assert code == 0
    summary = json.loads((tmp_path / "p" / "summary.json").read_text())
    assert summary["best"]["generations"] == 2
    best = json.loads((tmp_path / "p" / "best.json").read_text())
    assert best["settings"]["strike_limit_bw"] == 0.3
    assert best["settings"]["w_lean"] == 2.0 and best["settings"]["run_up"] is True
    code = main(
        [
            "predict",
            "--method",
            "reflex",
            "--model",
            "able",
            "--generations",
            "3",
            "--popsize",
            "4",
            "--duration",
            "0.5",
            "--resume",
            "--out",
            str(tmp_path / "p"),
        ]
    )
    assert code == 0
    assert json.loads((tmp_path / "p" / "best.json").read_text())["generation"] == 3
    capsys.readouterr()
    assert main(["predict", "--method", "reflex",
                 "--model", "robot", "--out", str(tmp_path / "x")]) == 2
    assert "robot" in capsys.readouterr().err
    assert main(["predict", "--method", "reflex",
                 "--init", str(tmp_path / "missing.json"), "--out", str(tmp_path)]) == 2
    assert "not found" in capsys.readouterr().err


def test_resume_keeps_the_runs_settings(tmp_path):
    full = _run(out=tmp_path / "full", generations=3)
    _run(out=tmp_path / "part", generations=1)
    other = ObjectiveSettings(duration=0.3)
    resumed = _run(out=tmp_path / "part", generations=3, resume=True, settings=other, seed=99)
    assert resumed.history == full.history


def test_robust_evaluation_is_the_mean_over_jittered_copies():
    from bladelab.predict.reflex.objective import simulate_controlled
    from bladelab.predict.reflex.robust import jittered_parameters

    model, layout = runner_and_layout("able", None)
    robust = ObjectiveSettings(duration=1.0, robust_samples=3, robust_jitter=1e-4)
    x = layout.x0
    copies = jittered_parameters(x, 2, 1e-4)
    # the copies move every parameter, by about the requested relative amount
    for xj in copies:
        rel = np.abs(xj - x) / (np.abs(x) + 1e-3)
        assert 0 < np.median(rel) < 1e-3
    assert not np.array_equal(copies[0], copies[1])
    costs = [simulate_controlled(model, xi, layout=layout, settings=SHORT)[0].cost
             for xi in [x, *copies]]
    got = evaluate_candidates({"model": "able", "settings": robust.to_dict(), "xs": [x.tolist()]})
    assert got[0]["cost"] == pytest.approx(np.mean(costs), rel=1e-12)


def test_verification_copies_are_not_the_objectives(monkeypatch):
    # a solution optimised to survive the objective's jittered copies must be checked on others
    import bladelab.predict.reflex.robust as robust
    import bladelab.predict.reflex.verify as opt

    x = runner_and_layout("able", None)[1].x0
    seen = robust.jittered_parameters(x, 4, 1e-3)
    checked = robust.jittered_parameters(x, 4, 1e-3, robust.VERIFY_JITTER_SEED)
    assert not any(np.allclose(a, b) for a in seen for b in checked)
    seeds = []
    real = opt.jittered_parameters

    def spy(*args, **kwargs):
        seeds.append(args[3] if len(args) > 3 else kwargs.get("seed"))
        return real(*args, **kwargs)

    monkeypatch.setattr(opt, "jittered_parameters", spy)
    shipped = Path(opt.__file__).resolve().parents[2] / "data/runner/reflex-starts/able-3.5.json"
    opt.verify_solution(shipped, duration=0.5, jittered_copies=1, jitter=1e-9)
    assert seeds == [robust.VERIFY_JITTER_SEED]


def test_verification_copies_move_the_files_parameters_by_name(tmp_path, monkeypatch):
    # each parameter's moves are drawn from the seed and its name: reordering or adding
    # parameters changes no other parameter's moves; only the moved ones move
    import bladelab.predict.reflex.robust as robust

    x = np.array([1.0, -2.0, 0.5, 3.0])
    names = ["a", "b", "c", "d"]
    one = robust.jittered_parameters(x, 3, 1e-3, 7, names=names)
    swapped = robust.jittered_parameters(x[[2, 0, 3, 1]], 3, 1e-3, 7, names=["c", "a", "d", "b"])
    grown = robust.jittered_parameters(np.insert(x, 1, 9.0), 3, 1e-3, 7,
                                       names=["a", "new", "b", "c", "d"])
    part = robust.jittered_parameters(x, 3, 1e-3, 7, names=names,
                                      moved=np.array([True, False, True, True]))
    for k in range(3):
        assert np.all(one[k] != x)
        np.testing.assert_array_equal(swapped[k], one[k][[2, 0, 3, 1]])
        np.testing.assert_array_equal(np.delete(grown[k], 1), one[k])
        np.testing.assert_array_equal(part[k][[0, 2, 3]], one[k][[0, 2, 3]])
        assert part[k][1] == x[1]
    assert len({tuple(c) for c in one}) == 3  # three different copies
    # verify_solution moves only the file's parameters: a file without the placement terms
    # keeps them at their defaults in every copy
    import bladelab.predict.reflex.verify as verify

    _, layout = runner_and_layout("able", None)
    held = {n: v for n, v in layout.to_dict(layout.x0).items() if "pelvis_tx" not in n}
    path = tmp_path / "old.json"
    path.write_text(json.dumps({"model": "able", "speed_m_per_s": 3.5, "parameters": held}))
    copies = []
    real = robust.jittered_parameters

    def spy(*args, **kwargs):
        copies.extend(real(*args, **kwargs))
        return copies

    monkeypatch.setattr(verify, "jittered_parameters", spy)
    verify.verify_solution(path, duration=0.2, jittered_copies=2, jitter=1e-3)
    placement = np.array(["pelvis_tx" in n for n in layout.names])
    assert placement.sum() >= 8
    for c in copies:
        np.testing.assert_array_equal(c[placement], layout.x0[placement])
        assert np.all(c[~placement] != layout.x0[~placement])


def test_fixed_parameters_are_held_and_a_resume_keeps_them(tmp_path):
    # CMA-ES over the free parameters only; resuming equals not stopping
    _, layout = runner_and_layout("able", None)
    fixed = [0, 5, layout.size - 1]
    kw = {"generations": 3, "popsize": 4, "sigma": 0.5, "fixed": fixed}
    full = _run(out=tmp_path / "full", **kw)
    np.testing.assert_array_equal(full.x[fixed], np.clip(layout.x0, layout.lower,
                                                         layout.upper)[fixed])
    _run(out=tmp_path / "part", **{**kw, "generations": 1, "checkpoint_every": 1})
    resumed = _run(out=tmp_path / "part", resume=True, **kw)
    np.testing.assert_array_equal(resumed.x, full.x)
    assert resumed.history == full.history


def test_a_warm_start_is_never_lost():
    # from the able reflex start a wide first step (sigma 3) scatters every candidate to a
    # worse cost; the best stays the start itself, evaluated once before the first generation
    from pathlib import Path

    import bladelab
    from bladelab.predict.reflex.controller import read_parameters

    _, layout = runner_and_layout("able", None)
    shipped = Path(bladelab.__file__).parent / "data" / "runner" / "reflex-starts" / "able-3.5.json"
    x0 = read_parameters(shipped, layout)
    start = evaluate_candidates(
        {"model": "able", "settings": THREE_S.to_dict(), "xs": [x0.tolist()]}
    )
    res = _run(x0=x0, sigma=3.0, generations=1, settings=THREE_S)
    assert res.evaluations == 1 + 6
    assert res.best_cost == start[0]["cost"]  # every candidate was worse (seeded)
    assert np.array_equal(res.x, x0)
    assert res.history[0][2] == start[0]["cost"]


def test_a_folder_holding_a_run_is_refused_unless_resumed_or_forced(tmp_path, capsys):
    from bladelab.cli import main
    from bladelab.errors import InputFileError

    args = {"generations": 1, "popsize": 4, "seed": 3, "settings": ObjectiveSettings(duration=0.2)}
    optimize_controller("able", out=tmp_path, **args)
    history = (tmp_path / "history.csv").read_text()
    with pytest.raises(InputFileError, match="holds a run"):
        optimize_controller("able", out=tmp_path, **args)
    assert (tmp_path / "history.csv").read_text() == history  # nothing erased
    code = main(["predict", "--method", "reflex",
                 "--model", "able", "--generations", "1", "--popsize", "4",
                 "--duration", "0.2", "--out", str(tmp_path)])
    assert code == 2 and "--resume continues it" in capsys.readouterr().err
    assert (tmp_path / "history.csv").read_text() == history
    optimize_controller("able", out=tmp_path, force=True, **{**args, "seed": 4})
    assert (tmp_path / "history.csv").read_text() != history


def test_robust_copies_can_start_at_other_speeds():
    # the acceptance's "±5 % of the initial speed" inside the objective: copies alternate 1 + s, 1 - s
    from bladelab.predict.reflex.objective import simulate_controlled
    from bladelab.predict.reflex.robust import robust_copies

    model, layout = runner_and_layout("able", None)
    x = layout.x0
    plain = ObjectiveSettings(duration=0.6, robust_samples=4, robust_jitter=1e-4)
    assert all(s is plain for _, s in robust_copies(x, plain))
    changed = ObjectiveSettings(duration=0.6, robust_samples=4, robust_jitter=1e-4,
                                robust_speed_change=0.05, initial_speed=4.0)
    copies = robust_copies(x, changed)
    assert [s.initial_speed for _, s in copies] == pytest.approx([4.2, 3.8, 4.2])
    # the same parameter jitter as without the speed change
    for (a, _), (b, _) in zip(copies, robust_copies(x, plain), strict=True):
        np.testing.assert_array_equal(a, b)
    costs = [simulate_controlled(model, x, layout=layout, settings=changed)[0].cost]
    costs += [simulate_controlled(model, xj, layout=layout, settings=s)[0].cost
              for xj, s in copies]
    assert len(set(costs)) == 4
    got = evaluate_candidates({"model": "able", "settings": changed.to_dict(),
                               "xs": [x.tolist()]})
    assert got[0]["cost"] == pytest.approx(np.mean(costs), rel=1e-12)


def test_robust_copies_can_be_pushed_in_mid_run():
    # robust_push p: copy k is pushed by +p, -p, ... at a seeded time inside the push window
    from bladelab.predict.reflex.objective import push_window
    from bladelab.predict.reflex.robust import robust_copies

    x = runner_and_layout("able", None)[1].x0
    pushed = ObjectiveSettings(duration=10.0, robust_samples=5, robust_push=0.03)
    copies = robust_copies(x, pushed, seed=[1, 2])
    lo, hi = push_window(10.0)
    assert 0 < lo < hi < 10.0
    times = [s.push[0] for _, s in copies]
    assert all(lo <= t <= hi for t in times) and len(set(times)) == 4
    assert [s.push[1] for _, s in copies] == [0.03, -0.03, 0.03, -0.03]
    assert all(s.initial_speed is None and s.robust_push == 0.03 for _, s in copies)
    # the same times for the same seed, others for another; the jitter directions do not
    # depend on the pushes
    assert [s.push for _, s in robust_copies(x, pushed, seed=[1, 2])] == [s.push for _, s in copies]
    assert [s.push[0] for _, s in robust_copies(x, pushed, seed=[1, 3])] != times
    plain = ObjectiveSettings(duration=10.0, robust_samples=5)
    for (a, _), (b, _) in zip(copies, robust_copies(x, plain, seed=[1, 2]), strict=True):
        np.testing.assert_array_equal(a, b)
    both = ObjectiveSettings(duration=10.0, robust_samples=3, robust_push=0.03,
                             robust_speed_change=0.05, initial_speed=4.0)
    assert [(s.initial_speed, s.push[1]) for _, s in robust_copies(x, both)] == [
        (pytest.approx(4.2), 0.03), (pytest.approx(3.8), -0.03)]


def test_the_last_robust_copy_can_run_at_half_the_step():
    # robust_half_step: the last copy halves the time step (and only that changes); the
    # evaluated cost is the mean with that copy simulated at the half step
    from bladelab.predict.reflex.objective import simulate_controlled
    from bladelab.predict.reflex.robust import robust_copies

    model, layout = runner_and_layout("able", None)
    x = layout.x0
    base = {"duration": 0.6, "robust_samples": 3, "robust_jitter": 1e-4, "dt": 1e-3,
            "integrator": "newmark"}
    plain = ObjectiveSettings(**base)
    halved = ObjectiveSettings(**base, robust_half_step=True)
    copies = robust_copies(x, halved)
    assert [s.dt for _, s in copies] == [1e-3, 5e-4]
    assert copies[1][1] == replace(halved, dt=5e-4) and copies[0][1] is halved
    for (a, _), (b, _) in zip(copies, robust_copies(x, plain), strict=True):
        np.testing.assert_array_equal(a, b)
    costs = [simulate_controlled(model, x, layout=layout, settings=halved)[0].cost]
    costs += [simulate_controlled(model, xj, layout=layout, settings=s)[0].cost
              for xj, s in copies]
    got = evaluate_candidates({"model": "able", "settings": halved.to_dict(),
                               "xs": [x.tolist()]})
    assert got[0]["cost"] == pytest.approx(np.mean(costs), rel=1e-12)
    with pytest.raises(SpecError, match="robust_half_step"):
        ObjectiveSettings(robust_half_step=True)


def test_per_generation_copies_are_new_every_generation_and_resume_exactly(tmp_path):
    from bladelab.predict.reflex.robust import generation_jitter_seed, jittered_parameters

    fixed = ObjectiveSettings(duration=0.5, robust_samples=2, robust_jitter=1e-3)
    fresh = ObjectiveSettings(duration=0.5, robust_samples=2, robust_jitter=1e-3,
                              robust_directions="per-generation")
    x0 = runner_and_layout("able", None)[1].x0
    assert generation_jitter_seed(fixed, 3, 1) == generation_jitter_seed(fixed, 4, 2)
    seeds = [generation_jitter_seed(fresh, 3, g) for g in (1, 2)] + [
        generation_jitter_seed(fresh, 4, 1)]
    dirs = [jittered_parameters(x0, 1, 1e-3, s)[0] for s in seeds]
    assert not any(np.array_equal(a, b) for i, a in enumerate(dirs) for b in dirs[i + 1:])
    assert seeds[0] == generation_jitter_seed(fresh, 3, 1)

    kw = {"x0": x0, "popsize": 4, "settings": fresh}
    full = _run(generations=3, **kw)
    # the warm start once, then every generation its candidates and the best so far again
    assert full.evaluations == 1 + 3 * (4 + 1)
    # the best's cost is its cost on the last generation's copies
    last = evaluate_candidates({"model": "able", "settings": fresh.to_dict(),
                                "jitter_seed": generation_jitter_seed(fresh, 3, 3),
                                "xs": [full.x.tolist()]})
    assert full.best_cost == pytest.approx(last[0]["cost"], rel=1e-12)
    _run(generations=1, out=tmp_path / "r", checkpoint_every=1, **kw)
    resumed = _run(generations=3, out=tmp_path / "r", resume=True, **kw)
    assert resumed.history == full.history
    np.testing.assert_array_equal(resumed.x, full.x)


def test_verify_solution_from_changed_initial_speeds():
    import bladelab.predict.reflex.verify as opt

    shipped = Path(opt.__file__).resolve().parents[2] / "data/runner/reflex-starts/able-3.5.json"
    out = opt.verify_solution(shipped, duration=0.5, initial_speed_change=0.05)
    speeds = [c["initial_speed_m_per_s"] for c in out["initial_speed"]]
    assert speeds == pytest.approx([3.5 * 1.05, 3.5 * 0.95])
    assert len({out["cost"], *(c["cost"] for c in out["initial_speed"])}) == 3
    assert out["ok"] == all(c["ok"] for c in [out, *out["initial_speed"]])
    assert "initial_speed" not in opt.verify_solution(shipped, duration=0.5)


def test_verify_solution_after_pushes():
    import bladelab.predict.reflex.verify as opt

    shipped = Path(opt.__file__).resolve().parents[2] / "data/runner/reflex-starts/able-3.5.json"
    out = opt.verify_solution(shipped, duration=3.0, push_change=0.3, push_phases=2)
    assert [(c["push_time_s"], c["push_change"]) for c in out["pushed"]] == [
        (2.0, 0.3), (2.0, -0.3), (2.5, 0.3), (2.5, -0.3)]
    # a 30 % push changes the run: other costs, and the runs are judged like the nominal one
    assert len({out["cost"], *(c["cost"] for c in out["pushed"])}) == 5
    assert out["ok"] == all(c["ok"] for c in [out, *out["pushed"]])
    assert "pushed" not in opt.verify_solution(shipped, duration=0.5)


@pytest.mark.parametrize(("option", "value", "named"), [
    ("--robust-directions", "sometimes", "--robust-directions"),
    ("--robust-speed-change", "0.7", "--robust-speed-change"),
    ("--robust-push", "-0.1", "--robust-push"),
    ("--robust-push", "0.02", "--duration"),  # the default 10 s has room; 4 s has not
    ("--strike-limit", "-0.2", "--strike-limit"),
    ("--lean-weight", "nan", "--lean-weight"),
])
def test_cli_refuses_bad_robust_copies(tmp_path, capsys, option, value, named):
    args = ["predict", "--method", "reflex", option, value, "--out", str(tmp_path / "x")]
    if named == "--duration":
        args += ["--duration", "4"]
    assert main(args) == 2
    assert named in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_cli_refuses_a_half_step_copy_without_copies(tmp_path, capsys):
    assert main(["predict", "--method", "reflex",
                 "--robust-half-step", "--out", str(tmp_path / "x")]) == 2
    assert "--robust-half-step" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_run_on_the_human_body_is_that_bodys_everywhere(tmp_path, capsys):
    """``body="human"``: the candidates run on the human body (its toe joints: a cost that
    differs from seed 001's for the same parameters), best.json and the checkpoint name the
    body, a resume on another body is refused, the file is refused as seed 001's solution
    and accepted as its warm start (``transfer``), and the CLI's ``--body`` reaches the run."""
    from bladelab.predict.reflex.controller import read_parameters
    from bladelab.predict.reflex.verify import verify_solution

    _, seed_layout = runner_and_layout("able", None)
    human, layout = runner_and_layout("able", None, "human")
    assert "mtp_angle_l" in human.dof_names and layout.names == seed_layout.names
    x = layout.x0.tolist()
    costs = {body: evaluate_candidates({"model": "able", "body": body, "xs": [x],
                                        "settings": settings.to_dict()})[0]["cost"]
             for body, settings in (("seed001", SHORT), ("human", SHORT_HUMAN))}
    assert costs["seed001"] != costs["human"]
    run = _run(out=tmp_path / "h", generations=1, body="human", settings=SHORT_HUMAN)
    assert run.body == "human" and run.to_dict()["body"] == "human"
    best = json.loads((tmp_path / "h" / "best.json").read_text())
    assert best["body"] == "human"
    again = evaluate_candidates({"model": "able", "body": "human",
                                 "settings": SHORT_HUMAN.to_dict(),
                                 "xs": [layout.vector(best["parameters"]).tolist()]})
    assert again[0]["cost"] == pytest.approx(run.best_cost, rel=1e-12)
    with pytest.raises(InputFileError, match="seed001 body"):
        _run(out=tmp_path / "h", generations=2, resume=True)  # seed 001's body by default
    with pytest.raises(InputFileError, match="human body, not the seed001 body") as err:
        read_parameters(tmp_path / "h" / "best.json", seed_layout)
    assert err.value.where == "body"
    np.testing.assert_array_equal(
        read_parameters(tmp_path / "h" / "best.json", seed_layout, transfer=True),
        read_parameters(tmp_path / "h" / "best.json", layout, body="human"))
    # the file's own body re-simulates it
    report = verify_solution(tmp_path / "h" / "best.json", duration=1.0)
    assert report["cost"] == pytest.approx(run.best_cost, rel=1e-9)
    assert main(["predict", "--method", "reflex", "--body", "human", "--generations", "1",
                 "--popsize", "4", "--duration", "1", "--out", str(tmp_path / "cli")]) == 0
    assert json.loads((tmp_path / "cli" / "best.json").read_text())["body"] == "human"
    capsys.readouterr()
