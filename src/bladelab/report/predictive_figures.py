"""Figures of predicted gaits in seed 001's layout, several solutions overlaid with a legend.

Each function takes ``{label: GaitCycles}`` (:class:`bladelab.report.gait_cycle.GaitCycles`, one
per solution: a category, a speed, a method) and returns a matplotlib figure; curves are the
mean over strides (or stances) with a ±1 SD band, one colour per solution, dotted vertical
lines at each solution's mean toe-off. Rows are legs (left/intact, right/prosthetic).

- :func:`joint_angles_figure` (Figs. 3.1, 3.8, B.1), :func:`spatiotemporal_figure` (3.2, 3.9),
  :func:`grf_figure` (3.3), :func:`power_balance_figure` (3.4), :func:`joint_power_figure`
  (3.5, 3.10), :func:`joint_moment_figure`, :func:`muscle_figure` (3.6, C.1–C.2 powers; E.1
  excitations), :func:`power_asymmetry_figure` (3.11), :func:`leg_stiffness_figure` (3.12).
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping

import numpy as np
import pandas as pd

from bladelab.report.gait_cycle import CycleAverage, GaitCycles

__all__ = [
    "STYLE",
    "grf_figure",
    "joint_angles_figure",
    "joint_moment_figure",
    "joint_power_figure",
    "leg_stiffness_figure",
    "muscle_figure",
    "power_asymmetry_figure",
    "power_balance_figure",
    "spatiotemporal_figure",
]

#: Matplotlib settings of these figures (font sizes legible at the report's width).
STYLE = {"font.size": 10, "axes.titlesize": 10.5, "axes.labelsize": 10, "legend.fontsize": 9,
         "xtick.labelsize": 9, "ytick.labelsize": 9}
_JOINT_KINDS = ("hip", "knee", ("ankle", "socket"))
_JOINT_TITLE = {"hip": "hip flexion", "knee": "knee angle", "ankle": "ankle angle",
                "socket": "socket angle"}


def _colors(labels) -> dict[str, tuple]:
    import matplotlib

    cmap = matplotlib.colormaps["tab10"]
    return {label: cmap(i % 10) for i, label in enumerate(labels)}


#: Said in a panel whose curves have no data: a leg without a complete stride or stance.
NO_CYCLE_TEXT = "no complete stride or stance of this leg\n(its contacts are not steps: see the gait warnings)"


def _band(ax, curve: CycleAverage, color, label: str | None = None, style: str = "-") -> None:
    """Mean curve and ±1 SD band; marks ``ax`` as holding data or not (:func:`_finish` writes
    :data:`NO_CYCLE_TEXT` into a panel whose every curve was empty)."""
    has_data = int(np.isfinite(np.asarray(curve.mean, float)).sum()) > 1
    ax._bladelab_has_data = getattr(ax, "_bladelab_has_data", False) or has_data
    ax.plot(curve.pct, curve.mean, style, color=color, lw=1.6, label=label)
    if curve.n > 1 and np.isfinite(curve.sd).any():
        ax.fill_between(curve.pct, curve.mean - curve.sd, curve.mean + curve.sd, color=color,
                        alpha=0.18, lw=0)


def _row_name(cycles: Mapping[str, GaitCycles], i: int) -> str:
    return "/".join(dict.fromkeys(c.legs[i] for c in cycles.values()))


def _legend(fig, cycles: Mapping[str, GaitCycles], colors: dict, extra=()) -> None:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=colors[lab], lw=2) for lab in cycles]
    labels = list(cycles)
    for handle, text in extra:
        handles.append(handle)
        labels.append(text)
    fig.legend(handles, labels, loc="upper center", ncol=min(len(labels), 4), frameon=False,
               bbox_to_anchor=(0.5, 1.0))


def _finish(fig, n_legend: int) -> None:
    for ax in fig.axes:
        if ax.get_visible() and getattr(ax, "_bladelab_has_data", True) is False:
            ax.text(0.5, 0.5, NO_CYCLE_TEXT, transform=ax.transAxes, ha="center", va="center",
                    fontsize=8, color="#777777")
    rows = math.ceil(n_legend / 4)
    top = 1.0 - (0.045 + 0.035 * rows) * 6.0 / fig.get_size_inches()[1]
    fig.tight_layout(rect=(0, 0, 1, top))


def _toe_off(ax, cyc: GaitCycles, leg: str, color) -> None:
    to = cyc.toe_off_pct(leg)
    if math.isfinite(to):
        ax.axvline(to, color=color, ls=":", lw=1.1)


def _leg_panel(ax, cycles, colors, row: int, kind: str, curve, name) -> bool:
    """Draw one leg's (``row``) joint of ``kind`` for every solution on ``ax``: band of
    ``curve(cyc, dof)``, toe-off line, title from ``name(dof)``; False if no solution has it."""
    names = []
    for label, cyc in cycles.items():
        leg = cyc.legs[row]
        dofs = [d for d in cyc.leg_dofs(leg) if d.startswith(kind)]
        if not dofs:
            continue
        names.append(name(dofs[0]))
        _band(ax, curve(cyc, dofs[0]), colors[label])
        _toe_off(ax, cyc, leg, colors[label])
    if names:
        shown = "/".join(_JOINT_TITLE.get(n.split("_")[0], n) for n in dict.fromkeys(names))
        ax.set_title(f"{_row_name(cycles, row)} leg: {shown}")
    return bool(names)


def _cycle_grid(cycles, kinds, curve, ylabel: str, title: str, figsize) -> object:
    """Rows: legs; columns: joint kinds; ``curve(cyc, dof) -> CycleAverage``."""
    import matplotlib.pyplot as plt

    colors = _colors(cycles)
    fig, axes = plt.subplots(2, len(kinds), figsize=figsize, sharex=True, squeeze=False)
    for row in range(2):
        for col, kind in enumerate(kinds):
            ax = axes[row, col]
            if not _leg_panel(ax, cycles, colors, row, kind, curve,
                              lambda d: d.rsplit("_", 1)[0]):
                ax.set_visible(False)
                continue
            ax.set_ylabel(ylabel)
            ax.axhline(0.0, color="0.6", lw=0.6)
            if row == 1:
                ax.set_xlabel(f"% of {title}")
            ax.set_xlim(0, 100)
    _legend(fig, cycles, colors)
    _finish(fig, len(cycles))
    return fig


def joint_angles_figure(cycles: Mapping[str, GaitCycles]):
    """Joint angles [deg] over % of each leg's stride (Figs. 3.1, 3.8) and the trunk (pelvis
    tilt, lumbar extension [deg], pelvis height [m]; Fig. B.1) over the first leg's stride."""
    import matplotlib.pyplot as plt

    colors = _colors(cycles)
    fig, axes = plt.subplots(3, 3, figsize=(12, 9.5), squeeze=False)
    for row in range(2):
        for col, kind in enumerate(_JOINT_KINDS):
            ax = axes[row, col]
            if not _leg_panel(ax, cycles, colors, row, kind, lambda c, d: c.angle(d),
                              lambda d: d.split("_")[0]):  # the transfemoral prosthesis
                ax.text(0.5, 0.5, "no such joint (prosthesis)", transform=ax.transAxes,
                        ha="center", va="center", fontsize=8, color="#777777")
                ax.set_title(f"{_row_name(cycles, row)} leg")
            ax.set_ylabel("angle (deg)")
            ax.set_xlabel("% of the leg's stride")
    trunk = (("pelvis_tilt", "pelvis tilt", "angle (deg)"),
             ("lumbar_extension", "lumbar extension", "angle (deg)"),
             ("pelvis_tz", "pelvis height", "height (m)"))
    for col, (dof, title, unit) in enumerate(trunk):
        ax = axes[2, col]
        for label, cyc in cycles.items():
            if dof in cyc.result.model.dof_names:
                _band(ax, cyc.angle(dof), colors[label])
        ax.set_title(f"trunk: {title}")
        ax.set_ylabel(unit)
        ax.set_xlabel(f"% of the {_row_name(cycles, 0)} leg's stride")
    for ax in axes.ravel():
        ax.set_xlim(0, 100)
    _legend(fig, cycles, colors)
    _finish(fig, len(cycles))
    return fig


