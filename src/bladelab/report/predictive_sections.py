"""Report sections of predictive simulations (seed 001 §3: Figs. 3.1–3.9, Tables 3.1–3.3).

:func:`add_predictive_sections` appends to a :class:`bladelab.report.Report`: joint angles per
leg, GRF in body weights, spatiotemporal bars, joint power curves, the P+/P− table (Table 3.2
layout: mean positive and negative power per stride in W/kg), the energy table (Table 3.3), and,
given a sweep summary, maximum speed, metabolic cost at 4 m/s, 200/400 m times and contact times
per category set beside seed 001's values (:func:`seed001_results`, a packaged table citing the
seed's table, figure or text for every number). :func:`power_table`, :func:`energy_table` and
:func:`seed_comparison` are the tables alone.
"""

from __future__ import annotations

import math
from importlib import resources

import numpy as np
import pandas as pd

from bladelab.runner.analyses import (
    gait_events,
    joint_angles,
    joint_powers,
    leg_energy,
    spatiotemporal,
)
from bladelab.runner.simulate import RunnerResult, leg_names


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


def _solution_first(frames: list[pd.DataFrame]) -> pd.DataFrame:
    df = pd.concat(frames, ignore_index=True)
    return df[["solution", *[c for c in df.columns if c != "solution"]]]


def _power_display(result: RunnerResult) -> pd.DataFrame:
    tab = power_table(result)
    tab["joint"] = [j if j == "total" else _joint_label(j) for j in tab.joint]
    return tab.rename(columns={"P_pos": "P+ (W/kg)", "P_neg": "P− (W/kg)"})


# Sweep summary columns and their display names (with units)
SUMMARY_LABELS = {
    "category": "category",
    "max_speed": "maximum speed (m/s)",
    "cot_4": "metabolic cost at 4 m/s (J/(kg·m))",
    "t200": "200 m time (s)",
    "t400": "400 m time (s)",
    "contact_time_intact": "intact contact time at maximum speed (s)",
    "contact_time_prosthetic": "prosthetic contact time at maximum speed (s)",
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
    for col in SUMMARY_LABELS:
        if col not in summary.columns:
            summary[col] = math.nan
    summary = summary[list(SUMMARY_LABELS)]
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
        "(Table 3.1) and contact times at maximum speed",
        summary.rename(columns=SUMMARY_LABELS),
    )]
    text = None
    if seed is not None:
        tables.append(("bladelab beside seed 001 (Fig. 3.7, Table 3.1, Fig. 3.9)",
                       seed_comparison(summary)))
        text = ("Seed 001's values come from its §3.2 text and Table 3.1 (every number is stated "
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


def add_predictive_sections(
    report,
    results: dict[str, RunnerResult],
    *,
    sweep_summary: pd.DataFrame | None = None,
    compare_seed: bool = True,
) -> None:
    """Append the predictive sections for the labelled simulations ``results`` (e.g.
    ``{"able 3.5 m/s": r1, "amputee Cat6 3.5 m/s": r2}``) to ``report``; with a sweep summary
    (:func:`bladelab.predict.reflex.sweep.summarise`) also the category section, and with
    ``compare_seed`` seed 001's values beside ours."""
    import matplotlib.pyplot as plt

    for label, res in results.items():
        names = leg_names(res.model)
        ang = joint_angles(res)
        fig, axes = plt.subplots(1, 2, figsize=(10, 3.5), sharey=True)
        for ax, leg in zip(axes, names, strict=True):
            for joint, df in ang.groupby("joint", sort=False):
                if _leg_of(joint, names) == leg:
                    ax.plot(df.time, df.angle_deg, label=joint)
            ax.set_title(f"{leg} leg")
            ax.set_xlabel("time (s)")
            ax.legend(fontsize=7)
        axes[0].set_ylabel("angle (deg)")
        grf = res.leg_grf()
        fig2, ax2 = plt.subplots(figsize=(8, 3))
        for leg, df in grf.groupby("leg", sort=False):
            ax2.plot(df.time, df.Fz_bw, label=f"{leg} vertical")
            ax2.plot(df.time, df.Fx_bw, "--", label=f"{leg} horizontal")
        ax2.set_xlabel("time (s)")
        ax2.set_ylabel("GRF (BW)")
        ax2.legend(fontsize=7)
        st = spatiotemporal(res)
        fig3, ax3 = plt.subplots(figsize=(7, 3))
        piv = st.pivot(index="variable", columns="leg", values="value")
        piv = piv.reindex([v for v in st.variable.unique() if v in piv.index])[list(names)]
        piv.index = [v.replace("_time", "") for v in piv.index]
        piv.plot.bar(ax=ax3, rot=0)
        ax3.set_xlabel("")
        ax3.set_ylabel("mean time (s)")
        pw = joint_powers(res)
        fig4, ax4 = plt.subplots(figsize=(8, 3))
        for joint, df in pw.groupby("joint", sort=False):
            ax4.plot(df.time, df.power / res.model.total_mass, label=joint)
        ax4.set_xlabel("time (s)")
        ax4.set_ylabel("power (W/kg)")
        ax4.legend(fontsize=7, ncol=2)
        for f in (fig, fig2, fig3, fig4):
            f.tight_layout()
        report.add_section(
            f"Predictive simulation: {label}",
            figures=[
                ("Joint angles per leg", fig),
                ("Ground reaction force in body weights", fig2),
                ("Spatiotemporal variables", fig3),
                ("Joint powers", fig4),
            ],
            tables=[
                (
                    "Spatiotemporal variables (means over complete cycles)",
                    st.rename(columns={"value": "value (s)", "n": "cycles (count)"}),
                ),
                (
                    "Mean positive/negative power per stride (W/kg), Table 3.2 quantities",
                    _power_display(res),
                ),
                (
                    "Energy per leg, mean over stances, Table 3.3 quantities",
                    energy_table(res).rename(columns=_ENERGY_LABELS),
                ),
            ],
        )
        for f in (fig, fig2, fig3, fig4):
            plt.close(f)
    if len(results) > 1:
        rows_p, rows_e = [], []
        for label, res in results.items():
            rows_p.append(power_table_wide(res).assign(solution=label))
            rows_e.append(energy_table_wide(res).assign(solution=label))
        report.add_section(
            "Joint power and leg energy of every solution",
            tables=[
                ("Mean positive (P+) and negative (P−) power per stride, seed 001 Table 3.2 "
                 "layout", _solution_first(rows_p)),
                ("Energy stored, generated, hysteresis and recoil per leg, seed 001 Table 3.3 "
                 "layout", _solution_first(rows_e)),
            ],
        )
    if sweep_summary is not None and len(sweep_summary):
        _sweep_section(report, sweep_summary, compare_seed)


__all__ = [
    "SUMMARY_LABELS",
    "add_predictive_sections",
    "energy_table",
    "energy_table_wide",
    "power_table",
    "power_table_wide",
    "seed001_results",
    "seed_comparison",
]
