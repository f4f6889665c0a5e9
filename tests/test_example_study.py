"""The example-study generator: the cohort design, ground truth, determinism, caching, C3D output."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import yaml

from bladelab.example.study import (
    GROUND_TRUTH,
    is_complete,
    make_example_study,
    plan_trials,
    read_ground_truth,
)
from bladelab.study import load_study
from bladelab.study.tasks import read_trial_stance
from bladelab.trial import detect_stances, read_c3d


def test_the_plan_mirrors_seed_000s_cohort():
    plans = plan_trials(0)
    df = pd.DataFrame([p.to_dict() for p in plans])
    assert len(df) == 50 and df["trial_id"].is_unique
    tf, tt = df[df["athlete"] == "TF1"], df[df["athlete"] == "TT1"]
    assert set(tf["blade"]) == {"xceed-cat2"} and sorted(tf["configuration"].unique()) == list("ABCD")
    assert (tf["mass_kg"] == 65).all() and (tt["mass_kg"] == 76).all()
    assert sorted(tt["category"].unique()) == [4, 5, 6]
    assert tf["amputation"].eq("transfemoral").all() and tt["amputation"].eq("transtibial").all()
    # speeds: 50–70 % or 100 % of the personal best, both bands in every cell
    slow = df["speed_pct_pb"] < 90
    assert df.loc[slow, "speed_pct_pb"].between(50, 70).all()
    assert (df.loc[~slow, "speed_pct_pb"] == 100).all()
    cells = df.groupby(["blade", "configuration"], dropna=False)["speed_pct_pb"]
    assert cells.apply(lambda s: (s < 90).any() and (s >= 90).any()).all()
    # ground truth in the published ranges (seed 000 §3.3)
    assert df["K_Nm_per_deg"].between(13, 22).all()
    assert df["D_Nms_per_deg"].between(0.15, 0.5).all()
    # K rises with category, falls with speed; D higher for TT
    k_cat = df.groupby("category")["K_Nm_per_deg"].mean()
    assert list(k_cat.sort_index()) == sorted(k_cat)
    for _, sub in df.groupby("blade"):
        assert sub.loc[sub.speed_pct_pb < 90, "K_Nm_per_deg"].mean() > \
            sub.loc[sub.speed_pct_pb >= 90, "K_Nm_per_deg"].mean()
    assert tt["D_Nms_per_deg"].min() > tf["D_Nms_per_deg"].max()


def test_the_plan_is_deterministic_and_the_seed_matters():
    a = [p.to_dict() for p in plan_trials(3)]
    assert a == [p.to_dict() for p in plan_trials(3)]
    assert a != [p.to_dict() for p in plan_trials(4)]
    small = plan_trials(3, n_trials=4)
    assert len(small) == 4 and len({p.athlete for p in small}) == 2


@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    folder = tmp_path_factory.mktemp("example") / "study"
    res = make_example_study(folder, seed=0, n_trials=2, jobs=1, progress=False)
    return res


def test_a_small_study_is_written_completely(small_study):
    folder = small_study.folder
    assert small_study.generated and small_study.n_trials == 2
    study, _ = load_study(folder)  # the study developer's schema validates it
    assert len(study.trials) == 2
    gt = read_ground_truth(folder)
    assert list(gt["trial_id"]) == [t.id for t in study.trials]
    assert is_complete(folder, seed=0, n_trials=2)
    assert not is_complete(folder, seed=1, n_trials=2)
    raw = yaml.safe_load((folder / "study.yaml").read_text())
    assert all(t["file"].endswith(".c3d") for t in raw["trials"])
    assert (folder / GROUND_TRUTH).read_text().startswith("# bladelab example study")
    # the stiffening hinge: τ/q = K (1 + 0.15 |q| / 20°) at the peak deflection
    expect = gt["K_Nm_per_deg"] * (1 + 0.15 * gt["min_deflection_deg"].abs() / 20.0)
    np.testing.assert_allclose(gt["K_secant_peak_Nm_per_deg"], expect, rtol=1e-3)
    assert (gt["K_secant_peak_Nm_per_deg"] > gt["K_Nm_per_deg"] * 1.05).all()


def test_trials_read_back_through_the_trial_pipeline_like_their_truth(small_study):
    folder = small_study.folder
    gt = read_ground_truth(folder).set_index("trial_id")
    for tid, row in gt.iterrows():
        trial = read_c3d(folder / "trials" / f"{tid}.c3d")
        assert trial.marker_rate == 100.0 and trial.platforms[0].rate == 1000.0
        assert {"CLAMP_ANT", "CLAMP_POST", "BLADE_TIP"} <= set(trial.markers)
        assert trial.metadata["athlete"] == row["athlete"]
        assert len(detect_stances(trial)) == 1
        # contact time and peak force in the file match the simulation's truth
        fz = sum(p.force[:, 2] for p in trial.platforms)
        on = np.flatnonzero(fz > 50.0)
        assert (on[-1] - on[0] + 1) / 1000.0 == pytest.approx(row["contact_time_s"], abs=0.004)
        assert fz.max() == pytest.approx(row["peak_grf_z_N"], rel=0.05)
        stance = read_trial_stance(str(folder / "trials" / f"{tid}.c3d"), 1)
        # published ranges (DESIGN.md): peak GRF 1.5–3 kN, compression and deflection
        assert 1400 < stance.grf_z.max() < 3200
        d0 = stance.metadata["d0_m"]
        assert 0.03 < d0 - stance.distance.min() < 0.11
        # mid-stance the clamp moves forward slower than the runner (it pivots over the sole)
        assert np.ptp(stance.clamp_x) / np.ptp(stance.time) < row["speed_mps"]


def test_a_complete_study_is_reused_and_force_regenerates_identically(small_study):
    folder = small_study.folder
    before = {p.name: read_c3d(p).markers["BLADE_TIP"] for p in (folder / "trials").glob("*.c3d")}
    again = make_example_study(folder, seed=0, n_trials=2, jobs=1, progress=False)
    assert not again.generated
    forced = make_example_study(folder, seed=0, n_trials=2, jobs=1, force=True, progress=False)
    assert forced.generated
    for name, tip in before.items():
        np.testing.assert_array_equal(read_c3d(folder / "trials" / name).markers["BLADE_TIP"], tip)


def test_cli_example_make_and_its_errors(small_study, tmp_path, capsys):
    from bladelab.cli import main

    # a complete study is reused (no simulation) and reported as such
    folder = small_study.folder
    assert main(["example", "make", str(folder), "--trials", "2", "--json"]) == 0
    assert '"generated": false' in capsys.readouterr().out
    assert main(["example", "make", str(tmp_path / "x"), "--jobs", "0"]) == 2
    err = capsys.readouterr().err
    assert "--jobs" in err and "Traceback" not in err
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    assert main(["example", "make", str(blocker), "--trials", "1", "--jobs", "1"]) == 2
    assert "not a folder" in capsys.readouterr().err
