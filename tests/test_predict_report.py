"""Predictive report sections and the Table 3.2 power table."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import bladelab.runner.predictive_report as pr
from bladelab.report import Report
from bladelab.runner import build_runner
from bladelab.runner.controller import controller_layout
from bladelab.runner.objective import ObjectiveSettings, simulate_controlled


class _FakeModel:
    kind = "able"
    total_mass = 80.0


class _FakeResult:
    model = _FakeModel()


def test_power_table_by_hand(monkeypatch):
    t = np.linspace(0.0, 2.0, 2001)
    # hip_l: +160 W for the first half of each 0.5 s stride, -80 W in the second half
    p = np.where((t % 0.5) < 0.25, 160.0, -80.0)
    pw = pd.DataFrame({"time": t, "joint": "hip_flexion_l", "power": p})
    ev = pd.DataFrame({"leg": "left", "event": "touchdown", "time": [0.0, 0.5, 1.0, 1.5, 2.0]})
    monkeypatch.setattr(pr, "joint_powers", lambda r: pw)
    monkeypatch.setattr(pr, "gait_events", lambda r: ev)
    tab = pr.power_table(_FakeResult())
    row = tab[(tab.leg == "left") & (tab.joint == "hip_flexion_l")].iloc[0]
    # mean positive power: 160 W half the time / 80 kg = 1.0 W/kg; negative -0.5 W/kg
    assert row.P_pos == pytest.approx(1.0, rel=2e-3)
    assert row.P_neg == pytest.approx(-0.5, rel=2e-3)
    tot = tab[(tab.leg == "left") & (tab.joint == "total")].iloc[0]
    assert tot.P_pos == pytest.approx(row.P_pos)


def test_report_sections_are_written(tmp_path):
    model = build_runner("amputee", blade="Cat6")
    layout = controller_layout(model)
    _, res = simulate_controlled(
        model, layout.x0, layout=layout, settings=ObjectiveSettings(duration=0.6), record_every=4
    )
    report = Report("Predictive running")
    summary = pd.DataFrame(
        {
            "category": ["Cat5", "Cat6"],
            "max_speed": [4.3, 4.6],
            "cot_4": [7.2, 6.9],
            "t200": [200 / 4.3, 200 / 4.6],
            "t400": [400 / 4.3, 400 / 4.6],
        }
    )
    pr.add_predictive_sections(report, {"amputee Cat6": res}, sweep_summary=summary)
    index = report.write(tmp_path / "report")
    html = index.read_text()
    assert "Predictive simulation: amputee Cat6" in html
    assert "Table 3.1" in html and "Joint powers" in html