def joint_moment_figure(cycles: Mapping[str, GaitCycles]):
    """Joint moments (muscle + ligament) [N·m/kg] over % of each leg's stride."""
    return _cycle_grid(cycles, _JOINT_KINDS, lambda c, d: c.moment(d), "moment (N·m/kg)",
                       "the leg's stride", (12, 6.4))


def joint_power_figure(cycles: Mapping[str, GaitCycles]):
    """Joint powers [W/kg] over % of each leg's stride (Figs. 3.5, 3.10): hip, knee, ankle or
    socket, and the blade (RSP: power the blade contact delivers to the body)."""
    import matplotlib.pyplot as plt

    colors = _colors(cycles)
    has_blade = any(c.has_joint_power("blade_r") for c in cycles.values())
    kinds = [*_JOINT_KINDS, "blade"] if has_blade else list(_JOINT_KINDS)
    fig, axes = plt.subplots(2, len(kinds), figsize=(3.2 * len(kinds), 6.4), squeeze=False)
    for row in range(2):
        for col, kind in enumerate(kinds):
            ax = axes[row, col]
            names = []
            for label, cyc in cycles.items():
                leg = cyc.legs[row]
                if kind == "blade":
                    joint = "blade_r" if row == 1 and cyc.has_joint_power("blade_r") else None
                else:
                    dofs = [d for d in cyc.leg_dofs(leg) if d.startswith(kind)]
                    joint = dofs[0] if dofs else None
                if joint is None:
                    continue
                names.append("RSP (blade)" if kind == "blade" else _JOINT_TITLE[
                    joint.split("_")[0]].split()[0])
                _band(ax, cyc.joint_power(joint), colors[label])
                _toe_off(ax, cyc, leg, colors[label])
            if not names:
                ax.set_visible(False)
                continue
            ax.set_title(f"{_row_name(cycles, row)} leg: {'/'.join(dict.fromkeys(names))}")
            ax.set_ylabel("power (W/kg)")
            ax.axhline(0.0, color="0.6", lw=0.6)
            ax.set_xlabel("% of the leg's stride")
            ax.set_xlim(0, 100)
    _legend(fig, cycles, colors)
    _finish(fig, len(cycles))
    return fig


