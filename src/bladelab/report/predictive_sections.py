"""Report sections of predictive simulations (seed 001 §3: Figs. 3.1–3.12, B.1, E.1, Tables
3.1–3.3, D.1).

:func:`add_predictive_sections` appends to a :class:`bladelab.report.Report`: for each solution
an animated runner (:mod:`bladelab.report.animation`); then, all solutions overlaid in one
figure each with a legend, mean ± SD over strides per leg over % of the gait cycle
(:mod:`bladelab.report.predictive_figures`): joint angles and spatiotemporal variables, GRF and
power balance, joint powers and moments, the positive-power asymmetry, muscle–tendon powers
and excitations of every muscle, leg stiffness with the GRF–COM displacement loops; the tables
of seed 001 with units: spatiotemporal variables, P+/P− per joint (Table 3.2), leg energy
(Table 3.3), leg stiffness and the blade's energy (Table D.1); and, given a sweep summary,
maximum speed, metabolic cost at 4 m/s, 200/400 m times and contact times per category beside
seed 001's values (:func:`seed001_results`, a packaged table citing the seed's table, figure or
text for every number). :func:`power_table`, :func:`energy_table`, :func:`blade_energy_table`,
:func:`leg_stiffness_table`, :func:`spatiotemporal_table` and :func:`seed_comparison` are the
tables alone.
"""

from __future__ import annotations

import math
from importlib import resources

import numpy as np
import pandas as pd

from bladelab.report.animation import animation_html
from bladelab.report.builder import ReportTable
from bladelab.report.gait_cycle import GaitCycles
from bladelab.report.predictive_figures import (
    STYLE,
    grf_figure,
    joint_angles_figure,
    joint_moment_figure,
    joint_power_figure,
    leg_stiffness_figure,
    muscle_figure,
    power_asymmetry_figure,
    power_balance_figure,
    spatiotemporal_figure,
)
from bladelab.runner.analyses import gait_events, joint_powers, spatiotemporal
from bladelab.runner.simulate import RunnerResult, leg_names
from bladelab.runner.stance_mechanics import blade_energy, leg_energy, leg_stiffness


def _leg_of(joint: str, names: tuple[str, str]) -> str | None:
    if joint.endswith("_l"):
        return names[0]
    if joint.endswith("_r"):
        return names[1]
    return None


def power_table(result: RunnerResult) -> pd.DataFrame:
    """Mean positive and negative joint power per stride [W/kg] (Table 3.2 layout).

    For each leg, the joint powers (hip, knee, ankle or socket + blade) are integrated over the
    complete strides (first to last touch-down of that leg) and divided by that time and the
    body mass. Tidy: leg, joint, P_pos, P_neg [W/kg]; rows ``total`` per leg sum the joints.
    """
    names = leg_names(result.model)
    pw = joint_powers(result)
    ev = gait_events(result)
    mass = result.model.total_mass
    rows = []
    for leg in names:
        td = ev.time[(ev.leg == leg) & (ev.event == "touchdown")].to_numpy()
        if len(td) < 2:
            continue
        t0, t1 = td[0], td[-1]
        for joint, df in pw.groupby("joint", sort=False):
            if _leg_of(joint, names) != leg:
                continue
            sel = (df.time >= t0) & (df.time <= t1)
            t, p = df.time[sel].to_numpy(), df.power[sel].to_numpy()
            pos = np.trapezoid(np.maximum(p, 0.0), t) / (t1 - t0) / mass
            neg = np.trapezoid(np.minimum(p, 0.0), t) / (t1 - t0) / mass
            rows.append({"leg": leg, "joint": joint, "P_pos": pos, "P_neg": neg})
    df = pd.DataFrame(rows, columns=["leg", "joint", "P_pos", "P_neg"])
    if len(df):
        tot = df.groupby("leg", sort=False)[["P_pos", "P_neg"]].sum().reset_index()
        tot.insert(1, "joint", "total")
        df = pd.concat([df, tot], ignore_index=True)
    return df


