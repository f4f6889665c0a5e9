"""Report sections of predictive simulations (seed 001 §3: Figs. 3.1–3.9, Tables 3.1–3.3).

:func:`add_predictive_sections` appends to a :class:`bladelab.report.Report`: joint angles per
leg, GRF in body weights, spatiotemporal bars, joint power curves, the P+/P− table (Table 3.2
layout: mean positive and negative power per stride in W/kg), the energy table (Table 3.3), and,
given a sweep summary, maximum speed, metabolic cost at 4 m/s and 200/400 m times per category.
:func:`power_table` and :func:`energy_table` are the tables alone.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from bladelab.runner.analyses import (
    gait_events,
    joint_angles,
    joint_powers,
    leg_energy,
    spatiotemporal,
)
from bladelab.runner.simulate import RunnerResult, _leg_names


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
    names = _leg_names(result.model)
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


def add_predictive_sections(
    report,
    results: dict[str, RunnerResult],
    *,
    sweep_summary: pd.DataFrame | None = None,
) -> None:
    """Append the predictive sections for the labelled simulations ``results`` (e.g.
    ``{"able 3.5 m/s": r1, "amputee Cat6 3.5 m/s": r2}``) to ``report``."""
    import matplotlib.pyplot as plt

    for label, res in results.items():
        names = _leg_names(res.model)
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
        piv.plot.bar(ax=ax3)
        ax3.set_ylabel("time (s)")
        pw = joint_powers(res)
        fig4, ax4 = plt.subplots(figsize=(8, 3))
        for joint, df in pw.groupby("joint", sort=False):
            ax4.plot(df.time, df.power / res.model.total_mass, label=joint)
        ax4.set_xlabel("time (s)")
        ax4.set_ylabel("power (W/kg)")
        ax4.legend(fontsize=7, ncol=2)
        report.add_section(
            f"Predictive simulation: {label}",
            figures=[
                ("Joint angles per leg", fig),
                ("Ground reaction force in body weights", fig2),
                ("Spatiotemporal variables", fig3),
                ("Joint powers", fig4),
            ],
            tables=[
                ("Spatiotemporal variables (s)", st),
                (
                    "Mean positive/negative power per stride (W/kg), Table 3.2 layout",
                    power_table(res),
                ),
                ("Energy per leg and stance (J), Table 3.3 layout", energy_table(res)),
            ],
        )
    if sweep_summary is not None and len(sweep_summary):
        fig, axes = plt.subplots(1, 2, figsize=(9, 3))
        axes[0].bar(sweep_summary.category, sweep_summary.cot_4)
        axes[0].set_ylabel("metabolic cost at 4 m/s (J/kg/m)")
        axes[1].bar(sweep_summary.category, sweep_summary.max_speed)
        axes[1].set_ylabel("maximum speed (m/s)")
        report.add_section(
            "Blade categories: maximum speed and metabolic cost",
            figures=[("Metabolic cost at 4 m/s and maximum speed per category", fig)],
            tables=[
                ("Maximum speed, cost at 4 m/s, 200 m and 400 m times (Table 3.1)", sweep_summary)
            ],
        )


__all__ = ["add_predictive_sections", "energy_table", "power_table"]