def grf_figure(cycles: Mapping[str, GaitCycles]):
    """Horizontal and vertical GRF [body weights] over % of each leg's stance (Fig. 3.3)."""
    import matplotlib.pyplot as plt

    colors = _colors(cycles)
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.4), sharex=True, squeeze=False)
    for col in range(2):
        for row, (comp, name) in enumerate((("Fx", "horizontal"), ("Fz", "vertical"))):
            ax = axes[row, col]
            for label, cyc in cycles.items():
                _band(ax, cyc.grf(cyc.legs[col], comp), colors[label])
            ax.set_title(f"{_row_name(cycles, col)} leg: {name} GRF")
            ax.set_ylabel("GRF (BW)")
            ax.axhline(0.0, color="0.6", lw=0.6)
            ax.set_xlim(0, 100)
            if row == 1:
                ax.set_xlabel("% of the stance")
    _legend(fig, cycles, colors)
    _finish(fig, len(cycles))
    return fig


_BALANCE = (("muscle", "muscles", "#1f77b4"), ("ligament", "ligaments", "#9467bd"),
            ("contact", "ground contact", "#ff7f0e"), ("gravity", "gravity", "#8c564b"),
            ("external", "total external", "#000000"), ("kinetic", "kinetic (dE/dt)", "#2ca02c"))