def energy_table(result: RunnerResult) -> pd.DataFrame:
    """Mean energy stored, generated, hysteresis [J] and recoil [%] per leg (Table 3.3)."""
    e = leg_energy(result)
    if e.empty:
        return e
    return (
        e.groupby("leg", sort=False)[["E_stored", "E_generated", "hysteresis", "recoil_pct"]]
        .mean()
        .reset_index()
    )


_JOINT_LABEL = {"hip_flexion": "hip", "knee_angle": "knee", "ankle_angle": "ankle",
                "socket_angle": "socket", "blade": "RSP"}


def _joint_label(joint: str) -> str:
    base = joint.rsplit("_", 1)[0]
    return _JOINT_LABEL.get(base, base)


def power_table_wide(result: RunnerResult) -> pd.DataFrame:
    """:func:`power_table` as one row in seed 001's Table 3.2 layout: ``<leg> <joint> P+ (W/kg)``
    and ``P− (W/kg)`` per leg and joint (P− negative), then each leg's and the TOTAL sums."""
    tab = power_table(result)
    row: dict[str, float] = {}
    for r in tab.itertuples():
        name = "total" if r.joint == "total" else _joint_label(r.joint)
        row[f"{r.leg} {name} P+ (W/kg)"] = r.P_pos
        row[f"{r.leg} {name} P− (W/kg)"] = r.P_neg
    tot = tab[tab.joint == "total"]
    row["TOTAL P+ (W/kg)"] = float(tot.P_pos.sum()) if len(tot) else math.nan
    row["TOTAL P− (W/kg)"] = float(tot.P_neg.sum()) if len(tot) else math.nan
    return pd.DataFrame([row])


def energy_table_wide(result: RunnerResult) -> pd.DataFrame:
    """:func:`energy_table` as one row in seed 001's Table 3.3 layout: per leg E stored,
    E generated, hysteresis [J] and recoil [%], and the total E generated [J]."""
    e = energy_table(result)
    row: dict[str, float] = {}
    for r in e.itertuples():
        row[f"{r.leg} E stored (J)"] = r.E_stored
        row[f"{r.leg} E generated (J)"] = r.E_generated
        row[f"{r.leg} hysteresis (J)"] = r.hysteresis
        row[f"{r.leg} recoil (%)"] = r.recoil_pct
    row["total E generated (J)"] = float(e.E_generated.sum()) if len(e) else math.nan
    return pd.DataFrame([row])


_ENERGY_LABELS = {"E_stored": "E stored (J)", "E_generated": "E generated (J)",
                  "hysteresis": "hysteresis (J)", "recoil_pct": "recoil (%)"}


def _pm(mean: float, sd: float, digits: int = 3) -> str:
    """``"mean ± SD"``, the mean to ``digits`` significant digits (trailing zeros kept) and
    the SD to the same decimal place (an SD below it, e.g. the round-off among the repeated
    stances of one periodic stride, reads 0 there, not 1.8e-15)."""
    if not math.isfinite(mean):
        return "–"
    magnitude = math.floor(math.log10(abs(mean))) if mean != 0 else 0
    decimals = max(0, digits - 1 - magnitude)
    text = f"{mean:.{decimals}f}"
    return f"{text} ± {sd:.{decimals}f}" if math.isfinite(sd) else text


def _long(frames: list[pd.DataFrame]) -> pd.DataFrame:
    frames = [f for f in frames if len(f)]
    if not frames:
        return pd.DataFrame(columns=["solution"])
    df = pd.concat(frames, ignore_index=True)
    return df[["solution", *[c for c in df.columns if c != "solution"]]]


_SPATIO = ("stride_time", "step_time", "contact_time", "flight_time", "swing_time")


