"""Figures of response surfaces: main effects and contours with constraints and the optimum.

Figures are built with matplotlib's object interface (no pyplot, no global state); axes are in
the factors' units and the response's unit. :func:`save_figure` writes atomically.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from bladelab._io import atomic_path, figure_format
from bladelab.design.optimum import OptimumResult, SurfaceConstraint, surface_constraints
from bladelab.design.settling_effects import RESOLVED_P
from bladelab.design.space import DesignSpace
from bladelab.design.surfaces import ResponseSurface
from bladelab.errors import SpecError

__all__ = ["contour_plot", "effects_by_stage_plot", "figure_pairs", "main_effects_plot", "save_figure",
           "write_design_figures"]


def _levels(space: DesignSpace, at: Mapping[str, float] | None) -> np.ndarray:
    base = np.zeros(space.n_factors)
    for name, v in (at or {}).items():
        v = float(v)
        if abs(v) > 1.0 + 1e-9:
            raise SpecError(f"coded level {v} of {name} lies outside [-1, 1]", where="at")
        base[space.index(name)] = v
    return base


def _check(surface: ResponseSurface, space: DesignSpace) -> None:
    if tuple(surface.factor_names) != tuple(space.names):
        raise SpecError(
            f"surface {surface.response!r} is over factors {surface.factor_names}, the space "
            f"has {space.names}",
            where="plot",
        )


def main_effects_plot(
    surfaces: ResponseSurface | Sequence[ResponseSurface],
    space: DesignSpace,
    *,
    at: Mapping[str, float] | None = None,
    level: float = 0.95,
    n: int = 51,
) -> Figure:
    """Main-effect plots: each response (rows) against each factor (columns).

    One factor is varied over its range while the others stay at ``at`` (coded levels, default
    0: the centre). The band is the confidence interval of the fitted mean at ``level``.
    """
    surfs = [surfaces] if isinstance(surfaces, ResponseSurface) else list(surfaces)
    if not surfs:
        raise SpecError("no surfaces to plot", where="plot")
    for s in surfs:
        _check(s, space)
    base = _levels(space, at)
    k = space.n_factors
    fig = Figure(figsize=(2.8 * k, 2.4 * len(surfs)), layout="constrained")
    axes = fig.subplots(len(surfs), k, squeeze=False, sharey="row")
    c = np.linspace(-1.0, 1.0, n)
    for r, s in enumerate(surfs):
        for j, f in enumerate(space.factors):
            pts = np.tile(base, (n, 1))
            pts[:, j] = c
            pred = s.predict(pts, level=level)
            x = f.mid + c * f.half_range
            ax = axes[r, j]
            ax.fill_between(x, pred.ci_lower, pred.ci_upper, color="C0", alpha=0.25, lw=0)
            ax.plot(x, pred.mean, color="C0")
            ax.set_xlabel(f.axis_label)
            if j == 0:
                ax.set_ylabel(s.label)
            ax.grid(True, alpha=0.3)
    fig.suptitle(f"Main effects (other factors at coded {np.round(base, 2).tolist()}; "
                 f"band: {level:.0%} CI)", fontsize="medium")
    return fig


def effects_by_stage_plot(effects: Mapping[str, Any], space: DesignSpace) -> Figure:
    """Each factor's first-order effect (columns) on each response (rows) after the runs and
    after each settling pass, with its confidence interval; a filled marker is resolved
    (p < :data:`~bladelab.design.settling_effects.RESOLVED_P`), a hollow one not.
    ``effects``: response -> the table of
    :func:`~bladelab.design.settling_effects.effects_by_stage`."""
    if not effects:
        raise SpecError("no effects to plot", where="plot")
    k = space.n_factors
    fig = Figure(figsize=(2.8 * k, 2.6 * len(effects)), layout="constrained")
    axes = fig.subplots(len(effects), k, squeeze=False, sharey="row")
    for r, (response, table) in enumerate(effects.items()):
        for j, name in enumerate(space.names):
            rows = table[table["factor"] == name]
            x = np.arange(len(rows))
            eff = rows["effect"].to_numpy(float)
            err = np.vstack([eff - rows["ci_lower"].to_numpy(float),
                             rows["ci_upper"].to_numpy(float) - eff])
            ax = axes[r, j]
            ax.axhline(0.0, color="0.5", lw=0.8)
            ax.errorbar(x, eff, yerr=err, fmt="none", ecolor="C0", capsize=3)
            resolved = rows["p_value"].to_numpy(float) < RESOLVED_P
            ax.plot(x[resolved], eff[resolved], "o", color="C0")
            ax.plot(x[~resolved], eff[~resolved], "o", mfc="white", color="C0")
            ax.set_xticks(x, [s.replace(" designs)", ")") for s in rows["stage"]],
                          rotation=30, ha="right", fontsize="small")
            if r == 0:
                ax.set_title(name, fontsize="medium")
            if j == 0:
                unit = rows["unit"].iloc[0] if len(rows) else ""
                ax.set_ylabel(f"{response}\n[{unit}]", fontsize="small")
            ax.grid(True, alpha=0.3)
    fig.suptitle("First-order effects after the runs and each settling pass (bars: 95 % CI; "
                 f"filled: p < {RESOLVED_P:g})", fontsize="medium")
    return fig


def contour_plot(
    surface: ResponseSurface,
    space: DesignSpace,
    *,
    x: str,
    y: str,
    at: Mapping[str, float] | None = None,
    constraints: Sequence[SurfaceConstraint] = (),
    optimum: OptimumResult | None = None,
    n: int = 81,
    show_runs: bool = True,
    missing: np.ndarray | None = None,
    missing_label: str = "failed runs (projected)",
) -> Figure:
    """Contours of a fitted surface over two factors, others held at ``at``.

    Parameters
    ----------
    surface
        The fitted surface.
    space
        The design space (axes in the factors' units).
    x, y
        The two factors varied.
    at
        Coded levels of the other factors; default the optimum's if given, else 0.
    constraints
        Drawn as a boundary line (surface = minimum) with the infeasible side hatched.
    optimum
        Marked with a star.
    n
        Grid points per axis.
    show_runs
        Mark the design runs (projected onto the plane).
    missing
        Coded points (rows) of runs that are not in the surface (failed, or left out): marked
        with a red cross and ``missing_label``.
    """
    _check(surface, space)
    ix, iy = space.index(x), space.index(y)
    if ix == iy:
        raise SpecError("x and y must be different factors", where="plot")
    if at is None and optimum is not None:
        at = dict(optimum.coded)
    base = _levels(space, at)
    fx, fy = space.factors[ix], space.factors[iy]
    c = np.linspace(-1.0, 1.0, n)
    cx, cy = np.meshgrid(c, c)
    pts = np.tile(base, (cx.size, 1))
    pts[:, ix], pts[:, iy] = cx.ravel(), cy.ravel()
    X = fx.mid + cx * fx.half_range
    Y = fy.mid + cy * fy.half_range
    Z = np.asarray(surface.predict_mean(pts)).reshape(cx.shape)
    fig = Figure(figsize=(5.6, 4.4), layout="constrained")
    ax = fig.subplots()
    cf = ax.contourf(X, Y, Z, levels=15, cmap="viridis")
    ax.contour(X, Y, Z, levels=15, colors="k", linewidths=0.3, alpha=0.5)
    fig.colorbar(cf, ax=ax, label=surface.label)
    for i, con in enumerate(constraints):
        _check(con.surface, space)
        G = con.margin(np.asarray(con.surface.predict_mean(pts)).reshape(cx.shape))
        if G.min() < 0 < G.max():
            ax.contour(X, Y, G, levels=[0.0], colors=f"C{(i + 1) % 10}", linewidths=2)
            ax.contourf(X, Y, G, levels=[G.min() - 1.0, 0.0], colors="none", hatches=["//"])
        ax.plot([], [], color=f"C{(i + 1) % 10}", lw=2,
                label=f"{con.name} {con.relation} {con.bound:g} (hatched: infeasible)")
    if show_runs:
        rx = fx.mid + surface.coded[:, ix] * fx.half_range
        ry = fy.mid + surface.coded[:, iy] * fy.half_range
        ax.plot(rx, ry, "o", ms=3, color="w", mec="k", mew=0.5, label="runs (projected)")
    if missing is not None and len(missing):
        miss = np.atleast_2d(np.asarray(missing, float))
        ax.plot(fx.mid + miss[:, ix] * fx.half_range, fy.mid + miss[:, iy] * fy.half_range,
                "x", ms=8, mew=2, color="r", clip_on=False, zorder=4, label=missing_label)
    if optimum is not None:
        ox = fx.mid + optimum.coded[fx.name] * fx.half_range
        oy = fy.mid + optimum.coded[fy.name] * fy.half_range
        ax.plot([ox], [oy], "*", ms=14, color="r", mec="k", clip_on=False, zorder=5,
                label=f"optimum: {optimum.predicted:.4g} {optimum.unit}".rstrip())
    ax.set_xlabel(fx.axis_label)
    ax.set_ylabel(fy.axis_label)
    others = [f"{f.name}={base[j]:+.2f}" for j, f in enumerate(space.factors) if j not in (ix, iy)]
    ax.set_title(f"{surface.response}" + (f" ({', '.join(others)} coded)" if others else ""),
                 fontsize="small")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="x-small", loc="best")
    return fig


def save_figure(fig: Figure, path: str | Path, *, dpi: int = 150) -> Path:
    """Save a figure atomically; the format follows the suffix (.png, .pdf, .svg)."""
    path = Path(path)
    fmt = figure_format(path, where="figure")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=dpi)
    return path


def figure_pairs(names: Sequence[str]) -> list[tuple[str, str]]:
    """Factor pairs drawn as contour plots: (stiffness, width) and (height, toe length) when
    present (seed 002's figures), else consecutive pairs."""
    pairs = [(a, b) for a, b in (("stiffness_kN_per_m", "width_m"), ("height_m", "toe_length_m"))
             if a in names and b in names]
    if not pairs and len(names) >= 2:
        pairs = [(names[i], names[i + 1]) for i in range(0, len(names) - 1, 2)]
    return pairs


def write_design_figures(result, out_dir: str | Path, *, objective: str,
                         constraints: Mapping[str, Any]) -> list[Path]:
    """Main-effect and contour figures of a finished study
    (:class:`~bladelab.design.study.DesignStudyResult`) into ``out_dir/figures``; returns the
    paths written."""
    fig_dir = Path(out_dir) / "figures"
    names = [objective, *[c for c in constraints if c != objective]]
    surfs = [result.surfaces[n] for n in names if n in result.surfaces]
    written = [save_figure(main_effects_plot(surfs, result.space), fig_dir / "main_effects.png")]
    cons = surface_constraints(result.surfaces, constraints)
    for x, y in figure_pairs(result.space.names):
        fig = contour_plot(result.surfaces[objective], result.space, x=x, y=y, constraints=cons,
                           optimum=result.optimum,
                           missing=result.design.coded[[r - 1 for r in result.failed]])
        written.append(save_figure(fig, fig_dir / f"contour_{objective}_{x}_{y}.png"))
    return written
