"""``bladelab runner ...`` command line."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from bladelab.cli import main


def test_simulate_json_and_outputs(tmp_path, capsys):
    out = tmp_path / "sim"
    code = main(
        [
            "runner",
            "simulate",
            "--model",
            "amputee",
            "--blade",
            "Cat5",
            "--duration",
            "0.3",
            "--out",
            str(out),
            "--json",
        ]
    )
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    for key in (
        "fell",
        "duration_s",
        "mean_speed_mps",
        "contact_time_intact_s",
        "contact_time_prosthetic_s",
        "power_balance_residual_pct",
    ):
        assert key in summary
    assert summary["blade"] == "Cat5"
    assert summary["duration_s"] == pytest.approx(0.3)
    assert json.loads((out / "summary.json").read_text()) == summary
    grf = pd.read_csv(out / "grf.csv")
    assert set(grf.leg) == {"intact", "prosthetic"}
    assert {"pelvis_tx", "socket_angle_r"} <= set(pd.read_csv(out / "states.csv").columns)
    assert not list(out.glob(".*part"))  # no temporary files left


def test_simulate_with_controller_file(tmp_path, capsys):
    ctrl = tmp_path / "ctrl.json"
    ctrl.write_text(
        json.dumps({"excitations": {"vasti_l": 0.6, "glut_max_l": 0.3}, "default": 0.1})
    )
    code = main(
        [
            "runner",
            "simulate",
            "--model",
            "able",
            "--controller",
            str(ctrl),
            "--duration",
            "0.1",
            "--out",
            str(tmp_path / "o"),
        ]
    )
    assert code == 0
    m = pd.read_csv(tmp_path / "o" / "muscles.csv")
    last = m[m.time == m.time.max()].set_index("muscle").excitation
    assert last["vasti_l"] == 0.6 and last["glut_max_r"] == 0.1
    assert "able" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--blade", "Cat9"], "Cat9"),
        (["--model", "robot"], "robot"),
        (["--duration", "-1"], "--duration"),
    ],
)
def test_bad_options_exit_2_without_traceback(args, needle, tmp_path, capsys):
    out = tmp_path / "never"
    code = main(["runner", "simulate", "--out", str(out), *args])
    err = capsys.readouterr().err
    assert code == 2
    assert needle in err and "Traceback" not in err
    assert not out.exists()


def test_bad_controller_file(tmp_path, capsys):
    ctrl = tmp_path / "ctrl.json"
    ctrl.write_text(json.dumps({"excitations": {"soleus_r": 0.5}}))
    code = main(["runner", "simulate", "--controller", str(ctrl), "--duration", "0.1"])
    err = capsys.readouterr().err
    assert code == 2 and "soleus_r" in err and "ctrl.json" in err
    ctrl.write_text("{not json")
    assert main(["runner", "simulate", "--controller", str(ctrl), "--duration", "0.1"]) == 2


def test_blades_listing(capsys):
    assert main(["runner", "blades", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in rows] == ["Cat4", "Cat5", "Cat6", "Cat6High", "Cat7"]


def test_simulate_wearing_a_multilink_blade(capsys):
    code = main(
        [
            "runner",
            "simulate",
            "--wear",
            "xtreme-cat5",
            "--K",
            "16",
            "--D",
            "0.25",
            "--duration",
            "0.05",
            "--json",
        ]
    )
    assert code == 0
    assert json.loads(capsys.readouterr().out)["blade"] == "xtreme-cat5"
    assert main(["runner", "simulate", "--wear", "nope", "--duration", "0.05"]) == 2
    assert "nope" in capsys.readouterr().err


def test_simulate_with_the_implicit_scheme(capsys):
    args = ["runner", "simulate", "--duration", "0.2", "--dt", "1e-3", "--json"]
    assert main([*args, "--integrator", "implicit"]) == 0
    assert json.loads(capsys.readouterr().out)["duration_s"] == pytest.approx(0.2)
    assert main([*args, "--integrator", "rk4"]) == 2
    assert "integrator" in capsys.readouterr().err


@pytest.mark.parametrize("body, integrator", [("human", "newmark"), ("seed001", "explicit")])
def test_simulate_runs_the_named_body_with_an_integrator_its_feet_allow(body, integrator, capsys):
    args = ["runner", "simulate", "--model", "able", "--duration", "0.05", "--json"]
    assert main([*args, "--body", body]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["body"] == body and out["integrator"] == integrator
    assert out["duration_s"] == pytest.approx(0.05)
    # the human body's toe damper: an explicit step at the default 0.25 ms is refused, by name
    if body == "human":
        assert main([*args, "--body", body, "--integrator", "explicit"]) == 2
        assert "mtp_angle" in capsys.readouterr().err
    assert main([*args, "--body", "robot"]) == 2
    assert "--body" in capsys.readouterr().err
