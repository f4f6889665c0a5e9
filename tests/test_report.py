"""The HTML report builder, its figures and tables (the browser check is test_report_browser.py)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bladelab.errors import DataError
from bladelab.mechanics import stance_mechanics
from bladelab.report import (
    Report,
    ReportTable,
    compressive_stiffness_curves,
    hysteresis_loops,
    mean_curve_nrmse,
    nrmse_pct,
    nrmse_table,
    parameter_bars,
    parameter_summary_display,
    stats_display,
    time_series_bands,
    trial_nrmse,
)
from bladelab.stats import compare_groups, speed_band, summarize
from bladelab.trial.stance import Stance

GROUPS = {  # group: (amputation, k [N/m], c [N·s/m], contact time [s], peak compression [m])
    "TF (Cat 2)": ("TF", 18e3, 120.0, 0.115, 0.050),
    "TT-C (Cat 4)": ("TT", 24e3, 260.0, 0.105, 0.085),
    "TT-A (Cat 5)": ("TT", 25e3, 300.0, 0.110, 0.095),
}


def _stance(rng, k, c, T, x0, *, pct, sim=False, n_pre=6, rate=1000.0):
    """A Kelvin–Voigt blade with a hardening spring, carried forward by a pitching clamp."""
    t = np.arange(-n_pre, int(T * rate) + 1) / rate
    s = np.clip(t / T, 0.0, 1.0)
    x = x0 * np.sin(np.pi * s) ** 1.3
    xdot = np.gradient(x, t)
    force = np.clip(k * x * (1 + 4 * x) + c * xdot, 0.0, None)
    if not sim:
        force = force + rng.normal(0, 15, len(t)) * (s > 0)
    theta0, length = np.deg2rad(22.0), 0.42
    theta = theta0 + x / 0.22  # rad: ~25° at 95 mm
    d = length - x
    pitch = np.deg2rad(-30 + 70 * s)
    cx, cz = d * np.sin(theta), -d * np.cos(theta)  # tip in the clamp frame
    clamp_x = 4.0 * t
    clamp_z = 0.50 - 0.3 * x
    tip_x = clamp_x + cx * np.cos(pitch) + cz * np.sin(pitch)
    tip_z = clamp_z - cx * np.sin(pitch) + cz * np.cos(pitch)
    zeros = np.zeros_like(t)
    stance = Stance(
        time=t,
        clamp_x=clamp_x,
        clamp_y=zeros,
        clamp_z=clamp_z,
        clamp_pitch=pitch,
        grf_x=0.1 * force * np.cos(np.pi * s),
        grf_y=zeros,
        grf_z=force,
        distance=d,
        metadata={"speed_pct_pb": pct},
    )
    return stance, tip_x, tip_z


def example_inputs(seed: int = 3):
    """Measured/simulated stances, mechanics and a per-trial parameter table of a small cohort."""
    rng = np.random.default_rng(seed)
    measured, simulated, mech, trials = {}, {}, {}, []
    for group, (amp, k, c, T, x0) in GROUPS.items():
        measured[group], simulated[group], mech[group] = [], [], []
        for i in range(6):
            pct = 100.0 if i % 2 == 0 else 60.0
            scale = rng.uniform(0.9, 1.1)
            m, tx, tz = _stance(rng, k * scale, c, T, x0 * scale, pct=pct)
            s, _, _ = _stance(
                rng, k * scale * 1.08, c * 0.8, T, x0 * scale * 0.96, pct=pct, sim=True
            )
            measured[group].append(m)
            simulated[group].append(s)
            mech[group].append(stance_mechanics(m, tip_x=tx, tip_z=tz, hinge=(0.03, -0.20)))
            trials.append(
                {
                    "group": group,
                    "amputation": amp,
                    "speed_pct_pb": pct,
                    "K_Nm_per_deg": k / 1500 - (1.0 if pct >= 90 else 0.0) + rng.normal(0, 0.5),
                    "D_Nms_per_deg": c / 800 + rng.normal(0, 0.03),
                }
            )
    return measured, simulated, mech, pd.DataFrame(trials)


def example_report(seed: int = 3) -> Report:
    """A report with every section kind the characterise workflow produces."""
    measured, simulated, mech, trials = example_inputs(seed)
    report = Report(
        "Blade characterisation — example",
        subtitle="Synthetic cohort (test data, not measurements)",
        settings={"identify": {"method": "pso", "particles": 20, "iterations": 30}},
        seed=seed,
    )
    grf_trials = trial_nrmse(measured, simulated, signal="grf")
    grf_mean = mean_curve_nrmse(measured, simulated, signal="grf")
    report.add_section(
        "Ground reaction force",
        text="Measured vs simulated vertical GRF, group mean ± SD.\n\nStances are normalised "
        "to 0–100 % of contact.",
        figures=[("GRF vs stance, mean ± SD", time_series_bands(measured, simulated))],
        tables=[
            (
                "nRMSE of GRF per group",
                nrmse_table(grf_trials, grf_mean, formatted=True),
            )
        ],
    )
    report.add_section(
        "Characteristic distance",
        figures=[time_series_bands(measured, simulated, signal="distance")],
    )
    trials["speed_band"] = speed_band(trials["speed_pct_pb"])
    summary = summarize(
        trials, values=["K_Nm_per_deg", "D_Nms_per_deg"], by=["group", "speed_band"]
    )
    report.add_section(
        "K* and D*",
        figures=[("K* and D* per group and speed band", parameter_bars(summary))],
        text="Bars: mean; whiskers: 95 % confidence interval of the mean (t distribution).",
        tables=[
            ReportTable(
                "K* and D* per group and speed band",
                parameter_summary_display(summary),
                "parameters-summary",
                csv=summary,
            )
        ],
    )
    report.add_section(
        "Hysteresis and compressive stiffness",
        figures=[hysteresis_loops(mech), compressive_stiffness_curves(mech)],
    )
    results = compare_groups(trials)
    report.add_section(
        "Statistics",
        text="Mann–Whitney U, Kruskal–Wallis with Dunn–Bonferroni post-hoc; α = 0.05; "
        "r = Z/√N; * significant.",
        tables=[
            ReportTable("Group comparisons", stats_display(results), "statistics", csv=results)
        ],
    )
    return report


def test_report_is_self_contained_with_csv_tables_and_settings(tmp_path: Path):
    report = example_report()
    report.add_section("Escaping", text="<script>alert(1)</script> & more")
    index = report.write(tmp_path / "report")
    assert index == tmp_path / "report" / "index.html"
    html = index.read_text(encoding="utf-8")
    imgs = re.findall(r'<img src="([^"]+)"', html)
    assert len(imgs) == 5
    assert all(src.startswith("data:image/png;base64,") for src in imgs)
    assert not re.search(r'(src|href)="(https?:|//)', html)  # nothing fetched from outside
    assert "<script>alert" not in html and "&lt;script&gt;" in html
    titles = re.findall(r'<h2><span class="num">\d+\.</span>([^<]+)</h2>', html)
    assert titles[0] == "Ground reaction force" and titles[-1] == "Settings, versions and seed"
    csvs = sorted(p.name for p in (tmp_path / "report" / "tables").glob("*.csv"))
    assert "statistics.csv" in csvs and "versions.csv" in csvs
    for name in re.findall(r'href="tables/([^"]+)"', html):
        assert (tmp_path / "report" / "tables" / name).is_file()
    stats_csv = pd.read_csv(tmp_path / "report" / "tables" / "statistics.csv")
    assert {"test", "p", "p_adjusted", "effect_size_r"} <= set(stats_csv.columns)
    settings = json.loads((tmp_path / "report" / "settings.json").read_text())
    assert settings["seed"] == 3 and settings["settings"]["identify"]["particles"] == 20
    assert "numpy" in settings["versions"]
    assert "identify.particles" in html  # flattened settings shown in the page
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp leftovers


def test_tables_with_very_long_titles_get_short_distinct_file_names(tmp_path: Path):
    """A table's CSV name stays far below the file system's 255 bytes however long its title
    (a sweep's per-category table has a 250-character title), and two long titles that
    share their first 120 characters keep apart."""
    from bladelab.report import Report
    from bladelab.report.builder import MAX_TABLE_NAME

    report = Report("long")
    head = "Blade categories: maximum speed and metabolic cost per category " * 3
    frame = pd.DataFrame({"a": [1.0]})
    report.add_section("A section with a long title as well, " * 2,
                       tables=[(head + "first", frame), (head + "second", frame)])
    html = report.write(tmp_path / "report").read_text(encoding="utf-8")
    names = [n for n in re.findall(r'href="tables/([^"]+)"', html)
             if n.startswith("a-section")]
    assert len(set(names)) == 2
    for name in names:
        assert len(name) <= MAX_TABLE_NAME + len(".csv")
        assert (tmp_path / "report" / "tables" / name).is_file()


def test_write_is_atomic_and_replaces_an_old_report(tmp_path: Path, monkeypatch):
    out = tmp_path / "report"
    Report("first").write(out)
    (out / "stale.txt").write_text("old")
    Report("second").write(out)
    assert "second" in (out / "index.html").read_text() and not (out / "stale.txt").exists()

    def boom(*args, **kwargs):
        raise OSError("disk full")

    report = Report("third")
    report.add_section("t", tables=[pd.DataFrame({"a": [1]})])
    monkeypatch.setattr(pd.DataFrame, "to_csv", boom)
    with pytest.raises(OSError, match="disk full"):
        report.write(out)
    assert "second" in (out / "index.html").read_text()  # the old report is untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


def test_nrmse_by_hand_and_seed_table_layout():
    # RMSE of [1,1,2,3] vs [0,1,2,3] = sqrt(1/4) = 0.5; range 3 -> 16.667 %.
    assert nrmse_pct(np.array([0, 1, 2, 3.0]), np.array([1, 1, 2, 3.0])) == pytest.approx(50 / 3)
    trials = pd.DataFrame(
        {
            "group": ["TF", "TF", "TT", "TT", "TT"],
            "signal": "grf",
            "nrmse_pct": [10.0, 12.0, 15.0, 17.0, 19.0],
        }
    )
    mean = pd.DataFrame({"group": ["TF", "TT"], "signal": "grf", "nrmse_pct": [6.5, 14.0]})
    num = nrmse_table(trials, mean, signal="grf")
    assert num["nrmse_trials_mean_pct"].tolist() == [11.0, 17.0]
    assert num["nrmse_trials_sd_pct"].tolist() == pytest.approx([np.sqrt(2), 2.0])
    shown = nrmse_table(trials, mean, formatted=True)
    assert shown["nRMSE [%] individual trials"].tolist() == ["11.00 ± 1.41", "17.00 ± 2.00"]
    assert shown["nRMSE [%] mean curves"].tolist() == ["6.50", "14.00"]


def test_figures_label_every_axis_with_units():
    measured, simulated, mech, trials = example_inputs()
    trials["speed_band"] = speed_band(trials["speed_pct_pb"])
    summary = summarize(
        trials, values=["K_Nm_per_deg", "D_Nms_per_deg"], by=["group", "speed_band"]
    )
    figs = [
        time_series_bands(measured, simulated),
        time_series_bands(measured, None, signal="distance"),
        hysteresis_loops(mech),
        compressive_stiffness_curves(mech),
        parameter_bars(summary),
    ]
    for fig in figs:
        for ax in (a for a in fig.axes if a.get_visible()):
            assert re.search(r"\[.+\]", ax.get_ylabel()), ax.get_ylabel()
            if ax.get_xlabel() != "group":
                assert re.search(r"\[.+\]", ax.get_xlabel()), ax.get_xlabel()
            assert ax.lines or ax.patches or ax.collections
    # The hysteresis panel of a Kelvin–Voigt blade: loading above unloading (seed §3.4), and
    # the angular deformation negative under load.
    m = mech["TT-A (Cat 5)"][0]
    assert m.peak_angular_deformation < np.deg2rad(-15)
    assert 0 < m.efficiency < 100


def test_bad_figure_input_is_a_clear_error():
    with pytest.raises(DataError, match="missing columns"):
        parameter_bars(pd.DataFrame({"group": ["a"], "speed_band": ["x"]}))
    with pytest.raises(DataError, match="no measured stances"):
        time_series_bands({})
    with pytest.raises(DataError, match="signal"):
        time_series_bands({"a": []}, signal="speed")  # type: ignore[arg-type]


def test_html_blocks_and_attached_files(tmp_path: Path):
    from bladelab.errors import BladelabError
    from bladelab.report.builder import EmbeddedHTML

    report = Report("Blocks")
    block = EmbeddedHTML('<div id="live"><svg></svg></div>', caption="a <caption>")
    report.add_section("Animated", html=[block], text="text first")
    name = report.add_file("export/run/data.txt", lambda p: p.write_text("42\n"))
    assert name == "export/run/data.txt"
    for bad in ("../x.txt", "/abs.txt", "index.html", "tables/x.csv"):
        with pytest.raises(BladelabError):
            report.add_file(bad, lambda p: None)
    with pytest.raises(BladelabError, match="EmbeddedHTML"):
        report.add_section("Bad", html=["<p>raw</p>"])
    index = report.write(tmp_path / "r")
    html = index.read_text(encoding="utf-8")
    assert '<div id="live"><svg></svg></div>' in html  # placed as it is
    assert "a &lt;caption&gt;" in html  # the caption is text
    assert html.index("text first") < html.index('id="live"')
    assert (tmp_path / "r" / "export" / "run" / "data.txt").read_text() == "42\n"


def test_curves_are_normalised_over_contact_and_every_panel_has_tick_labels():
    import dataclasses

    from bladelab.report.figures import contact_span

    measured, simulated, mech, _ = example_inputs()
    # four groups: three panels on the first row, one below: the panels above the empty slots
    # (third column) used to lose their x tick labels
    extra = {f"{g} copy": v for g, v in list(measured.items())[:1]}
    groups = {**measured, **extra}
    sims = {**simulated, **{f"{g} copy": v for g, v in list(simulated.items())[:1]}}
    for fig in (time_series_bands(groups, sims), compressive_stiffness_curves(
            {**mech, "copy": mech[next(iter(mech))]}), hysteresis_loops(mech)):
        fig.canvas.draw()
        for ax in (a for a in fig.axes if a.get_visible()):
            labels = [t.get_text() for t in ax.get_xticklabels() if t.get_visible()]
            assert any(labels), ax.get_title()
    # over contact: 0 % is touch-down (GRF above 20 N), 100 % toe-off; flight is left out
    st = measured["TF (Cat 2)"][0]
    pad = 50
    dt = st.time[1] - st.time[0]
    flight = dataclasses.replace(  # 50 samples of flight before the stance
        st, time=np.concatenate([st.time[0] - dt * np.arange(pad, 0, -1), st.time]),
        **{k: np.concatenate([np.full(pad, getattr(st, k)[0] if k != "grf_z" else 0.0),
                              getattr(st, k)])
           for k in ("clamp_x", "clamp_y", "clamp_z", "clamp_pitch", "grf_x", "grf_y", "grf_z",
                     "distance")})
    t0, t1 = contact_span(flight)
    assert flight.grf_z[np.searchsorted(flight.time, t0)] > 20 and t0 > flight.time[pad - 1]
    a = time_series_bands({"g": [flight]}, window="contact")
    b = time_series_bands({"g": [flight]}, window="stance")
    ya = a.axes[0].lines[0].get_ydata()
    yb = b.axes[0].lines[0].get_ydata()
    assert ya[0] > 20 and yb[0] == 0.0  # the window starts in flight, contact at touch-down
    assert "touch-down to toe-off" in a.axes[0].get_xlabel()
    with pytest.raises(DataError, match="unknown window"):
        time_series_bands({"g": [flight]}, window="swing")  # type: ignore[arg-type]
