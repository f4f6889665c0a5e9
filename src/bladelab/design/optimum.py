"""The constrained optimum of response surfaces over the coded design box.

Maximise (or minimise) an objective surface over c ∈ [-1, 1]^k subject to constraint surfaces
g_i(c) ≥ bound_i or g_i(c) ≤ bound_i (e.g. the minimum knee extension moment ≥ 0 N·m, the
minimum swing clearance ≥ 0.01 m, the peak socket moment ≤ 150 N·m). scipy's SLSQP is started
from the best run of the design, the centre and seeded random points; the best feasible local
optimum wins. With ``conservative=True`` a constraint is imposed on the bound of its prediction
interval on the infeasible side (the lower bound of a minimum, the upper of a maximum) instead of
its fitted mean.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize

from bladelab.design.space import DesignSpace
from bladelab.design.surfaces import ResponseSurface
from bladelab.errors import OptimizationError, SpecError

__all__ = ["OptimumResult", "SurfaceConstraint", "constrained_optimum", "read_bound",
           "surface_constraints"]

_FEAS_TOL = 1e-6


@dataclass(frozen=True, eq=False)
class SurfaceConstraint:
    """``surface(c) >= bound``, or ``surface(c) <= bound`` when ``upper`` (in the surface's
    unit): a knee moment's minimum, a socket moment's maximum."""

    surface: ResponseSurface
    bound: float
    upper: bool = False

    @property
    def name(self) -> str:
        return self.surface.response

    @property
    def relation(self) -> str:
        """"≤" or "≥"."""
        return "≤" if self.upper else "≥"

    def margin(self, value):
        """How far ``value`` lies inside the constraint (negative: violated), in its unit."""
        return self.bound - value if self.upper else value - self.bound


def read_bound(value, *, name: str = "constraint") -> tuple[float, bool]:
    """(bound, upper) of one entry of a study's constraints: a number is a minimum (the form
    written before maxima existed), ``{"min": v}`` a minimum, ``{"max": v}`` a maximum."""
    if isinstance(value, Mapping) and len(value) == 1 and next(iter(value)) in ("min", "max"):
        kind, bound = next(iter(value.items()))
        upper = kind == "max"
    elif isinstance(value, Mapping):
        raise SpecError(f"constraint {value!r} is neither {{'min': v}} nor {{'max': v}}",
                        where=name)
    else:
        bound, upper = value, False
    try:
        bound = float(bound)
    except (TypeError, ValueError):
        raise SpecError(f"constraint bound {bound!r} is not a number", where=name) from None
    if not np.isfinite(bound):
        raise SpecError(f"constraint bound {bound!r} is not finite", where=name)
    return bound, upper


def surface_constraints(surfaces: Mapping[str, ResponseSurface],
                        constraints: Mapping[str, Any]) -> list[SurfaceConstraint]:
    """The :class:`SurfaceConstraint` of each entry of a study's ``constraints`` ({response:
    minimum | {"min": v} | {"max": v}}, :func:`read_bound`) on its fitted ``surfaces``."""
    return [SurfaceConstraint(surfaces[k], *read_bound(v, name=f"constraint {k}"))
            for k, v in constraints.items()]


@dataclass(frozen=True)
class OptimumResult:
    """The constrained optimum.

    Attributes
    ----------
    objective, sense
        The objective's response name and ``"max"`` or ``"min"``.
    coded
        The design point in coded units ``{factor: c}``.
    point
        The design point in the factors' units (``None`` if no space was given).
    predicted, ci, pi
        Predicted objective, its confidence interval (of the mean surface) and prediction
        interval (of a new run), at ``level``.
    constraints
        Per constraint: predicted value, its minimum or maximum, slack (how far inside the
        bound the prediction lies), and the prediction bound on the infeasible side (pi_lower
        of a minimum, pi_upper of a maximum).
    level
        Confidence level of the intervals.
    n_starts, n_feasible
        Starts tried and how many ended feasible.
    """

    objective: str
    unit: str
    sense: str
    coded: dict[str, float]
    point: dict[str, float] | None
    predicted: float
    ci: tuple[float, float]
    pi: tuple[float, float]
    constraints: dict[str, dict[str, float]]
    level: float
    n_starts: int
    n_feasible: int

    def to_dict(self) -> dict:
        return {
            "objective": self.objective,
            "unit": self.unit,
            "sense": self.sense,
            "coded": dict(self.coded),
            "point": None if self.point is None else dict(self.point),
            "predicted": self.predicted,
            "ci": list(self.ci),
            "pi": list(self.pi),
            "level": self.level,
            "constraints": {k: dict(v) for k, v in self.constraints.items()},
            "n_starts": self.n_starts,
            "n_feasible": self.n_feasible,
        }


def _constraint_value(con: SurfaceConstraint, c: np.ndarray, conservative: bool, level: float):
    """The constraint's margin at ``c`` (≥ 0 feasible): of the fitted mean, or of the
    prediction bound on the infeasible side when ``conservative``."""
    if conservative:
        pred = con.surface.predict(c[None, :], level=level)
        return float(con.margin((pred.pi_upper if con.upper else pred.pi_lower)[0]))
    return float(con.margin(con.surface.predict_mean(c)))


def constrained_optimum(
    objective: ResponseSurface,
    *,
    sense: str = "max",
    constraints: Sequence[SurfaceConstraint] = (),
    space: DesignSpace | None = None,
    n_starts: int = 20,
    seed: int | np.random.Generator = 0,
    level: float = 0.95,
    conservative: bool = False,
) -> OptimumResult:
    """Optimum of ``objective`` over the coded box subject to ``constraints``.

    Parameters
    ----------
    objective
        The surface to maximise or minimise.
    sense
        ``"max"`` or ``"min"``.
    constraints
        Each ``SurfaceConstraint(surface, minimum)`` demands surface ≥ minimum.
    space
        If given, the optimum is also returned in the factors' units.
    n_starts
        Random starting points (plus the centre and the best run of the design).
    seed
        Seed or Generator of the starting points.
    level
        Confidence level of the reported intervals.
    conservative
        Impose the constraints on the lower prediction bound instead of the fitted mean.

    Raises
    ------
    OptimizationError
        If no start reaches a feasible point; the message names the constraint that cannot be
        met and the best value found for it.
    """
    if sense not in ("max", "min"):
        raise SpecError(f"sense must be 'max' or 'min', got {sense!r}", where="sense")
    names = objective.factor_names
    k = len(names)
    for con in constraints:
        if tuple(con.surface.factor_names) != tuple(names):
            raise SpecError(
                f"constraint {con.name!r} is fitted over other factors than the objective",
                where="constraints",
            )
    if space is not None and tuple(space.names) != tuple(names):
        raise SpecError("the design space's factors differ from the surface's", where="space")
    sign = -1.0 if sense == "max" else 1.0
    rng = np.random.default_rng(seed)

    starts = [np.zeros(k)]
    ys = objective.y if sense == "max" else -objective.y
    starts.append(np.clip(objective.coded[int(np.argmax(ys))], -1, 1))
    starts += list(rng.uniform(-1.0, 1.0, size=(max(0, int(n_starts)), k)))

    def fun(c: np.ndarray) -> float:
        return sign * float(objective.predict_mean(c))

    def jac(c: np.ndarray) -> np.ndarray:
        return sign * objective.gradient(c)

    cons = []
    for con in constraints:
        if conservative:
            cons.append(
                {"type": "ineq", "fun": (lambda c, con=con: _constraint_value(con, c, True, level))}
            )
        else:
            cons.append(
                {
                    "type": "ineq",
                    "fun": (lambda c, con=con: _constraint_value(con, c, False, level)),
                    "jac": (lambda c, con=con: (-1.0 if con.upper else 1.0)
                            * con.surface.gradient(c)),
                }
            )

    best_c, best_f, n_feasible = None, np.inf, 0
    worst: dict[str, float] = {con.name: -np.inf for con in constraints}
    for x0 in starts:
        res = optimize.minimize(
            fun, x0, jac=jac, bounds=[(-1.0, 1.0)] * k, constraints=cons, method="SLSQP",
            options={"maxiter": 200, "ftol": 1e-10},
        )
        c = np.clip(res.x, -1.0, 1.0)
        values = {con.name: _constraint_value(con, c, conservative, level) for con in constraints}
        for name, v in values.items():
            worst[name] = max(worst[name], v)
        if all(v >= -_FEAS_TOL for v in values.values()):
            n_feasible += 1
            f = fun(c)
            if f < best_f:
                best_c, best_f = c, f
    if best_c is None:
        name = min(worst, key=worst.get) if worst else "?"
        raise OptimizationError(
            f"no design in the box satisfies the constraints; {name} reached at best "
            f"{worst[name]:+.4g} inside its bound (negative: outside)",
            where=f"constraint {name}",
            hint="lower the margin, widen the factor ranges, or check the fitted surface",
        )
    pred = objective.predict(best_c[None, :], level=level)
    con_out = {}
    for con in constraints:
        pc = con.surface.predict(best_c[None, :], level=level)
        side = "upper" if con.upper else "lower"
        con_out[con.name] = {
            "predicted": float(pc.mean[0]),
            "maximum" if con.upper else "minimum": float(con.bound),
            "slack": float(con.margin(pc.mean[0])),
            f"pi_{side}": float(getattr(pc, f"pi_{side}")[0]),
        }
    return OptimumResult(
        objective=objective.response,
        unit=objective.unit,
        sense=sense,
        coded={n: float(v) for n, v in zip(names, best_c, strict=True)},
        point=None if space is None else space.point(best_c),
        predicted=float(pred.mean[0]),
        ci=(float(pred.ci_lower[0]), float(pred.ci_upper[0])),
        pi=(float(pred.pi_lower[0]), float(pred.pi_upper[0])),
        constraints=con_out,
        level=level,
        n_starts=len(starts),
        n_feasible=n_feasible,
    )
