"""Seed 002's motion adaptation: gait cycles as response surfaces of the design factors.

:func:`fit_motion_model` fits the period [s] and every joint angle at ``n_nodes`` normalised
times as response surfaces of the coded design factors (quadratic, or ``model="auto"``:
quadratic if the cycles can estimate it, else linear), from gait cycles
(:class:`bladelab.design.gait_cycle.GaitCycle`) measured or predicted with several blades, with
leave-one-blade-out errors; :meth:`MotionModel.predict` / :meth:`MotionModel.predict_point` give
the cycle of a new design. Motion files (cycles with their blades) are read by
:mod:`bladelab.design.motion`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from bladelab.design.doe import require_estimable
from bladelab.design.gait_cycle import ANGLE_NAMES, GaitCycle
from bladelab.design.terms import model_matrix, parse_terms, term_name
from bladelab.errors import DataError, SpecError

__all__ = ["MotionModel", "fit_motion_model"]


def _nan_to_none(v: float) -> float | None:
    return None if not math.isfinite(v) else float(v)


@dataclass(frozen=True, eq=False)
class MotionModel:
    """Period and time-normalised joint angles as response surfaces of coded design factors.

    Attributes
    ----------
    factor_names, terms
        The factors and surface terms (coded factors).
    phase
        The normalised times of the angle surfaces.
    period_coef
        Coefficients of the period surface [s].
    angle_coef
        Name -> (n_terms, n_phase) coefficients [rad].
    r2_period
        R² of the period fit (NaN without residual degrees of freedom).
    model
        The model fitted: a named model (``"quadratic"``, ``"linear"`` ...) or its terms.
    centre, half_range
        Coding of the factors, in their units: c = (x − centre)/half_range (``None``: the model
        was fitted on coded points and predicts only from coded points).
    loo_period_s
        Leave-one-blade-out RMS error of the period [s]: every blade (all cycles at one design
        point) left out in turn, the model refitted on the others and the left-out cycles
        predicted; NaN when the other blades cannot estimate the model.
    loo_angles_deg
        Name -> leave-one-blade-out RMS error of that angle over all normalised times [deg].
    n_cycles, n_blades
        Cycles fitted and distinct design points among them.
    sources
        Where each cycle came from.
    """

    factor_names: tuple[str, ...]
    terms: tuple
    phase: np.ndarray
    period_coef: np.ndarray
    angle_coef: Mapping[str, np.ndarray]
    r2_period: float
    model: str = ""
    centre: np.ndarray | None = None
    half_range: np.ndarray | None = None
    loo_period_s: float = float("nan")
    loo_angles_deg: Mapping[str, float] = field(default_factory=dict)
    n_cycles: int = 0
    n_blades: int = 0
    sources: tuple[str, ...] = ()

    @property
    def term_names(self) -> tuple[str, ...]:
        """Readable term names (``"1"``, ``"A"``, ``"A*B"``, ``"A^2"``)."""
        return tuple(term_name(t, self.factor_names) for t in self.terms)

    def code(self, point: Mapping[str, float]) -> np.ndarray:
        """Coded values of a design point ``{factor: value in its unit}``.

        Raises
        ------
        SpecError
            The model has no coding, or the point lacks one of its factors or has another.
        """
        if self.centre is None or self.half_range is None:
            raise SpecError("this motion model was fitted on coded points: pass coded values "
                            "to predict()", where="motion model")
        missing = [n for n in self.factor_names if n not in point]
        unknown = [str(k) for k in point if k not in self.factor_names]
        if missing:
            raise SpecError(f"the design point lacks the motion model's factor(s) {missing}",
                            where="motion model",
                            hint=f"the motion model's factors are {list(self.factor_names)}")
        if unknown:
            raise SpecError(f"the motion model has no factor(s) {unknown}", where="motion model",
                            hint="give every design factor's value for each motion cycle "
                                 f"(it has {list(self.factor_names)})")
        x = np.array([float(point[n]) for n in self.factor_names])
        return (x - self.centre) / self.half_range

    def predict(self, coded: Sequence[float]) -> GaitCycle:
        """The predicted gait cycle at a coded design point."""
        c = np.asarray(coded, float).reshape(1, -1)
        if c.shape[1] != len(self.factor_names):
            raise SpecError(f"expected {len(self.factor_names)} coded factors", where="motion")
        X = model_matrix(c, self.terms)[0]
        period = float(X @ self.period_coef)
        if not (period > 0 and math.isfinite(period)):
            pt = ", ".join(f"{n}={v:+.3g}" for n, v in zip(self.factor_names, c[0], strict=True))
            raise DataError(f"the motion model predicts a period of {period:.4g} s at the coded "
                            f"point ({pt})", where="motion model",
                            hint="the point lies too far outside the blades of the motion cycles")
        return GaitCycle(period, self.phase, {n: X @ a for n, a in self.angle_coef.items()},
                         "motion model (response surfaces)")

    def predict_point(self, point: Mapping[str, float]) -> GaitCycle:
        """The predicted gait cycle of a design point ``{factor: value in its unit}``."""
        return self.predict(self.code(point))

    def to_dict(self) -> dict:
        coding = None
        if self.centre is not None and self.half_range is not None:
            coding = {n: {"centre": float(c), "half_range": float(h)} for n, c, h in
                      zip(self.factor_names, self.centre, self.half_range, strict=True)}
        return {
            "model": self.model,
            "factors": list(self.factor_names),
            "terms": list(self.term_names),
            "coding": coding,
            "n_cycles": self.n_cycles,
            "n_blades": self.n_blades,
            "n_phase_nodes": int(self.phase.size),
            "r2_period": _nan_to_none(self.r2_period),
            "loo_period_s": _nan_to_none(self.loo_period_s),
            "loo_angles_deg": {k: _nan_to_none(v) for k, v in self.loo_angles_deg.items()},
            "period_coefficients_s": dict(zip(self.term_names,
                                              (float(v) for v in self.period_coef), strict=True)),
            "sources": list(self.sources),
        }


def _blade_groups(coded: np.ndarray) -> list[np.ndarray]:
    """Row indices of the cycles at each distinct design point (a blade)."""
    _, inverse = np.unique(np.round(coded, 9), axis=0, return_inverse=True)
    inverse = np.asarray(inverse).reshape(-1)
    return [np.flatnonzero(inverse == g) for g in range(int(inverse.max()) + 1)]


def _leave_one_blade_out(X: np.ndarray, Y: np.ndarray, groups: list[np.ndarray]) -> np.ndarray:
    """Prediction errors of every row with its blade's rows left out (NaN rows: not estimable)."""
    err = np.full(Y.shape, np.nan)
    p = X.shape[1]
    for rows in groups:
        keep = np.ones(X.shape[0], bool)
        keep[rows] = False
        Xk = X[keep]
        if Xk.shape[0] < p or np.linalg.matrix_rank(Xk) < p:
            continue
        coef = np.linalg.lstsq(Xk, Y[keep], rcond=None)[0]
        err[rows] = Y[rows] - X[rows] @ coef
    return err


