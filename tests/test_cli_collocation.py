"""``bladelab predict --method collocation`` and ``bladelab report`` of its files:
failure path, output folder rules, resume, bad input."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from bladelab.cli import main
from collocation_fake import SPEED, fake_solution
from conftest import FUKUCHI_RUN

N = 12


@pytest.fixture(scope="module")
def solved():
    """A converged-looking solution of the able model at 3.5 m/s on 12 intervals (no solve)."""
    return fake_solution("able", N)[2]


def _predict(out, *extra):
    """The command on seed 001's body (the fake solution's)."""
    return main(["predict", "--method", "collocation", "--model", "able", "--body", "seed001",
                 "--out", str(out), *extra])


def test_a_solve_that_does_not_converge_exits_2_and_keeps_only_the_best_iterate(tmp_path, capsys):
    out = tmp_path / "run"
    assert _predict(out, "--speed", "3.5", "--mesh", "6", "--max-iter", "5", "--json") == 2
    cap = capsys.readouterr()
    summary = json.loads(cap.out)  # stdout: exactly one JSON object
    assert summary["converged"] is False and summary["iterations"] == 5
    assert summary["status"] == "Maximum_Iterations_Exceeded"
    assert "tracking stage: started" in cap.err
    assert "IPOPT status Maximum_Iterations_Exceeded in the tracking stage" in cap.err
    assert "worst-violated constraints: path dynamics" in cap.err  # by name
    assert sorted(p.name for p in out.iterdir()) == ["best_iterate.json"]
    assert json.loads((out / "best_iterate.json").read_text())["kind"] == \
        "collocation-best-iterate"
    # a used folder is refused; --resume warm-starts the predictive stage from the iterate
    assert _predict(out, "--mesh", "6", "--max-iter", "5") == 2
    assert "holds a collocation solve" in capsys.readouterr().err
    assert _predict(out, "--mesh", "6", "--max-iter", "5", "--resume") == 2
    cap = capsys.readouterr()
    assert "in the predictive stage" in cap.err and "tracking stage" not in cap.err
    assert sorted(p.name for p in out.iterdir()) == ["best_iterate.json"]
    # a best iterate is not a solution: the report refuses it
    assert main(["report", str(out / "best_iterate.json")]) == 2
    assert "did not converge" in capsys.readouterr().err


def test_resume_reads_a_stored_solution_back(solved, tmp_path, capsys):
    out = tmp_path / "run"
    solved.write(out / "solution.json")
    args = ("--speed", str(SPEED), "--mesh", str(N), "--json")
    assert _predict(out, *args, "--resume") == 0
    assert json.loads(capsys.readouterr().out) == json.loads(json.dumps(solved.summary()))
    # as text: where it was read from and where it started
    assert _predict(out, *args[:-1], "--resume") == 0
    text = capsys.readouterr().out
    assert "(already solved: read back)" in text
    assert f"  started from: {solved.guess_source}\n" in text
    assert _predict(out, *args) == 2
    assert "--resume continues it, --force starts over" in capsys.readouterr().err
    assert _predict(out, "--speed", "4", "--mesh", str(N), "--resume") == 2
    err = capsys.readouterr().err
    assert "another problem" in err and "able, 3.5 m/s, 12 mesh intervals" in err
    assert _predict(out, *args, "--resume", "--force") == 2


def test_a_failed_force_run_removes_the_old_solution(solved, tmp_path, capsys):
    """--force starts over: a new solve that does not converge leaves its best iterate and no
    stale solution.json."""
    out = tmp_path / "run"
    solved.write(out / "solution.json")
    assert _predict(out, "--mesh", "6", "--max-iter", "2", "--force") == 2
    capsys.readouterr()
    assert sorted(p.name for p in out.iterdir()) == ["best_iterate.json"]


@pytest.mark.parametrize(("args", "where"), [
    (("--method", "shooting"), "--method"),
    (("--method", "collocation", "--model", "robot"), "--model"),
    (("--method", "collocation", "--mesh", "3"), "--mesh"),
    (("--method", "collocation", "--max-iter", "0"), "--max-iter"),
    (("--method", "collocation", "--speed", "-1"), "--speed"),
    (("--method", "collocation", "--swing-clearance", "-0.01"), "--swing-clearance"),
    (("--method", "collocation", "--knee-moment-min", "0"), "--knee-moment-min"),  # able
    (("--method", "collocation", "--model", "transfemoral", "--knee-moment-min", "5"),
     "--knee-moment-min"),  # above 0: infeasible in swing
    (("--method", "collocation", "--knee-flexion-max", "5"), "--knee-flexion-max"),  # able
    (("--method", "collocation", "--model", "transfemoral", "--knee-flexion-max", "-5"),
     "--knee-flexion-max"),
    (("--method", "collocation", "--guess", "no-such-file.json"), "--guess"),
    (("--method", "collocation", "--tilt-range", "-16"), "--tilt-range"),
    (("--method", "collocation", "--tilt-range=-2,-16"), "--tilt-range"),  # lo >= hi
    (("--method", "reflex", "--tilt-range=-16,-2"), "--tilt-range"),  # its lean weight
    (("--method", "collocation", "--stride-time", "0.7,0.6"), "--stride-time"),  # lo > hi
    (("--method", "collocation", "--stride-time", "0.3"), "--stride-time"),  # below 0.4 s
    (("--method", "collocation", "--stride-time", "fast"), "--stride-time"),
    (("--method", "reflex", "--stride-time", "0.7"), "--stride-time"),
    (("--method", "collocation", "--alternating-steps", "0.5"), "--alternating-steps"),
    (("--method", "reflex", "--alternating-steps", "0.1"), "--alternating-steps"),
    (("--method", "collocation", "--symmetric", "--mesh", "51"), "--mesh"),
    (("--method", "collocation", "--model", "amputee", "--symmetric"), "--symmetric"),
    (("--method", "reflex", "--symmetric"), "--symmetric"),
    (("--method", "collocation", "--body-mass", "-70"), "--body-mass"),
    (("--method", "collocation", "--height", "0"), "--height"),
    (("--method", "collocation", "--muscle-strength", "0"), "--muscle-strength"),
    (("--method", "collocation", "--max-shortening-velocity", "40"),
     "--max-shortening-velocity"),
    (("--method", "collocation", "--model", "amputee", "--residual-limb", "0.5"),
     "--residual-limb"),
    (("--method", "collocation", "--model", "able", "--residual-limb", "0.2"),
     "--residual-limb"),
    (("--method", "collocation", "--thigh-length", "0.7"), "--thigh-length"),
    (("--method", "collocation", "--shank-length", "0.2"), "--shank-length"),
    # a running trial has no epicondyle or malleolus markers: no lengths, refused
    (("--method", "collocation", "--static", str(FUKUCHI_RUN)), "--static"),
    (("--method", "reflex", "--muscle-strength", "1.5"), "--muscle-strength"),
])
def test_bad_options_are_refused_naming_the_option(args, where, tmp_path, capsys):
    assert main(["predict", "--out", str(tmp_path / "run"), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and where in err
    assert not (tmp_path / "run" / "solution.json").exists()


def test_the_transfemoral_runner_is_solved_with_its_own_blade(tmp_path, capsys):
    """``--model transfemoral`` runs end to end: its default blade (Cat4) and the default
    (human) body go into the file, and the legs are named intact and prosthetic."""
    out = tmp_path / "tf"
    code = main(["predict", "--method", "collocation", "--model", "transfemoral", "--out",
                 str(out), "--speed", "4", "--mesh", "6", "--max-iter", "2", "--json"])
    assert code == 2  # two iterations do not converge
    summary = json.loads(capsys.readouterr().out)
    assert "contact_time_prosthetic_s" in summary and "contact_time_intact_s" in summary
    stored = json.loads((out / "best_iterate.json").read_text())
    assert stored["model"] == {"model": "transfemoral", "blade": "Cat4", "body": "human"}


def test_a_transtibial_stride_starts_the_transfemoral_runner(tmp_path, capsys):
    """``--guess`` with the other amputee kind's solution: mapped by name (the socket hinge
    dropped), grounded when nothing is known of the source's contacts, its flights kept when
    the source's contact heights are given; the able model's solution is still refused."""
    from bladelab.predict.collocation.guess import prosthetic_stride_on
    from bladelab.runner import build_runner
    from bladelab.runner.model import contact_heights

    _, _, transtibial = fake_solution("amputee", 12)
    src = transtibial.write(tmp_path / "tt.json")
    tf = build_runner("transfemoral")
    g = prosthetic_stride_on(tf, transtibial.to_guess())
    lowest = [contact_heights(tf, q).min() for q in g.q]
    assert lowest == pytest.approx([-0.01] * len(lowest), abs=1e-9)
    assert g.q.shape[1] == len(tf.dof_names) and "grounded" in g.source
    # with the source runner: the same lowest contact heights on this runner, node by node
    # where the source is on the ground, and the flights (above it) kept
    tt = build_runner("amputee", blade="Cat6")
    stride = transtibial.to_guess()
    q = stride.q.copy()
    q[3:6, tt.dof("pelvis_tz")] += 0.1  # a flight
    stride = dataclasses.replace(stride, q=q)
    src_low = np.array([contact_heights(tt, qk).min() for qk in q])
    assert (src_low[3:6] > 0.0).all()
    kept = prosthetic_stride_on(tf, stride, source=tt)
    low = np.array([contact_heights(tf, qk).min() for qk in kept.q])
    ground = src_low <= 0.0
    assert 3 <= ground.sum() <= len(ground) - 3  # stances and flights to keep
    assert low[ground] == pytest.approx(src_low[ground], abs=1e-9)
    assert (low[3:6] > 0.0).all() and "flights kept" in kept.source
    out = tmp_path / "tf"
    code = main(["predict", "--method", "collocation", "--model", "transfemoral", "--out",
                 str(out), "--mesh", "6", "--max-iter", "1", "--guess", str(src),
                 "--speed", str(SPEED)])
    assert code == 2  # one iteration does not converge; the start was accepted
    stored = json.loads((out / "best_iterate.json").read_text())
    assert "transfemoral model's coordinates" in stored["guess_source"]
    capsys.readouterr()
    _, _, able = fake_solution("able", 12)
    assert main(["predict", "--method", "collocation", "--model", "transfemoral", "--out",
                 str(tmp_path / "x"), "--guess", str(able.write(tmp_path / "a.json"))]) == 2
    assert "another model" in capsys.readouterr().err