def power_balance_figure(cycles: Mapping[str, GaitCycles]):
    """Power balance [W/kg] over % of the first leg's stride, one panel per solution (Fig.
    3.4): muscle, ligament, ground-contact and gravity power, their sum (total external) and
    the rate of change of kinetic energy (equal to it when energy is conserved)."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    n = len(cycles)
    ncol = min(n, 3)
    nrow = math.ceil(n / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(11, 3.6 * nrow + 0.6), squeeze=False,
                             sharey=True)
    for ax, (label, cyc) in zip(axes.ravel(), cycles.items(), strict=False):
        for term, _, color in _BALANCE:
            curve = cyc.power_balance(term)
            style = "--" if term == "kinetic" else "-"
            if term in ("external", "kinetic"):
                _band(ax, curve, color, style=style)
            else:
                ax.plot(curve.pct, curve.mean, style, color=color, lw=1.2)
        _toe_off(ax, cyc, cyc.legs[0], "0.4")
        ax.set_title(label)
        ax.set_xlabel(f"% of the {cyc.legs[0]} leg's stride")
        ax.set_ylabel("power (W/kg)")
        ax.set_xlim(0, 100)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    handles = [Line2D([], [], color=c, lw=2, ls="--" if t == "kinetic" else "-")
               for t, _, c in _BALANCE]
    fig.legend(handles, [name for _, name, _ in _BALANCE], loc="upper center", ncol=6,
               frameon=False, bbox_to_anchor=(0.5, 1.0))
    _finish(fig, 4)
    return fig


def muscle_figure(cycles: Mapping[str, GaitCycles], row: int, quantity: str = "power"):
    """Every muscle of one leg (``row`` 0: left/intact, 1: right/prosthetic; the torso muscles
    of that side included) over % of its stride: muscle–tendon power [W/kg] (Figs. 3.6, C.1,
    C.2) or excitation [0–1] (Fig. E.1)."""
    import matplotlib.pyplot as plt

    colors = _colors(cycles)
    side = "_l" if row == 0 else "_r"
    muscles = list(dict.fromkeys(m for c in cycles.values()
                                 for m in c.result.model.muscle_names if m.endswith(side)))
    ncol = 4
    nrow = math.ceil(len(muscles) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(12, 2.6 * nrow + 0.7), squeeze=False)
    for ax, muscle in zip(axes.ravel(), muscles, strict=False):
        for label, cyc in cycles.items():
            if muscle not in cyc.result.model.muscle_names:
                continue
            curve = cyc.muscle_power(muscle) if quantity == "power" else cyc.excitation(muscle)
            _band(ax, curve, colors[label])
            _toe_off(ax, cyc, cyc.legs[row], colors[label])
        ax.set_title(muscle.removesuffix(side).replace("_", " "))
        ax.set_ylabel("MTU power (W/kg)" if quantity == "power" else "excitation (0–1)")
        if quantity == "power":
            ax.axhline(0.0, color="0.6", lw=0.6)
        else:
            ax.set_ylim(-0.02, 1.02)
        ax.set_xlim(0, 100)
    for ax in axes.ravel()[len(muscles):]:
        ax.set_visible(False)
    for ax in axes.ravel()[max(0, len(muscles) - ncol):len(muscles)]:
        ax.set_xlabel(f"% of the {_row_name(cycles, row)} leg's stride")
    _legend(fig, cycles, colors)
    _finish(fig, len(cycles))
    return fig


def spatiotemporal_figure(tables: Mapping[str, pd.DataFrame]):
    """Stride, contact and flight times [s], mean ± SD per leg (Figs. 3.2, 3.9); ``tables``:
    ``{label: spatiotemporal(result)}``, bars coloured by solution, hatched for the second leg."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    colors = _colors(tables)
    labels = list(tables)
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.2), squeeze=False)
    width = 0.38
    xs = np.arange(len(labels))
    legs0 = "/".join(dict.fromkeys(t.leg.iloc[0] for t in tables.values()))
    legs1 = "/".join(dict.fromkeys(t.leg.iloc[-1] for t in tables.values()))
    for ax, var in zip(axes[0], ("stride_time", "contact_time", "flight_time"), strict=True):
        for i, label in enumerate(labels):
            t = tables[label]
            for k, leg in enumerate(dict.fromkeys(t.leg)):
                r = t[(t.leg == leg) & (t.variable == var)].iloc[0]
                sd = r.sd if np.isfinite(r.sd) else 0.0
                ax.bar(xs[i] + (k - 0.5) * width, r.value, width, yerr=sd, capsize=3,
                       color=colors[label], hatch="//" if k else None, edgecolor="white")
        ax.set_title(var.replace("_", " "))
        ax.set_ylabel("time (s)")
        ax.set_xticks(xs, [textwrap.fill(lab, 16) for lab in labels],
                      rotation=20 if len(labels) > 3 else 0,
                      ha="right" if len(labels) > 3 else "center")
    _legend(fig, tables, colors, extra=[(Patch(facecolor="0.6"), f"{legs0} leg"),
                                       (Patch(facecolor="0.6", hatch="//"), f"{legs1} leg")])
    _finish(fig, len(tables) + 2)
    return fig


