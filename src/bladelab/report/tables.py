"""Report tables: nRMSE per group in the layout of seed 000 Tables 1–2.

nRMSE = RMSE(simulated − measured) / (max − min of the measured signal) · 100 [%] (seed 000
§2.3), computed on individual trials (reported as mean ± SD per group) and on the group mean
curves (each stance normalised to 0–100 % of its contact, then averaged). By default both use the
measured contact (touch-down to toe-off, vertical GRF > 20 N), as the identification's cost does;
``window="stance"`` uses the whole window (flight included, which lowers the GRF's nRMSE).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from bladelab.errors import DataError
from bladelab.parameters import JOINT_PARAMETERS
from bladelab.report.figures import (
    SIGNALS,
    Signal,
    Window,
    contact_span,
    normalisation_spans,
    paired_spans,
    resample_percent,
)
from bladelab.trial.stance import Stance

__all__ = [
    "nrmse_pct",
    "trial_nrmse",
    "mean_curve_nrmse",
    "nrmse_table",
    "stats_display",
    "parameter_summary_display",
]


def nrmse_pct(measured: np.ndarray, simulated: np.ndarray) -> float:
    """RMSE normalised by the range of ``measured`` [%] (NaN if the range is 0)."""
    measured = np.asarray(measured, float)
    simulated = np.asarray(simulated, float)
    if measured.shape != simulated.shape:
        raise DataError(
            f"shapes differ: measured {measured.shape}, simulated {simulated.shape}",
            where="nRMSE",
            hint="compare signals sampled on the same time base",
        )
    span = float(np.nanmax(measured) - np.nanmin(measured))
    if span <= 0:
        return float("nan")
    return float(np.sqrt(np.nanmean((simulated - measured) ** 2)) / span * 100.0)


def trial_nrmse(
    measured: Mapping[str, Sequence[Stance]],
    simulated: Mapping[str, Sequence[Stance]],
    *,
    signal: Signal = "grf",
    window: Window = "contact",
    contact_threshold: float = 20.0,
) -> pd.DataFrame:
    """nRMSE of each simulated stance against its measured one (same samples), over the
    measured contact (``window="contact"``) or the whole window (``"stance"``).

    Returns a tidy table with columns ``group``, ``trial`` (index in the group, or the
    ``trial`` metadata), ``signal`` and ``nrmse_pct``.
    """
    name = SIGNALS[signal][0]
    rows = []
    for group, stances in measured.items():
        sims = simulated.get(group, [])
        if len(sims) != len(stances):
            raise DataError(
                f"{len(stances)} measured but {len(sims)} simulated stances",
                where=f"group {group}",
                hint="pass one simulated stance per measured stance, in the same order",
            )
        for i, (m, s) in enumerate(zip(stances, sims, strict=True)):
            a, b = getattr(m, name), getattr(s, name)
            if window == "contact":
                t0, t1 = contact_span(m, threshold=contact_threshold)
                keep = (m.time >= t0) & (m.time <= t1)
                if np.shape(b) == np.shape(a):
                    a, b = np.asarray(a)[keep], np.asarray(b)[keep]
            rows.append(
                {
                    "group": group,
                    "trial": m.metadata.get("trial", i),
                    "signal": signal,
                    "nrmse_pct": nrmse_pct(a, b),
                }
            )
    return pd.DataFrame(rows, columns=["group", "trial", "signal", "nrmse_pct"])


def mean_curve_nrmse(
    measured: Mapping[str, Sequence[Stance]],
    simulated: Mapping[str, Sequence[Stance]],
    *,
    signal: Signal = "grf",
    n_points: int = 101,
    window: Window = "contact",
    contact_threshold: float = 20.0,
) -> pd.DataFrame:
    """nRMSE between the group mean curves (0–100 % of the measured contact, or of the window)
    of simulated and measured stances.

    Returns columns ``group``, ``signal``, ``nrmse_pct``.
    """
    name = SIGNALS[signal][0]
    rows = []
    for group, stances in measured.items():
        sims = simulated.get(group, [])
        if not stances or not sims:
            continue
        spans = normalisation_spans(stances, window=window, contact_threshold=contact_threshold)
        m = np.mean([resample_percent(s, name, n_points=n_points, span=spans[i])
                     for i, s in enumerate(stances)], axis=0)
        s = np.mean([resample_percent(x, name, n_points=n_points, span=sp)
                     for x, sp in zip(sims, paired_spans(stances, sims, spans), strict=True)],
                    axis=0)
        rows.append({"group": group, "signal": signal, "nrmse_pct": nrmse_pct(m, s)})
    return pd.DataFrame(rows, columns=["group", "signal", "nrmse_pct"])


def nrmse_table(
    trials: pd.DataFrame,
    mean_curves: pd.DataFrame | None = None,
    *,
    signal: str | None = None,
    formatted: bool = False,
) -> pd.DataFrame:
    """nRMSE per group: individual trials (mean ± SD) and mean curves (seed 000 Tables 1–2).

    Parameters
    ----------
    trials
        Per-trial nRMSE: columns ``group``, ``nrmse_pct`` (and ``signal`` to filter on).
    mean_curves
        Per-group nRMSE of the mean curves: columns ``group``, ``nrmse_pct`` (and ``signal``).
    signal
        Keep only rows of this signal (``"grf"`` or ``"distance"``).
    formatted
        Return the display layout (``Group``, ``nRMSE [%] individual trials`` as
        ``"10.27 ± 2.28"``, ``nRMSE [%] mean curves``) instead of numbers.

    Returns
    -------
    pandas.DataFrame
        Numeric: ``group``, ``n_trials``, ``nrmse_trials_mean_pct``, ``nrmse_trials_sd_pct``,
        ``nrmse_mean_curve_pct``; groups in order of first appearance.
    """
    for name, df in (("trials", trials), ("mean_curves", mean_curves)):
        if df is not None and not {"group", "nrmse_pct"} <= set(df.columns):
            raise DataError(
                "needs columns 'group' and 'nrmse_pct'", where=name, hint="see trial_nrmse()"
            )

    def pick(df):
        if signal is not None and "signal" in df.columns:
            return df[df["signal"] == signal]
        return df

    t = pick(trials)
    groups = list(dict.fromkeys(t["group"]))
    stats = t.groupby("group", sort=False)["nrmse_pct"].agg(["count", "mean", "std"])
    out = pd.DataFrame(
        {
            "group": groups,
            "n_trials": [int(stats.loc[g, "count"]) for g in groups],
            "nrmse_trials_mean_pct": [float(stats.loc[g, "mean"]) for g in groups],
            "nrmse_trials_sd_pct": [float(stats.loc[g, "std"]) for g in groups],
        }
    )
    if mean_curves is not None:
        mc = pick(mean_curves).set_index("group")["nrmse_pct"]
        out["nrmse_mean_curve_pct"] = [float(mc.get(g, np.nan)) for g in groups]
    else:
        out["nrmse_mean_curve_pct"] = np.nan
    if not formatted:
        return out

    def pm(m, s):
        return f"{m:.2f} ± {s:.2f}" if np.isfinite(s) else f"{m:.2f}"

    return pd.DataFrame(
        {
            "Group": out["group"],
            "n": out["n_trials"],
            "nRMSE [%] individual trials": [
                pm(m, s)
                for m, s in zip(
                    out["nrmse_trials_mean_pct"], out["nrmse_trials_sd_pct"], strict=True
                )
            ],
            "nRMSE [%] mean curves": [
                f"{v:.2f}" if np.isfinite(v) else "–" for v in out["nrmse_mean_curve_pct"]
            ],
        }
    )


def _p_text(p: float) -> str:
    if not np.isfinite(p):
        return "–"
    return "< 0.001" if p < 1e-3 else f"{p:.3f}"


_SHORT_TESTS = {
    "Mann-Whitney U": "Mann–Whitney U",
    "Kruskal-Wallis H": "Kruskal–Wallis",
    "Dunn (Bonferroni)": "Dunn–Bonferroni",
    "Mann-Whitney U (speed band)": "Speed band (U)",
}
_SHORT_PARAMETERS = {JOINT_PARAMETERS[n].edge_key: f"{n}*" for n in ("K", "D")}


def stats_display(results: pd.DataFrame) -> pd.DataFrame:
    """A readable layout of :func:`bladelab.stats.compare_groups` results for the page.

    Columns: Test, Parameter (``K*``/``D*`` for the standard columns), Subset (the category or
    amputation level, or ``all``), Groups, n, Statistic (``"U = 12"``, ``"H = 9.83"``,
    ``"z = −1.63"``), p, p (Bonferroni) — shown for Dunn rows, r, and ``*`` where significant.
    Write the full numeric table as the CSV (``ReportTable(..., csv=results)``).
    """
    rows = []
    for r in results.itertuples(index=False):
        stat = f"{r.statistic_name} = {r.statistic:.3g}" if np.isfinite(r.statistic) else "–"
        rows.append(
            {
                "Test": _SHORT_TESTS.get(r.test, r.test),
                "Parameter": _SHORT_PARAMETERS.get(r.parameter, r.parameter),
                "Subset": r.subset.split("=", 1)[-1],
                "Groups": r.groups.replace(" | ", " vs "),
                "n": r.n,
                "Statistic": stat.replace("-", "−"),
                "p": _p_text(r.p),
                "p (Bonferroni)": _p_text(r.p_adjusted) if r.test.startswith("Dunn") else "",
                "r": f"{r.effect_size_r:.2f}".replace("-", "−")
                if np.isfinite(r.effect_size_r)
                else "–",
                "": "*" if bool(r.significant) else "",
            }
        )
    return pd.DataFrame(rows)


def parameter_summary_display(
    summary: pd.DataFrame,
    *,
    parameters: Sequence[tuple[str, str]] = tuple(
        (JOINT_PARAMETERS[n].edge_key, f"{n}* [{JOINT_PARAMETERS[n].edge_unit}]") for n in ("K", "D")
    ),
    by: Sequence[str] = ("group", "speed_band"),
) -> pd.DataFrame:
    """``mean (CI low–high)`` per parameter from :func:`bladelab.stats.summarize` output; a lower
    limit clipped at its physical minimum (``<value>_ci_clipped``) is marked ``‡``."""
    out = summary[list(by)].copy()
    out.columns = [c.replace("_", " ") for c in by]
    out["n"] = summary["n"].to_numpy()
    for col, label in parameters:
        digits = 3 if float(np.nanmax(np.abs(summary[col]))) < 1 else 2
        clipped = (summary[f"{col}_ci_clipped"] if f"{col}_ci_clipped" in summary
                   else pd.Series(False, index=summary.index))
        out[f"{label} mean (95 % CI)"] = [
            f"{m:.{digits}f} ({lo:.{digits}f}{'‡' if c else ''}–{hi:.{digits}f})"
            if np.isfinite(lo)
            else f"{m:.{digits}f}"
            for m, lo, hi, c in zip(
                summary[col], summary[f"{col}_ci_low"], summary[f"{col}_ci_high"],
                clipped.fillna(False).astype(bool), strict=True
            )
        ]
    return out
