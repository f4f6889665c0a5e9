"""Sections of the study report that stand apart: recovered vs true parameters (a synthetic
study's ground truth) and how far to trust K* and D* (the measured sensitivity to noise)."""

from __future__ import annotations

from collections.abc import Collection
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab.parameters import JOINT_PARAMETERS
from bladelab.report.sensitivity import read_sensitivity, sensitivity_figure, sensitivity_summary
from bladelab.report.study_quality import flag_column

__all__ = ["add_sensitivity_section", "add_truth_section"]


def _truth_figure(merged: pd.DataFrame):
    """Identified vs true K and D with CI whiskers; flagged trials as grey crosses."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10.0, 4.2))
    for i, (col, true, label) in enumerate(
            (p.edge_key, f"{p.name}_true", f"{p.name} [{p.edge_unit}]")
            for p in (JOINT_PARAMETERS["K"], JOINT_PARAMETERS["D"])):
        ax = fig.add_subplot(1, 2, i + 1)
        bad = merged["flagged"].fillna(False).astype(bool) if "flagged" in merged else \
            pd.Series(False, index=merged.index)
        for g, sub in merged[~bad].groupby("group", sort=False):
            ax.scatter(sub[true], sub[col], s=22, label=g, alpha=0.85)
            if f"{col}_ci_low" in sub and sub[f"{col}_ci_low"].notna().any():
                ax.errorbar(sub[true], sub[col],
                            yerr=[np.clip(sub[col] - sub[f"{col}_ci_low"], 0, None),
                                  np.clip(sub[f"{col}_ci_high"] - sub[col], 0, None)],
                            fmt="none", ecolor="#999999", linewidth=0.7, capsize=1.5)
        if bad.any():
            ax.scatter(merged.loc[bad, true], merged.loc[bad, col], s=40, marker="x",
                       color="#555555", label="flagged trial")
        lo = float(np.nanmin([merged[true].min(), merged[col].min()]))
        hi = float(np.nanmax([merged[true].max(), merged[col].max()]))
        pad = 0.05 * (hi - lo if hi > lo else 1.0)
        ax.plot([lo - pad, hi + pad], [lo - pad, hi + pad], color="#333333", linewidth=1.0,
                linestyle="--", label="identity")
        # long whiskers (poorly determined trials) must not squash the points
        ax.set_ylim(lo - 4 * pad, hi + 4 * pad)
        ax.set_xlabel(f"true {label}")
        ax.set_ylabel(f"identified {label}")
        ax.set_title(f"{label.split(' ')[0]}: identified vs true")
        ax.grid(True, alpha=0.3)
    fig.axes[0].legend(loc="upper left", fontsize=7)
    fig.tight_layout()
    return fig


def add_truth_section(rep, per_trial: pd.DataFrame, gt_path: Path, *, kept_ids: Collection[str],
                      include_flagged: bool) -> None:
    """The "Recovered vs true parameters" section: ground_truth.csv against the identified K*, D* (flagged
    trials marked; left out of the errors per group unless ``include_flagged``)."""
    gt = pd.read_csv(gt_path, comment="#")
    merged = per_trial.merge(
        gt[["trial_id", "K_Nm_per_deg", "D_Nms_per_deg"]].rename(
            columns={"K_Nm_per_deg": "K_true", "D_Nms_per_deg": "D_true"}), on="trial_id")
    merged = merged.rename(columns={
        "K_ci_low_Nm_per_deg": "K_Nm_per_deg_ci_low", "K_ci_high_Nm_per_deg": "K_Nm_per_deg_ci_high",
        "D_ci_low_Nms_per_deg": "D_Nms_per_deg_ci_low",
        "D_ci_high_Nms_per_deg": "D_Nms_per_deg_ci_high"})
    merged["K_error_pct"] = 100 * (merged["K_Nm_per_deg"] / merged["K_true"] - 1)
    merged["D_error_pct"] = 100 * (merged["D_Nms_per_deg"] / merged["D_true"] - 1)
    secant = ""
    if "K_secant_peak_Nm_per_deg" in gt.columns:
        merged = merged.merge(gt[["trial_id", "K_secant_peak_Nm_per_deg"]], on="trial_id")
        merged["K_vs_secant_error_pct"] = 100 * (
            merged["K_Nm_per_deg"] / merged["K_secant_peak_Nm_per_deg"] - 1)
        secant = (f" Against the secant stiffness of the generator's stiffening hinge at its "
                  f"peak deflection (K_secant_peak in ground_truth.csv), the median K error is "
                  f"{float(np.median(merged['K_vs_secant_error_pct'])):+.1f} %.")
    for p in ("K", "D"):
        col = "K_Nm_per_deg" if p == "K" else "D_Nms_per_deg"
        lo, hi = merged.get(f"{col}_ci_low"), merged.get(f"{col}_ci_high")
        merged[f"{p}_true_in_ci"] = (lo <= merged[f"{p}_true"]) & (merged[f"{p}_true"] <= hi) \
            if lo is not None else np.nan
    agg = merged[merged["trial_id"].isin(kept_ids)].groupby("group", sort=False).agg(
        n=("trial_id", "size"),
        K_error_median_pct=("K_error_pct", "median"),
        K_abs_error_median_pct=("K_error_pct", lambda x: float(np.median(np.abs(x)))),
        D_error_median_pct=("D_error_pct", "median"),
        D_abs_error_median_pct=("D_error_pct", lambda x: float(np.median(np.abs(x)))),
        K_true_in_ci_pct=("K_true_in_ci", lambda x: 100 * float(np.mean(x.astype(float)))),
        D_true_in_ci_pct=("D_true_in_ci", lambda x: 100 * float(np.mean(x.astype(float)))),
    ).reset_index()
    shown = merged.assign(quality=flag_column(merged["flagged"]))
    within = (np.abs(merged["K_error_pct"]) <= 5) & (np.abs(merged["D_error_pct"]) <= 20)
    rep.add_section(
        "Recovered vs true parameters",
        text=f"The generator's ground truth (ground_truth.csv) against the identified K*, D* "
             f"(whiskers: the identification's confidence intervals). "
             f"{int(within.sum())} of {len(merged)} trials are within K ±5 % and D ±20 %; "
             f"median |K error| {float(np.median(np.abs(merged['K_error_pct']))):.1f} %, "
             f"median |D error| {float(np.median(np.abs(merged['D_error_pct']))):.1f} %. "
             "The generating model is richer than the identified one (stiffening hinge, "
             "softer ground, marker and force noise, 100 Hz kinematics), so exact recovery "
             f"is not expected.{secant} Flagged trials: grey crosses; the errors per group "
             + ("include them." if include_flagged else "leave them out."),
        figures=[("Identified vs true K and D", _truth_figure(merged))],
        tables=[("Errors per group", agg),
                ("Per trial", shown[[c for c in (
                    "trial_id", "quality", "group", "speed_pct_pb", "K_true", "K_secant_peak_Nm_per_deg",
                    "K_Nm_per_deg", "K_error_pct", "K_vs_secant_error_pct", "D_true",
                    "D_Nms_per_deg", "D_error_pct") if c in shown.columns]])],
    )


def add_sensitivity_section(rep, formulations) -> None:
    """How far to trust K* and D*: the measured sensitivity to marker noise and rate."""
    table = read_sensitivity()
    summary = sensitivity_summary(table)
    rep.add_section(
        "How far to trust K* and D*",
        text="Sensitivity of the identified parameters to marker noise and kinematic sampling rate, "
             f"measured on {table['case'].nunique()} synthetic stances from the MuJoCo runner "
             "generator (blades " + ", ".join(sorted(table["blade"].unique())) + "), degraded "
             "as a lab records them: clamp cluster and tip markers at 100 or 250 Hz with the noise "
             "on the axis, 20 Hz low-pass; forces at 1 kHz with 1 % noise "
             "(benchmarks/bench_robust.py, docs/robust-identification.md). This study was "
             f"identified with: {', '.join(sorted(formulations))}. Dotted lines: K 5 %, D 20 %.",
        figures=[("Sensitivity to marker noise and rate", sensitivity_figure(table))],
        tables=[("Sensitivity: errors and CI half-widths [%]", summary)],
    )

