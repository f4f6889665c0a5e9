"""run_design with a cheap analytic evaluator: files, surfaces, optimum, resume, refusals."""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest

from bladelab.design.plots import contour_plot, main_effects_plot, save_figure
from bladelab.design.space import default_design_space
from bladelab.design.study import run_design
from bladelab.errors import DataError, SpecError

SPACE = default_design_space()


def _evaluator(point):
    c = SPACE.code([point[n] for n in SPACE.names])
    k, w, h, t = c
    return {
        "delta_vx_m_per_s": 0.2 + 0.08 * k + 0.05 * w + 0.01 * h - 0.02 * k**2 + 0.01 * k * w,
        "knee_moment_min_Nm": 10.0 + 25.0 * t - 3.0 * k,
        "clearance_min_m": 0.04 - 0.03 * t - 0.005 * t**2,
    }


class _Crash(Exception):
    pass


def test_run_design_fits_surfaces_and_finds_the_optimum(tmp_path):
    res = run_design(
        SPACE, runs="ccd", evaluator=_evaluator, out_dir=tmp_path, seed=3,
        objective="delta_vx_m_per_s", constraints={"knee_moment_min_Nm": 0.0,
                                                   "clearance_min_m": 0.02},
        units={"delta_vx_m_per_s": "m/s"}, progress=False,
    )
    assert res.design.n_runs == 25 and res.n_evaluated == 25
    for f in ("study.json", "results.csv", "surfaces.json", "coefficients.csv", "anova.csv",
              "optimum.json", "estimability.json"):
        assert (tmp_path / f).is_file()
    table = pd.read_csv(tmp_path / "results.csv")
    assert len(table) == 25 and "width_m_coded" in table
    s = res.surfaces["delta_vx_m_per_s"]
    coef = dict(zip(s.term_names, s.coef, strict=True))
    assert coef["stiffness_kN_per_m"] == pytest.approx(0.08, abs=1e-10)
    assert coef["stiffness_kN_per_m^2"] == pytest.approx(-0.02, abs=1e-10)
    # the optimum: k and w high (k² term: d/dk = 0.08 - 0.04k + 0.01w > 0 on the box), toe
    # length between the knee (t >= (3k - 10)/25) and clearance (t <= ~0.64) limits
    opt = res.optimum
    assert opt is not None and res.optimum_error is None
    assert opt.coded["stiffness_kN_per_m"] == pytest.approx(1.0, abs=1e-6)
    assert opt.coded["width_m"] == pytest.approx(1.0, abs=1e-6)
    assert opt.constraints["knee_moment_min_Nm"]["slack"] >= -1e-6
    assert opt.constraints["clearance_min_m"]["slack"] >= -1e-6
    assert opt.point["stiffness_kN_per_m"] == pytest.approx(32.0, abs=1e-5)
    saved = json.loads((tmp_path / "optimum.json").read_text())
    assert saved["objective"] == "delta_vx_m_per_s"
    assert res.to_dict()["design"]["n_runs"] == 25
    assert set(res.coefficients()["response"]) == set(res.responses)

    figs = tmp_path / "figs"
    fig = main_effects_plot(list(res.surfaces.values()), SPACE)
    assert fig.axes[0].get_xlabel() == "vertical stiffness [kN/m]"
    assert fig.axes[0].get_ylabel() == "delta_vx_m_per_s [m/s]"
    save_figure(fig, figs / "main_effects.png")
    from bladelab.design.optimum import SurfaceConstraint

    cons = [SurfaceConstraint(res.surfaces["knee_moment_min_Nm"], 0.0),
            SurfaceConstraint(res.surfaces["clearance_min_m"], 0.02)]
    fig2 = contour_plot(s, SPACE, x="stiffness_kN_per_m", y="toe_length_m", constraints=cons,
                        optimum=opt)
    assert fig2.axes[0].get_ylabel() == "toe length [m]"
    save_figure(fig2, figs / "contour.png")
    assert (figs / "main_effects.png").stat().st_size > 1000
    assert (figs / "contour.png").stat().st_size > 1000
    assert not list(figs.glob("*.part"))


def test_interrupted_study_resumes(tmp_path):
    calls = {"n": 0}

    def flaky(point):
        calls["n"] += 1
        if calls["n"] > 10:
            raise _Crash("power cut")
        return _evaluator(point)

    with pytest.raises(_Crash):
        run_design(SPACE, runs="bbd", evaluator=flaky, out_dir=tmp_path, progress=False)
    assert len(list((tmp_path / "runs").glob("run_*.json"))) == 10
    assert not (tmp_path / "results.csv").exists()
    calls["n"] = -100
    res = run_design(SPACE, runs="bbd", evaluator=flaky, out_dir=tmp_path, progress=False)
    assert res.n_resumed == 10 and res.n_evaluated == 15
    # the same folder with another design is refused
    with pytest.raises(SpecError, match="different design"):
        run_design(SPACE, runs="ccd", evaluator=_evaluator, out_dir=tmp_path, progress=False)