def spatiotemporal_table(results: dict[str, RunnerResult]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Spatiotemporal variables per solution and leg: (display with "mean ± SD" cells, numbers:
    ``<variable> (s)`` and ``<variable> SD (s)``, cycles (count))."""
    disp, num = [], []
    for label, res in results.items():
        st = spatiotemporal(res)
        for leg in dict.fromkeys(st.leg):
            rows = st[st.leg == leg].set_index("variable")
            d = {"solution": label, "leg": leg}
            n = {"solution": label, "leg": leg}
            for var in _SPATIO:
                name = var.replace("_", " ")
                d[f"{name} (s)"] = _pm(rows.value[var], rows.sd[var])
                n[f"{name} (s)"] = rows.value[var]
                n[f"{name} SD (s)"] = rows.sd[var]
            d["strides (count)"] = n["strides (count)"] = int(rows.n["stride_time"])
            disp.append(d)
            num.append(n)
    return pd.DataFrame(disp), pd.DataFrame(num)


def power_table_long(results: dict[str, RunnerResult]) -> pd.DataFrame:
    """:func:`power_table` of every solution, a row per solution and leg: P+ and P− [W/kg] of
    the hip, knee, ankle or socket, the blade (RSP) and the leg's total (Table 3.2 quantities)."""
    rows = []
    for label, res in results.items():
        tab = power_table(res)
        for leg in dict.fromkeys(tab.leg):
            row = {"solution": label, "leg": leg}
            for r in tab[tab.leg == leg].itertuples():
                name = {"ankle": "ankle/socket", "socket": "ankle/socket"}.get(
                    _joint_label(r.joint), _joint_label(r.joint))
                name = "leg total" if r.joint == "total" else name
                row[f"{name} P+ (W/kg)"] = r.P_pos
                row[f"{name} P− (W/kg)"] = r.P_neg
            rows.append(row)
    cols = ["solution", "leg"] + [f"{j} {s} (W/kg)" for j in
                                  ("hip", "knee", "ankle/socket", "RSP", "leg total")
                                  for s in ("P+", "P−")]
    df = pd.DataFrame(rows)
    return df.reindex(columns=[c for c in cols if c in df.columns])


def leg_stiffness_table(results: dict[str, RunnerResult]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """K_leg per solution and leg over its stances (seed 001 eq. 2.19–2.21, Fig. 3.12a):
    (display "mean ± SD", numbers): K_leg (kN/m), peak vertical GRF (BW), COM drop Δy (cm),
    leg compression ΔL (cm), contact time (s), stances (count)."""
    disp, num = [], []
    for label, res in results.items():
        k = leg_stiffness(res)
        bw = res.model.body_weight
        for leg in leg_names(res.model):
            r = k[k.leg == leg]
            cols = {"K_leg (kN/m)": r.K_leg / 1e3, "peak vertical GRF (BW)": r.F_peak / bw,
                    "COM drop Δy (cm)": r.delta_y * 100, "leg compression ΔL (cm)":
                    r.delta_L * 100, "contact time (s)": r.contact_time}
            d = {"solution": label, "leg": leg}
            n = {"solution": label, "leg": leg}
            for name, v in cols.items():
                mean = float(v.mean()) if len(v) else math.nan
                sd = float(v.std(ddof=1)) if len(v) > 1 else math.nan
                d[name] = _pm(mean, sd)
                n[name] = mean
                n[name.replace(" (", " SD (")] = sd
            d["stances (count)"] = n["stances (count)"] = len(r)
            disp.append(d)
            num.append(n)
    return pd.DataFrame(disp), pd.DataFrame(num)


def energy_table_long(results: dict[str, RunnerResult]) -> pd.DataFrame:
    """:func:`energy_table` of every solution, a row per solution and leg, with the number of
    stances averaged (Table 3.3 quantities)."""
    rows = []
    for label, res in results.items():
        e = leg_energy(res)
        for leg in dict.fromkeys(e.leg):
            r = e[e.leg == leg]
            rows.append({"solution": label, "leg": leg,
                         **{_ENERGY_LABELS[c]: float(r[c].mean()) for c in _ENERGY_LABELS},
                         "stances (count)": len(r)})
    return pd.DataFrame(rows)


def blade_energy_table(results: dict[str, RunnerResult]) -> pd.DataFrame:
    """The blade's energy per prosthetic stance, mean per solution (seed 001 Table D.1 layout):
    E stored, E returned, hysteresis [J], recoil [%] from the simulated compression
    (:func:`bladelab.runner.stance_mechanics.blade_energy`), the recoil the seed's bookkeeping gives
    (compression from the force by eq. 2.3), peak compression [mm], stances (count). Solutions
    without a blade are left out."""
    rows = []
    for label, res in results.items():
        e = blade_energy(res)
        if not len(e) and res.model.kind != "amputee":
            continue
        hertz = blade_energy(res, compression="hertz") if res.model.blade_model is None else None
        rows.append({
            "solution": label,
            "E stored (J)": float(e.E_stored_J.mean()) if len(e) else math.nan,
            "E returned (J)": float(e.E_returned_J.mean()) if len(e) else math.nan,
            "hysteresis (J)": float(e.hysteresis_J.mean()) if len(e) else math.nan,
            "recoil (%)": float(e.recoil_pct.mean()) if len(e) else math.nan,
            "recoil, compression from eq. 2.3 (%)":
                float(hertz.recoil_pct.mean()) if hertz is not None and len(hertz) else math.nan,
            "peak compression (mm)": float(e.peak_compression_m.mean() * 1e3) if len(e)
            else math.nan,
            "stances (count)": len(e),
        })
    return pd.DataFrame(rows)

# Sweep summary columns and their display names (with units)
SUMMARY_LABELS = {
    "category": "category",
    "max_speed": "maximum speed (m/s)",
    "max_speed_floor": "maximum speed against its floor (on it / above it, floor m/s)",
    "cot_4": "metabolic cost at 4 m/s (J/(kg·m))",
    "t200": "200 m time (s)",
    "t400": "400 m time (s)",
    "contact_time_intact": "intact contact time at maximum speed (s)",
    "contact_time_prosthetic": "prosthetic contact time at maximum speed (s)",
    "settled": "settled on twice the mesh intervals",
}
# quantities whose seed range across categories is a meaningful yardstick (the 200/400 m times
# follow from the maximum speed, so they get no verdict of their own)
_RANGE_VERDICT = ("max_speed", "cot_4", "contact_time_intact", "contact_time_prosthetic")


def seed001_results() -> pd.DataFrame:
    """Seed 001's per-category results (packaged ``data/runner/seed001_results.csv``).

    Tidy: category, quantity (a :func:`bladelab.predict.reflex.sweep.summarise` column name, or
    stride/flight times), value, unit, source (the seed's table, figure or text section), note.
    """
    ref = resources.files("bladelab") / "data" / "runner" / "seed001_results.csv"
    with resources.as_file(ref) as path:
        return pd.read_csv(path)


def seed_comparison(summary: pd.DataFrame) -> pd.DataFrame:
    """Our sweep summary beside seed 001's values, one row per category and quantity.

    Columns: category, quantity (with unit), bladelab, seed 001, difference (%) (ours relative to
    the seed's), seed 001 range (over its five categories), within seed range (only for maximum
    speed, cost at 4 m/s and contact times; blank for the 200/400 m times, which follow from
    the maximum speed), source (where in seed 001 the number is).
    """
    seed = seed001_results()
    rows = []
    for r in summary.itertuples(index=False):
        ours = r._asdict()
        for q in SUMMARY_LABELS:
            if q == "category":
                continue
            ref = seed[(seed.category == r.category) & (seed.quantity == q)]
            if ref.empty:
                continue
            all_cats = seed[seed.quantity == q].value
            lo, hi = float(all_cats.min()), float(all_cats.max())
            v = float(ours.get(q, math.nan))
            s = float(ref.value.iloc[0])
            verdict = ""
            if q in _RANGE_VERDICT and math.isfinite(v):
                verdict = "yes" if lo <= v <= hi else "no"
            rows.append(
                {
                    "category": r.category,
                    "quantity": SUMMARY_LABELS[q],
                    "bladelab": v,
                    "seed 001": s,
                    "difference (%)": 100.0 * (v - s) / s if math.isfinite(v) else math.nan,
                    "seed 001 range": f"{lo:g}–{hi:g}",
                    "within seed range": verdict,
                    "source": ref.source.iloc[0],
                }
            )
    return pd.DataFrame(
        rows,
        columns=["category", "quantity", "bladelab", "seed 001", "difference (%)",
                 "seed 001 range", "within seed range", "source"],
    )


def _sweep_section(report, summary: pd.DataFrame, compare_seed: bool) -> None:
    import matplotlib.pyplot as plt

    summary = summary.copy()
    shown = [c for c in SUMMARY_LABELS if c != "settled" or c in summary.columns]
    for col in shown:
        if col not in summary.columns:
            summary[col] = math.nan
    summary = summary[shown]
    seed = seed001_results() if compare_seed else None
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.5))
    cats = summary.category.astype(str).tolist()
    xs = np.arange(len(cats))
    for ax, q in zip(axes, ("cot_4", "max_speed"), strict=True):
        ax.bar(xs, summary[q].to_numpy(float), width=0.6, label="bladelab")
        if seed is not None:
            ref = [seed[(seed.category == c) & (seed.quantity == q)].value for c in cats]
            vals = [float(v.iloc[0]) if len(v) else np.nan for v in ref]
            ax.plot(xs, vals, "k_", markersize=22, mew=2, label="seed 001")
        ax.set_xticks(xs, cats)
        ax.set_ylabel(SUMMARY_LABELS[q])
        top = ax.get_ylim()[1]
        ax.set_ylim(0, top * 1.25 if np.isfinite(top) and top > 0 else 1.0)
        ax.legend(fontsize=7, loc="upper center", ncol=2)
    fig.tight_layout()
    tables = [(
        "Per category: maximum speed, metabolic cost at 4 m/s, 200 m and 400 m times "
        "(Table 3.1) and contact times at maximum speed"
        + (", and whether those solves settled on twice the mesh intervals (objective and "
           "stride time within 1 %)" if "settled" in summary.columns else ""),
        summary.rename(columns=SUMMARY_LABELS),
    )]
    text = None
    if summary.drop(columns=["category", "settled"], errors="ignore").isna().to_numpy().any():
        text = ("A dash: nothing to report for that category (no solution at that speed, one "
                "that did not converge, or, in a collocation sweep, one flagged by the gait "
                "checks: the sweep's first section names it).")
    if seed is not None:
        tables.append(("bladelab beside seed 001 (Fig. 3.7, Table 3.1, Fig. 3.9)",
                       seed_comparison(summary)))
        text = ((text + " ") if text else "") + (
            "Seed 001's values come from its §3.2 text and Table 3.1 (every number is stated "
            "there; the source column names the table or figure that shows it). 'within seed "
            "range' asks whether our value lies within the seed's spread over its five "
            "categories.")
    report.add_section(
        "Blade categories: maximum speed and metabolic cost",
        figures=[("Metabolic cost at 4 m/s and maximum speed per category "
                  "(bars: bladelab; black lines: seed 001)", fig)],
        tables=tables,
        text=text,
    )
    plt.close(fig)


