"""Quality of one identification: is K*, D* a result a reviewer would accept?

Computed once, at the end of :func:`bladelab.identify.identify_stance`, stored with the result
(``results.sqlite`` columns, see :meth:`TrialQuality.to_row`) and read by the study report, which
marks flagged trials and leaves them out of group statistics by default.

A trial is **flagged** when any of these holds (thresholds in :class:`QualityThresholds`):

- **not converged**: the profile-likelihood step still found a clearly lower residual sum of
  squares than at the estimate after re-centring (:mod:`bladelab.identify.identifiability`);
- **at a bound**: K* or D* lies within ``bound_tolerance`` (1 %) of the search box's width of a
  search bound (the optimum may lie beyond it);
- **wide interval**: the 95 % confidence interval's half-width exceeds ``max_ci_halfwidth_pct``
  (25 %) of the estimate, or the interval is open (reaches a search bound);
- **K–D compensation**: |correlation(K, D)| > ``max_abs_correlation`` (0.95);
- **poor fit**: nRMSE of the GRF or of the distance above ``max_nrmse_pct`` (30 %; seed 000's
  worst group mean was 19.4 ± 3.4 %);
- **peak-force mismatch**: the simulated peak vertical GRF differs from the measured one by more
  than ``max_peak_mismatch_pct`` (25 %) of the measured peak (a simulated impact spike or a
  stance the model does not reproduce).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

__all__ = ["QUALITY_COLUMNS", "QualityThresholds", "TrialQuality", "assess_quality"]


@dataclasses.dataclass(frozen=True)
class QualityThresholds:
    """Limits beyond which a trial is flagged (percentages in %, tolerance as a fraction)."""

    max_ci_halfwidth_pct: float = 25.0
    max_abs_correlation: float = 0.95
    max_nrmse_pct: float = 30.0
    max_peak_mismatch_pct: float = 25.0
    bound_tolerance: float = 0.01


QUALITY_COLUMNS: dict[str, str] = {
    "converged": "INTEGER",
    "at_bound": "TEXT",
    "K_ci_halfwidth_pct": "REAL",
    "D_ci_halfwidth_pct": "REAL",
    "peak_force_measured_N": "REAL",
    "peak_force_simulated_N": "REAL",
    "peak_force_mismatch_pct": "REAL",
    "flagged": "INTEGER",
    "flags": "TEXT",
}
"""The ``results.sqlite`` columns written by :meth:`TrialQuality.to_row` (SQLite types)."""


@dataclasses.dataclass(frozen=True)
class TrialQuality:
    """Quality indicators of one identification (edge units; percentages in %).

    Attributes
    ----------
    converged
        False when the profiles still found a lower cost than the estimate; None when no
        identifiability analysis was run.
    at_bound
        ``"<name> lower"`` / ``"<name> upper"`` for each parameter at a search bound.
    ci_halfwidth_pct
        Parameter name -> half-width of its confidence interval in % of the estimate.
    ci_open
        Names of the parameters whose interval reaches a search bound.
    KD_correlation
        Correlation of the K and D estimates (NaN if not computed).
    nrmse_grf_pct, nrmse_distance_pct
        Fit at the estimate [%].
    peak_force_measured_N, peak_force_simulated_N
        Peak vertical GRF of the measured and the simulated stance [N].
    reasons
        Why the trial is flagged (empty: not flagged).
    """

    converged: bool | None
    at_bound: tuple[str, ...]
    ci_halfwidth_pct: dict[str, float]
    ci_open: tuple[str, ...]
    KD_correlation: float
    nrmse_grf_pct: float
    nrmse_distance_pct: float
    peak_force_measured_N: float
    peak_force_simulated_N: float
    reasons: tuple[str, ...]

    @property
    def flagged(self) -> bool:
        """True when any quality criterion failed."""
        return bool(self.reasons)

    @property
    def peak_force_mismatch_pct(self) -> float:
        """(simulated − measured peak) / measured peak [%]."""
        if not self.peak_force_measured_N > 0:
            return float("nan")
        return 100.0 * (self.peak_force_simulated_N / self.peak_force_measured_N - 1.0)

    def to_row(self) -> dict:
        """The :data:`QUALITY_COLUMNS` of ``results.sqlite``."""
        def num(v):
            return None if v is None or not math.isfinite(v) else float(v)

        return {
            "converged": None if self.converged is None else int(self.converged),
            "at_bound": ", ".join(self.at_bound),
            "K_ci_halfwidth_pct": num(self.ci_halfwidth_pct.get("K")),
            "D_ci_halfwidth_pct": num(self.ci_halfwidth_pct.get("D")),
            "peak_force_measured_N": num(self.peak_force_measured_N),
            "peak_force_simulated_N": num(self.peak_force_simulated_N),
            "peak_force_mismatch_pct": num(self.peak_force_mismatch_pct),
            "flagged": int(self.flagged),
            "flags": "; ".join(self.reasons),
        }

    def to_dict(self) -> dict:
        """JSON-ready dictionary (the row plus the reasons as a list)."""
        out = self.to_row()
        out["flagged"] = self.flagged
        out["converged"] = self.converged
        out["flags"] = list(self.reasons)
        return out


def assess_quality(
    *,
    estimate: Mapping[str, float],
    bounds: Mapping[str, tuple[float, float]],
    ci: Mapping[str, tuple[float, float]],
    ci_open: Mapping[str, bool] | None = None,
    correlation: float,
    converged: bool | None,
    nrmse_grf_pct: float,
    nrmse_distance_pct: float,
    peak_force_measured_N: float,
    peak_force_simulated_N: float,
    thresholds: QualityThresholds = QualityThresholds(),
) -> TrialQuality:
    """Quality indicators and flags of one identification (see the module docstring).

    Parameters
    ----------
    estimate
        Parameter name (``K``, ``D``, ``K2``) -> estimate in edge units.
    bounds
        Parameter name -> search bounds (low, high) in the same units.
    ci
        Parameter name -> confidence interval (empty without an identifiability analysis).
    ci_open
        Parameter name -> True when its interval reaches a search bound.
    correlation
        K–D correlation (NaN if not computed).
    converged
        From the identifiability analysis (None if not run).
    nrmse_grf_pct, nrmse_distance_pct
        Fit at the estimate [%].
    peak_force_measured_N, peak_force_simulated_N
        Peak vertical GRF measured and simulated at the estimate [N].
    thresholds
        Flag limits.
    """
    th = thresholds
    reasons: list[str] = []
    if converged is False:
        reasons.append("not converged (the profiles found a lower cost)")
    at_bound = []
    for name, value in estimate.items():
        if name not in bounds or name == "K2":
            continue
        lo, hi = bounds[name]
        tol = th.bound_tolerance * (hi - lo)
        if value <= lo + tol:
            at_bound.append(f"{name} lower")
        elif value >= hi - tol:
            at_bound.append(f"{name} upper")
    for b in at_bound:
        name, side = b.split()
        reasons.append(f"{name}* at the {side} search bound ({bounds[name][0 if side == 'lower' else 1]:.3g})")
    half = {}
    for name, (lo, hi) in ci.items():
        value = estimate.get(name)
        if value is None or not (math.isfinite(lo) and math.isfinite(hi)):
            continue
        half[name] = 100.0 * 0.5 * (hi - lo) / max(abs(value), 1e-300)
        if name != "K2" and half[name] > th.max_ci_halfwidth_pct:
            reasons.append(f"{name} CI half-width {half[name]:.0f} % > {th.max_ci_halfwidth_pct:.0f} %")
    opened = tuple(n for n, o in (ci_open or {}).items() if o and n != "K2")
    if opened:
        reasons.append(f"CI of {', '.join(opened)} reaches a search bound")
    if math.isfinite(correlation) and abs(correlation) > th.max_abs_correlation:
        reasons.append(f"K–D compensation (|correlation| {abs(correlation):.3f} > "
                       f"{th.max_abs_correlation})")
    for label, v in (("GRF", nrmse_grf_pct), ("distance", nrmse_distance_pct)):
        if math.isfinite(v) and v > th.max_nrmse_pct:
            reasons.append(f"poor fit: nRMSE {label} {v:.1f} % > {th.max_nrmse_pct:.0f} %")
    q = TrialQuality(
        converged=converged, at_bound=tuple(at_bound), ci_halfwidth_pct=half, ci_open=opened,
        KD_correlation=float(correlation), nrmse_grf_pct=float(nrmse_grf_pct),
        nrmse_distance_pct=float(nrmse_distance_pct),
        peak_force_measured_N=float(peak_force_measured_N),
        peak_force_simulated_N=float(peak_force_simulated_N), reasons=tuple(reasons),
    )
    mismatch = q.peak_force_mismatch_pct
    if math.isfinite(mismatch) and abs(mismatch) > th.max_peak_mismatch_pct:
        reasons.append(f"peak force {peak_force_simulated_N:.0f} N simulated vs "
                       f"{peak_force_measured_N:.0f} N measured ({mismatch:+.0f} % > "
                       f"±{th.max_peak_mismatch_pct:.0f} %)")
        q = dataclasses.replace(q, reasons=tuple(reasons))
    return q