class _Named:
    """An evaluator that names its responses; ``extra`` adds one (a newer library's)."""

    def __init__(self, extra: bool):
        self.extra, self.calls = extra, 0

    @property
    def response_names(self):
        return tuple(_evaluator(SPACE.point(np.zeros(4)))) + (("added_m",) if self.extra else ())

    def __call__(self, point):
        self.calls += 1
        out = _evaluator(point)
        return {**out, "added_m": 1.0} if self.extra else out


def test_stored_runs_without_a_newer_response_are_evaluated_again(tmp_path):
    older = _Named(extra=False)
    run_design(SPACE, runs="bbd", evaluator=older, out_dir=tmp_path, progress=False)
    again = run_design(SPACE, runs="bbd", evaluator=older, out_dir=tmp_path, progress=False)
    assert again.n_resumed == 25 and older.calls == 25  # read back, not evaluated
    newer = _Named(extra=True)
    res = run_design(SPACE, runs="bbd", evaluator=newer, out_dir=tmp_path, progress=False)
    assert res.n_resumed == 0 and res.n_evaluated == 25 and newer.calls == 25
    assert "added_m" in pd.read_csv(tmp_path / "results.csv")
    run = json.loads((tmp_path / "runs" / "run_0001.json").read_text())
    assert run["responses"]["added_m"] == 1.0


def test_refusals_before_and_during_evaluation(tmp_path):
    runs = tmp_path / "nine.csv"
    rng = np.random.default_rng(0)
    pts = SPACE.decode(rng.choice([-1.0, 0.0, 1.0], size=(9, 4)))
    pd.DataFrame(pts, columns=list(SPACE.names)).to_csv(runs, index=False)
    called = []
    with pytest.raises(SpecError, match="9 runs cannot estimate the 15-term model"):
        run_design(SPACE, runs=runs, evaluator=lambda p: called.append(p) or {"y": 1.0},
                   out_dir=tmp_path / "o", progress=False)
    assert not called  # refused before any (expensive) evaluation

    def bad(point):
        return {"y": float("nan")}

    with pytest.raises(DataError, match="run 25"):  # the centre, evaluated first
        run_design(SPACE, evaluator=bad, out_dir=tmp_path / "p", progress=False)
    with pytest.raises(SpecError, match="unknown response"):
        run_design(SPACE, evaluator=_evaluator, out_dir=tmp_path / "q", objective="speed",
                   progress=False)


def test_runs_are_evaluated_from_the_centre_outwards(tmp_path):
    """So that an evaluator warm-starting from solved neighbours always has a near one."""
    space = default_design_space()
    seen = []

    def recording(point):
        seen.append(space.code([point[n] for n in space.names]))
        return _evaluator(point)

    res = run_design(space, runs="ccd", evaluator=recording, out_dir=tmp_path, progress=False)
    norms = np.linalg.norm(np.array(seen), axis=1)
    assert norms[0] == pytest.approx(0.0, abs=1e-12)  # the centre first
    assert np.all(np.diff(norms) >= -1e-9)  # then the axial points, then the corners
    assert len(seen) == res.design.n_runs == 25
    assert np.allclose(np.sort(np.array(seen), axis=0), np.sort(res.design.coded, axis=0))


class _Prepared(_Named):
    """An evaluator with a ``prepare`` step (the collocation evaluator's start continuation)."""

    def __init__(self):
        super().__init__(extra=False)
        self.prepared = []

    def prepare(self, point, progress=True):
        assert self.calls == 0  # before any run
        self.prepared.append(SPACE.code([point[n] for n in SPACE.names]))


def test_an_evaluator_is_prepared_with_the_first_run_before_the_runs(tmp_path):
    ev = _Prepared()
    run_design(SPACE, runs="ccd", evaluator=ev, out_dir=tmp_path, progress=False)
    assert len(ev.prepared) == 1 and np.allclose(ev.prepared[0], 0.0)  # the centre, once
    assert ev.calls == 25
    run_design(SPACE, runs="ccd", evaluator=ev, out_dir=tmp_path, progress=False)
    assert len(ev.prepared) == 1  # every run stored: nothing to prepare