_STANCE_NOTE = (
    "Strides run from a leg's touch-down to its next, stances from touch-down to lift-off; only "
    "real steps count (SCONE's step definition, as the objective counts them): a swinging foot "
    "or blade striking the ground is not a stance. Curves: mean over strides (stances for the "
    "GRF), band ±1 SD, dotted lines at each solution's mean toe-off."
)
_STIFFNESS_NOTE = (
    "Stances as in the gait cycle above (touch-down to lift-off, real steps only). K_leg: the "
    "peak vertical force over the leg's compression ΔL = Δy + L0·(1 − cos θ) (eq. 2.19–2.21)."
)
_BLADE_NOTE = (
    "Blade energy (Table D.1): the blade sphere's Hunt–Crossley law F = k·δ^1.5·(1 + 1.5·c·δ̇) "
    "with seed 001's dissipation c = 0.2 s/m returns about half the energy it stores at the "
    "model's touch-down speeds (1–2 m/s). Seed 001's Table D.1 reports 99.7 %: it computes the "
    "compression from the force by the elastic Hertz law (eq. 2.3, as in its eq. 2.14), and a "
    "loop along one curve F(δ) encloses no area, whatever the dissipation; the column "
    "'compression from eq. 2.3' repeats that bookkeeping on our simulation and gives the same "
    "≈ 100 %. See docs/runner-model.md, 'Blade energy return'."
)