def power_asymmetry_figure(tables: Mapping[str, pd.DataFrame]):
    """Average positive power per stride [W/kg] of each leg (Fig. 3.11); ``tables``:
    ``{label: power_table(result)}``. The second leg's bar stacks its muscles (hip + knee),
    the socket and the blade (RSP); the number above it is its total in % of the first leg's."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    labels = list(tables)
    fig, ax = plt.subplots(figsize=(11, 4.2))
    xs = np.arange(len(labels))
    width = 0.38
    parts = (("muscles (hip + knee + ankle)", "#1f5fa8"), ("socket", "#7f7f7f"),
             ("RSP (blade)", "#e67e22"))
    for i, label in enumerate(labels):
        t = tables[label]
        legs = list(dict.fromkeys(t.leg))
        totals = []
        for k, leg in enumerate(legs):
            rows = t[(t.leg == leg) & (t.joint != "total")]
            stack = [float(rows[rows.joint.str.startswith(("hip", "knee", "ankle"))].P_pos.sum()),
                     float(rows[rows.joint.str.startswith("socket")].P_pos.sum()),
                     float(rows[rows.joint.str.startswith("blade")].P_pos.sum())]
            bottom = 0.0
            for value, (_, color) in zip(stack, parts, strict=True):
                if value > 0:
                    ax.bar(xs[i] + (k - 0.5) * width, value, width, bottom=bottom, color=color,
                           hatch="//" if k else None, edgecolor="white")
                    bottom += value
            totals.append(bottom)
        if len(totals) == 2 and totals[0] > 0:
            ax.text(xs[i] + 0.5 * width, totals[1], f"{100 * totals[1] / totals[0]:.0f} %",
                    ha="center", va="bottom", fontsize=9)
    ax.set_xticks(xs, [textwrap.fill(lab, 22) for lab in labels],
                  rotation=15 if len(labels) > 4 else 0)
    ax.set_ylabel("average positive power P+ (W/kg)")
    ax.set_title("Left bar: first (left/intact) leg; hatched: second (right/prosthetic) leg, "
                 "in % of the first")
    ax.legend(handles=[Patch(facecolor=c, label=n) for n, c in parts], loc="upper left",
              bbox_to_anchor=(1.0, 1.0), frameon=False)
    fig.tight_layout()
    return fig


def leg_stiffness_figure(cycles: Mapping[str, GaitCycles], stiffness: Mapping[str, pd.DataFrame]):
    """Leg stiffness K_leg [kN/m], mean ± SD over stances (Fig. 3.12a), and the vertical GRF
    [BW] against the vertical displacement of the centre of mass [cm] over the stance, one panel
    per leg (Fig. 3.12b, c); ``stiffness``: ``{label: leg_stiffness(result)}``."""
    import matplotlib.pyplot as plt

    colors = _colors(cycles)
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.4), squeeze=False)
    ax = axes[0, 0]
    xs = np.arange(2)
    width = 0.8 / max(len(cycles), 1)
    for i, (label, cyc) in enumerate(cycles.items()):
        k = stiffness[label]
        means, sds = [], []
        for leg in cyc.legs:
            v = k[k.leg == leg].K_leg.to_numpy() / 1e3
            means.append(float(np.mean(v)) if len(v) else math.nan)
            sds.append(float(np.std(v, ddof=1)) if len(v) > 1 else 0.0)
        ax.bar(xs - 0.4 + (i + 0.5) * width, means, width, yerr=sds, capsize=3,
               color=colors[label])
    ax.set_xticks(xs, [f"{_row_name(cycles, i)} leg" for i in range(2)])
    ax.set_ylabel("K_leg (kN/m)")
    ax.set_title("leg stiffness")
    for col in range(2):
        ax = axes[0, col + 1]
        for label, cyc in cycles.items():
            force, disp = cyc.stance_loop(cyc.legs[col])
            ax.plot(disp.mean * 100.0, force.mean, color=colors[label], lw=1.6)
            if np.isfinite(force.mean[0]):
                ax.plot(disp.mean[0] * 100.0, force.mean[0], "o", color=colors[label], ms=4)
        ax.set_title(f"{_row_name(cycles, col)} leg: GRF vs COM displacement")
        ax.set_xlabel("vertical COM displacement from touch-down (cm)")
        ax.set_ylabel("vertical GRF (BW)")
    _legend(fig, cycles, colors)
    _finish(fig, len(cycles))
    return fig