def _no_gait_at_short_toe(point):
    """The analytic evaluator, failing (as a solve with no clean stride does) at the two
    corners with the shortest toe, the lowest stiffness and the narrowest blade."""
    from bladelab.errors import OptimizationError

    c = SPACE.code([point[n] for n in SPACE.names])
    if c[0] < -0.5 and c[1] < -0.5 and c[3] < -0.5:
        raise OptimizationError("no clean stride for this blade", where="test evaluator")
    return _evaluator(point)


@pytest.mark.parametrize("jobs", [1, 2])
def test_failed_runs_are_recorded_and_skipped_on_request(tmp_path, jobs):
    """Without skip_failed a failed run stops the study (its reason recorded); with it the
    surfaces are fitted to the 23 runs that finished, failed.csv names the 2 others, and the
    next call does not evaluate them again; once they succeed the record is gone."""
    from bladelab.errors import BladelabError

    with pytest.raises(BladelabError, match="no clean stride") as err:
        run_design(SPACE, evaluator=_no_gait_at_short_toe, out_dir=tmp_path, progress=False,
                   jobs=jobs)
    assert "run " in str(err.value) and not (tmp_path / "results.csv").exists()
    assert len(list((tmp_path / "runs").glob("*.failed.json"))) >= 1
    res = run_design(SPACE, evaluator=_no_gait_at_short_toe, out_dir=tmp_path, progress=False,
                     jobs=jobs, skip_failed=True, objective="delta_vx_m_per_s")
    failed = {r for r, c in enumerate(res.design.coded, 1)
              if c[0] < -0.5 and c[1] < -0.5 and c[3] < -0.5}
    assert set(res.failed) == failed and len(failed) == 2
    assert all("no clean stride" in why for why in res.failed.values())
    table = pd.read_csv(tmp_path / "results.csv")
    assert len(table) == 23 and not set(table["run"]) & failed
    listed = pd.read_csv(tmp_path / "failed.csv")
    assert set(listed["run"]) == failed and "error" in listed.columns
    surface = res.surfaces["delta_vx_m_per_s"]
    assert len(surface.y) == 23
    assert surface.r2 == pytest.approx(1.0)  # the analytic response is quadratic
    calls = []

    def counting(point):
        calls.append(point)
        return _no_gait_at_short_toe(point)

    again = run_design(SPACE, evaluator=counting, out_dir=tmp_path, progress=False,
                       skip_failed=True)
    assert not calls and set(again.failed) == failed  # recorded failures are not retried
    if jobs == 1:  # the report names them
        from bladelab.report.design import design_report_sections

        sections = {x["title"]: x for x in design_report_sections(tmp_path)}
        gone = sections["Design study: runs without a result"]
        assert set(dict(gone["tables"])["Failed runs"]["run"]) == failed
        assert "25 runs (ccd design; 2 failed" in sections[
            "Design study: response surfaces"]["text"]
        levels = dict(gone["tables"])["Failed runs per factor level"]
        short = levels[(levels["factor"] == "toe_length_m") & (levels["coded level"] == -1)]
        assert short[["runs", "failed"]].values.tolist() == [[9, 2]]
        assert levels.loc[levels["factor"] == "height_m", "failed"].tolist() == [1, 0, 1]
    fixed = run_design(SPACE, evaluator=_evaluator, out_dir=tmp_path, progress=False)
    assert fixed.n_evaluated == 2 and not fixed.failed
    assert not (tmp_path / "failed.csv").exists()
    assert not list((tmp_path / "runs").glob("*.failed.json"))


def test_too_many_failed_runs_cannot_fit_the_model(tmp_path):
    def mostly_failing(point):
        from bladelab.errors import OptimizationError

        if SPACE.code([point[n] for n in SPACE.names])[0] != 0.0:
            raise OptimizationError("no stride", where="test evaluator")
        return _evaluator(point)

    with pytest.raises(SpecError, match="runs failed .* cannot fit the model"):
        run_design(SPACE, evaluator=mostly_failing, out_dir=tmp_path, progress=False,
                   skip_failed=True)


def test_contours_cross_out_runs_without_a_result(tmp_path):
    res = run_design(SPACE, evaluator=_evaluator, out_dir=tmp_path, progress=False)
    surface = res.surfaces["delta_vx_m_per_s"]
    fig = contour_plot(surface, SPACE, x="stiffness_kN_per_m", y="toe_length_m",
                       missing=res.design.coded[:2], missing_label="failed runs (projected)")
    ax = fig.axes[0]
    crosses = [ln for ln in ax.get_lines() if ln.get_label() == "failed runs (projected)"]
    assert len(crosses) == 1 and len(crosses[0].get_xdata()) == 2
    assert crosses[0].get_xdata()[0] == pytest.approx(
        SPACE.point(res.design.coded[0])["stiffness_kN_per_m"])
    plain = contour_plot(surface, SPACE, x="stiffness_kN_per_m", y="toe_length_m")
    assert not [ln for ln in plain.axes[0].get_lines() if "failed" in ln.get_label()]