def add_predictive_sections(
    report,
    results: dict[str, RunnerResult],
    *,
    sweep_summary: pd.DataFrame | None = None,
    compare_seed: bool = True,
    animate: bool = True,
    animation_seconds: float | None = None,
) -> None:
    """Append the predictive sections for the labelled trajectories ``results`` (e.g.
    ``{"able 3.5 m/s": r1, "amputee Cat6 3.5 m/s": r2}``; any
    :class:`~bladelab.runner.RunnerResult`, whichever method found the gait) to ``report``.

    Parameters
    ----------
    report
        A :class:`bladelab.report.Report`.
    results
        The solutions, by label (the legend's names).
    sweep_summary
        A sweep's category summary (:func:`bladelab.predict.reflex.sweep.summarise`): adds the
        category section.
    compare_seed
        Set seed 001's values beside ours in the category section.
    animate
        Add an animated runner per solution.
    animation_seconds
        Animate at most this much simulated time [s] per solution (default: all).
    """
    import matplotlib.pyplot as plt

    for label, res in results.items():
        report.add_section(
            f"Predictive simulation: {label}",
            html=[animation_html(res, label=label, max_duration=animation_seconds)]
            if animate else [],
            text=None if animate else "Animation left out (animate=False).",
        )
    if results:
        cycles = {label: GaitCycles(res) for label, res in results.items()}
        with plt.rc_context(STYLE):
            _gait_sections(report, results, cycles)
        plt.close("all")
    if sweep_summary is not None and len(sweep_summary):
        _sweep_section(report, sweep_summary, compare_seed)


