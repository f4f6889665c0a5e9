"""Seed 002's reported trends, checked on a study's own response surfaces.

Seed 002 reports five trends (fig. 7, 9, 10 and the conclusion):

====================================  ==================  ===================================
trend                                 response            test
====================================  ==================  ===================================
stiffer blades increase Δv_x          delta_vx_m_per_s    linear coefficient of stiffness > 0
wider blades increase Δv_x            delta_vx_m_per_s    linear coefficient of width > 0
height and toe length matter less     delta_vx_m_per_s    main-effect ranges (see below)
shorter toe lowers the knee margin    knee_moment_min_Nm  linear coefficient of toe length > 0
longer toe lowers swing clearance     swing_clearance_m   linear coefficient of toe length < 0
====================================  ==================  ===================================

Seed 002's performance response was Δv_x over the stance. On a study that predicts each design's
maximum speed (the collocation evaluator's maximum-speed problem), the same three performance
trends are also read on ``max_speed_m_per_s`` (:data:`SPEED_TRENDS`): faster is what seed 002
meant by better.

Sign tests: the linear coefficient per coded unit of the fitted surface, two-sided t-test
(α = 0.05 by default, the surface's residual degrees of freedom): **holds** when it is
significant with the stated sign; **does not hold** when it is significant with the opposite
sign ("reversed") or not significant ("no significant effect"). Effect-size test ("matter
less"): the range of each factor's main-effect curve over [−1, 1] (others at the centre) on the
fitted surface; holds when the height and toe-length ranges are both smaller than the stiffness
and width ranges. **not estimable**: the response or a factor is not in the study, the term is
not in the model, or the surface has no residual degree of freedom.

**undecided**: the study measured how far the solver's start moves the response
(``ceilings``, the R² ceiling of its start spread, :mod:`bladelab.design.start_spread`) and
that ceiling is below :data:`CEILING_MIN`: strides of one design differ in the response about
as much as the designs do, so whichever test passes or fails, the start decided it, not the
blade. The test's numbers stay in the evidence.

A trend that does not hold, or is undecided, gets a reason: the known mechanism of the
evaluator that produced the study (:data:`TREND_REASONS`, keyed by evaluator and trend;
measured and explained in docs/design.md), else :data:`NOT_EXPLAINED` (undecided:
:data:`START_DECIDES`). A surface whose predicted R² is below 0.5 is
flagged in the evidence.

**not tested**: the study's evaluator has no runner (:data:`NO_RUNNER`, the ``blade``
evaluator: the blade under one prescribed passive stance). Seed 002's trends are about a
runner's stride, so such a study draws no verdict on them; the evidence (the blade's own
coefficients) is still given, with what the evaluator is and, where known, the mechanism
behind the blade's response.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from bladelab.design.blade_generator import DEFAULT_FACTOR_ROLES
from bladelab.design.surfaces import ResponseSurface
from bladelab.errors import SpecError

__all__ = [
    "CEILING_MIN",
    "NOT_EXPLAINED",
    "NO_RUNNER",
    "SEED002_TRENDS",
    "SPEED_TRENDS",
    "START_DECIDES",
    "TREND_REASONS",
    "Trend",
    "TrendVerdict",
    "evaluate_trends",
    "trends_frame",
]


@dataclasses.dataclass(frozen=True)
class Trend:
    """One reported trend.

    Attributes
    ----------
    key
        Identifier (used in :data:`TREND_REASONS`).
    statement
        The trend in words.
    response
        Response column it concerns.
    roles
        Factor role(s) (``stiffness``, ``width``, ``height``, ``toe_length``).
    sign
        +1 / −1: expected sign of the linear coefficient; 0: effect-size comparison
        (``roles`` smaller than ``versus``).
    versus
        Roles that must have the larger effects (comparison trends).
    """

    key: str
    statement: str
    response: str
    roles: tuple[str, ...]
    sign: int
    versus: tuple[str, ...] = ()


SEED002_TRENDS: tuple[Trend, ...] = (
    Trend("stiffness_increases_dvx", "stiffer blades increase Δv_x (performance)",
          "delta_vx_m_per_s", ("stiffness",), +1),
    Trend("width_increases_dvx", "wider blades increase Δv_x (performance)",
          "delta_vx_m_per_s", ("width",), +1),
    Trend("height_toe_matter_less", "height and toe length matter less than stiffness and width",
          "delta_vx_m_per_s", ("height", "toe_length"), 0, ("stiffness", "width")),
    Trend("shorter_toe_lowers_knee_margin", "shorter toe lowers the knee extension margin",
          "knee_moment_min_Nm", ("toe_length",), +1),
    Trend("longer_toe_lowers_clearance", "longer toe lowers swing clearance",
          "swing_clearance_m", ("toe_length",), -1),
)

#: Seed 002's performance trends read on the maximum speed (module docstring).
SPEED_TRENDS: tuple[Trend, ...] = (
    Trend("stiffness_raises_max_speed", "stiffer blades raise the maximum speed (performance)",
          "max_speed_m_per_s", ("stiffness",), +1),
    Trend("width_raises_max_speed", "wider blades raise the maximum speed (performance)",
          "max_speed_m_per_s", ("width",), +1),
    Trend("height_toe_matter_less_speed",
          "height and toe length matter less than stiffness and width (maximum speed)",
          "max_speed_m_per_s", ("height", "toe_length"), 0, ("stiffness", "width")),
)

_SCATTER = (
    "Each design's predicted stride is one local optimum, reached from a neighbouring "
    "design's stride; on the 25-run study (docs/design.md) one settling pass lowered 12 of 25 "
    "objectives, by up to 22 %, and two clean strides of the same design differ in Δv_x by "
    "0.06 m/s (SD) against 0.07 m/s across all designs: the start caps the R² of Δv_x at "
    "about 0.3 and of E at 0 (the report's 'what the solver's start decides'), so these trends "
    "cannot be resolved from strides of this quality. ")

_TT_SCATTER = (
    "On the transtibial runner's strides Δv_x is not a property of the blade: a periodic "
    "stride at a prescribed speed shares its horizontal impulse between the legs at almost the "
    "same cost, so clean strides of one design differ in Δv_x about as much as the designs do "
    "(the start caps its R² at about 0.3 at free stride time and at 0 at people's, the report's "
    "'what the solver's start decides'; one "
    "farther start moved the centre design's Δv_x by 0.05 m/s against an SD of 0.031 m/s "
    "across the box). ")

#: Below this R² ceiling of the start spread a trend's verdict is "undecided" (module docstring).
CEILING_MIN = 0.5

#: Why the start decides a response, where no reason of the evaluator is known.
START_DECIDES = (
    "Clean strides of one design differ in this response about as much as the designs do "
    "(the report's 'what the solver's start decides'): which near-equal optimum a solve kept, "
    "not the blade, sets it. ")

#: Why a trend does not hold, by (evaluator, trend key): see docs/design.md for the measurements.
TREND_REASONS: dict[tuple[str, str], str] = {
    ("blade", "stiffness_increases_dvx"): (
        "The blade evaluator's stance is passive (a point mass on a spring leg at a fixed "
        "touch-down angle): it cannot push off, so Δv_x < 0 in every run, and a stiffer blade "
        "gives a larger vertical impulse and more braking. Seed 002's runner follows measured "
        "joint angles whose hip extension supplies the propulsion and adapts to the blade; a "
        "passive stance has no such mechanism."),
    ("blade", "width_increases_dvx"): (
        "At a fixed target stiffness the blade generator lets width change only the blade's mass "
        "and contact stiffness, which barely affect the stance; in seed 002 width also changed "
        "the bending-stiffness distribution and the contact area."),
    ("blade", "height_toe_matter_less"): (
        "Toe length moves the contact point forward of the clamp (the leg rolls over a longer "
        "lever and brakes less) and height lengthens the leg (the pylon is fixed): both change "
        "Δv_x of the passive stance about as much as stiffness, while width barely changes it "
        "(see the width trend)."),
    ("blade", "shorter_toe_lowers_knee_margin"): (
        "The blade evaluator's knee moment is a proxy (a virtual knee 0.08 m above the clamp, "
        "the GRF line through the hip); its minimum falls in the touch-down transient, where "
        "braking tilts the GRF line behind the knee and width and height move it more than the "
        "toe's lever does."),
    ("runner", "stiffness_increases_dvx"): (
        "With open-loop (template or measured) kinematics the transfemoral runner is not "
        "periodic: Δv_x over the cycle depends on when the next contact happens and its surface "
        "is not predictive (predicted R² < 0 on the template); the passive knee yields and the "
        "blade lands sliding. Average v_x does rise with stiffness on the template "
        "(docs/design.md)."),
    ("runner", "width_increases_dvx"): (
        "At a fixed target stiffness the blade generator lets width change only the blade's mass "
        "and contact stiffness, which barely affect the cycle; in seed 002 width also changed "
        "the bending-stiffness distribution and the contact area."),
    ("runner", "height_toe_matter_less"): (
        "Under fixed (open-loop) joint angles toe length moves the contact point and the timing "
        "of touch-down, so it changes Δv_x about as much as stiffness, while at a fixed target "
        "stiffness width barely matters (see the width trend); on the template cycle Δv_x is "
        "not even predictive. Toe length also dominates the knee moment and contact time."),
    ("runner", "shorter_toe_lowers_knee_margin"): (
        "The passive knee (no stance lock) yields: after the sliding touch-down the GRF line "
        "settles through the knee axis, so the minimum moment is set by the touch-down "
        "transient more than by the toe's lever."),
    ("runner", "longer_toe_lowers_clearance"): (
        "The kinematics-driven runner's swing clearance is erratic between neighbouring designs "
        "(predicted R² < 0 on the template): the passive knee's swing depends on the stance "
        "before it. The blade evaluator's geometric proxy shows the trend."),
    ("collocation", "stiffness_increases_dvx"): (
        _SCATTER + "The stiffness coefficient has the seed's sign (p 0.11 on that study)."),
    ("collocation", "width_increases_dvx"): (
        _SCATTER + "The width coefficient has the seed's sign; at a fixed target stiffness the "
        "generator lets width change only the blade's mass and sole contact."),
    ("collocation", "height_toe_matter_less"): (
        _SCATTER + "The main-effect ranges compared here are within that scatter."),
    ("collocation", "shorter_toe_lowers_knee_margin"): (
        _SCATTER + "The knee moment minimum falls at touch-down, where the load line passes "
        "behind the knee before the toe's lever acts."),
    ("collocation", "longer_toe_lowers_clearance"): (
        _SCATTER + "The 2 cm swing-clearance constraint binds (within 0.5 mm) in 9 of the free "
        "study's 25 strides, which caps the response the trend is read from."),
    # the transtibial runner on the human body (``--amputation transtibial``), measured on its
    # 25-run study (docs/design.md, "Predicted transtibial strides")
    ("collocation-transtibial", "stiffness_increases_dvx"): (
        _TT_SCATTER + "In the free-stride study, before five of its strides were replaced by "
        "cheaper ones from a farther start, the stiffness effect had the seed's sign (+0.021 m/s "
        "per coded unit, p 0.002); after, +0.011 (p 0.14, first-order fit): the start, not the "
        "blade, decided it. At people's stride time it was +0.004 (p 0.73) after two settling "
        "passes and +0.016 (p 0.014) after five."),
    ("collocation-transtibial", "width_increases_dvx"): (
        _TT_SCATTER + "At a fixed target stiffness the blade generator lets width change only "
        "the blade's mass and sole contact; in seed 002 width also changed the "
        "bending-stiffness distribution and the contact area."),
    ("collocation-transtibial", "height_toe_matter_less"): (
        _TT_SCATTER + "The main-effect ranges compared here are within that scatter."),
}

#: Evaluators with no runner, and what they are: their studies test no trend of seed 002
#: (verdict "not tested"), which are about a runner's stride.
NO_RUNNER: dict[str, str] = {
    "blade": ("Not tested: the blade evaluator has no runner. It loads the blade under one "
              "prescribed, passive stance (a point mass on a rigid pylon lands at a fixed "
              "angle and speed), so its responses are the blade's, not a runner's stride's, "
              "and seed 002's trends about running can be neither confirmed nor refuted by "
              "it (use the collocation evaluator)."),
}

#: Reason given when no known mechanism of the evaluator explains a trend that does not hold.
NOT_EXPLAINED = ("not explained: no known mechanism of this evaluator accounts for it; check the "
                 "surface fit (predicted R²), the factor ranges and the runs")


@dataclasses.dataclass(frozen=True)
class TrendVerdict:
    """The verdict on one trend.

    Attributes
    ----------
    key, statement, response
        The trend (see :class:`Trend`).
    test
        The test used, in words.
    verdict
        ``"holds"``, ``"does not hold"``, ``"undecided"`` (the start spread's R² ceiling
        below :data:`CEILING_MIN`), ``"not estimable"`` or ``"not tested"`` (an evaluator with
        no runner, :data:`NO_RUNNER`).
    evidence
        The numbers behind it (coefficients per coded unit with p-values, or effect ranges).
    reason
        Why it does not hold, is undecided or is not tested (empty otherwise).
    mechanism
        For a trend not tested: the mechanism known for the blade's own response where it
        lacks the seed's sign (also in ``reason``; empty otherwise).
    estimate, p_value
        Linear coefficient per coded unit and its p-value (sign tests; NaN otherwise).
    """

    key: str
    statement: str
    response: str
    test: str
    verdict: str
    evidence: str
    reason: str = ""
    mechanism: str = ""
    estimate: float = math.nan
    p_value: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def _coef(surface: ResponseSurface, factor: str) -> tuple[float, float] | None:
    tab = surface.coefficients()
    row = tab[tab["term"] == factor]
    if row.empty:
        return None
    return float(row["estimate"].iloc[0]), float(row["p_value"].iloc[0])


def _effect_range(surface: ResponseSurface, factor: str) -> float:
    k = list(surface.factor_names).index(factor)
    pts = np.zeros((41, len(surface.factor_names)))
    pts[:, k] = np.linspace(-1.0, 1.0, 41)
    y = np.asarray(surface.predict_mean(pts), float)
    return float(y.max() - y.min())


def _fmt(v: float) -> str:
    return f"{v:.3g}"


def evaluate_trends(
    surfaces: Mapping[str, ResponseSurface],
    *,
    evaluator: str | None = None,
    roles: Mapping[str, str] | None = None,
    alpha: float = 0.05,
    trends: tuple[Trend, ...] = SEED002_TRENDS,
    held: Mapping[str, str] | None = None,
    ceilings: Mapping[str, float] | None = None,
) -> list[TrendVerdict]:
    """Check seed 002's trends on fitted response surfaces (see the module docstring).

    Parameters
    ----------
    surfaces
        Response name -> fitted surface over coded factors (all over the same factors).
    evaluator
        ``"runner"`` or ``"collocation"`` (selects the reasons), ``"blade"`` (no runner:
        every trend "not tested", :data:`NO_RUNNER`), or None (generic reasons).
    roles
        Role -> factor name (default the generator's: ``stiffness_kN_per_m``, ``width_m``,
        ``height_m``, ``toe_length_m``).
    alpha
        Significance level of the coefficient t-tests.
    held
        Response -> how every solve of the study held it (a constraint of each design's
        stride, e.g. the knee moment kept at or above 0 N·m): a trend on such a response is
        not estimable, since the response is a bound the solve enforced, not an outcome.
    ceilings
        Response -> R² ceiling of the study's start spread (of the strides that compete to be
        kept, e.g. those within 5 % of each design's best); below :data:`CEILING_MIN` a
        trend on that response is "undecided".

    Returns
    -------
    list of TrendVerdict
    """
    if not 0 < alpha < 1:
        raise SpecError(f"alpha must lie in (0, 1), got {alpha}", where="alpha")
    roles = {**DEFAULT_FACTOR_ROLES, **(roles or {})}
    out = []
    for tr in trends:
        sign_test = (f"t-test of the linear coefficient per coded unit (two-sided, α = {alpha:g}),"
                     f" expected sign {'+' if tr.sign > 0 else '−'}")
        size_test = ("range of the main-effect curve over the coded interval (others at the "
                     "centre): " + " and ".join(tr.roles) + " both below " + " and ".join(tr.versus))
        test = sign_test if tr.sign else size_test
        base = {"key": tr.key, "statement": tr.statement, "response": tr.response, "test": test}
        surf = surfaces.get(tr.response)
        if tr.response in (held or {}):
            out.append(TrendVerdict(**base, verdict="not estimable", evidence=(
                f"{tr.response} is {held[tr.response]}: a constraint of each design's "
                "stride, not an outcome; what holding it costs shows in the other responses "
                "(cost of transport, feasibility)")))
            continue
        if surf is None:
            out.append(TrendVerdict(**base, verdict="not estimable",
                                    evidence=f"the study has no response {tr.response}"))
            continue
        needed = [*tr.roles, *tr.versus]
        missing = [r for r in needed if roles.get(r) not in surf.factor_names]
        if missing:
            out.append(TrendVerdict(**base, verdict="not estimable",
                                    evidence=f"no factor for {', '.join(missing)} in the study"))
            continue
        note = ""
        if not (surf.r2_pred >= 0.5):
            note = f"; caution: the surface is not predictive (R²pred {surf.r2_pred:.2f})"
        unit = f" {surf.unit}" if surf.unit else ""
        if tr.sign:
            fac = roles[tr.roles[0]]
            c = _coef(surf, fac)
            if c is None or surf.df_resid < 1:
                why = ("the model has no linear term of " + fac if c is None
                       else "no residual degree of freedom")
                out.append(TrendVerdict(**base, verdict="not estimable", evidence=why))
                continue
            b, p = c
            ev = f"{fac}: {b:+.3g}{unit} per coded unit, p = {p:.2g}{note}"
            if p < alpha and np.sign(b) == tr.sign:
                verdict, reason = "holds", ""
            else:
                verdict = "does not hold"
                ev += "; reversed" if p < alpha else "; no significant effect"
                reason = TREND_REASONS.get((str(evaluator), tr.key), NOT_EXPLAINED)
            out.append(TrendVerdict(**base, verdict=verdict, evidence=ev, reason=reason,
                                    estimate=b, p_value=p))
        else:
            rng = {r: _effect_range(surf, roles[r]) for r in needed}
            ev = ", ".join(f"{r} {_fmt(v)}" for r, v in rng.items()) + f"{unit}{note}"
            holds = max(rng[r] for r in tr.roles) < min(rng[r] for r in tr.versus)
            reason = "" if holds else TREND_REASONS.get((str(evaluator), tr.key), NOT_EXPLAINED)
            out.append(TrendVerdict(**base, verdict="holds" if holds else "does not hold",
                                    evidence="main-effect ranges: " + ev, reason=reason))
    if str(evaluator) in NO_RUNNER:
        return [_not_tested(v, str(evaluator)) for v in out]
    return [_undecided(v, (ceilings or {}).get(v.response), str(evaluator)) for v in out]


def _undecided(verdict: TrendVerdict, ceiling: float | None, evaluator: str) -> TrendVerdict:
    """``verdict`` made "undecided" where the start spread's R² ``ceiling`` of its response is
    below :data:`CEILING_MIN` (unchanged otherwise, and when not estimable)."""
    if (ceiling is None or not ceiling < CEILING_MIN
            or verdict.verdict not in ("holds", "does not hold")):
        return verdict
    reason = TREND_REASONS.get((evaluator, verdict.key), START_DECIDES)
    return dataclasses.replace(
        verdict, verdict="undecided", reason=reason,
        evidence=(f"{verdict.evidence}; the test alone would say '{verdict.verdict}', but the "
                  f"start spread caps the R² of {verdict.response} at {ceiling:.2f}"))


def _not_tested(verdict: TrendVerdict, evaluator: str) -> TrendVerdict:
    """``verdict`` from an evaluator without a runner: "not tested", the evidence kept, the
    reason saying what the evaluator is (and, where the blade's response lacks the seed's
    sign, the mechanism known for it)."""
    if verdict.verdict == "not estimable":
        return verdict
    mechanism = (TREND_REASONS.get((evaluator, verdict.key), "")
                 if verdict.verdict == "does not hold" else "")  # why it lacks the sign
    sign = {"holds": "the blade's response has the seed's sign",
            "does not hold": "the blade's response lacks the seed's sign"}[verdict.verdict]
    reason = NO_RUNNER[evaluator] + (f" {mechanism}" if mechanism else "")
    return dataclasses.replace(verdict, verdict="not tested",
                               evidence=f"{verdict.evidence} ({sign})", reason=reason,
                               mechanism=mechanism)


def trends_frame(verdicts: list[TrendVerdict]) -> pd.DataFrame:
    """Tidy table: trend, response, verdict, evidence, test, reason, mechanism."""
    return pd.DataFrame([{"trend": v.statement, "response": v.response, "verdict": v.verdict,
                          "evidence": v.evidence, "test": v.test, "reason": v.reason,
                          "mechanism": v.mechanism}
                         for v in verdicts])
