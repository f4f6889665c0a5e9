"""Seed 002's trends checked on a study's surfaces, and the trends section of the report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bladelab.design import central_composite, default_design_space, fit_surface, run_design
from bladelab.design.trends import (
    CEILING_MIN,
    NO_RUNNER,
    NOT_EXPLAINED,
    SEED002_TRENDS,
    SPEED_TRENDS,
    START_DECIDES,
    TREND_REASONS,
    evaluate_trends,
    trends_frame,
)
from bladelab.errors import SpecError

NAMES = ("stiffness_kN_per_m", "width_m", "height_m", "toe_length_m")


def _surfaces(coef: dict[str, tuple[float, float, float, float]], *, seed=0, noise=1e-3,
              names=NAMES):
    """Surfaces of synthetic responses y = Σ b_i·c_i + small noise on a 25-run CCD."""
    coded = central_composite(len(names)).coded
    rng = np.random.default_rng(seed)
    out = {}
    for resp, b in coef.items():
        y = coded @ np.asarray(b[:len(names)]) + noise * rng.standard_normal(len(coded))
        out[resp] = fit_surface(coded, y, factor_names=list(names), response=resp)
    return out


def _by_key(verdicts):
    return {v.key: v for v in verdicts}


HOLD = {  # each trend holds: k, w > 0 and larger than h, toe; toe raises knee, lowers clearance
    "delta_vx_m_per_s": (0.10, 0.08, 0.02, 0.01),
    "knee_moment_min_Nm": (0.0, 0.0, 0.0, 0.05),
    "swing_clearance_m": (0.0, 0.0, -0.01, -0.02),
}
REVERSED = {  # each trend reversed
    "delta_vx_m_per_s": (-0.10, -0.08, 0.02, 0.30),
    "knee_moment_min_Nm": (0.0, 0.0, 0.0, -0.05),
    "swing_clearance_m": (0.0, 0.0, -0.01, 0.02),
}


def test_all_trends_hold_on_a_table_built_to_hold():
    v = evaluate_trends(_surfaces(HOLD), evaluator="runner")
    assert [x.verdict for x in v] == ["holds"] * len(SEED002_TRENDS)
    assert all(x.reason == "" for x in v)
    k = _by_key(v)
    assert k["stiffness_increases_dvx"].estimate == pytest.approx(0.10, abs=2e-3)
    assert k["stiffness_increases_dvx"].p_value < 1e-6


@pytest.mark.parametrize("evaluator", ["runner", "collocation", None])
def test_reversed_trends_do_not_hold_with_the_reason(evaluator):
    v = _by_key(evaluate_trends(_surfaces(REVERSED), evaluator=evaluator))
    for t in SEED002_TRENDS:
        assert v[t.key].verdict == "does not hold", t.key
        assert v[t.key].reason == TREND_REASONS.get((str(evaluator), t.key), NOT_EXPLAINED)
    assert "reversed" in v["stiffness_increases_dvx"].evidence
    if evaluator is None:
        assert all(x.reason == NOT_EXPLAINED for x in v.values())
    if evaluator == "collocation":  # the predicted strides' scatter, for every trend
        assert all("local optimum" in x.reason for x in v.values())


@pytest.mark.parametrize("table", [HOLD, REVERSED])
def test_an_evaluator_without_a_runner_tests_no_trend(table):
    """The blade evaluator (no runner) draws no verdict, whatever its surfaces say: each trend
    is "not tested", its evidence (the blade's coefficient) kept and the reason says what the
    evaluator is, with the blade's mechanism where one is known."""
    v = _by_key(evaluate_trends(_surfaces(table), evaluator="blade"))
    judged = _by_key(evaluate_trends(_surfaces(table), evaluator="runner"))
    for t in SEED002_TRENDS:
        assert v[t.key].verdict == "not tested", t.key
        assert v[t.key].reason.startswith(NO_RUNNER["blade"])
        assert v[t.key].evidence.startswith(judged[t.key].evidence)
        assert v[t.key].estimate == judged[t.key].estimate or t.key == "height_toe_matter_less"
    sign = "has the seed's sign" if table is HOLD else "lacks the seed's sign"
    assert all(sign in x.evidence for x in v.values())
    if table is REVERSED:  # the blade's mechanism where its response lacks the sign
        assert "cannot push off" in v["stiffness_increases_dvx"].reason
        assert "cannot push off" in v["stiffness_increases_dvx"].mechanism
        assert NO_RUNNER["blade"] not in v["stiffness_increases_dvx"].mechanism
    else:
        assert all(x.reason == NO_RUNNER["blade"] and x.mechanism == "" for x in v.values())
    assert v["longer_toe_lowers_clearance"].reason == NO_RUNNER["blade"]


def test_no_significant_effect_does_not_hold():
    coef = dict(HOLD, delta_vx_m_per_s=(0.10, 0.0, 0.02, 0.01))
    v = _by_key(evaluate_trends(_surfaces(coef, noise=0.01), evaluator="runner"))
    w = v["width_increases_dvx"]
    assert w.verdict == "does not hold" and "no significant effect" in w.evidence
    assert w.p_value > 0.05
    # width now has the smallest effect: height/toe no longer matter less than both
    assert v["height_toe_matter_less"].verdict == "does not hold"


def test_not_estimable():
    # no clearance response, and a study without a toe-length factor
    surf = _surfaces({"delta_vx_m_per_s": (0.1, 0.08, 0.02)}, names=NAMES[:3])
    v = _by_key(evaluate_trends(surf))
    assert v["longer_toe_lowers_clearance"].verdict == "not estimable"
    assert v["height_toe_matter_less"].verdict == "not estimable"
    assert v["stiffness_increases_dvx"].verdict == "holds"
    # a model without the linear term
    coded = central_composite(4).coded
    s = fit_surface(coded, coded[:, 1] * 0.1, factor_names=list(NAMES), model="width_m",
                    response="delta_vx_m_per_s")
    v = _by_key(evaluate_trends({"delta_vx_m_per_s": s}))
    assert v["stiffness_increases_dvx"].verdict == "not estimable"
    with pytest.raises(SpecError):
        evaluate_trends(surf, alpha=1.5)


def test_a_response_held_by_every_solve_is_not_a_trend():
    """A knee-safe study holds the knee moment at >= 0 N·m in every stride: its surface is
    a bound, so the knee trend is not estimable (even where the numbers would say 'holds'),
    and the other trends are judged as before."""
    held = {"knee_moment_min_Nm": "held at or above 0 N·m"}
    v = _by_key(evaluate_trends(_surfaces(HOLD), evaluator="collocation", held=held))
    knee = v["shorter_toe_lowers_knee_margin"]
    assert knee.verdict == "not estimable" and "held at or above 0 N·m" in knee.evidence
    assert all(x.verdict == "holds" for k, x in v.items() if k != knee.key)
    assert _by_key(evaluate_trends(_surfaces(HOLD)))[knee.key].verdict == "holds"


def test_a_response_the_start_decides_leaves_its_trends_undecided():
    """Where clean strides of one design differ in Δv_x as much as the designs do (R² ceiling
    below CEILING_MIN), a significant coefficient is no verdict: 'undecided', the test's numbers
    kept, the evaluator's reason given; a ceiling at the limit or above leaves it judged."""
    below = {"delta_vx_m_per_s": CEILING_MIN - 0.01, "knee_moment_min_Nm": 0.95}
    for table, test_said in ((HOLD, "holds"), (REVERSED, "does not hold")):
        v = _by_key(evaluate_trends(_surfaces(table), evaluator="collocation-transtibial",
                                    ceilings=below))
        dvx = [x for x in v.values() if x.response == "delta_vx_m_per_s"]
        assert len(dvx) == 3 and all(x.verdict == "undecided" for x in dvx)
        assert all(f"would say '{test_said}'" in x.evidence for x in dvx)
        assert all(x.reason == TREND_REASONS[("collocation-transtibial", x.key)] for x in dvx)
        assert v["shorter_toe_lowers_knee_margin"].verdict == test_said
    at = _by_key(evaluate_trends(_surfaces(HOLD), ceilings={"delta_vx_m_per_s": CEILING_MIN}))
    assert at["stiffness_increases_dvx"].verdict == "holds"
    # no reason known for this evaluator and trend: the generic one
    clear = _by_key(evaluate_trends(_surfaces(HOLD), evaluator="collocation-transtibial",
                                    ceilings={"swing_clearance_m": 0.0}))
    assert clear["longer_toe_lowers_clearance"].reason == START_DECIDES


def test_the_performance_trends_are_read_on_the_maximum_speed_where_a_study_has_it():
    """A maximum-speed study: seed 002's performance trends also on max_speed_m_per_s (stiffer
    and wider faster here, height and toe smaller; the reversed width effect does not hold),
    and the report's trends section adds those rows only where the response exists."""
    from bladelab.report.design_trends import trends_section

    speed = {"max_speed_m_per_s": (0.05, -0.04, 0.01, 0.005), **HOLD}
    verdicts = _by_key(evaluate_trends(_surfaces(speed), evaluator="collocation",
                                       trends=SEED002_TRENDS + SPEED_TRENDS))
    assert verdicts["stiffness_raises_max_speed"].verdict == "holds"
    assert verdicts["width_raises_max_speed"].verdict == "does not hold"
    assert "reversed" in verdicts["width_raises_max_speed"].evidence
    assert verdicts["height_toe_matter_less_speed"].verdict == "holds"
    rows = trends_section(_surfaces(speed), {"evaluator": "collocation"})["tables"][0][1]
    assert (rows["response"] == "max_speed_m_per_s").sum() == len(SPEED_TRENDS)
    plain = trends_section(_surfaces(HOLD), {"evaluator": "collocation"})["tables"][0][1]
    assert len(plain) == len(SEED002_TRENDS)


def test_roles_map_other_factor_names():
    names = ("k", "w", "h", "toe")
    surf = _surfaces(HOLD, names=names)
    v = evaluate_trends(surf, roles={"stiffness": "k", "width": "w", "height": "h",
                                     "toe_length": "toe"})
    assert all(x.verdict == "holds" for x in v)
    frame = trends_frame(v)
    assert list(frame.columns) == ["trend", "response", "verdict", "evidence", "test", "reason",
                                   "mechanism"]


def test_report_has_the_trends_section(tmp_path):
    from bladelab.report.design import build_design_report, design_report_sections

    space = default_design_space()
    mid = {n: 0.5 * (space.factor(n).low + space.factor(n).high) for n in NAMES}
    half = {n: 0.5 * (space.factor(n).high - space.factor(n).low) for n in NAMES}

    def evaluator(point):
        c = np.array([(point[n] - mid[n]) / half[n] for n in NAMES])
        return {r: float(np.dot(b, c) + 1e-3 * np.sin(7 * c.sum() + i + c[0]))
                for i, (r, b) in enumerate(REVERSED.items())}

    out = tmp_path / "ds"
    run_design(space, runs="ccd", evaluator=evaluator, out_dir=out, objective="delta_vx_m_per_s",
               progress=False)
    (out / "evaluator.json").write_text(json.dumps({"evaluator": "runner"}))
    sections = design_report_sections(out)
    assert sections[0]["text"].startswith("Each run is one transfemoral gait cycle")
    trend = [s for s in sections if s["title"] == "Seed 002 trends"]
    assert len(trend) == 1
    table = trend[0]["tables"][0][1]
    assert set(table["verdict"]) == {"does not hold"}
    index = build_design_report(out)
    html = index.read_text(encoding="utf-8")
    assert "Seed 002 trends" in html and "does not hold" in html
    assert "open-loop" in html  # the kinematics-driven runner's stiffness reason
    # the same study from an evaluator with no runner: no verdict, and the section says why
    (out / "evaluator.json").write_text(json.dumps({"evaluator": "blade"}))
    section = next(s for s in design_report_sections(out) if s["title"] == "Seed 002 trends")
    assert "has no runner" in section["text"] and "not a verdict" in section["text"]
    table = section["tables"][0][1]  # what the evaluator is is said once, not per row
    assert "verdict" not in table and not table["the blade's mechanism"].str.contains(
        "has no runner").any()
    assert "cannot push off" in table["the blade's mechanism"].iloc[0]


def test_shipped_example_draws_no_trend_verdict(tmp_path):
    """The demo's design example (25-run CCD, blade evaluator: no runner) says what its
    evaluator is and draws no verdict on seed 002's trends, in its printed lines and in its
    report, which still gives the blade's own evidence."""
    from bladelab.demo import design_example
    from bladelab.report.design import design_report_sections

    report, lines = design_example(tmp_path / "design-study")
    text = "\n".join(lines)
    assert "no runner" in text and "not tested" in text
    assert not any(w in text for w in ("holds", "does not hold"))
    assert "Seed 002 trends" in report.read_text(encoding="utf-8")
    section = next(s for s in design_report_sections(tmp_path / "design-study")
                   if s["title"] == "Seed 002 trends")
    first = design_report_sections(tmp_path / "design-study")[0]["text"]
    assert first.startswith("Each run is the generated blade alone")
    assert "a 76 kg point mass" in first and "at 8 m/s" in first and "no runner" in first
    table = section["tables"][0][1]
    assert len(table) == len(SEED002_TRENDS)
    assert "not tested" in section["tables"][0][0] and "verdict" not in table
    assert all("per coded unit" in e or "main-effect ranges" in e for e in table["evidence"])


def _keys(statements):
    by_statement = {t.statement: t.key for t in SEED002_TRENDS}
    return [by_statement[s] for s in statements]


def test_the_demo_renders_the_committed_predicted_design_study(tmp_path):
    """The demo's predicted-gait design example rebuilds the committed transtibial study's
    report from its files (no solve): its first section says what each run is, and every run's
    stride file is found and checked; without the study (an installed wheel) it says so."""
    from bladelab.demo import PREDICTED_DESIGN_STUDY, predicted_design_example
    from bladelab.report.design import design_report_sections

    study = Path(__file__).resolve().parents[1] / PREDICTED_DESIGN_STUDY
    report, lines = predicted_design_example(tmp_path / "report", study=study)
    assert report is not None and report.is_file() and "J/(kg·m)" in lines[1]
    sections = design_report_sections(study)
    assert sections[0]["text"].startswith("Each run is a predicted transtibial stride at 4 m/s")
    strides = next(s for s in sections if s["title"] == "Design study: predicted strides")
    assert "stride files were not found" not in strides["text"]
    # each stride against people's running: the count met and the names missed add up, and
    # the sentence counts what the table lists
    runs = strides["tables"][-1][1]
    met = runs["criteria of people's running met"].str.split(" of ", expand=True).astype(int)
    outside = runs["outside people's running"].map(lambda t: [n for n in t.split("; ") if n])
    assert (met[0] + outside.map(len) == met[1]).all() and (met[1] == 14).all()
    for name in {n for names in outside for n in names}:
        assert f"{name} by {sum(name in names for names in outside)}" in strides["text"]
    # its settling passes recorded every response, the loads too: each has a start spread
    spread = next(s for s in sections if s["title"] == "Design study: what the solver's start "
                  "decides")
    assert {"cost_of_transport_J_per_kg_m", "socket_moment_max_Nm"} <= set(
        spread["tables"][0][1]["response"])
    assert "No spread of" not in spread["text"]
    # its trends carry the transtibial runner's reasons, not the transfemoral studies'
    trends = next(s for s in sections if s["title"] == "Seed 002 trends")
    table, notes = trends["tables"][0][1], trends["tables"][1][1].set_index("note")["reason"]
    failed = table[table["verdict"].isin(["does not hold", "undecided"])]
    assert len(failed) and all(
        notes[note] == TREND_REASONS.get(("collocation-transtibial", key), START_DECIDES)
        for note, key in zip(failed["reason"], _keys(failed["trend"]), strict=True))
    # Δv_x is a feature of the kept optimum there (its start-spread ceiling below the limit)
    assert set(table.loc[table["response"] == "delta_vx_m_per_s", "verdict"]) == {"undecided"}
    assert notes.is_unique  # a reason shared by two trends is written once
    none, said = predicted_design_example(tmp_path / "r2", study=tmp_path / "nowhere")
    assert none is None and "not found" in said[0]


def test_the_report_names_the_athlete_and_the_mesh_of_a_predicted_study(tmp_path):
    """A study of a scaled athlete says so in its first sentence, with its mesh."""
    import json
    import shutil

    from bladelab.demo import PREDICTED_DESIGN_STUDY
    from bladelab.report.design import design_report_sections

    study = tmp_path / "study"
    shutil.copytree(Path(__file__).resolve().parents[1] / PREDICTED_DESIGN_STUDY, study)
    first = design_report_sections(study)[0]["text"]
    assert "50 mesh intervals" in first and "the athlete" not in first
    evaluator = json.loads((study / "evaluator.json").read_text())
    evaluator["athlete"] = {"muscle_strength": 1.5, "prosthesis_extra_length_m": 0.045}
    (study / "evaluator.json").write_text(json.dumps(evaluator))
    first = design_report_sections(study)[0]["text"]
    assert ("the athlete: muscle strength ×1.5, prosthetic leg 4.5 cm longer, 50 mesh "
            "intervals") in first