def _gait_sections(report, results: dict[str, RunnerResult], cycles: dict) -> None:
    st_disp, st_num = spatiotemporal_table(results)
    report.add_section(
        "Gait cycle: joint angles and spatiotemporal variables",
        text=_STANCE_NOTE,
        figures=[
            ("Joint angles per leg over % of its stride (Figs. 3.1, 3.8) and the trunk (pelvis "
             "tilt, lumbar extension, pelvis height; Fig. B.1), mean ± SD", joint_angles_figure(
                 cycles)),
            ("Spatiotemporal variables, mean ± SD over cycles (Figs. 3.2, 3.9)",
             spatiotemporal_figure({lab: spatiotemporal(r) for lab, r in results.items()})),
        ],
        tables=[ReportTable("Spatiotemporal variables per leg, mean ± SD over complete cycles",
                            st_disp, "spatiotemporal", st_num)],
    )
    report.add_section(
        "Ground reaction forces and power balance",
        figures=[
            ("Ground reaction force in body weights over % of the stance (Fig. 3.3)",
             grf_figure(cycles)),
            ("Power balance over the first leg's stride (Fig. 3.4): muscle, ligament, contact and "
             "gravity power sum to the total external power, which equals the rate of change of "
             "kinetic energy", power_balance_figure(cycles)),
        ],
    )
    power_tables = {lab: power_table(r) for lab, r in results.items()}
    wide_p = [power_table_wide(r).assign(solution=lab) for lab, r in results.items()]
    report.add_section(
        "Joint powers and moments",
        text=("Joint power = (muscle + ligament) torque × angular velocity; RSP = power the blade "
              "contact delivers to the body. P+ and P−: mean positive and negative power per "
              "stride over the complete strides, per kg of body mass (Table 3.2 quantities; the "
              "CSV holds the seed's one-row-per-solution layout)."),
        figures=[
            ("Joint powers over % of each leg's stride (Figs. 3.5, 3.10)",
             joint_power_figure(cycles)),
            ("Joint moments (muscle + ligament) over % of each leg's stride",
             joint_moment_figure(cycles)),
            ("Average positive power per leg (Fig. 3.11)", power_asymmetry_figure(power_tables)),
        ],
        tables=[ReportTable("Mean positive (P+) and negative (P−) power per stride, seed 001 "
                            "Table 3.2 quantities", power_table_long(results), "table-3-2",
                            _long(wide_p))],
    )
    names = [_row_label(results, i) for i in range(2)]
    report.add_section(
        "Muscle power and excitation",
        text=("Muscle–tendon power F_t·(−v_mtu) per kg of body mass (positive: shortening under "
              "tension) and excitation (0–1) of every muscle, the torso muscles of each side "
              "included, over % of that side's stride."),
        figures=[
            (f"Muscle–tendon power, {names[0]} side (Figs. 3.6, C.1)", muscle_figure(cycles, 0)),
            (f"Muscle–tendon power, {names[1]} side (Figs. 3.6, C.2)", muscle_figure(cycles, 1)),
            (f"Excitations, {names[0]} side (Fig. E.1 for every muscle)",
             muscle_figure(cycles, 0, "excitation")),
            (f"Excitations, {names[1]} side (Fig. E.1 for every muscle)",
             muscle_figure(cycles, 1, "excitation")),
        ],
    )
    k_disp, k_num = leg_stiffness_table(results)
    wide_e = [energy_table_wide(r).assign(solution=lab) for lab, r in results.items()]
    tables = [
        ReportTable("Leg stiffness per leg, mean ± SD over stances (eq. 2.19–2.21)", k_disp,
                    "leg-stiffness", k_num),
        ReportTable("Energy stored, generated, hysteresis and recoil per leg, mean over stances "
                    "(seed 001 Table 3.3 quantities)", energy_table_long(results), "table-3-3",
                    _long(wide_e)),
    ]
    blade = blade_energy_table(results)
    if len(blade):
        tables.append(ReportTable("Energy the blade stores and returns per prosthetic stance "
                                  "(seed 001 Table D.1)", blade, "table-d-1"))
    report.add_section(
        "Leg stiffness and energy",
        text=_STIFFNESS_NOTE + "\n\n" + _BLADE_NOTE if len(blade) else _STIFFNESS_NOTE,
        figures=[("Leg stiffness and the vertical GRF against the vertical displacement of the "
                  "centre of mass over the stance, per leg (Fig. 3.12; dot: touch-down)",
                  leg_stiffness_figure(cycles, {lab: leg_stiffness(r)
                                                for lab, r in results.items()}))],
        tables=tables,
    )


def _row_label(results: dict[str, RunnerResult], i: int) -> str:
    return "/".join(dict.fromkeys(leg_names(r.model)[i] for r in results.values()))

__all__ = [
    "SUMMARY_LABELS",
    "add_predictive_sections",
    "blade_energy_table",
    "energy_table",
    "energy_table_wide",
    "power_table",
    "leg_stiffness_table",
    "power_table_long",
    "power_table_wide",
    "seed001_results",
    "seed_comparison",
    "spatiotemporal_table",
]