def _rms(err: np.ndarray) -> float:
    return float(np.sqrt(np.mean(err**2))) if np.all(np.isfinite(err)) else float("nan")


def _motion_terms(coded: np.ndarray, model, names: Sequence[str], n_blades: int):
    """(model label, terms, estimability report); ``"auto"``: quadratic, else linear."""
    n = coded.shape[0]

    def refuse(err: SpecError, what: str) -> SpecError:
        msg = err.message.replace(" runs ", " cycles ")
        return SpecError(f"{n} cycles at {n_blades} blade(s) cannot fit {what}: {msg}",
                         where="motion model",
                         hint=(err.hint or "").replace("add runs", "add cycles of other blades"))

    if isinstance(model, str) and model == "auto":
        for m in ("quadratic", "linear"):
            terms = parse_terms(m, list(names))
            try:
                return m, terms, require_estimable(coded, terms, names)
            except SpecError as err:
                last = err
        raise refuse(last, "even the linear motion model")
    terms = parse_terms(model, list(names))
    label = model if isinstance(model, str) else ",".join(term_name(t, names) for t in terms)
    try:
        return label, terms, require_estimable(coded, terms, names)
    except SpecError as err:
        raise refuse(err, f"the {label} motion model") from None


def fit_motion_model(
    coded: np.ndarray,
    cycles: Sequence[GaitCycle],
    *,
    factor_names: Sequence[str],
    model: str | Sequence = "quadratic",
    n_nodes: int = 51,
    centre: Sequence[float] | None = None,
    half_range: Sequence[float] | None = None,
) -> MotionModel:
    """Fit seed 002's motion response surfaces from cycles observed at coded design points.

    The period [s] and every joint angle at ``n_nodes`` normalised times are least-squares
    surfaces of the coded factors (one model for all). Several cycles may share a design point
    (trials with the same blade).

    Parameters
    ----------
    coded
        Coded design point of each cycle (n_cycles × n_factors).
    cycles
        The cycles.
    factor_names
        Names of the factors (columns of ``coded``).
    model
        ``"quadratic"``, ``"linear"``, ``"interaction"``, ``"pure_quadratic"``, a term list
        (``"k,w,k^2"``), or ``"auto"``: the quadratic if the cycles can estimate it, else the
        linear model.
    n_nodes
        Normalised times of the angle surfaces.
    centre, half_range
        The coding used for ``coded``, in the factors' units (recorded so that
        :meth:`MotionModel.predict_point` takes values in units).

    Raises
    ------
    SpecError
        The cycles cannot estimate the model, or leave no residual degree of freedom
        (:func:`bladelab.design.doe.require_estimable`); the hint names models that fit.
    """
    coded = np.atleast_2d(np.asarray(coded, float))
    if coded.shape[0] != len(cycles):
        raise DataError(f"{coded.shape[0]} design points but {len(cycles)} cycles",
                        where="motion model")
    names = list(factor_names)
    if coded.shape[1] != len(names):
        raise DataError(f"{coded.shape[1]} coded columns but {len(names)} factor names",
                        where="motion model")
    if n_nodes < 4:
        raise SpecError(f"n_nodes must be >= 4, got {n_nodes}", where="motion model")
    groups = _blade_groups(coded)
    label, terms, _ = _motion_terms(coded, model, names, len(groups))
    X = model_matrix(coded, terms)
    phase = np.arange(n_nodes) / n_nodes
    T = np.array([c.period for c in cycles])
    sampled = [c.at(phase * c.period) for c in cycles]
    period_coef = np.linalg.lstsq(X, T, rcond=None)[0]
    angle_coef = {}
    loo_angles = {}
    for n in ANGLE_NAMES:
        Y = np.array([s[n] for s in sampled])
        angle_coef[n] = np.linalg.lstsq(X, Y, rcond=None)[0]
        loo_angles[n] = math.degrees(_rms(_leave_one_blade_out(X, Y, groups)))
    resid = T - X @ period_coef
    ss = float(np.sum((T - T.mean()) ** 2))
    r2 = 1.0 - float(resid @ resid) / ss if ss > 0 and X.shape[0] > X.shape[1] else float("nan")
    loo_period = _rms(_leave_one_blade_out(X, T, groups))
    cen = None if centre is None else np.asarray(centre, float)
    half = None if half_range is None else np.asarray(half_range, float)
    for arr, what in ((cen, "centre"), (half, "half_range")):
        if arr is not None and arr.shape != (len(names),):
            raise SpecError(f"{what} needs one value per factor", where="motion model")
    return MotionModel(tuple(names), tuple(terms), phase, period_coef, angle_coef, r2,
                       model=label, centre=cen, half_range=half, loo_period_s=loo_period,
                       loo_angles_deg=loo_angles, n_cycles=len(cycles), n_blades=len(groups),
                       sources=tuple(c.source for c in cycles))
