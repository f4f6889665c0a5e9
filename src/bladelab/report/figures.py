"""Report figures from stances, mechanics and parameter tables (seed 000 Figs. 1–3, §3.4–3.5).

Every function returns a :class:`matplotlib.figure.Figure` (object-oriented API, no pyplot
state), with units on every axis; pass it to :meth:`bladelab.report.Report.add_section`.
Groups are given as ``{group name: [items...]}`` mappings, in display order.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Collection, Mapping, Sequence
from typing import Literal, TypeVar

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from bladelab.errors import DataError
from bladelab.identify.cost import contact_window
from bladelab.mechanics import StanceMechanics
from bladelab.trial.stance import Stance

__all__ = [
    "PALETTE",
    "contact_span",
    "normalisation_spans",
    "paired_spans",
    "resample_percent",
    "time_series_bands",
    "hysteresis_loops",
    "compressive_stiffness_curves",
    "parameter_bars",
]

# Colour-blind safe (Okabe–Ito).
PALETTE = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442")
MEASURED = "#222222"
SIMULATED = "#D55E00"
LOADING = "#0072B2"
UNLOADING = "#D55E00"
FLAGGED = "#8a8a8a"

_RC = {
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.titleweight": "bold",
    "axes.labelsize": 9,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.grid": True,
    "grid.color": "#e3e3e3",
    "grid.linewidth": 0.6,
    "legend.frameon": False,
    "legend.fontsize": 8,
}

Signal = Literal["grf", "distance"]
_F = TypeVar("_F", bound=Callable[..., Figure])


def _styled(func: _F) -> _F:
    """Draw the whole figure under the report's matplotlib style (no global rcParams change)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        import matplotlib as mpl

        with mpl.rc_context(_RC):
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


SIGNALS = {
    "grf": ("grf_z", 1.0, "vertical GRF [N]"),
    "distance": ("distance", 1e3, "clamp–tip distance [mm]"),
}


def _figure(
    n_panels: int,
    *,
    width: float = 3.3,
    height: float = 2.6,
    ncols: int | None = None,
    share: bool = True,
):
    ncols = min(n_panels, ncols or 3)
    nrows = int(np.ceil(n_panels / ncols))
    fig = Figure(figsize=(width * ncols, height * nrows + 0.35), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=share, sharey=share)
    for ax in axes.flat[n_panels:]:
        ax.set_visible(False)
    shown = list(axes.flat[:n_panels])
    for ax in shown:
        # shared x: matplotlib keeps tick labels on the bottom row only, so a panel above an
        # empty slot (e.g. the last of an incomplete row's column) would have none
        ax.tick_params(axis="x", labelbottom=True)
    return fig, shown


def _style(ax) -> None:
    ax.spines[["top", "right"]].set_visible(False)
    ax.grid(True, color="#e3e3e3", linewidth=0.6)
    ax.set_axisbelow(True)
    ax.tick_params(labelsize=8)


def _check_groups(groups: Mapping, what: str) -> None:
    if not groups or not any(len(v) for v in groups.values()):
        raise DataError(f"no {what} to plot", where=what, hint="pass {group: [items...]}")


Window = Literal["contact", "stance"]


def contact_span(stance: Stance, *, threshold: float = 20.0) -> tuple[float, float]:
    """(touch-down, toe-off) times [s]: the first and last sample of the identification's contact
    window (:func:`bladelab.identify.contact_window`: vertical GRF > threshold [N])."""
    idx = np.flatnonzero(contact_window(stance.grf_z, threshold=threshold))
    return float(stance.time[idx[0]]), float(stance.time[idx[-1]])


def resample_percent(
    stance: Stance, name: str, *, n_points: int = 101, span: tuple[float, float] | None = None
) -> np.ndarray:
    """Channel ``name`` of ``stance`` resampled to 0–100 % of ``span`` (start, end) [s]
    (``n_points`` samples); default span: the whole window."""
    t = stance.time
    t0, t1 = (float(t[0]), float(t[-1])) if span is None else span
    return np.interp(np.linspace(t0, t1, n_points), t, getattr(stance, name))


