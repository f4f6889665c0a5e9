"""The study report's handling of flagged trials (quality stored by identification).

Each result row of ``results.sqlite`` carries ``flagged`` and ``flags`` (the reasons), computed once
by :func:`bladelab.identify.quality.assess_quality`. The report marks flagged trials wherever
they appear (``⚑`` in tables, grey dotted lines in figures), lists them in one "Flagged trials"
section with the reasons, and leaves them out of group statistics unless ``include_flagged``.
Rows written before the quality columns existed are "not assessed" (kept, and counted).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from bladelab.identify.quality import QualityThresholds

__all__ = ["FLAG_MARK", "add_flagged_section", "flag_column", "row_quality"]

FLAG_MARK = "⚑ flagged"
"""What a flagged trial's row shows in the report's tables."""


def row_quality(row) -> tuple[bool | None, str]:
    """(flagged, reasons) of one stored result row; flagged None when not assessed."""
    value = row.get("flagged") if hasattr(row, "get") else None
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return None, ""
    flags = row.get("flags")
    return bool(int(value)), "" if flags is None or flags != flags else str(flags)


def flag_column(flagged: pd.Series) -> list[str]:
    """The display column: ``⚑ flagged`` for flagged trials, else empty."""
    return [FLAG_MARK if bool(v) else "" for v in flagged.fillna(False)]


def add_flagged_section(rep, per_trial: pd.DataFrame, *, include_flagged: bool) -> None:
    """The "Flagged trials" section: every flagged trial with its reasons, and what was done."""
    th = QualityThresholds()
    flagged = per_trial[per_trial["flagged"].fillna(False).astype(bool)]
    unassessed = int(per_trial["flagged"].isna().sum())
    n = len(per_trial)
    criteria = (
        f"A trial is flagged when the identification did not converge, K* or D* lies at a search "
        f"bound, a 95 % interval is wider than ±{th.max_ci_halfwidth_pct:.0f} % of its estimate or "
        f"reaches a search bound, |correlation(K, D)| > {th.max_abs_correlation} (compensation), "
        f"the fit's nRMSE exceeds {th.max_nrmse_pct:.0f} %, or the simulated peak vertical GRF "
        f"differs from the measured one by more than {th.max_peak_mismatch_pct:.0f} %. The quality "
        "is computed once, by the identification, and stored in results.sqlite (columns flagged, "
        "flags).")
    if flagged.empty:
        text = f"No trial of the {n} reported is flagged.\n\n{criteria}"
    elif include_flagged:
        text = (f"{len(flagged)} of {n} trials are flagged. They are KEPT in the group statistics "
                f"(--include-flagged) and marked {FLAG_MARK} in the tables and as grey dotted "
                f"lines in the figures.\n\n{criteria}")
    else:
        text = (f"{len(flagged)} of {n} trials are flagged and LEFT OUT of every group statistic "
                "(nRMSE tables, mean curves, K* and D* per group, statistical tests); they stay "
                f"in the per-trial tables, marked {FLAG_MARK}, and in the figures as grey dotted "
                "lines. Keep them with `bladelab report STUDY --include-flagged`."
                f"\n\n{criteria}")
    if unassessed:
        text += (f"\n\n{unassessed} trial(s) were identified before quality flags existed (not "
                 "assessed, kept): re-identify them with `bladelab identify STUDY --force`.")
    cols = [c for c in ("trial_id", "group", "athlete", "K_Nm_per_deg", "D_Nms_per_deg",
                        "nrmse_grf_pct", "peak_force_mismatch_pct", "flags")
            if c in flagged.columns]
    table = flagged[cols].rename(columns={"flags": "reasons"})
    rep.add_section("Flagged trials", text=text,
                    tables=[("Flagged trials and why", table)] if len(table) else [])
