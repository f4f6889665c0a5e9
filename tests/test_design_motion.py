"""Motion adaptation (seed 002): motion files, the fitted motion model, the runner evaluator and
``bladelab design --motion``."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
import yaml

from bladelab.cli import main
from bladelab.design import DesignSpace, run_design
from bladelab.design.gait_cycle import ANGLE_NAMES, GaitCycle, default_gait_cycle
from bladelab.design.motion import (
    check_motion_factors,
    load_motion_cycles,
    load_motion_model,
    read_motion_file,
)
from bladelab.errors import InputFileError, SpecError
from conftest import FUKUCHI_RUN, FUKUCHI_STATIC

SPACE2 = DesignSpace.parse("stiffness_kN_per_m=18:32,width_m=0.05:0.08")
SPACE1 = DesignSpace.parse("stiffness_kN_per_m=18:32")
BASE = default_gait_cycle().resampled(51)
SIN = np.sin(2 * np.pi * BASE.phase)


def _coded(k_kN: float, w: float = 0.065) -> tuple[float, float]:
    return (k_kN - 25.0) / 7.0, (w - 0.065) / 0.015


def _true_period(k_kN: float, w: float = 0.065) -> float:
    """Known dependence: linear + quadratic in the coded stiffness k and width w [s]."""
    k, w = _coded(k_kN, w)
    return 0.50 + 0.02 * k + 0.01 * w - 0.008 * k * k + 0.004 * k * w + 0.006 * w * w


def _true_cycle(k_kN: float, w: float = 0.065) -> GaitCycle:
    """The template cycle with a hip amplitude linear + quadratic in k and w."""
    k, c = _coded(k_kN, w)
    amp = math.radians(4.0 * k - 2.0 * c + 1.5 * c * c - 1.0 * k * c)
    ang = dict(BASE.angles)
    ang["hip_prosthetic"] = BASE.angles["hip_prosthetic"] + amp * SIN
    ang["hip_sound"] = BASE.angles["hip_sound"] - 0.5 * amp * SIN
    ang["knee_prosthetic"] = BASE.angles["knee_prosthetic"] + math.radians(2.0) * k * k
    return GaitCycle(_true_period(k_kN, w), BASE.phase, ang, "synthetic")


def _write_motion(folder, blades, *, fmt="yaml", model=None, extra=None):
    """Gait CSVs of the true cycles and a motion file listing them (paths relative)."""
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for i, b in enumerate(blades):
        name = f"cycle_{i}.csv"
        _true_cycle(*b).to_frame().to_csv(folder / name, index=False)
        row = {"stiffness_kN_per_m": b[0]}
        if len(b) > 1:
            row["width_m"] = b[1]
        row["gait"] = name
        rows.append(row)
    for i, e in (extra or {}).items():
        rows[i].update(e)
    if fmt == "csv":
        path = folder / "motion.csv"
        pd.DataFrame(rows).to_csv(path, index=False)
    else:
        path = folder / "motion.yaml"
        data = {"cycles": rows} if model is None else {"model": model, "cycles": rows}
        path.write_text(yaml.safe_dump(data))
    return path


GRID = [(k, w) for k in (18.0, 25.0, 32.0) for w in (0.05, 0.065, 0.08)]


def test_predicted_cycle_of_an_unseen_design_is_the_known_one(tmp_path):
    """Noise-free quadratic motion at 9 blades: the quadratic motion model gives the true
    period and angles of a blade it has not seen."""
    path = _write_motion(tmp_path, GRID)
    mm = load_motion_model(path, space=SPACE2)
    assert mm.model == "quadratic" and len(mm.terms) == 6
    assert mm.n_cycles == 9 and mm.n_blades == 9
    point = {"stiffness_kN_per_m": 21.3, "width_m": 0.0712}
    pred, truth = mm.predict_point(point), _true_cycle(21.3, 0.0712)
    assert pred.period == pytest.approx(_true_period(21.3, 0.0712), abs=1e-12)
    np.testing.assert_allclose(pred.phase, truth.phase, atol=1e-15)
    for n in ANGLE_NAMES:
        np.testing.assert_allclose(pred.angles[n], truth.angles[n], atol=1e-10, err_msg=n)
    # exact data: the leave-one-blade-out errors vanish
    assert mm.loo_period_s < 1e-10
    assert max(mm.loo_angles_deg.values()) < 1e-8
    d = mm.to_dict()
    assert d["terms"][0] == "1" and "stiffness_kN_per_m^2" in d["terms"]
    assert d["coding"]["width_m"] == {"centre": pytest.approx(0.065), "half_range":
                                      pytest.approx(0.015)}
    # the same cycles as CSV give the same model; the file's own coding does too (full models
    # do not depend on the coding)
    csv = _write_motion(tmp_path / "csv", GRID, fmt="csv")
    other = load_motion_model(csv)
    assert other.predict_point(point).period == pytest.approx(pred.period, abs=1e-12)


def test_leave_one_blade_out_error_against_brute_force(tmp_path):
    """A cubic period is not quadratic: the model's leave-one-blade-out error equals refitting
    a quadratic (numpy.polyfit) without each blade in turn; two trials of one blade are left
    out together."""
    ks = [18.0, 21.5, 25.0, 25.0, 28.5, 32.0]
    periods = [0.5 + 0.03 * _coded(k)[0] ** 3 for k in ks]
    periods[3] += 0.002  # a second trial with the centre blade
    rows = []
    for i, (k, T) in enumerate(zip(ks, periods, strict=True)):
        GaitCycle(T, BASE.phase, BASE.angles).to_frame().to_csv(tmp_path / f"c{i}.csv",
                                                                 index=False)
        rows.append({"stiffness_kN_per_m": k, "gait": f"c{i}.csv"})
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump(rows))
    mm = load_motion_model(path, space=SPACE1, model="quadratic")
    assert mm.n_cycles == 6 and mm.n_blades == 5
    x, y = np.array(ks), np.array(periods)
    errs = []
    for blade in np.unique(x):
        out = x == blade
        coef = np.polyfit(x[~out], y[~out], 2)
        errs += list(y[out] - np.polyval(coef, x[out]))
    assert mm.loo_period_s == pytest.approx(math.sqrt(np.mean(np.square(errs))), rel=1e-9)
    assert mm.loo_period_s > 1e-3
    assert max(mm.loo_angles_deg.values()) < 1e-8  # the angles do not change


def test_three_cycles_refuse_the_quadratic(tmp_path):
    """3 blades: a quadratic in one factor leaves no residual degree of freedom (refused), the
    linear one is used; in two factors even the linear model is refused."""
    one = _write_motion(tmp_path / "one", [(18.0,), (25.0,), (32.0,)])
    with pytest.raises(SpecError, match="3 cycles at 3 blade.*quadratic motion model"):
        load_motion_model(one, space=SPACE1, model="quadratic")
    mm = load_motion_model(one, space=SPACE1)  # auto
    assert mm.model == "linear" and mm.term_names == ("1", "stiffness_kN_per_m")
    two = _write_motion(tmp_path / "two", [(18.0, 0.05), (32.0, 0.05), (25.0, 0.08)])
    with pytest.raises(SpecError, match="even the linear motion model") as err:
        load_motion_model(two, space=SPACE2)
    assert err.value.file == str(two)
    with pytest.raises(SpecError, match="cannot fit the quadratic"):
        load_motion_model(two, space=SPACE2, model="quadratic")
    # a blade repeated (two trials) adds no information about the shape
    rep = _write_motion(tmp_path / "rep", [(18.0,), (18.0,), (32.0,), (32.0,)])
    with pytest.raises(SpecError, match="cannot fit the quadratic"):
        load_motion_model(rep, space=SPACE1, model="quadratic")
    # the file's model: key is used, the argument overrides it
    forced = _write_motion(tmp_path / "forced", GRID, model="linear")
    assert load_motion_model(forced, space=SPACE2).model == "linear"
    assert load_motion_model(forced, space=SPACE2, model="auto").model == "quadratic"


@pytest.mark.parametrize("fmt", ["yaml", "csv"])
def test_motion_file_errors_name_file_row_and_field(tmp_path, fmt):
    blades = [(18.0, 0.05), (25.0, 0.065), (32.0, 0.08)]
    cases = [
        ({1: {"width_m": None}}, SpecError, "row 2, width_m: missing factor 'width_m'"),
        ({2: {"toe_length_m": 0.2}}, SpecError, "row 3, toe_length_m: unknown factor"),
        ({0: {"gait": "nope.csv"}}, InputFileError, "row 1, gait: no such file 'nope.csv'"),
        ({0: {"stiffness_kN_per_m": "stiff"}}, SpecError, "row 1, stiffness_kN_per_m: 'stiff'"),
        ({1: {"trial": "cycle_0.csv"}}, SpecError, "row 2, gait/trial: .*not both"),
        ({2: {"leg": "left"}}, SpecError, "row 3, leg: 'leg' applies to a 'trial' entry"),
    ]
    for i, (extra, exc, msg) in enumerate(cases):
        ex = {r: {k: v for k, v in e.items() if v is not None} for r, e in extra.items()}
        path = _write_motion(tmp_path / f"c{i}", blades, fmt=fmt, extra=ex)
        if fmt == "yaml" and None in [v for e in extra.values() for v in e.values()]:
            data = yaml.safe_load(path.read_text())
            for r, e in extra.items():
                for k, v in e.items():
                    if v is None:
                        del data["cycles"][r][k]
            path.write_text(yaml.safe_dump(data))
        elif fmt == "csv" and None in [v for e in extra.values() for v in e.values()]:
            df = pd.read_csv(path)
            for r, e in extra.items():
                for k, v in e.items():
                    if v is None:
                        df.loc[r, k] = np.nan
            df.to_csv(path, index=False)
        with pytest.raises(exc, match=msg) as err:
            read_motion_file(path, space=SPACE2)
        assert str(path) in str(err.value)
    with pytest.raises(InputFileError, match="no such motion file"):
        read_motion_file(tmp_path / "none.yaml")
    bad = tmp_path / "m.txt"
    bad.write_text("x")
    with pytest.raises(InputFileError, match="YAML"):
        read_motion_file(bad)


def test_trial_entry_gives_the_measured_mean_cycle(tmp_path):
    """A C3D entry: the mean cycle of the Fukuchi 3.5 m/s trial (force-plate stride 0.701 s,
    swing knee flexion above 80°), beside a gait-CSV entry."""
    run, static = FUKUCHI_RUN, FUKUCHI_STATIC
    _true_cycle(25.0).to_frame().to_csv(tmp_path / "g.csv", index=False)
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump({"cycles": [
        {"stiffness_kN_per_m": 25.0, "gait": "g.csv", "label": "centre"},
        {"stiffness_kN_per_m": 18.0, "trial": str(run), "static": str(static), "leg": "right",
         "label": "soft"},
    ]}))
    motion = read_motion_file(path, space=SPACE1)
    cycles = load_motion_cycles(motion)
    assert cycles[0].period == pytest.approx(_true_period(25.0), abs=1e-12)
    assert cycles[1].period == pytest.approx(0.701, abs=0.01)
    assert np.degrees(cycles[1].angles["knee_prosthetic"]).max() > 80
    assert cycles[1].source.startswith("row 2 (soft): ")


class _CheapEvaluator:
    """Evaluator with a motion model: responses from the predicted cycle only."""

    def __init__(self, motion):
        self.motion = motion

    def __call__(self, point):
        c = self.motion.predict_point(point)
        return {"predicted_period_s": c.period,
                "hip_range_deg": float(np.degrees(np.ptp(c.angles["hip_prosthetic"])))}


def test_run_design_records_the_motion_model(tmp_path):
    mm = load_motion_model(_write_motion(tmp_path / "m", GRID), space=SPACE2)
    res = run_design(SPACE2, runs="ccd", model="quadratic", evaluator=_CheapEvaluator(mm),
                     out_dir=tmp_path / "o", progress=False)
    table = res.table
    want = [_true_period(k, w) for k, w in zip(table["stiffness_kN_per_m"], table["width_m"],
                                               strict=True)]
    np.testing.assert_allclose(table["predicted_period_s"], want, atol=1e-12)
    saved = json.loads((tmp_path / "o" / "motion.json").read_text())
    assert saved["model"] == "quadratic" and saved["n_cycles"] == 9
    assert json.loads((tmp_path / "o" / "study.json").read_text())["motion"] == "motion.json"
    # the design report shows the motion model and its leave-one-blade-out errors
    from bladelab.report.design import design_report_sections

    section = next(s for s in design_report_sections(tmp_path / "o")
                   if s["title"] == "Design study: motion adaptation")
    errors = dict(section["tables"][0][1].to_numpy()[:, :2])
    assert errors["period"] == pytest.approx(saved["loo_period_s"], nan_ok=True)
    assert len(section["tables"][2][1]) == 9
    # the design's factors must be the motion model's: refused before any run
    space3 = DesignSpace.parse("stiffness_kN_per_m=18:32,width_m=0.05:0.08,height_m=0.4:0.48")
    with pytest.raises(SpecError, match=r"missing factor\(s\) \['height_m'\]"):
        run_design(space3, evaluator=_CheapEvaluator(mm), out_dir=tmp_path / "p",
                   progress=False)
    assert not (tmp_path / "p").exists()
    with pytest.raises(SpecError, match="unknown factor"):
        check_motion_factors(mm, ["stiffness_kN_per_m"])


def test_runner_evaluator_motion_and_gait_exclude_each_other(tmp_path):
    from bladelab.design.transfemoral import RunnerEvaluator

    path = _write_motion(tmp_path, [(18.0,), (21.5,), (25.0,), (32.0,)])
    with pytest.raises(SpecError, match="not both"):
        RunnerEvaluator(gait=str(tmp_path / "cycle_0.csv"), motion=str(path))
    ev = RunnerEvaluator(motion=str(path))  # fitted once, coded over the file's blades
    assert ev.motion.model == "quadratic" and ev.units["predicted_period_s"] == "s"
    d = ev.to_dict()
    assert d["motion"]["terms"] == ["1", "stiffness_kN_per_m", "stiffness_kN_per_m^2"]
    json.dumps(d)
    with pytest.raises(SpecError, match="motion"):
        RunnerEvaluator(motion=3.0)


def test_design_command_with_motion(tmp_path, capsys):
    """A 3-run study on the runner: each run's predicted period is the known one, and the run
    simulated the predicted cycle (the same responses as simulating it directly)."""
    from bladelab.design import generate_blade
    from bladelab.design.transfemoral import simulate_transfemoral

    motion = _write_motion(tmp_path / "m", [(18.0,), (21.5,), (25.0,), (28.5,), (32.0,)])
    runs = tmp_path / "runs.csv"
    pd.DataFrame({"stiffness_kN_per_m": [18.0, 25.0, 32.0]}).to_csv(runs, index=False)
    out = tmp_path / "study"
    args = ["design", "--factors", "stiffness_kN_per_m=18:32", "--runs", str(runs), "--model",
            "linear", "--evaluator", "runner", "--motion", str(motion), "--dt", "4e-5",
            "--objective", "avg_vx_m_per_s", "--out", str(out), "--no-figures"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "motion model: quadratic (3 terms" in text and "from 5 cycles at 5 blades" in text
    table = pd.read_csv(out / "results.csv")
    np.testing.assert_allclose(table["predicted_period_s"],
                               [_true_period(k) for k in table["stiffness_kN_per_m"]], atol=1e-9)
    saved = json.loads((out / "motion.json").read_text())
    assert saved["terms"] == ["1", "stiffness_kN_per_m", "stiffness_kN_per_m^2"]
    assert saved["loo_period_s"] < 1e-9 and set(saved["loo_angles_deg"]) == set(ANGLE_NAMES)
    ev = json.loads((out / "evaluator.json").read_text())
    assert ev["motion"]["model"] == "quadratic" and ev["dt"] == 4e-5 and ev["gait"] is None
    # run 1 simulated the predicted cycle of its blade (equal to the true one within 1e-14 rad;
    # the contact simulation turns such differences into ~1e-4 of peak force, so the direct
    # simulation uses the model's cycle)
    mm = load_motion_model(motion, space=SPACE1)
    cycle = mm.predict_point({"stiffness_kN_per_m": 18.0})
    for n in ANGLE_NAMES:
        np.testing.assert_allclose(cycle.angles[n], _true_cycle(18.0).angles[n], atol=1e-12)
    blade = generate_blade({"stiffness_kN_per_m": 18.0}, base="xtreme").model
    direct = simulate_transfemoral(blade, cycle=cycle, dt=4e-5).responses()
    row = table.iloc[0]
    for k in ("contact_time_prosthetic_s", "peak_grf_z_prosthetic_N", "knee_moment_min_Nm",
              "avg_vx_m_per_s"):
        assert row[k] == pytest.approx(direct[k], rel=1e-12, abs=1e-12), k


def test_design_command_motion_errors(tmp_path, capsys):
    """Bad motion input: exit 2, one ``error:`` line naming the problem, nothing written."""
    good = _write_motion(tmp_path / "good", [(18.0, 0.05), (25.0, 0.065), (32.0, 0.08)])
    no_width = _write_motion(tmp_path / "nw", [(18.0,), (25.0,), (32.0,)])
    extra = _write_motion(tmp_path / "ex", [(18.0, 0.05), (25.0, 0.065), (32.0, 0.08)],
                          extra={0: {"height_m": 0.44}})
    base = ["design", "--factors", "stiffness_kN_per_m=18:32,width_m=0.05:0.08", "--runs", "ccd",
            "--model", "linear", "--evaluator", "runner", "--no-figures"]
    cases = [
        (["--motion", str(tmp_path / "none.yaml")], "no such motion file"),
        (["--motion", str(no_width)], "row 1, width_m: missing factor 'width_m'"),
        (["--motion", str(extra)], "row 1, height_m: unknown factor 'height_m'"),
        (["--motion", str(good), "--gait", str(tmp_path / "good" / "cycle_0.csv")],
         "--gait/--motion: --gait (one cycle for every design) and --motion"),
        (["--motion", str(good)], "even the linear motion model"),
    ]
    for i, (more, msg) in enumerate(cases):
        out = tmp_path / f"out{i}"
        assert main([*base, "--out", str(out), *more]) == 2, msg
        err = capsys.readouterr().err
        lines = [ln for ln in err.splitlines() if ln.startswith("error:")]
        assert len(lines) == 1 and msg in lines[0] and "Traceback" not in err, err
        assert not out.exists()
    out = tmp_path / "blade"
    args = ["design", "--factors", "stiffness_kN_per_m=18:32,width_m=0.05:0.08", "--evaluator",
            "blade", "--motion", str(good), "--out", str(out)]
    assert main(args) == 2
    assert "--motion: only with --evaluator runner" in capsys.readouterr().err
    assert not out.exists()
