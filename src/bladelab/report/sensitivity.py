"""How far to trust K* and D*: their sensitivity to marker noise and kinematic sampling rate.

The numbers come from the robust-identification measurement study (``benchmarks/bench_robust.py``):
stances made by the MuJoCo runner generator (not the identification model), degraded
as a lab records them (clamp cluster and tip markers at 100 or 250 Hz with 0–3 mm noise per
coordinate, 20 Hz low-pass; forces at 1 kHz with 1 % noise) and identified with each
formulation. The benchmark writes the table into the package (``data/sensitivity/``), so every
study report can show it without re-running the study.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from bladelab.errors import InputFileError

#: Columns of the measurement table (one row per stance × marker rate × noise × formulation).
SENSITIVITY_COLUMNS = ("case", "blade", "marker_rate_Hz", "marker_noise_mm", "formulation",
                       "K_err_pct", "D_err_pct", "K_ci_halfwidth_pct", "D_ci_halfwidth_pct")


def packaged_sensitivity_path() -> Path:
    """Path of the sensitivity table shipped with bladelab (written by ``bench_robust``)."""
    return Path(str(resources.files("bladelab") / "data" / "sensitivity" / "robust-sensitivity.csv"))


def read_sensitivity(path: str | Path | None = None) -> pd.DataFrame:
    """Read a sensitivity table (default: the packaged one) and check its columns."""
    path = packaged_sensitivity_path() if path is None else Path(path)
    if not path.is_file():
        raise InputFileError("sensitivity table not found", file=path,
                             hint="run `python benchmarks/run.py robust` to measure it")
    table = pd.read_csv(path)
    missing = [c for c in SENSITIVITY_COLUMNS if c not in table.columns]
    if missing:
        raise InputFileError(f"missing column(s) {', '.join(missing)}", file=path)
    return table


def sensitivity_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Median and 90th percentile of |K error|, |D error| [%] and the median CI half-widths [%],
    per formulation, marker rate [Hz] and marker noise [mm]."""
    t = table.assign(K_abs=table["K_err_pct"].abs(), D_abs=table["D_err_pct"].abs())
    grouped = t.groupby(["formulation", "marker_rate_Hz", "marker_noise_mm"], sort=True)
    return grouped.agg(
        n_stances=("case", "size"),
        K_abs_error_median_pct=("K_abs", "median"),
        K_abs_error_p90_pct=("K_abs", lambda x: float(np.quantile(x, 0.9))),
        D_abs_error_median_pct=("D_abs", "median"),
        D_abs_error_p90_pct=("D_abs", lambda x: float(np.quantile(x, 0.9))),
        K_ci_halfwidth_median_pct=("K_ci_halfwidth_pct", "median"),
        D_ci_halfwidth_median_pct=("D_ci_halfwidth_pct", "median"),
    ).reset_index()


def sensitivity_figure(table: pd.DataFrame) -> Figure:
    """|K error| and |D error| [%] against marker noise [mm], one line per formulation and
    marker rate (solid: median, faint: 90th percentile); dotted: the 5 % / 20 % targets."""
    fig = Figure(figsize=(10, 4), layout="constrained")
    axes = fig.subplots(1, 2, sharex=True)
    colors = {"seed": "#D55E00", "utilised-friction": "#0072B2", "grf-driven": "#009E73"}
    for ax, col, limit in ((axes[0], "K_err_pct", 5.0), (axes[1], "D_err_pct", 20.0)):
        for (form, rate), g in table.groupby(["formulation", "marker_rate_Hz"]):
            agg = g.assign(a=g[col].abs()).groupby("marker_noise_mm")["a"]
            med, p90 = agg.median(), agg.quantile(0.9)
            color = colors.get(form, "#444444")
            style = "--" if rate < 200 else "-"
            ax.plot(med.index, med.values, color=color, ls=style, marker="o",
                    label=f"{form}, {rate:.0f} Hz (median)")
            ax.plot(p90.index, p90.values, color=color, ls=style, alpha=0.35)
        ax.axhline(limit, color="k", lw=0.8, ls=":")
        ax.set_xlabel("marker noise per coordinate [mm]")
        ax.set_ylabel(f"|{col.split('_')[0]}* error| [%] (faint: 90th percentile)")
        ax.set_yscale("symlog", linthresh=1)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Sensitivity of K* and D* to marker noise and rate (forces 1 kHz, 1 % noise)")
    return fig