def normalisation_spans(
    measured: Sequence[Stance],
    *,
    window: Window = "contact",
    contact_threshold: float = 20.0,
) -> dict[int, tuple[float, float] | None]:
    """Span of each measured stance (by position): its contact (touch-down to toe-off, seed 000)
    or None for the whole window. A simulated stance is normalised with the span of its
    measured one, so that both curves share the measured contact."""
    if window not in ("contact", "stance"):
        raise DataError(f"unknown window {window!r}", where="window", hint="contact or stance")
    return {i: contact_span(s, threshold=contact_threshold) if window == "contact" else None
            for i, s in enumerate(measured)}


def paired_spans(measured: Sequence[Stance], others: Sequence[Stance], spans: dict) -> list:
    """The span of each of ``others`` from its measured stance (same trial id, else position)."""
    by_trial = {_trial_id(m): spans[i] for i, m in enumerate(measured) if _trial_id(m) is not None}
    return [by_trial.get(_trial_id(o), spans.get(i)) for i, o in enumerate(others)]


WINDOW_LABELS = {"contact": "contact [%] (touch-down to toe-off)",
                 "stance": "stance window [%]"}


def _mean_sd(stances: Sequence[Stance], name: str, n_points: int,
             spans: Sequence | None = None) -> tuple[np.ndarray, np.ndarray]:
    spans = list(spans) if spans is not None else [None] * len(stances)
    curves = np.array([resample_percent(s, name, n_points=n_points, span=sp)
                       for s, sp in zip(stances, spans, strict=True)])
    sd = curves.std(axis=0, ddof=1) if len(curves) > 1 else np.zeros(n_points)
    return curves.mean(axis=0), sd


def _trial_id(item) -> str | None:
    meta = getattr(item, "metadata", None) or {}
    t = meta.get("trial")
    return None if t is None else str(t)


def _split_flagged(items: Sequence, flagged: Collection[str]) -> tuple[list, list]:
    """(kept, flagged) items by their ``metadata["trial"]``."""
    keep = [it for it in items if _trial_id(it) not in flagged]
    out = [it for it in items if _trial_id(it) in flagged]
    return keep, out


@_styled
def time_series_bands(
    measured: Mapping[str, Sequence[Stance]],
    simulated: Mapping[str, Sequence[Stance]] | None = None,
    *,
    signal: Signal = "grf",
    n_points: int = 101,
    flagged: Collection[str] = (),
    include_flagged: bool = False,
    window: Window = "contact",
    contact_threshold: float = 20.0,
) -> Figure:
    """GRF or distance vs time, measured vs simulated, group mean ± SD (Figs. 1–2).

    Each stance is normalised to 0–100 % of its contact (touch-down to toe-off: vertical GRF
    above ``contact_threshold`` [N], as seed 000 draws them) before averaging, so stances of
    different durations share one axis; a simulated stance uses the contact of its measured one.
    ``window="stance"`` normalises over the whole stance window instead (flight included).

    Parameters
    ----------
    measured
        ``{group: [measured Stance, ...]}``, one panel per group.
    simulated
        ``{group: [simulated Stance, ...]}`` (same groups), or None.
    signal
        ``"grf"`` (vertical GRF [N]) or ``"distance"`` (clamp–tip distance, shown in mm).
    n_points
        Samples of the normalised curves.
    flagged
        Trial ids (``metadata["trial"]``) of flagged trials: drawn one by one as thin grey dotted
        lines (measured) and, unless ``include_flagged``, left out of the mean ± SD bands.
    include_flagged
        Keep flagged trials in the bands (they are still drawn and marked).
    """
    if signal not in SIGNALS:
        raise DataError(f"unknown signal {signal!r}", where="signal", hint="'grf' or 'distance'")
    _check_groups(measured, "measured stances")
    name, scale, label = SIGNALS[signal]
    pct = np.linspace(0.0, 100.0, n_points)
    fig, axes = _figure(len(measured))
    marked = False
    for ax, (group, stances) in zip(axes, measured.items(), strict=True):
        _style(ax)
        spans = normalisation_spans(stances, window=window, contact_threshold=contact_threshold)
        kept, bad = _split_flagged(stances, flagged)
        sims = list(simulated.get(group, [])) if simulated is not None else []
        series = [("measured", MEASURED, "-", stances if include_flagged else kept)]
        if sims:
            sims_kept, _ = _split_flagged(sims, flagged)
            series.append(("simulated", SIMULATED, "--", sims if include_flagged else sims_kept))
        for lab, colour, ls, items in series:
            if not items:
                continue
            mean, sd = _mean_sd(items, name, n_points, paired_spans(stances, items, spans))
            ax.fill_between(
                pct, (mean - sd) * scale, (mean + sd) * scale, color=colour, alpha=0.18, linewidth=0
            )
            ax.plot(
                pct,
                mean * scale,
                color=colour,
                linestyle=ls,
                linewidth=1.6,
                label=f"{lab} mean ± SD",
            )
        for st, sp in zip(bad, paired_spans(stances, bad, spans), strict=True):
            ax.plot(pct, resample_percent(st, name, n_points=n_points, span=sp) * scale,
                    color=FLAGGED,
                    linestyle=":", linewidth=1.0,
                    label=None if marked else ("flagged trial (in the band)" if include_flagged
                                               else "flagged trial (left out)"))
            marked = True
        n_in = len(stances) if include_flagged else len(kept)
        extra = f", {len(bad)} flagged" if bad else ""
        ax.set_title(f"{group} (n = {n_in}{extra})")
        ax.set_xlabel(WINDOW_LABELS[window])
        ax.set_ylabel(label)
        ax.set_xlim(0, 100)
    handles = [h for ax in axes for h in ax.get_legend_handles_labels()[0]]
    labels = [lab for ax in axes for lab in ax.get_legend_handles_labels()[1]]
    uniq = dict(zip(labels, handles, strict=True))
    axes[0].legend(list(uniq.values()), list(uniq), loc="best")
    return fig