class _Described:
    """A cheap evaluator with settings (as the built-in ones write to evaluator.json)."""

    LEGACY_SETTINGS = {"body": "seed001"}

    def __init__(self, **settings):
        self.settings = settings

    def to_dict(self):
        return dict(self.settings)

    def __call__(self, point):
        return _evaluator(point)


def test_a_study_resumes_only_with_the_evaluator_that_made_its_runs(tmp_path):
    """Finished runs are reused only by the evaluator that made them: another setting is
    refused naming it (where results are kept may change); a setting the study's file predates
    counts as the evaluator's legacy value."""
    run_design(SPACE, evaluator=_Described(speed_mps=4.0, solutions_dir="a", body="human"),
               out_dir=tmp_path, progress=False)
    with pytest.raises(SpecError, match=r"another evaluator \(speed_mps: 4.0 -> 5.0\)"):
        run_design(SPACE, evaluator=_Described(speed_mps=5.0, solutions_dir="a", body="human"),
                   out_dir=tmp_path, progress=False)
    res = run_design(SPACE, evaluator=_Described(speed_mps=4.0, solutions_dir="b",
                                                 body="human"),
                     out_dir=tmp_path, progress=False)
    assert res.n_resumed == res.design.n_runs
    (tmp_path / "evaluator.json").write_text(json.dumps({"speed_mps": 4.0}))  # before bodies
    with pytest.raises(SpecError, match="body: 'seed001' -> 'human'"):
        run_design(SPACE, evaluator=_Described(speed_mps=4.0, body="human"), out_dir=tmp_path,
                   progress=False)
    (tmp_path / "evaluator.json").write_text(json.dumps({"speed_mps": 4.0}))
    again = run_design(SPACE, evaluator=_Described(speed_mps=4.0, body="seed001"),
                       out_dir=tmp_path, progress=False)
    assert again.n_resumed == again.design.n_runs


def test_the_report_names_the_best_run_and_cautions_an_unpredictive_optimum(tmp_path):
    """Beside the surface's optimum the report gives the best run measured, and where the
    surface predicts its response poorly (R²pred below 0.5) it says the optimum is the fit's."""
    from bladelab.report.design import design_report_sections

    rng = np.random.default_rng(7)
    noise = {}

    def noisy(point):
        key = tuple(point[n] for n in SPACE.names)
        noise.setdefault(key, float(rng.normal(0.0, 0.05)))
        return {**_evaluator(point), "noisy_m_per_s": 0.2 + noise[key]}

    for objective, cautioned in (("delta_vx_m_per_s", False), ("noisy_m_per_s", True)):
        out = tmp_path / objective
        res = run_design(SPACE, evaluator=noisy, out_dir=out, objective=objective,
                         units={objective: "m/s"}, progress=False)
        assert (res.surfaces[objective].r2_pred < 0.5) == cautioned
        table = pd.read_csv(out / "results.csv")
        best = table.loc[table[objective].idxmax()]
        text = {s["title"]: s for s in design_report_sections(out)}[
            "Design study: optimum"]["text"]
        assert text.startswith(f"Maximising {objective}: the surface predicts")
        # an optimum on a corner of the box is that run's own design, and the text says so
        assert re.search(rf"The best run measured: run {int(best['run'])}, "
                         rf"{re.escape(f'{best[objective]:.4g}')}(\.| \(the optimum's own "
                         r"design\)\.)", text)
        assert "  " not in text  # no unit known to the report: none printed
        assert ("Caution: the surface predicts" in text) == cautioned


def test_a_response_the_same_in_every_run_is_named_not_fitted():
    import pandas as pd

    from bladelab.report.design import _constant_responses

    class Fit:
        unit = "m/s"

    table = pd.DataFrame({"avg_vx_m_per_s": [4.0, 4.0 + 1e-13, 4.0 - 2e-13],
                          "delta_vx_m_per_s": [0.10, 0.12, 0.11],
                          "missing": [1.0, float("nan"), 1.0]})
    surfaces = {"avg_vx_m_per_s": Fit(), "delta_vx_m_per_s": Fit(), "missing": Fit(),
                "not_in_the_table": Fit()}
    constant = _constant_responses(table, surfaces)
    assert list(constant) == ["avg_vx_m_per_s", "missing"]
    assert constant["avg_vx_m_per_s"] == pytest.approx(4.0)
