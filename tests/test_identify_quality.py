"""Quality flags of one identification (bladelab.identify.quality) and their storage."""

from __future__ import annotations

import sqlite3

import pytest

from bladelab.identify.quality import QUALITY_COLUMNS, QualityThresholds, assess_quality
from bladelab.study.store import ResultsStore

GOOD = dict(
    estimate={"K": 18.0, "D": 0.30}, bounds={"K": (8.0, 40.0), "D": (0.01, 1.0)},
    ci={"K": (17.5, 18.6), "D": (0.27, 0.33)}, ci_open={"K": False, "D": False},
    correlation=-0.2, converged=True, nrmse_grf_pct=8.0, nrmse_distance_pct=4.0,
    peak_force_measured_N=2400.0, peak_force_simulated_N=2450.0,
)


def test_a_good_identification_is_not_flagged():
    q = assess_quality(**GOOD)
    assert not q.flagged and q.reasons == ()
    assert q.ci_halfwidth_pct["K"] == pytest.approx(100 * 0.55 / 18.0)
    assert q.peak_force_mismatch_pct == pytest.approx(100 * 50 / 2400)
    row = q.to_row()
    assert set(row) == set(QUALITY_COLUMNS) and row["flagged"] == 0 and row["converged"] == 1


@pytest.mark.parametrize(("change", "words"), [
    ({"converged": False}, "not converged"),
    ({"estimate": {"K": 18.0, "D": 0.0101}}, "D* at the lower search bound"),
    ({"ci": {"K": (17.5, 18.6), "D": (0.01, 0.9)}}, "D CI half-width"),
    ({"ci_open": {"K": True, "D": False}}, "CI of K reaches a search bound"),
    ({"correlation": -0.97}, "K–D compensation"),
    ({"nrmse_grf_pct": 35.0}, "poor fit: nRMSE GRF"),
    ({"peak_force_simulated_N": 4080.0}, "peak force 4080 N simulated vs 2400 N measured (+70 %"),
])
def test_each_criterion_flags_with_its_reason(change, words):
    q = assess_quality(**{**GOOD, **change})
    assert q.flagged
    assert any(words in r for r in q.reasons), q.reasons
    assert q.to_row()["flagged"] == 1 and words in q.to_row()["flags"]


def test_thresholds_are_parameters():
    loose = QualityThresholds(max_peak_mismatch_pct=80.0)
    assert not assess_quality(**{**GOOD, "peak_force_simulated_N": 4080.0}, thresholds=loose).flagged


def test_an_old_results_database_gains_the_quality_columns(tmp_path):
    db = tmp_path / "results.sqlite"
    con = sqlite3.connect(db)
    con.execute("CREATE TABLE results (trial_id TEXT NOT NULL, variant TEXT NOT NULL, "
                "status TEXT NOT NULL, K_Nm_per_deg REAL, PRIMARY KEY (trial_id, variant))")
    con.execute("INSERT INTO results VALUES ('t1', 'linear', 'ok', 18.0)")
    con.commit()
    con.close()
    with ResultsStore(db) as store:
        store.write({"trial_id": "t2", "variant": "linear", "status": "ok", "K_Nm_per_deg": 17.0,
                     **assess_quality(**GOOD).to_row()})
        df = store.table().set_index("trial_id")
    assert set(QUALITY_COLUMNS) <= set(df.columns)
    assert df.loc["t2", "flagged"] == 0 and df.loc["t1", "flagged"] != df.loc["t1", "flagged"]