def _loop_panels(
    mechanics: Mapping[str, Sequence[StanceMechanics]],
    *,
    xlabel: str,
    ylabel: str,
    get,
    flagged: Collection[str] = (),
) -> Figure:
    _check_groups(mechanics, "mechanics")
    fig, axes = _figure(len(mechanics))
    marked = False
    for ax, (group, items) in zip(axes, mechanics.items(), strict=True):
        _style(ax)
        plotted = n_flagged = 0
        for m in items:
            xy = get(m)
            if xy is None:
                continue
            (xl, yl), (xu, yu) = xy
            if _trial_id(m) in flagged:
                ax.plot(np.concatenate([xl, xu]), np.concatenate([yl, yu]), color=FLAGGED,
                        linewidth=1.0, linestyle=":", label=None if marked else "flagged trial")
                marked = True
                n_flagged += 1
                continue
            ax.plot(
                xl,
                yl,
                color=LOADING,
                linewidth=1.0,
                alpha=0.75,
                label="loading" if plotted == 0 else None,
            )
            ax.plot(
                xu,
                yu,
                color=UNLOADING,
                linewidth=1.0,
                alpha=0.75,
                linestyle="--",
                label="unloading" if plotted == 0 else None,
            )
            plotted += 1
        extra = f", {n_flagged} flagged" if n_flagged else ""
        ax.set_title(f"{group} (n = {plotted}{extra})")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        if plotted + n_flagged == 0:
            ax.text(0.5, 0.5, "no data", transform=ax.transAxes, ha="center", color="#888888")
    handles, labels = [], []
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    axes[0].legend(handles, labels, loc="best")
    return fig


@_styled
def hysteresis_loops(
    mechanics: Mapping[str, Sequence[StanceMechanics]], *, flagged: Collection[str] = ()
) -> Figure:
    """GRF vs angular deformation Δθ per group, loading and unloading branches (§3.4).

    Stances without a blade angle are left out of their panel; flagged trials (ids in
    ``flagged``, matched on ``metadata["trial"]``) are drawn grey and dotted.
    """

    def get(m: StanceMechanics):
        loop = m.angle_loop
        if loop is None:
            return None
        i0 = m.contact_index
        (xl, yl), (xu, yu) = loop.loading, loop.unloading
        return (np.rad2deg(xl[i0:]), yl[i0:]), (np.rad2deg(xu), yu)

    return _loop_panels(mechanics, xlabel="angular deformation Δθ [deg]", ylabel="GRF [N]",
                        get=get, flagged=flagged)


@_styled
def compressive_stiffness_curves(
    mechanics: Mapping[str, Sequence[StanceMechanics]], *, flagged: Collection[str] = ()
) -> Figure:
    """Equivalent compressive stiffness K_c vs compression Δd per group (§3.5); flagged trials
    grey and dotted. K_c is drawn where Δd is above each stance's compression threshold
    (:func:`bladelab.mechanics.stance_mechanics`: above the distance noise); the panel's median
    threshold is a dash-dotted line, the range written beside it."""

    def get(m: StanceMechanics):
        loop = m.compression_loop
        kc = m.compressive_stiffness / 1e3
        i = loop.peak_index
        dd = m.compression * 1e3
        return (dd[: i + 1], kc[: i + 1]), (dd[i:], kc[i:])

    fig = _loop_panels(mechanics, xlabel="compression Δd [mm]", ylabel="K_c [kN/m]", get=get,
                       flagged=flagged)
    for ax, items in zip(fig.axes, mechanics.values(), strict=False):
        th = [m.compression_threshold * 1e3 for m in items]
        if th:
            med = float(np.median(th))
            ax.axvline(med, color="#999999", linewidth=0.8, linestyle="-.")
            ax.text(med, 0.98, f" K_c from Δd ≥ {min(th):.0f}–{max(th):.0f} mm\n (median {med:.0f})"
                    if min(th) < max(th) - 0.5 else f" K_c from Δd ≥ {med:.0f} mm",
                    transform=ax.get_xaxis_transform(), ha="left", va="top", fontsize=7,
                    color="#666666")
    return fig


@_styled
def parameter_bars(
    summary: pd.DataFrame,
    *,
    parameters: Sequence[tuple[str, str]] = (
        ("K_Nm_per_deg", "K* [N·m/deg]"),
        ("D_Nms_per_deg", "D* [N·m·s/deg]"),
    ),
    group: str = "group",
    band: str = "speed_band",
) -> Figure:
    """K* and D* per group and speed band with confidence intervals (seed 000 Fig. 3).

    Parameters
    ----------
    summary
        One row per (group, band): the value column (the mean) and ``<value>_ci_low``,
        ``<value>_ci_high`` (as from :func:`bladelab.stats.summarize`).
    parameters
        (column, axis label with unit) pairs, one panel each.
    group, band
        Column names of the group and speed band.

    Bars are the means, whiskers the confidence interval given (say so in the caption).
    """
    need = [group, band] + [
        c for col, _ in parameters for c in (col, f"{col}_ci_low", f"{col}_ci_high")
    ]
    missing = [c for c in need if c not in summary.columns]
    if missing:
        raise DataError(
            f"missing columns {missing}",
            where="parameter summary",
            hint="build it with bladelab.stats.summarize(values=[...], by=[group, speed_band])",
        )
    groups = list(dict.fromkeys(summary[group]))
    bands = list(dict.fromkeys(summary[band]))
    fig, axes = _figure(len(parameters), width=4.6, height=3.0, share=False)
    width = 0.8 / max(len(bands), 1)
    x = np.arange(len(groups))
    for ax, (col, label) in zip(axes, parameters, strict=True):
        _style(ax)
        ax.grid(False, axis="x")
        for j, b in enumerate(bands):
            sub = summary[summary[band] == b].set_index(group).reindex(groups)
            mean = sub[col].to_numpy(float)
            lo = np.nan_to_num(mean - sub[f"{col}_ci_low"].to_numpy(float))
            hi = np.nan_to_num(sub[f"{col}_ci_high"].to_numpy(float) - mean)
            pos = x - 0.4 + width * (j + 0.5)
            ax.bar(
                pos,
                mean,
                width * 0.92,
                color=PALETTE[j % len(PALETTE)],
                label=str(b),
                edgecolor="white",
                linewidth=0.5,
            )
            ax.errorbar(
                pos, mean, yerr=[lo, hi], fmt="none", ecolor="#333333", capsize=3, linewidth=1.0
            )
        ax.set_xticks(x, groups)
        ax.set_ylabel(label)
        ax.set_xlabel("group")
    axes[0].legend(title="speed band", loc="upper left", title_fontsize=8)
    return fig
